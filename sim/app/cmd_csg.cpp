// pp5sim csg: the parity and depth-interval applications of issue 15 against a CPU ray
// caster (sim/analysis/csg.hpp). Today: point in solid by parity, standard and accurate.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/analysis/csg.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"

namespace pp5 {

namespace {

namespace fs = std::filesystem;

struct CsgOptions {
  std::vector<std::string> scenes;
  std::vector<std::string> programs = {"parity", "parity_accurate"};
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/csg";
  int threads = default_threads();
};

int run_csg(const CsgOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  std::vector<std::string> names = o.scenes;
  if (names.empty()) names = parity_scene_names();
  std::vector<Scene> scenes;
  for (const std::string& name : names) scenes.push_back(make_parity_scene(name));
  std::vector<Program> programs;
  for (const std::string& name : o.programs) {
    programs.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    programs.back().name = name;
  }
  prepare_output_folder(o.out_dir, "--out");
  std::vector<ParityMeasure> rows;
  OutputSet outputs;
  for (const Scene& scene : scenes) {
    for (const Program& program : programs) {
      rows.push_back(measure_parity(config, scene, program, o.threads));
      const std::string base =
          (fs::path(o.out_dir) / fmt::format("{}-{}", scene.name, program.name)).string();
      outputs.add(base + ".png", encode_png(rows.back().image));
      outputs.add(base + "-difference.png", encode_png(rows.back().difference));
    }
  }
  const std::string table = format_parity(rows);
  outputs.add((fs::path(o.out_dir) / "csg.md").string(), table);
  outputs.commit();
  std::cout << fmt::format(
                   "{} x {} screen; pixels compared with a double-precision ray caster "
                   "at the pixel centre, those within 0.75 pixel of an edge left out\n\n",
                   config.screen.width, config.screen.height)
            << table << "\n"
            << fmt::format("wrote {0}/csg.md and {0}/SCENE-PROGRAM{{,-difference}}.png\n",
                           o.out_dir);
  return 0;
}

}  // namespace

Command add_csg_command(CLI::App& app) {
  auto o = std::make_shared<CsgOptions>();
  auto* cmd = app.add_subcommand(
      "csg",
      "Parity applications on the machine (issue 15) against a double-precision ray caster: "
      "point in solid by parity, with standard and accurate scan conversion, on scenes made "
      "for it (a plane of points through closed solids). Prints the agreement table (pixels "
      "disagreeing, passes, bits, cycles, frame time) and writes each image and an image of "
      "the differing pixels (white; grey: near an edge, not compared).");
  cmd->add_option("-s,--scene", o->scenes,
                  "A parity scene (repeatable): plane-sphere, "
                  "plane-boxes; default both");
  cmd->add_option("-p,--program", o->programs,
                  "A program defining 'parity' (repeatable); default parity and parity_accurate");
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder (default out/csg)");
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  return {cmd, [o] { return run_csg(*o); }};
}

}  // namespace pp5
