// pp5sim extremes: the numerical-stability report (sim/analysis/extremes.hpp).
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "sim/analysis/extremes.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/output/report_html.hpp"
#include "sim/scene/scene_loader.hpp"

namespace pp5 {

namespace {

struct ExtremesOptions {
  std::string scene_name;
  std::string config_path;
  std::vector<std::string> sets;
  int threads = default_threads();
  bool synthetic = true;
  std::string report;  // also this HTML file (sim/output/report_html.hpp)
};

int run_extremes(const ExtremesOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  std::vector<ExtremeCase> cases;
  if (o.synthetic) cases = synthetic_extreme_cases(config, o.threads);
  if (!o.scene_name.empty()) {
    const Scene scene = load_scene(o.scene_name);
    std::cout << fmt::format("scene '{}' ({} triangles) on a {} x {} screen\n", scene.name,
                             scene.mesh.triangles.size(), config.screen.width,
                             config.screen.height);
    const auto more = scene_extreme_cases(config, scene, o.threads);
    cases.insert(cases.end(), more.begin(), more.end());
  }
  std::cout << format_extremes(cases);
  if (!o.report.empty()) {
    report::Report r = extremes_report(cases);
    r.subtitle = o.synthetic
                     ? "The synthetic cases, each on a 256 x 256 screen of the configured machine"
                     : std::string();
    if (!o.scene_name.empty()) {
      r.subtitle +=
          fmt::format("{}scene '{}' on the configured {} x {} screen", o.synthetic ? "; " : "",
                      o.scene_name, config.screen.width, config.screen.height);
    }
    const std::filesystem::path folder = std::filesystem::path(o.report).parent_path();
    if (!folder.empty()) prepare_output_folder(folder.string(), "--report");
    write_file_atomically(o.report, report::html(r));
    std::cout << fmt::format("wrote {}\n", o.report);
  }
  for (const ExtremeCase& c : cases) {
    if (!c.pass) return 1;
  }
  return 0;
}

}  // namespace

Command add_extremes_command(CLI::App& app) {
  auto o = std::make_shared<ExtremesOptions>();
  auto* cmd = app.add_subcommand(
      "extremes",
      "Numerical stability at the extremes: depth precision, coefficient overflow, edge-on "
      "triangles, slivers, sub-pixel triangles, huge coordinates, nearly parallel and "
      "coincident planes, both ends of the depth range and pixel-centre ownership along "
      "shared edges, each with what is expected, what happened and PASS or FAIL (exit 1 if "
      "any fails). With --scene, also the checks on that scene: set-up drops, coverage "
      "against an exact reference, parity across a closed mesh.");
  cmd->add_option("-s,--scene", o->scene_name,
                  "Also check this scene: a built-in name, a mesh file or a scene file");
  add_config_options(*cmd, o->config_path, o->sets);
  add_fidelity_option(*cmd, o->sets);
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  cmd->add_flag("!--no-synthetic", o->synthetic, "Only the checks on --scene");
  cmd->add_option("--report", o->report,
                  "Also write the cases to FILE as a self-contained HTML page (a sortable, "
                  "searchable table)");
  return {cmd, [o] { return run_extremes(*o); }};
}

}  // namespace pp5
