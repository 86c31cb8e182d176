// pp5sim spheres: the quadric-versus-tessellation trade (models/gp/sphere.hpp,
// sim/analysis/spheres.hpp). The scene's spheres are drawn as sphere primitives and as UV
// spheres of several tessellations, each by the same firmware, and each frame is costed (the
// simulation's statistics) and measured against an exact CPU ray cast.
#include <fmt/format.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "models/gp/expressions.hpp"
#include "models/machine.hpp"
#include "sim/analysis/sphere_depth_methods.hpp"
#include "sim/analysis/spheres.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/scene/sphere_scenes.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

struct SpheresOptions {
  std::string scene_name = "spheres";
  std::string firmware = "phong";
  std::vector<std::string> tessellations = {"8x4", "16x8", "32x16", "64x32"};
  std::string config_path;
  std::vector<std::string> sets;
  int threads = default_threads();
  std::string out_dir;  // "" for none: only the table on stdout
  bool report = false;
};

struct SphereRow {
  std::string what;
  double gp_clocks = 0, packet_words = 0, ring_words = 0, renderer_cycles = 0;
  double rate = 0;
  SphereAccuracy accuracy;
};

std::uint64_t sum(const Statistics& s, const char* group, const char* name) {
  std::uint64_t t = 0;
  for (std::size_t k = 0; k < s.elements(group); ++k) {
    t += static_cast<std::uint64_t>(s.integer(fmt::format("{}.{}.{}", group, k, name)));
  }
  return t;
}

// One row per way of drawing the spheres (the typed values in CSV, the text as before).
report::Table spheres_table(const std::vector<SphereRow>& rows) {
  using namespace report;
  auto right = [](Column c, const char* heading) {
    c.heading = heading;
    c.align = Align::right;
    return c;
  };
  Table t;
  t.id = "spheres";
  Column what = text_column("spheres as", "Sphere primitives, or UV spheres of U x V");
  Column gp = real_column("GP clocks", "i860 clocks", 0, "GP geometry clocks per sphere");
  gp.heading = "GP clocks";
  Column packet = real_column("packet words", "words", 0, "Set-up packet words per sphere");
  packet.heading = "packet words";
  Column ring = real_column("ring words", "words", 0, "Ring words per sphere");
  ring.heading = "ring words";
  Column cycles = real_column("Renderer cycles", "array cycles", 0,
                              "Renderer busy cycles per sphere, all Renderers");
  cycles.heading = "Renderer cycles";
  Column rate = real_column("spheres/s", "spheres/s", -1,
                            "Spheres per second the GPs or the Renderers could sustain, "
                            "whichever is less");
  rate.heading = "spheres/s";
  t.columns = {
      what,
      gp,
      packet,
      ring,
      cycles,
      rate,
      right(integer_column("coverage errors", "pixels",
                           "Pixels covered only by the drawing (extra) / only by the ray cast "
                           "(missing), of the pixels the ray cast covers"),
            "coverage errors (extra / missing of covered)"),
      right(real_column("depth error max", "z units", 0,
                        "Largest / mean depth error against the ray cast"),
            "depth error max / mean"),
      right(real_column("normal error max", "degrees", 1,
                        "Largest / mean angle between the drawn and the exact normal"),
            "normal error max / mean"),
      right(integer_column("overlap pixels: depth nearer another sphere", "pixels",
                           "Pixels where two spheres overlap and the depth is of the wrong one, "
                           "of the overlap pixels"),
            "overlap pixels: depth nearer another sphere"),
      right(integer_column("overlap pixels: showing another primitive", "pixels",
                           "Overlap pixels showing a primitive other than the ray cast's, of "
                           "the overlap pixels"),
            "overlap pixels: showing another primitive"),
      right(integer_column("intersection-curve pixels: showing another primitive", "pixels",
                           "Pixels on a curve where spheres meet showing a primitive other than "
                           "the ray cast's, of the curve pixels"),
            "intersection-curve pixels: showing another primitive"),
  };
  for (const SphereRow& r : rows) {
    const SphereAccuracy& a = r.accuracy;
    t.add_row(
        {r.what, r.gp_clocks, r.packet_words, r.ring_words, r.renderer_cycles,
         Cell::shown_as(r.rate, fmt::format("{:.3g}", r.rate)),
         Cell::shown_as(
             static_cast<std::int64_t>(a.coverage_extra + a.coverage_missing),
             fmt::format("{} / {} of {}", a.coverage_extra, a.coverage_missing, a.pixels)),
         Cell::shown_as(static_cast<double>(a.depth_max_error),
                        fmt::format("{:.0f} / {:.1f}", a.depth_max_error, a.depth_mean_error)),
         Cell::shown_as(static_cast<double>(a.normal_max_error_degrees),
                        fmt::format("{:.1f}° / {:.2f}°", a.normal_max_error_degrees,
                                    a.normal_mean_error_degrees)),
         Cell::shown_as(static_cast<std::int64_t>(a.overlap_depth_wrong),
                        fmt::format("{} of {}", a.overlap_depth_wrong, a.overlap_pixels)),
         Cell::shown_as(static_cast<std::int64_t>(a.overlap_shown_wrong),
                        fmt::format("{} of {}", a.overlap_shown_wrong, a.overlap_pixels)),
         Cell::shown_as(static_cast<std::int64_t>(a.curve_shown_wrong),
                        fmt::format("{} of {}", a.curve_shown_wrong, a.curve_pixels))});
  }
  return t;
}

