// pp5sim: the command-line program.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <thread>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/config/machine_config.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;
using namespace pp5;

namespace {

// A firmware argument is a path, or the name of a program in firmware/programs.
std::string resolve_firmware(const std::string& name) {
  if (fs::exists(name)) return name;
  const fs::path builtin = fs::path(PP5_SOURCE_DIR) / "firmware" / "programs" / (name + ".pp5");
  if (fs::exists(builtin)) return builtin.string();
  std::string names;
  for (const auto& entry : fs::directory_iterator(builtin.parent_path())) {
    if (entry.path().extension() == ".pp5") names += " " + entry.path().stem().string();
  }
  throw std::runtime_error(
      fmt::format("--firmware {}: no such file, and no built-in program of that name (built-in:{})",
                  name, names));
}

MachineConfig load_config(const std::string& path, const std::vector<std::string>& sets) {
  MachineConfig config = path.empty() ? MachineConfig::defaults() : MachineConfig::from_file(path);
  config.set(sets);
  return config;
}

// Markdown table cells must not contain a bare '|'.
std::string cell(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string isa_reference() {
  std::string out = "| instruction | operands | effect | cycles |\n|---|---|---|---|\n";
  for (const auto& i : instruction_table()) {
    out += fmt::format("| `{}` | {} | {} | {} |\n", i.syntax, i.operands[0] ? i.operands : "-",
                       cell(i.effect), cell(i.cycles));
  }
  out +=
      "\nOperand letters: F field (written), R field (read), V field or constant, K constant "
      "(integer or frame parameter), E expression, B backing-store block.\n"
      "Conditions: lt le eq ne ge gt.\n\nExpressions (procedure triangle only):\n\n";
  for (const auto& e : kExpressions) out += fmt::format("- `{}`: {}\n", e.name, e.meaning);
  out += "\nFrame parameters (any procedure):\n\n";
  for (const auto& p : kParameters) out += fmt::format("- `{}`: {}\n", p.name, p.meaning);
  out += "\nProcedures:\n\n";
  for (int k = 0; k < static_cast<int>(Procedure::count); ++k) {
    out += fmt::format("- `{}`: {}\n", kProcedureNames[k], kProcedureMeaning[k]);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pp5sim: a cycle-approximate simulator of the Pixel-Planes 5 graphics machine.\n"
      "With no subcommand it renders the built-in torus with the Phong firmware."};
  app.require_subcommand(0, 1);

  std::string scene_name = "torus";
  std::string firmware = "phong";
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<int> tessellation;

  auto* render = app.add_subcommand("render", "Render one frame of a scene and write its reports");
  render->add_option("-s,--scene", scene_name, "Built-in scene: torus, two-triangles, sphere")
      ->capture_default_str();
  render
      ->add_option("-f,--firmware", firmware,
                   "Firmware program: a .pp5 file, or a name in firmware/programs "
                   "(flat, gouraud, phong)")
      ->capture_default_str();
  render->add_option("-c,--config", config_path,
                     "Machine configuration (JSON); unspecified keys take their defaults");
  render->add_option("--set", sets,
                     "Override one parameter, KEY=VALUE (repeatable), e.g. "
                     "--set renderer.count=8");
  render->add_option("-o,--out", out_dir,
                     "Output folder for frame.png, config.json and stats.json [out/SCENE]");
  render
      ->add_option("-j,--threads", threads,
                   "Host threads for the pixel arrays (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  render
      ->add_option("--tessellation", tessellation,
                   "Tessellation U V of the torus or sphere (default 128 32 and 64 32)")
      ->expected(2);

  auto* isa =
      app.add_subcommand("isa", "Print the micro-instruction set and the firmware interface");
  std::string asm_file;
  auto* assemble_cmd =
      app.add_subcommand("asm", "Assemble a firmware program and print its field map and listing");
  assemble_cmd->add_option("program", asm_file, "A .pp5 file or a built-in program name")
      ->required();
  assemble_cmd->add_option("-c,--config", config_path, "Machine configuration (JSON)");
  assemble_cmd->add_option("--set", sets, "Override one parameter, KEY=VALUE");
  bool describe = false;
  auto* config_cmd = app.add_subcommand(
      "config", "Print the resolved machine configuration as JSON, or describe every parameter");
  config_cmd->add_option("-c,--config", config_path, "Machine configuration (JSON)");
  config_cmd->add_option("--set", sets, "Override one parameter, KEY=VALUE");
  config_cmd->add_flag("--describe", describe,
                       "A table of every parameter: default, range, unit, source, meaning");
  auto* scenes_cmd = app.add_subcommand("scenes", "List the built-in scenes");

  CLI11_PARSE(app, argc, argv);

  try {
    if (*isa) {
      std::cout << isa_reference();
      return 0;
    }
    if (*scenes_cmd) {
      for (const auto& name : builtin_scene_names()) {
        std::cout << fmt::format("{:<14} {}\n", name, make_builtin_scene(name).description);
      }
      return 0;
    }
    if (*config_cmd) {
      if (describe) {
        std::cout
            << "| key | default | range | unit | conf. | meaning |\n|---|---|---|---|---|---|\n";
        for (const auto& p : describe_parameters()) {
          std::cout << fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", p.key, p.default_value,
                                   p.range, p.unit, p.confidence, cell(p.description));
        }
        std::cout
            << "\nConfidence: P published (SIGGRAPH 1989), S secondary source, A assumption.\n";
      } else {
        std::cout << load_config(config_path, sets).to_json().dump(2) << "\n";
      }
      return 0;
    }
    if (*assemble_cmd) {
      const MachineConfig config = load_config(config_path, sets);
      const Program program = assemble_file(resolve_firmware(asm_file), assembler_options(config));
      std::cout << listing(program, timing_params(config));
      return 0;
    }

    // render, the default
    const MachineConfig config = load_config(config_path, sets);
    SceneOptions scene_options;
    if (tessellation.size() == 2) {
      scene_options.tessellation_u = tessellation[0];
      scene_options.tessellation_v = tessellation[1];
    }
    const Scene scene = make_builtin_scene(scene_name, scene_options);
    const Program program = assemble_file(resolve_firmware(firmware), assembler_options(config));
    if (out_dir.empty()) out_dir = (fs::path("out") / scene_name).string();
    fs::create_directories(out_dir);

    const FrameResult result = simulate_frame(config, scene, program, threads);
    const fs::path dir(out_dir);
    write_png((dir / "frame.png").string(), result.image);
    write_file_atomically((dir / "config.json").string(), config.to_json().dump(2) + "\n");
    write_file_atomically((dir / "stats.json").string(), result.stats.dump(2) + "\n");

    std::cout << fmt::format("pp5sim: scene '{}' ({} triangles), firmware {}\n\n", scene.name,
                             scene.mesh.triangles.size(), program.name);
    std::cout << summary(result, program, timing_params(config));
    std::cout << fmt::format("\nwrote {}/frame.png, {}/config.json, {}/stats.json\n", out_dir,
                             out_dir, out_dir);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "pp5sim: error: " << e.what() << "\n";
    return 1;
  }
}
