// pp5sim visible: the visible-surface comparison (sim/analysis/visible_surface.hpp): z-buffer
// and painter's on the machine, scan-line and Warnock on the CPU, against an exact reference.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "models/machine.hpp"
#include "sim/analysis/visible_surface.hpp"
#include "sim/app/commands.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene_loader.hpp"

namespace pp5 {

namespace {

struct VisibleOptions {
  std::vector<std::string> scenes;
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/visible";
  int threads = default_threads();
  PainterOptions painter;
  bool report = false;  // also OUT/report.html
};

// A scene's name as a file-name prefix: letters, digits, '-' and '_' kept, others '_'.
std::string file_stem(const std::string& name) {
  std::string s = name.empty() ? "scene" : name;
  for (char& c : s) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '_';
    if (!keep) c = '_';
  }
  return s;
}

int run_visible(const VisibleOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const Program zbuffer = assemble_file(resolve_firmware("gouraud"), assembler_options(config));
  const Program painter = assemble_file(resolve_firmware("painter"), assembler_options(config));
  const std::vector<std::string> names =
      o.scenes.empty() ? builtin_triangle_scene_names() : o.scenes;
  // Every scene loads before any runs, so a bad name fails at once.
  std::vector<Scene> scenes;
  for (const std::string& n : names) scenes.push_back(load_scene(n));
  std::vector<VisibleSceneReport> reports;
  for (const Scene& s : scenes) {
    reports.push_back(analyse_visible_surfaces(config, s, zbuffer, painter, o.threads, o.painter));
  }
  const report::Table comparison = visible_table(reports, config);
  const std::string notes = visible_notes(reports);
  const std::string table = report::markdown(comparison) + "\n" + notes;
  std::cout << table;
  report::Report rep;
  rep.title = "Visible-surface algorithms compared";
  rep.subtitle = fmt::format("{} x {} screen; each algorithm against an exact per-pixel ray cast",
                             config.screen.width, config.screen.height);
  report::Section& section = rep.add_section("visible", "Comparison");
  section.blocks.push_back(comparison);
  // The per-scene notes (a Markdown list), a paragraph per item.
  for (std::size_t at = 0, end; at < notes.size(); at = end + 1) {
    end = notes.find('\n', at);
    if (end == std::string::npos) end = notes.size();
    const std::string line = notes.substr(at, end - at);
    const std::size_t text = line.find("- ");
    if (text != std::string::npos)
      section.blocks.push_back(report::Paragraph{line.substr(text + 2)});
  }
  report::Section& frames = rep.add_section("frames", "Frames and differences");

  prepare_output_folder(o.out_dir, "--out");
  const std::filesystem::path dir(o.out_dir);
  OutputSet outputs;
  const char* const row_files[] = {"diff-zbuffer", "diff-painter", "diff-scanline", "diff-warnock"};
  for (const VisibleSceneReport& r : reports) {
    const std::string stem = file_stem(r.scene);
    auto image = [&](const std::string& file, const RgbImage& picture, const std::string& what) {
      std::string png = encode_png(picture);
      if (o.report) {
        frames.blocks.push_back(report::Figure{file, fmt::format("{}: {}", r.scene, what), "",
                                               "image/png", png,
                                               fmt::format("{} of {}", what, r.scene), file});
      }
      outputs.add((dir / file).string(), std::move(png));
    };
    image(stem + "-zbuffer.png", r.zbuffer_frame, "the z-buffer's frame");
    image(stem + "-painter.png", r.painter_frame, "painter's frame");
    for (std::size_t k = 0; k < r.rows.size(); ++k) {
      image(stem + "-" + row_files[k] + ".png", r.rows[k].image,
            r.rows[k].name + " against the reference (red: differs)");
    }
    outputs.add((dir / (stem + "-depth-flips.png")).string(), encode_png(r.flip_image));
  }
  outputs.add((dir / "visible.md").string(), table);
  add_report_outputs(outputs, o.out_dir, rep, o.report);
  outputs.add((dir / "visible.json").string(),
              visible_statistics(reports).to_json().dump(2) + "\n");
  outputs.commit();
  std::cout << fmt::format(
      "\nwrote {}/visible.md, visible.csv, visible.json{} and the difference images\n", o.out_dir,
      o.report ? ", report.html" : "");
  return 0;
}

}  // namespace

Command add_visible_command(CLI::App& app) {
  auto o = std::make_shared<VisibleOptions>();
  auto* cmd = app.add_subcommand(
      "visible",
      "Visible-surface algorithms compared, per scene: the z-buffer (gouraud.pp5) and "
      "painter's with a depth sort on the GPs (painter.pp5) on the machine, scan-line and "
      "Warnock area subdivision on the CPU, each against an exact per-pixel ray cast: pixels "
      "that differ and the regions they cluster in, bits, GP clocks per primitive, Renderer "
      "cycles, projected primitives per second; then the depth sort's tests, bad against "
      "correct perspective depth, and back-face removal. Writes the table (visible.md), the "
      "same figures as statistics (visible.json), the shaded frames and a difference image per "
      "algorithm (red: differs from the reference).");
  cmd->add_option("-s,--scene", o->scenes,
                  "A scene to compare (repeatable): a built-in name, a mesh file or a scene "
                  "file; default every built-in scene of triangles (not the sphere scenes)");
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder (default out/visible)");
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_flag("!--painter-every-face", o->painter.remove_back_faces,
                "Painter's sorts and draws every face (two-sided); by default back faces are "
                "removed before the sort, as the slides' drawing algorithm does");
  cmd->add_flag("--painter-overhead-factor", o->painter.overhead_factor,
                "Multiply the depth sort's clocks by gp.overhead_factor (fitted to the transform "
                "loop); by default the sort is costed from its own operation counts");
  cmd->add_flag("!--painter-resort", o->painter.insert_pieces,
                "Splitting sorts every polygon again each round; by default the pieces are "
                "inserted into the order and only the pairs they touch are checked again");
  cmd->add_option("--painter-containment", o->painter.containment,
                  "The depth sort's containment step: edges (a centroid against every edge of "
                  "the other polygon, the default) or rectangle (the slides' minimax test of a "
                  "centre against the other's containing rectangle)")
      ->transform(CLI::CheckedTransformer(
                      std::map<std::string, Containment>{{"edges", Containment::edges},
                                                         {"rectangle", Containment::rectangle}})
                      .description("{edges,rectangle}"))
      ->type_name("TEXT");
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  return {cmd, [o] { return run_visible(*o); }};
}

}  // namespace pp5
