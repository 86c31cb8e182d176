// pp5sim highlight: accuracy and cost of the intersection-highlighting firmware (Banks), a
// table of program x scene against the world-space truth, with overlay images.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/analysis/intersections.hpp"
#include "sim/app/commands.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;

namespace pp5 {

std::map<std::string, std::int64_t> parse_frame_parameters(const std::vector<std::string>& items) {
  std::map<std::string, std::int64_t> out;
  for (const std::string& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::runtime_error(fmt::format("--param '{}': expected NAME=VALUE", item));
    }
    const std::string name = item.substr(0, eq);
    if (parameter_index(name) < 0) {
      std::vector<std::string> names;
      for (const auto& p : kParameters) names.push_back(p.name);
      throw std::runtime_error(fmt::format("--param '{}': no frame parameter '{}' (known: {})",
                                           item, name, fmt::join(names, " ")));
    }
    const std::string value = item.substr(eq + 1);
    std::size_t used = 0;
    std::int64_t v = 0;
    try {
      v = std::stoll(value, &used, 0);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size()) {
      throw std::runtime_error(fmt::format("--param '{}': '{}' is not an integer", item, value));
    }
    out[name] = v;
  }
  return out;
}

namespace {

struct HighlightOptions {
  std::vector<std::string> scenes = {"two-triangles", "crossing-quads", "figure-eight", "torus"};
  std::vector<std::string> programs = {"exactmatch",
                                       "exactmatch_n",
                                       "threshold",
                                       "epsilon",
                                       "epsilon_normal",
                                       "epsilon_folded",
                                       "transparent_exactmatch",
                                       "transparent_threshold"};
  std::string speed_scene = "torus";
  std::vector<std::string> params;
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/highlight";
  int threads = default_threads();
};

std::string spilled_fields(const Program& p) {
  std::vector<std::string> names;
  for (const FieldDecl& f : p.fields) {
    if (f.spilled) names.push_back(f.name);
  }
  return names.empty() ? "-" : fmt::format("{}", fmt::join(names, " "));
}

int run_highlight(const HighlightOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const auto params = parse_frame_parameters(o.params);
  // Everything is checked before the first file is written.
  std::vector<Scene> scenes;
  for (const std::string& name : o.scenes) {
    scenes.push_back(make_builtin_scene(name));
    scenes.back().parameters = params;
    GeometryEngine(geometry_params(config), scenes.back()).frame_parameters();
  }

  struct Entry {
    std::string name;
    Program program;
    double speed = 0;
  };
  std::vector<Entry> programs;
  for (const std::string& name : o.programs) {
    Entry e{name, assemble_file(resolve_firmware(name), assembler_options(config))};
    if (e.program.find_field("iflag") == nullptr) {
      throw std::runtime_error(
          fmt::format("{}: not a highlighting program (it has no field 'iflag')", name));
    }
    programs.push_back(std::move(e));
  }
  fs::create_directories(o.out_dir);
  // Projected polygons per second, from the timing model, on one scene.
  if (!o.speed_scene.empty()) {
    Scene scene = make_builtin_scene(o.speed_scene);
    scene.parameters = params;
    for (Entry& e : programs) {
      e.speed = simulate_frame(config, scene, e.program, o.threads).triangles_per_second;
    }
  }

  std::string table = fmt::format(
      "| program | scene | truth px | flagged px | recall | precision | width mean | width sd | "
      "coverage | bits of {} | spilled | {} polygons/s "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      config.renderer.memory_bits, o.speed_scene);
  std::string csv =
      "program,scene,truth_pixels,flagged_pixels,recall,precision,width_mean,width_sd,coverage,"
      "bits_used,memory_bits,spilled,polygons_per_second\n";
  for (const Scene& scene : scenes) {
    const std::string& scene_name = scene.name;
    const GeometryEngine geometry(geometry_params(config), scene);
    const double delta =
        static_cast<double>(geometry.frame_parameters()[static_cast<int>(Parameter::delta)]) / 16.0;
    // Opaque programs are judged against the visible curves, multipass (transparency)
    // programs against all of them.
    IntersectionTruth truths[2];
    for (int all = 0; all < 2; ++all) {
      truths[all] = intersection_truth(scene, config.screen.width, config.screen.height, delta,
                                       0.25, all == 0);
    }
    std::cerr << fmt::format("{}: {} intersection segments; {} truth pixels visible, {} in all\n",
                             scene_name, truths[0].segments, truths[0].pixels, truths[1].pixels);
    const fs::path dir = fs::path(o.out_dir) / scene_name;
    fs::create_directories(dir);
    for (const Entry& e : programs) {
      const IntersectionTruth& truth = truths[e.program.passes > 1 ? 1 : 0];
      const FieldFrame frame = render_field(config, scene, e.program, "iflag", o.threads);
      std::vector<std::uint8_t> flagged(frame.values.size());
      for (std::size_t p = 0; p < flagged.size(); ++p) flagged[p] = frame.values[p] != 0;
      const Accuracy a = measure_accuracy(truth, flagged);
      write_png((dir / (e.name + ".png")).string(), frame.image);
      write_png((dir / (e.name + "-overlay.png")).string(),
                overlay_image(frame.image, truth, flagged));
      const std::string speed = o.speed_scene.empty() ? "-" : fmt::format("{:.0f}", e.speed);
      table += fmt::format(
          "| {} | {} | {} | {} | {:.3f} | {:.3f} | {:.2f} | {:.2f} | {:.3f} | {} | {} | {} |\n",
          e.name, scene_name, a.truth, a.flagged, a.recall, a.precision, a.width_mean, a.width_sd,
          a.coverage, e.program.bits_used(), spilled_fields(e.program), speed);
      csv += fmt::format("{},{},{},{},{:.6f},{:.6f},{:.4f},{:.4f},{:.6f},{},{},{},{}\n", e.name,
                         scene_name, a.truth, a.flagged, a.recall, a.precision, a.width_mean,
                         a.width_sd, a.coverage, e.program.bits_used(), config.renderer.memory_bits,
                         spilled_fields(e.program), speed);
    }
  }
  write_file_atomically((fs::path(o.out_dir) / "highlight.md").string(), table);
  write_file_atomically((fs::path(o.out_dir) / "highlight.csv").string(), csv);
  std::cout << table;
  std::cout << fmt::format(
      "\nwidths in pixels across the true curve (delta = {} px half-width); overlays: green = "
      "flagged and true, red = flagged only, blue = missed\nwrote {}/highlight.md, "
      "{}/highlight.csv and {}/SCENE/PROGRAM[-overlay].png\n",
      static_cast<double>(params.count("delta") ? params.at("delta") : 24) / 16.0, o.out_dir,
      o.out_dir, o.out_dir);
  return 0;
}

}  // namespace

Command add_highlight_command(CLI::App& app) {
  auto o = std::make_shared<HighlightOptions>();
  auto* cmd = app.add_subcommand(
      "highlight",
      "Measure the intersection-highlighting firmware: recall and precision of the flagged "
      "pixels against the true visible intersection curves, the curve's width, the bit budget "
      "and projected polygons per second, for every program x scene");
  cmd->add_option("-s,--scenes", o->scenes, "Built-in scenes")->capture_default_str();
  cmd->add_option("-f,--firmware", o->programs,
                  "Highlighting programs (.pp5 files or names in firmware/programs); each must "
                  "keep its flag in a field 'iflag'")
      ->capture_default_str();
  cmd->add_option("--speed-scene", o->speed_scene,
                  "Scene for the projected polygons/s column ('' to skip)")
      ->capture_default_str();
  cmd->add_option("--param", o->params,
                  "Set a frame parameter, NAME=VALUE (repeatable), e.g. --param delta=32 "
                  "--param threshold=8192 (see pp5sim isa)");
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder for the table and images")
      ->capture_default_str();
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  return {cmd, [o] { return run_highlight(*o); }};
}

}  // namespace pp5
