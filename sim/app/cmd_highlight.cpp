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
#include "sim/output/output_set.hpp"
#include "sim/scene/order.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

struct HighlightOptions {
  std::vector<std::string> scenes = {"two-triangles", "crossing-quads", "figure-eight", "torus",
                                     "receding-pairs"};
  std::vector<std::string> programs = {"exactmatch",
                                       "exactmatch_n",
                                       "threshold",
                                       "threshold_keep",
                                       "threshold_eyez",
                                       "epsilon",
                                       "epsilon_normal",
                                       "epsilon_folded",
                                       "epsilon_folded_squares",
                                       "transparent_exactmatch",
                                       "transparent_threshold"};
  std::string speed_scene = "torus";
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/highlight";
  int threads = default_threads();
  std::string order = "given";
  std::string compare_order = "reversed";
};

std::string spilled_fields(const Program& p) {
  std::vector<std::string> names;
  for (const FieldDecl& f : p.fields) {
    if (f.spilled) names.push_back(f.name);
  }
  return names.empty() ? "-" : fmt::format("{}", fmt::join(names, " "));
}

constexpr std::size_t kMaxCurvesReported = 8;

int run_highlight(const HighlightOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const DisplayOrder order = parse_display_order(o.order, "--order");
  const bool compare = o.compare_order != "none";
  const DisplayOrder other =
      compare ? parse_display_order(o.compare_order, "--compare-order") : DisplayOrder{};
  // Everything is checked before the first file is written.
  std::vector<Scene> scenes;
  for (const std::string& name : o.scenes) {
    scenes.push_back(make_builtin_scene(name));
    apply_display_order(scenes.back().mesh, order);
    GeometryEngine(geometry_params(config), scenes.back()).frame_parameters();
  }

  struct Entry {
    std::string name;
    Program program;
    double speed = 0;           // with the configured GP code profile
    double speed_compiled = 0;  // with gp.code=compiled (the C code the paper modified)
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
  prepare_output_folder(o.out_dir, "--out");
  OutputSet outputs;
  // Projected polygons per second, from the timing model, on one scene: with the configured
  // GP code and with the compiled C code, which Banks' variants were built on.
  MachineConfig compiled = config;
  compiled.set(std::vector<std::string>{"gp.code=compiled"});
  if (!o.speed_scene.empty()) {
    Scene scene = make_builtin_scene(o.speed_scene);
    apply_display_order(scene.mesh, order);
    for (Entry& e : programs) {
      e.speed = simulate_frame(config, scene, e.program, o.threads).triangles_per_second;
      e.speed_compiled =
          config.gp.code == MachineConfig::Gp::Code::compiled
              ? e.speed
              : simulate_frame(compiled, scene, e.program, o.threads).triangles_per_second;
    }
  }

  std::string table = fmt::format(
      "| program | scene | truth px | flagged px | recall | recall ceiling | precision | width "
      "mean | "
      "width sd | coverage | {} | bits of {} | spilled | {} polygons/s ({} GP code) | {} "
      "polygons/s (compiled GP code) "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      compare ? fmt::format("changed by {} order", other.text()) : std::string("order change"),
      config.renderer.memory_bits, o.speed_scene, name_of(config.gp.code), o.speed_scene);
  std::string curve_table;
  std::string csv =
      "program,scene,truth_pixels,flagged_pixels,recall,recall_ceiling,precision,width_mean,width_"
      "sd,coverage,"
      "order,compare_order,order_changed_pixels,order_change,bits_used,memory_bits,spilled,"
      "polygons_per_second,polygons_per_second_compiled\n";
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
    std::cerr << fmt::format(
        "{}: {} intersection segments; {} truth pixels visible ({} reached by two or more "
        "surfaces), {} in all ({})\n",
        scene_name, truths[0].segments, truths[0].pixels, truths[0].reachable, truths[1].pixels,
        truths[1].reachable);
    // The same scene in the other display-list order (from the built-in order, so that
    // "--order reversed --compare-order given" compares the same two orders both ways).
    Scene reordered = make_builtin_scene(scene_name);
    apply_display_order(reordered.mesh, other);
    // A scene of a few separate curves (receding-pairs) also gets the width along each, by
    // its midpoint's eye depth (distance along the view axis).
    const std::vector<Segment3>& curves = truths[0].curves;
    const bool by_curve = !curves.empty() && curves.size() <= kMaxCurvesReported;
    if (by_curve) {
      const glm::dvec3 eye(scene.camera.eye);
      const glm::dvec3 axis = glm::normalize(glm::dvec3(scene.camera.target) - eye);
      curve_table += fmt::format(
          "\nwidth in pixels along each curve of {} (mean +- sd):\n\n| program |", scene_name);
      for (const Segment3& c : curves)
        curve_table += fmt::format(" eye depth {:.2f} |", glm::dot(0.5 * (c.a + c.b) - eye, axis));
      curve_table += "\n|---|";
      for (std::size_t i = 0; i < curves.size(); ++i) curve_table += "---|";
      curve_table += "\n";
    }
    const fs::path dir = fs::path(o.out_dir) / scene_name;
    fs::create_directories(dir);
    for (const Entry& e : programs) {
      const IntersectionTruth& truth = truths[e.program.multipass() ? 1 : 0];
      const FieldFrame frame = render_field(config, scene, e.program, "iflag", o.threads);
      std::vector<std::uint8_t> flagged(frame.values.size());
      for (std::size_t p = 0; p < flagged.size(); ++p) flagged[p] = frame.values[p] != 0;
      const Accuracy a = measure_accuracy(truth, flagged);
      if (by_curve) {
        curve_table += fmt::format("| {} |", e.name);
        for (const Accuracy& c : measure_width_by_segment(truth, flagged)) {
          curve_table += c.width_samples
                             ? fmt::format(" {:.2f} +- {:.2f} |", c.width_mean, c.width_sd)
                             : std::string(" - |");
        }
        curve_table += "\n";
      }
      // Order sensitivity: pixels whose flag differs in the other order, as a share of the
      // pixels flagged in this one.
      std::size_t changed = 0;
      std::string change = "-";
      if (compare) {
        const FieldFrame second = render_field(config, reordered, e.program, "iflag", o.threads);
        for (std::size_t p = 0; p < flagged.size(); ++p)
          changed += (second.values[p] != 0) != (flagged[p] != 0);
        change = fmt::format(
            "{:.4f} ({} px)",
            a.flagged ? static_cast<double>(changed) / a.flagged : static_cast<double>(changed),
            changed);
      }
      outputs.add((dir / (e.name + ".png")).string(), encode_png(frame.image));
      outputs.add((dir / (e.name + "-overlay.png")).string(),
                  encode_png(overlay_image(frame.image, truth, flagged)));
      const std::string speed = o.speed_scene.empty() ? "-" : fmt::format("{:.0f}", e.speed);
      const std::string speed_compiled =
          o.speed_scene.empty() ? "-" : fmt::format("{:.0f}", e.speed_compiled);
      table += fmt::format(
          "| {} | {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.2f} | {:.2f} | {:.3f} | {} | {} | "
          "{} "
          "| {} | {} |\n",
          e.name, scene_name, a.truth, a.flagged, a.recall, a.ceiling, a.precision, a.width_mean,
          a.width_sd, a.coverage, change, e.program.bits_used(), spilled_fields(e.program), speed,
          speed_compiled);
      csv += fmt::format(
          "{},{},{},{},{:.6f},{:.6f},{:.6f},{:.4f},{:.4f},{:.6f},{},{},{},{},{},{},{},{},{}\n",
          e.name, scene_name, a.truth, a.flagged, a.recall, a.ceiling, a.precision, a.width_mean,
          a.width_sd, a.coverage, order.text(), compare ? other.text() : "none",
          compare ? changed : 0,
          compare && a.flagged ? static_cast<double>(changed) / a.flagged : 0.0,
          e.program.bits_used(), config.renderer.memory_bits, spilled_fields(e.program), speed,
          speed_compiled);
    }
  }
  table += curve_table;
  outputs.add((fs::path(o.out_dir) / "highlight.md").string(), table);
  outputs.add((fs::path(o.out_dir) / "highlight.csv").string(), csv);
  // The tables and every image together, or none of them (sim/output).
  outputs.commit();
  std::cout << table;
  std::cout << fmt::format(
      "\nwidths in pixels across the true curve (delta = {} px half-width); overlays: green = "
      "flagged and true, red = flagged only, blue = missed\nwrote {}/highlight.md, "
      "{}/highlight.csv and {}/SCENE/PROGRAM[-overlay].png\n",
      static_cast<double>(resolved_frame_parameter(config, Parameter::delta)) / 16.0, o.out_dir,
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
                  "Highlighting programs (bare names are built-in programs; a path with a '/' "
                  "or ending in .pp5 is a file); each must keep its flag in a field 'iflag'")
      ->capture_default_str();
  cmd->add_option("--speed-scene", o->speed_scene,
                  "Scene for the projected polygons/s column ('' to skip)")
      ->capture_default_str();
  cmd->add_option("--order", o->order,
                  "Display-list order of every scene's triangles: given, reversed, shuffled or "
                  "shuffled:SEED (deterministic)")
      ->capture_default_str();
  cmd->add_option("--compare-order", o->compare_order,
                  "Render every program again in this order and report the share of flagged "
                  "pixels that change (order sensitivity), or 'none' to skip")
      ->capture_default_str();
  add_config_options(*cmd, o->config_path, o->sets);
  add_fidelity_option(*cmd, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder for the table and images")
      ->capture_default_str();
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  return {cmd, [o] { return run_highlight(*o); }};
}

}  // namespace pp5