int run_spheres(const SpheresOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const Scene scene = load_scene(o.scene_name);
  if (scene.spheres.empty()) {
    std::cerr << fmt::format("error: scene '{}' has no spheres\n", scene.name);
    return 1;
  }
  const Program program = assemble_file(resolve_firmware(o.firmware), assembler_options(config));
  const double n = static_cast<double>(scene.spheres.size());
  // What every frame pays whatever it draws (clear, light, shade, shipping the regions): the
  // same scene without its spheres, subtracted from each row.
  Scene empty = scene;
  empty.spheres.clear();
  const FrameResult base = simulate_frame(config, empty, program, o.threads);
  const RayCast truth = ray_cast(config, scene);

  // `visibility`: the program that draws the index colours (shown_spheres_by): the one that
  // draws the row, light and shade taken out.
  auto row = [&](const std::string& what, const Scene& s, const std::vector<int>& stands_for,
                 const Program& program, const FrameResult& base, const Program& visibility) {
    const FrameResult r = simulate_frame(config, s, program, o.threads);
    SphereRow out;
    out.what = what;
    const Statistics& st = r.stats;
    out.gp_clocks = static_cast<double>(sum(st, "gp", "geometry_clocks") -
                                        sum(base.stats, "gp", "geometry_clocks")) /
                    n;
    out.ring_words =
        static_cast<double>(st.integer("ring.words") - base.stats.integer("ring.words")) / n;
    out.renderer_cycles = static_cast<double>(st.integer("renderers_total.busy_cycles") -
                                              base.stats.integer("renderers_total.busy_cycles")) /
                          n;
    const Procedure proc = s.spheres.empty() ? Procedure::triangle : Procedure::sphere;
    const std::uint64_t words =
        packet_words(program.procedure(proc).expressions,
                     coefficient_words(config.evaluator.coefficient_bits, config.ring.word_bits));
    out.packet_words =
        static_cast<double>(words) *
        static_cast<double>(st.integer("setup.packets") - base.stats.integer("setup.packets")) / n;
    const double gp_rate = config.gp.count * config.gp.clock_hz / std::max(1.0, out.gp_clocks);
    const double renderer_rate =
        config.renderer.count * config.renderer.clock_hz / std::max(1.0, out.renderer_cycles);
    out.rate = std::min(gp_rate, renderer_rate);
    out.accuracy =
        measure_spheres(config, scene, truth, draw_spheres(config, s, program, o.threads),
                        shown_spheres_by(config, s, stands_for, visibility, o.threads));
    return out;
  };

  std::vector<SphereRow> rows;
  // The quadric's and the tessellations' visibility is read from the --firmware itself, light
  // and shade taken out, so that it follows that program's own depth code (for phong,
  // shown_spheres' counts).
  const Program unshaded_own = unshaded_program(resolve_firmware(o.firmware), config);
  rows.push_back(row("quadric", scene, {}, program, base, unshaded_own));
  // The other depth methods, each by its own program (sphere_depth_methods.hpp).
  for (const SphereDepthMethod& m : sphere_depth_methods()) {
    const std::string path = resolve_firmware(m.firmware);
    const Program p = assemble_file(path, assembler_options(config));
    const Program unshaded = unshaded_program(path, config);
    rows.push_back(row(fmt::format("{} ({}, {} bits)", m.label, m.firmware, p.bits_used()), scene,
                       {}, p, simulate_frame(config, empty, p, o.threads), unshaded));
  }
  for (const std::string& t : o.tessellations) {
    int u = 0, v = 0;
    if (std::sscanf(t.c_str(), "%dx%d", &u, &v) != 2 || u < 3 || v < 2 || u > 1024 || v > 1024) {
      std::cerr << fmt::format(
          "error: --tessellations: '{}' is not UxV with 3 <= U <= 1024, 2 <= V <= 1024\n", t);
      return 1;
    }
    Scene tess = scene;
    tess.spheres.clear();
    append_tessellated_spheres(scene.spheres, u, v, tess.mesh);
    // The scene's own triangles stand for no sphere; then 2 u (v - 1) per sphere, in order.
    std::vector<int> stands_for(scene.mesh.triangles.size(), -1);
    for (std::size_t k = 0; k < scene.spheres.size(); ++k)
      stands_for.insert(stands_for.end(), static_cast<std::size_t>(2 * u * (v - 1)),
                        static_cast<int>(k));
    if (stands_for.size() != tess.mesh.triangles.size())
      throw std::logic_error("cmd_spheres: tessellation triangle count");
    // Drawn by the --firmware's triangle procedure, so their visibility is read from it too.
    rows.push_back(row(fmt::format("{} ({} triangles)", t, 2 * u * (v - 1)), tess, stands_for,
                       program, base, unshaded_own));
  }

  const std::string heading = fmt::format(
      "scene '{}': {} spheres, {} x {} screen, firmware {} ({} bits of pixel memory); per "
      "sphere, less a frame without the spheres; rate: spheres/s the GPs or the Renderers "
      "could sustain, whichever is less",
      scene.name, scene.spheres.size(), config.screen.width, config.screen.height, o.firmware,
      program.bits_used());
  const report::Table table = spheres_table(rows);
  std::cout << heading << "\n\n" << report::markdown(table);
  if (!o.out_dir.empty() || o.report) {
    const std::string dir = o.out_dir.empty() ? std::string("out/spheres") : o.out_dir;
    report::Report r;
    r.title = "Spheres: quadric against tessellated";
    r.subtitle = heading;
    r.add_section("spheres", "Per sphere").blocks.push_back(table);
    prepare_output_folder(dir, "--out");
    OutputSet outputs;
    outputs.add(dir + "/spheres.md", heading + "\n\n" + report::markdown(table));
    add_report_outputs(outputs, dir, r, o.report);
    outputs.commit();
    std::cout << fmt::format("\nwrote {}/spheres.md, spheres.csv{}\n", dir,
                             o.report ? " and report.html" : "");
  }
  return 0;
}

}  // namespace

Command add_spheres_command(CLI::App& app) {
  auto o = std::make_shared<SpheresOptions>();
  auto* cmd = app.add_subcommand(
      "spheres",
      "Spheres drawn with the evaluator's quadratic terms against tessellated spheres: per "
      "sphere the GP clocks, ring words, Renderer cycles and projected spheres per second, "
      "and the accuracy of each against an exact ray cast (coverage, depth, normals, the "
      "curves where spheres meet).");
  cmd->add_option("-s,--scene", o->scene_name,
                  "A scene with spheres: a built-in name, a scene file or a molecule file")
      ->capture_default_str();
  cmd->add_option("-f,--firmware", o->firmware, "A program with a `sphere` procedure")
      ->capture_default_str();
  cmd->add_option("--tessellations", o->tessellations,
                  "UxV tessellations to compare (u around, v pole to pole)")
      ->capture_default_str();
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  cmd->add_option("-o,--out", o->out_dir,
                  "Also write the table to OUT/spheres.md and OUT/spheres.csv (with --report "
                  "and no --out, OUT is out/spheres)");
  add_report_flag(*cmd, o->report, "OUT");
  return {cmd, [o] { return run_spheres(*o); }};
}

}  // namespace pp5
