// pp5sim highlight: accuracy and cost of the intersection-highlighting firmware (Banks), a
// table of program x scene against the world-space truth, with overlay images.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

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
  bool report = false;  // also OUT/report.html
};

std::string spilled_fields(const Program& p) {
  std::vector<std::string> names;
  for (const FieldDecl& f : p.fields) {
    if (f.spilled) names.push_back(f.name);
  }
  return names.empty() ? "-" : fmt::format("{}", fmt::join(names, " "));
}

constexpr std::size_t kMaxCurvesReported = 8;

// The main table regrouped by program (its rows are scene-major, `programs` a scene): each
// program's rows together, its accuracy beside the recall ceiling, and what belongs to the
// program alone (bits, polygons/s) on its first row only.
report::Table highlight_summary(const report::Table& main, std::size_t programs,
                                const std::string& speed_scene) {
  auto at = [&main](const char* key) {
    for (std::size_t k = 0; k < main.columns.size(); ++k)
      if (main.columns[k].csv_key() == key) return k;
    throw std::logic_error(fmt::format("highlight table: no column '{}'", key));
  };
  const std::size_t program = at("program"), scene = at("scene"), recall = at("recall"),
                    ceiling = at("recall_ceiling"), precision = at("precision"),
                    width_mean = at("width_mean"), width_sd = at("width_sd"),
                    coverage = at("coverage"), order = at("order_change"), bits = at("bits_used"),
                    speed = at("polygons_per_second"),
                    compiled = at("polygons_per_second_compiled");
  report::Table t;
  t.id = "highlight-summary";
  auto copy = [&main](std::size_t k) { return main.columns[k]; };
  t.columns = {
      copy(program),
      copy(scene),
      copy(recall),
      copy(ceiling),
      copy(precision),
      report::headed(report::real_column("width", "pixels", 2,
                                         "Mean width of the flagged band across the "
                                         "true curve, +- its standard deviation"),
                     "width mean +- sd (px)", report::Align::left),
      copy(order),
      copy(bits),
      report::headed(report::real_column("polygons/s", "polygons/s", 0,
                                         fmt::format("Projected polygons per second on "
                                                     "{}: configured GP code / compiled",
                                                     speed_scene)),
                     fmt::format("{} polygons/s, configured / compiled GP code",
                                 speed_scene.empty() ? std::string("(none)") : speed_scene),
                     report::Align::left)};
  t.columns[5].key = "width_mean";
  t.columns[8].key = "polygons_per_second";
  const std::size_t scenes = programs ? main.rows.size() / programs : 0;
  for (std::size_t p = 0; p < programs; ++p) {
    for (std::size_t s = 0; s < scenes; ++s) {
      const std::vector<report::Cell>& row = main.rows[s * programs + p];
      const bool first = s == 0;
      const std::optional<double> mean = row[width_mean].number(), sd = row[width_sd].number();
      const std::optional<double> fast = row[speed].number(), slow = row[compiled].number();
      t.add_row({first ? row[program] : report::Cell(std::string()), row[scene], row[recall],
                 row[ceiling], row[precision],
                 row[coverage].number().value_or(0) > 0
                     ? report::Cell::shown_as(*mean, fmt::format("{:.2f} +- {:.2f}", *mean, *sd))
                     : report::Cell::missing(),
                 row[order], first ? row[bits] : report::Cell(std::string()),
                 !first ? report::Cell(std::string())
                 : fast && slow
                     ? report::Cell::shown_as(*fast, fmt::format("{:.0f} / {:.0f}", *fast, *slow))
                     : report::Cell::missing()});
    }
  }
  return t;
}

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

  // The main table: one row per program x scene, every column left-aligned as it always was.
  auto left = [](report::Column c, const std::string& heading, const std::string& key) {
    c.heading = heading;
    c.key = key;
    c.align = report::Align::left;
    return c;
  };
  report::Table table;
  table.id = "highlight";
  table.columns = {
      left(report::text_column("program"), "program", "program"),
      left(report::text_column("scene"), "scene", "scene"),
      left(report::integer_column("truth px", "pixels", "Pixels on a true intersection curve"),
           "truth px", "truth_pixels"),
      left(report::integer_column("flagged px", "pixels", "Pixels the firmware flags"),
           "flagged px", "flagged_pixels"),
      left(report::real_column("recall", "", 3, "Truth pixels flagged, of the truth pixels"),
           "recall", "recall"),
      left(report::real_column("recall ceiling", "", 3,
                               "Truth pixels reached by two or more surfaces, of the truth pixels "
                               "(the most a per-pixel test can find)"),
           "recall ceiling", "recall_ceiling"),
      left(report::real_column("precision", "", 3,
                               "Flagged pixels near a true curve, of the "
                               "flagged pixels"),
           "precision", "precision"),
      left(report::real_column("width mean", "pixels", 2,
                               "Mean width of the flagged band across the true curve"),
           "width mean", "width_mean"),
      left(report::real_column("width sd", "pixels", 2, "Its standard deviation"), "width sd",
           "width_sd"),
      left(report::real_column("coverage", "", 3, "Share of the true curve's length flagged"),
           "coverage", "coverage"),
      left(report::real_column("order change", "", 4,
                               fmt::format("Pixels whose flag differs in {} order, as a share of "
                                           "the flagged pixels",
                                           compare ? other.text() : std::string("another"))),
           compare ? fmt::format("changed by {} order", other.text()) : std::string("order change"),
           "order_change"),
      left(report::integer_column("bits", "bits", "Pixel-memory bits the program uses"),
           fmt::format("bits of {}", config.renderer.memory_bits), "bits_used"),
      left(report::text_column("spilled", "Fields spilled to the backing store"), "spilled",
           "spilled"),
      left(report::real_column("polygons/s", "polygons/s", 0,
                               fmt::format("Projected polygons per second on {}, with the "
                                           "configured GP code",
                                           o.speed_scene)),
           fmt::format("{} polygons/s ({} GP code)", o.speed_scene, name_of(config.gp.code)),
           "polygons_per_second"),
      left(report::real_column("polygons/s compiled", "polygons/s", 0,
                               fmt::format("Projected polygons per second on {}, with the "
                                           "compiled GP code",
                                           o.speed_scene)),
           fmt::format("{} polygons/s (compiled GP code)", o.speed_scene),
           "polygons_per_second_compiled"),
  };
  // Per scene, the truth and its recall ceiling: the visible curves (opaque programs' truth)
  // and every curve (multipass programs').
  report::Table truth_table;
  truth_table.id = "highlight-truth";
  truth_table.columns = {
      report::text_column("scene"),
      report::integer_column("segments", "", "World-space intersection segments"),
      report::headed(report::integer_column("truth px", "pixels",
                                            "Pixels within delta of a visible intersection curve"),
                     "truth px"),
      report::headed(report::integer_column("reached by two", "pixels",
                                            "Truth pixels whose centre two or more triangles "
                                            "cover"),
                     "reached by two"),
      report::headed(report::real_column("recall ceiling", "", 3,
                                         "Reached by two, of the truth pixels: the largest recall "
                                         "a program that compares depths at a pixel can reach"),
                     "recall ceiling"),
      report::headed(report::integer_column("truth px, every curve", "pixels",
                                            "Pixels within delta of any intersection curve, "
                                            "hidden or not (the multipass programs' truth)"),
                     "truth px, every curve"),
      report::headed(report::integer_column("reached by two, every curve", "pixels",
                                            "Of those, the pixels two or more triangles cover"),
                     "reached by two, every curve"),
      report::headed(report::real_column("recall ceiling, every curve", "", 3,
                                         "The multipass programs' recall ceiling"),
                     "recall ceiling, every curve"),
  };
  {
    const char* keys[] = {"scene",
                          "segments",
                          "truth_pixels",
                          "reached_pixels",
                          "recall_ceiling",
                          "truth_pixels_every_curve",
                          "reached_pixels_every_curve",
                          "recall_ceiling_every_curve"};
    for (std::size_t k = 0; k < truth_table.columns.size(); ++k)
      truth_table.columns[k].key = keys[k];
  }
  auto ceiling_of = [](const IntersectionTruth& t) {
    return t.pixels ? static_cast<double>(t.reachable) / static_cast<double>(t.pixels) : 0.0;
  };
  // Per scene of a few separate curves, the width along each (its caption line, its table).
  std::vector<std::pair<std::string, report::Table>> curve_tables;
  // --report: per scene, the truth and each program's image beside its overlay.
  std::vector<report::Section> image_sections;
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
    truth_table.add_row({scene_name, static_cast<std::int64_t>(truths[0].segments),
                         static_cast<std::int64_t>(truths[0].pixels),
                         static_cast<std::int64_t>(truths[0].reachable), ceiling_of(truths[0]),
                         static_cast<std::int64_t>(truths[1].pixels),
                         static_cast<std::int64_t>(truths[1].reachable), ceiling_of(truths[1])});
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
      report::Table t;
      t.id = "highlight-curves-" + scene_name;
      t.columns.push_back(report::text_column("program"));
      for (const Segment3& c : curves) {
        const double depth = glm::dot(0.5 * (c.a + c.b) - eye, axis);
        report::Column column = report::real_column(
            fmt::format("eye depth {:.2f}", depth), "pixels", 2,
            "Mean width (+- its standard deviation) of the flagged band along the curve whose "
            "midpoint is at this eye depth");
        column.heading = column.name;
        column.align = report::Align::left;
        t.columns.push_back(column);
      }
      curve_tables.emplace_back(
          fmt::format("width in pixels along each curve of {} (mean +- sd):", scene_name),
          std::move(t));
    }
    const fs::path dir = fs::path(o.out_dir) / scene_name;
    fs::create_directories(dir);
    report::Section images{"images-" + scene_name, scene_name + ": images", {}};
    bool truth_shown[2] = {false, false};
    for (const Entry& e : programs) {
      const IntersectionTruth& truth = truths[e.program.multipass() ? 1 : 0];
      const FieldFrame frame = render_field(config, scene, e.program, "iflag", o.threads);
      std::vector<std::uint8_t> flagged(frame.values.size());
      for (std::size_t p = 0; p < flagged.size(); ++p) flagged[p] = frame.values[p] != 0;
      const Accuracy a = measure_accuracy(truth, flagged);
      if (by_curve) {
        std::vector<report::Cell> row = {e.name};
        for (const Accuracy& c : measure_width_by_segment(truth, flagged)) {
          row.push_back(c.width_samples ? report::Cell::shown_as(
                                              c.width_mean, fmt::format("{:.2f} +- {:.2f}",
                                                                        c.width_mean, c.width_sd))
                                        : report::Cell::missing());
        }
        curve_tables.back().second.add_row(std::move(row));
      }
      // Order sensitivity: pixels whose flag differs in the other order, as a share of the
      // pixels flagged in this one.
      std::size_t changed = 0;
      report::Cell change = report::Cell::missing();
      if (compare) {
        const FieldFrame second = render_field(config, reordered, e.program, "iflag", o.threads);
        for (std::size_t p = 0; p < flagged.size(); ++p)
          changed += (second.values[p] != 0) != (flagged[p] != 0);
        const double share =
            a.flagged ? static_cast<double>(changed) / a.flagged : static_cast<double>(changed);
        change = report::Cell::shown_as(share, fmt::format("{:.4f} ({} px)", share, changed));
      }
      RgbImage overlay = overlay_image(frame.image, truth, flagged);
      // A program given as a path names its images with its '/' made '_' (one file per program
      // in the scene's folder, not a folder per path component).
      std::string image_name = e.name;
      std::replace(image_name.begin(), image_name.end(), '/', '_');
      if (o.report) {
        const int all = e.program.multipass() ? 1 : 0;
        // The truth once per scene (and once more for the multipass programs' when it differs),
        // over the first program's image.
        if (!truth_shown[all] && (all == 0 || truths[1].pixels != truths[0].pixels ||
                                  truths[1].reachable != truths[0].reachable)) {
          truth_shown[all] = true;
          const std::string which = all ? "every intersection curve, hidden or not (the truth "
                                          "of the multipass programs)"
                                        : "the visible intersection curves";
          images.blocks.push_back(report::Figure{
              fmt::format("truth-{}{}", scene_name, all ? "-all" : ""),
              fmt::format("{}: the truth{}", scene_name, all ? " (every curve)" : ""),
              fmt::format("The pixels within delta of {}: {} truth pixels, {} of them (white) "
                          "reached by two or more triangles; the {} in orange are reached by one "
                          "surface or none, so no program can flag them (recall ceiling {:.3f})",
                          which, truth.pixels, truth.reachable, truth.pixels - truth.reachable,
                          a.ceiling),
              "image/png", encode_png(truth_image(frame.image, truth)),
              fmt::format("{}: the truth pixels over {}'s image", scene_name, e.name), ""});
        }
        images.blocks.push_back(report::Figure{
            fmt::format("{}-{}", scene_name, image_name),
            fmt::format("{} on {}", e.name, scene_name),
            fmt::format("Left: {0}'s image ({1}/{5}.png). Right: its flags against the truth "
                        "({1}/{5}-overlay.png): green flagged and true ({2} px), red flagged only "
                        "({3} px), blue missed ({4} px)",
                        e.name, scene_name, a.hits, a.flagged - a.hits, a.truth - a.hits,
                        image_name),
            "image/png", encode_png(side_by_side(frame.image, overlay)),
            fmt::format("{} on {}: the image and the flags against the truth", e.name, scene_name),
            ""});
      }
      outputs.add((dir / (image_name + ".png")).string(), encode_png(frame.image));
      outputs.add((dir / (image_name + "-overlay.png")).string(), encode_png(overlay));
      auto speed = [&](double v) {
        return o.speed_scene.empty() ? report::Cell::missing() : report::Cell(v);
      };
      table.add_row({e.name, scene_name, static_cast<std::int64_t>(a.truth),
                     static_cast<std::int64_t>(a.flagged), a.recall, a.ceiling, a.precision,
                     a.width_mean, a.width_sd, a.coverage, change, e.program.bits_used(),
                     spilled_fields(e.program), speed(e.speed), speed(e.speed_compiled)});
    }
    if (o.report) image_sections.push_back(std::move(images));
  }
  const report::Table summary = highlight_summary(table, programs.size(), o.speed_scene);
  std::string text =
      report::markdown(table) + "\nThe truth of each scene:\n\n" + report::markdown(truth_table) +
      "\nBy program (bits and polygons/s on its first row):\n\n" + report::markdown(summary);
  report::Report r;
  r.title = "Intersection highlighting";
  const std::string legend = fmt::format(
      "widths in pixels across the true curve (delta = {} px half-width); overlays: green = "
      "flagged and true, red = flagged only, blue = missed",
      static_cast<double>(resolved_frame_parameter(config, Parameter::delta)) / 16.0);
  r.subtitle = legend;
  r.add_section("highlight", "Programs and scenes").blocks.push_back(table);
  r.add_section("highlight-truth", "The truth of each scene").blocks.push_back(truth_table);
  r.add_section("highlight-summary", "By program").blocks.push_back(summary);
  for (auto& [caption, t] : curve_tables) {
    text += "\n" + caption + "\n\n" + report::markdown(t);
    r.add_section(t.id, caption.substr(0, caption.size() - 1)).blocks.push_back(std::move(t));
  }
  for (report::Section& s : image_sections) r.sections.push_back(std::move(s));
  outputs.add((fs::path(o.out_dir) / "highlight.md").string(), text);
  add_report_outputs(outputs, o.out_dir, r, o.report);
  // The tables and every image together, or none of them (sim/output).
  outputs.commit();
  std::cout << text;
  std::cout << fmt::format(
      "\n{0}\nwrote {1}/highlight.md, {1}/highlight{{,-truth,-summary}}.csv{2} and "
      "{1}/SCENE/PROGRAM[-overlay].png\n",
      legend, o.out_dir, o.report ? fmt::format(", {}/report.html", o.out_dir) : "");
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
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  return {cmd, [o] { return run_highlight(*o); }};
}

}  // namespace pp5
