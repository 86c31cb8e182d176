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

  // `visibility`: the program that draws the index colours (shown_spheres_by), or null for
  // shown_spheres' own; `program` and `base` default to the --firmware's.
  auto row = [&](const std::string& what, const Scene& s, const std::vector<int>& stands_for,
                 const Program& program, const FrameResult& base,
                 const Program* visibility = nullptr) {
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
    out.accuracy = measure_spheres(
        config, scene, truth, draw_spheres(config, s, program, o.threads),
        visibility != nullptr ? shown_spheres_by(config, s, stands_for, *visibility, o.threads)
                              : shown_spheres(config, s, stands_for, o.threads));
    return out;
  };

  std::vector<SphereRow> rows;
  // The first row's visibility is read from the --firmware itself, light and shade taken out,
  // so that it follows that program's own depth code (for phong, shown_spheres' counts).
  const Program unshaded_own = unshaded_program(resolve_firmware(o.firmware), config);
  rows.push_back(row("quadric", scene, {}, program, base, &unshaded_own));
  // The other depth methods, each by its own program (sphere_depth_methods.hpp).
  for (const SphereDepthMethod& m : sphere_depth_methods()) {
    const std::string path = resolve_firmware(m.firmware);
    const Program p = assemble_file(path, assembler_options(config));
    const Program unshaded = unshaded_program(path, config);
    rows.push_back(row(fmt::format("{} ({}, {} bits)", m.label, m.firmware, p.bits_used()), scene,
                       {}, p, simulate_frame(config, empty, p, o.threads), &unshaded));
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
    rows.push_back(
        row(fmt::format("{} ({} triangles)", t, 2 * u * (v - 1)), tess, stands_for, program, base));
  }

  std::cout << fmt::format(
      "scene '{}': {} spheres, {} x {} screen, firmware {} ({} bits of pixel memory); per "
      "sphere, less a frame without the spheres; rate: spheres/s the GPs or the Renderers "
      "could sustain, whichever is less\n\n",
      scene.name, scene.spheres.size(), config.screen.width, config.screen.height, o.firmware,
      program.bits_used());
  std::cout << "| spheres as | GP clocks | packet words | ring words | Renderer cycles | spheres/s "
               "| coverage "
               "errors (extra / missing of covered) | depth error max / mean | normal error max "
               "/ mean | overlap pixels: depth nearer another sphere | overlap pixels: showing "
               "another primitive | intersection-curve pixels: showing another primitive |\n";
  std::cout << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const SphereRow& r : rows) {
    const SphereAccuracy& a = r.accuracy;
    std::cout << fmt::format(
        "| {} | {:.0f} | {:.0f} | {:.0f} | {:.0f} | {:.3g} | {} / {} of {} | {:.0f} / {:.1f} | "
        "{:.1f}° / "
        "{:.2f}° | {} of {} | {} of {} | {} of {} |\n",
        r.what, r.gp_clocks, r.packet_words, r.ring_words, r.renderer_cycles, r.rate,
        a.coverage_extra, a.coverage_missing, a.pixels, a.depth_max_error, a.depth_mean_error,
        a.normal_max_error_degrees, a.normal_mean_error_degrees, a.overlap_depth_wrong,
        a.overlap_pixels, a.overlap_shown_wrong, a.overlap_pixels, a.curve_shown_wrong,
        a.curve_pixels);
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
  return {cmd, [o] { return run_spheres(*o); }};
}

}  // namespace pp5
