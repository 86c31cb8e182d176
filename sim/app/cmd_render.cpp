// pp5sim render: one frame of a scene, its image and its reports.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include "common/parallel_for.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/app/commands.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/run_report.hpp"
#include "sim/scene/order.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "sim/timeline_file.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

struct RenderOptions {
  std::string scene_name = "torus";
  std::string firmware;  // empty: the scene file's "firmware", else phong
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir;
  int threads = default_threads();
  std::vector<int> tessellation;
  std::string timeline;
  std::string order = "given";
  bool report = false;  // also OUT/report.html (sim/run_report.hpp)
  int frames = 1;       // --frames: a run of overlapped frames (Session::run_frames)
};

// `render --frames N`: N frames of the scene overlapped; writes the last frame's outputs, the
// run's statistics (run.json) and prints the sustained figures.
int run_render_frames(const RenderOptions& o, const MachineConfig& config, const Scene& scene,
                      const Program& program, double setup_seconds) {
  const bool pixels = config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
  // The outputs are staged as files (StagedOutputs), the timeline written out as the frames
  // run (TimelineFile): memory stays flat however many frames.
  StagedOutputs outputs;
  std::optional<TimelineFile> timeline;
  if (!o.timeline.empty()) timeline.emplace(outputs, o.timeline);
  FrameResult last;
  const RunSummary run = simulate_frames(
      config, std::make_shared<const Scene>(scene), std::make_shared<const Program>(program),
      o.threads, o.frames,
      [&last, n = o.frames](int f, FrameResult& r) {
        if (f == n - 1) last = std::move(r);
      },
      true, nullptr, setup_seconds, timeline ? &*timeline : nullptr);
  if (timeline) timeline->finish();
  const fs::path dir(o.out_dir);
  const bool heat_map = !last.regions.empty();
  std::string frame_png, regions_png;
  parallel_for(2, o.threads, [&](int image) {
    if (image == 0 && pixels) frame_png = encode_png(last.image);
    if (image == 1 && heat_map) {
      const RegionHeatMap map(last.image, last.regions, -1);
      regions_png = encode_png(map.width(), map.height(),
                               [&map](int y, std::uint8_t* row) { map.row(y, row); });
    }
  });
  if (pixels) outputs.add((dir / "frame.png").string(), frame_png);
  if (heat_map) outputs.add((dir / "regions.png").string(), regions_png);
  outputs.add((dir / "config.json").string(), config.to_json().dump(2) + "\n");
  outputs.add((dir / "stats.json").string(), last.stats_json.dump(2) + "\n");
  outputs.add((dir / "run.json").string(), run.statistics().to_json().dump(2) + "\n");
  outputs.commit();
  std::error_code ignored;
  if (!pixels) fs::remove(dir / "frame.png", ignored);
  if (!heat_map) fs::remove(dir / "regions.png", ignored);
  fs::remove(dir / "report.html", ignored);
  std::cout << fmt::format("pp5sim: scene '{}' ({} triangles), firmware {}\n{}\n\n", scene.name,
                           scene.mesh.triangles.size(), program.name, scene.description);
  std::cout << bit_budget_table(program, timing_params(config));
  std::cout << "\n" << run.text() << run.sustained_text();
  std::cout << fmt::format(
      "wrote {} (the last frame's frame.png, regions.png, stats.json; "
      "run.json: the run's statistics)\n",
      o.out_dir);
  return 0;
}

// What the scene asks for that the program would ignore, one warning each (printed to stderr
// and shown in report.html): opacity
// reaches the pixels only through the `opacity` expression, and a program that lights pixels
// itself (it reads light_x) but has no `light` procedure sees the first light only.
std::vector<std::string> ignored_scene_parts(const Scene& scene, const Program& program) {
  std::vector<std::string> warnings;
  const std::string name = fs::path(program.name).stem().string();
  const bool transparent = std::any_of(scene.mesh.vertices.begin(), scene.mesh.vertices.end(),
                                       [](const Vertex& v) { return v.opacity < 1.0f; });
  const int opacity = static_cast<int>(Expression::opacity);
  if (transparent && !program.procedure(Procedure::triangle).expressions.test(opacity)) {
    warnings.push_back(
        fmt::format("scene '{}' has materials with opacity < 1, but firmware '{}' has no 'opacity' "
                    "expression: the opacity is ignored (use --firmware transparent)",
                    scene.name, name));
  }
  bool reads_light = false;
  for (const ProcedureCode& code : program.procedures) {
    reads_light = reads_light || code.parameters.test(static_cast<int>(Parameter::light_x));
  }
  if (scene.lights.size() > 1 && reads_light && !program.procedure(Procedure::light).defined) {
    warnings.push_back(
        fmt::format("scene '{}' has {} lights, but firmware '{}' has no 'light' procedure: it "
                    "shades with the first light only (phong sums them all)",
                    scene.name, scene.lights.size(), name));
  }
  // A "csg" expression is drawn by a program with the CSG pass plan's procedures (its
  // `surface`, models/gp/pass_plan.hpp); any other draws every mesh as it is: say so rather
  // than let the union of the meshes pass for the result.
  if (!scene.csg.empty() && !program.procedure(Procedure::surface).defined) {
    warnings.push_back(fmt::format(
        "scene '{}' gives a CSG expression ({} product{} after normalising), but "
        "firmware '{}' does not draw CSG (it has no 'surface' procedure): it draws every mesh "
        "as it is (use --firmware csg)",
        scene.name, scene.csg.size(), scene.csg.size() == 1 ? "" : "s", name));
  }
  return warnings;
}

int run_render(RenderOptions o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const bool pixels = config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
  if (o.frames > 1 && o.report) {
    std::cerr << "pp5sim: error: --report describes one frame; drop it with --frames N\n";
    return 2;
  }
  if (!o.timeline.empty() && config.fidelity.timing != MachineConfig::Fidelity::Timing::event) {
    std::cerr << "pp5sim: error: --timeline records the event model's units; this run asks for "
                 "fidelity.timing=analytic, which has no events (drop --timeline or use "
                 "--fidelity timing)\n";
    return 2;
  }
  SceneOptions scene_options;
  if (o.tessellation.size() == 2) {
    scene_options.tessellation_u = o.tessellation[0];
    scene_options.tessellation_v = o.tessellation[1];
  }
  const DisplayOrder order = parse_display_order(o.order, "--order");
  // host.setup_seconds: making the scene and assembling the program.
  const auto setup_start = std::chrono::steady_clock::now();
  Scene scene = load_scene(o.scene_name, scene_options);
  apply_display_order(scene.mesh, order);
  GeometryEngine(geometry_params(config), scene).frame_parameters();  // check them first
  const Program program = assemble_file(firmware_for(o.firmware, scene), assembler_options(config));
  const double setup_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count();
  std::vector<std::string> warnings = ignored_scene_parts(scene, program);
  for (const std::string& w : warnings) std::cerr << "warning: " << w << "\n";
  if (o.out_dir.empty()) o.out_dir = default_output_folder(scene.name);
  const bool replacing = prepare_output_folder(o.out_dir, "--out");

  if (o.frames > 1) return run_render_frames(o, config, scene, program, setup_seconds);

  nlohmann::json timeline;
  // report.html draws the timeline: recorded for it too where the timing model has events.
  const bool record_timeline =
      !o.timeline.empty() ||
      (o.report && config.fidelity.timing == MachineConfig::Fidelity::Timing::event);
  FrameResult result =
      simulate_frame(config, scene, program, o.threads, {}, record_timeline ? &timeline : nullptr,
                     nullptr, setup_seconds);
  // All of the run's outputs, or none of them (sim/output/output_set.hpp).
  const fs::path dir(o.out_dir);
  OutputSet outputs;
  // With fidelity.pixels=none no pixel executed: there is no image to write, and regions.png
  // shows the regions' cycles on a black frame (the frame holds no pixels).
  const bool heat_map = !result.regions.empty();
  // The two images are independent: encoded at once on the run's host threads.
  std::string frame_png, regions_png;
  parallel_for(2, o.threads, [&](int image) {
    if (image == 0 && pixels) frame_png = encode_png(result.image);
    if (image == 1 && heat_map) {
      const RegionHeatMap map(result.image, result.regions,
                              static_cast<int>(result.stats.integer("timing.critical_renderer")));
      regions_png = encode_png(map.width(), map.height(),
                               [&map](int y, std::uint8_t* row) { map.row(y, row); });
    }
  });
  const Statistics& stats = result.stats;
  const std::int64_t overflow = stats.integer("setup.coefficient_overflow");
  if (overflow > 0) {
    warnings.push_back(
        fmt::format("{} triangles were not drawn because a coefficient did not fit "
                    "evaluator.coefficient_bits = {} (see 'pp5sim extremes')",
                    overflow, config.evaluator.coefficient_bits));
  }
  if (o.report) {
    RunReportInput in;
    in.title = fmt::format("scene '{}' ({} triangles), firmware {}", scene.name,
                           scene.mesh.triangles.size(), fs::path(program.name).stem().string());
    in.subtitle = scene.description;
    in.config = &config;
    in.program = &program;
    in.result = &result;
    in.frame_png = frame_png;
    in.regions_png = regions_png;
    in.timeline = record_timeline ? &timeline : nullptr;
    in.warnings = warnings;
    outputs.add((dir / "report.html").string(), report::html(run_report(in)));
  }
  if (pixels) outputs.add((dir / "frame.png").string(), std::move(frame_png));
  if (heat_map) outputs.add((dir / "regions.png").string(), std::move(regions_png));
  outputs.add((dir / "config.json").string(), config.to_json().dump(2) + "\n");
  outputs.add((dir / "stats.json").string(), result.stats_json.dump(2) + "\n");
  if (!o.timeline.empty()) outputs.add(o.timeline, timeline.dump() + "\n");
  outputs.commit();
  // A frame.png or regions.png left by an earlier run into this folder is not this run's.
  std::error_code ignored;
  if (!pixels) fs::remove(dir / "frame.png", ignored);
  if (!heat_map) fs::remove(dir / "regions.png", ignored);
  if (!o.report) fs::remove(dir / "report.html", ignored);

  std::cout << fmt::format("pp5sim: scene '{}' ({} triangles), firmware {}\n{}\n\n", scene.name,
                           scene.mesh.triangles.size(), program.name, scene.description);
  std::cout << summary(result, program, timing_params(config));
  // What set-up dropped, so that no triangle disappears silently.
  std::cout << fmt::format(
      "set-up dropped: {} clipped away, {} zero-area, {} without a pixel centre, {} with a "
      "coefficient overflow\n",
      stats.integer("setup.clipped_away"), stats.integer("setup.degenerate"),
      stats.integer("setup.no_pixel_centres"), overflow);
  // Spheres are dropped whole where their conic cannot be drawn (models/gp/sphere.hpp).
  const std::int64_t behind = stats.integer("setup.sphere_behind_eye");
  const std::int64_t near = stats.integer("setup.sphere_near_plane");
  const std::int64_t far = stats.integer("setup.sphere_far_plane");
  if (behind + near + far > 0) {
    std::cout << fmt::format(
        "spheres dropped: {} behind the eye, {} reaching the near plane, {} reaching the far "
        "plane\n",
        behind, near, far);
  }
  if (overflow > 0) {
    std::cout << fmt::format(
        "warning: {} triangles were not drawn because a coefficient did not fit "
        "evaluator.coefficient_bits = {} (see 'pp5sim extremes')\n",
        overflow, config.evaluator.coefficient_bits);
  }
  // Every primitive dropped: the frame is the background alone, which must not pass silently
  // (a mesh at 1e20, or scaled by 1e-30, is framed by the camera and then lost to
  // single-precision set-up).
  const std::int64_t triangles = static_cast<std::int64_t>(scene.mesh.triangles.size());
  const std::int64_t spheres = static_cast<std::int64_t>(scene.spheres.size());
  const std::int64_t dropped_triangles = stats.integer("setup.clipped_away") +
                                         stats.integer("setup.degenerate") +
                                         stats.integer("setup.no_pixel_centres") + overflow;
  if (triangles + spheres > 0 && dropped_triangles >= triangles && behind + near + far >= spheres) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const Vertex& v : scene.mesh.vertices) {
      lo = glm::min(lo, v.position);
      hi = glm::max(hi, v.position);
    }
    std::cerr << fmt::format(
        "warning: nothing was drawn: set-up dropped all {} triangles and {} spheres (above), so "
        "the frame is the background alone{}\n",
        triangles, spheres,
        triangles > 0 ? fmt::format("; the scene's vertices span ({:g}, {:g}, {:g}) to ({:g}, "
                                    "{:g}, {:g}), a size single-precision set-up may not resolve",
                                    lo.x, lo.y, lo.z, hi.x, hi.y, hi.z)
                      : "");
  }
  std::cout << fmt::format("\n{} {}{}{}/config.json, {}/stats.json{}\n",
                           replacing ? "wrote (replacing the previous run's)" : "wrote",
                           pixels ? o.out_dir + "/frame.png, " : "",
                           heat_map ? o.out_dir + "/regions.png, " : "", o.out_dir, o.out_dir,
                           pixels ? "" : " (fidelity.pixels=none: no frame.png)");
  if (!o.timeline.empty()) {
    std::cout << fmt::format("wrote {} (open it in ui.perfetto.dev)\n", o.timeline);
  }
  if (o.report) std::cout << fmt::format("wrote {}/report.html\n", o.out_dir);
  return 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  auto* render = app.add_subcommand("render", "Render one frame of a scene and write its reports");
  render
      ->add_option("-s,--scene", o->scene_name,
                   "A built-in scene (see 'pp5sim scenes'), a mesh file (.obj .ply .stl .off) or a "
                   "scene file (.json, described in docs/reference/scene-files.md)")
      ->capture_default_str();
  render->add_option("-f,--firmware", o->firmware, firmware_help());
  add_config_options(*render, o->config_path, o->sets);
  add_fidelity_option(*render, o->sets);
  render->add_option("-o,--out", o->out_dir,
                     "Output folder for frame.png, regions.png (Renderer cycles per region as a "
                     "heat map), config.json and stats.json [out/SCENE]; a later run into the "
                     "same folder replaces them (no frame.png with --fidelity timing or "
                     "analytic: regions.png then shows the cycles on a black frame)");
  render
      ->add_option("-j,--threads", o->threads,
                   "Host threads for the pixel arrays (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  render
      ->add_option("--tessellation", o->tessellation,
                   "Tessellation U V of the torus or sphere (default 128 32 and 64 32)")
      ->expected(2);
  render->add_option("--timeline", o->timeline,
                     "Also write a timeline of every GP, ring channel and Renderer to FILE, in the "
                     "Chrome trace-event JSON format that ui.perfetto.dev opens");
  render
      ->add_option("--frames", o->frames,
                   "Simulate N frames of the scene overlapped (a GP sets up frame n + 1 while the "
                   "Renderers draw frame n): writes the last frame's outputs and OUT/run.json, "
                   "and prints the sustained period, rates and latency")
      ->check(CLI::Range(1, 100000));
  render->add_flag("--report", o->report,
                   "Also write OUT/report.html: one self-contained page with the frame, the "
                   "regions heat map, the bit budget, utilisation, the timeline, every "
                   "statistic and the configuration");
  render
      ->add_option("--order", o->order,
                   "Display-list order of the scene's triangles: given, reversed, shuffled or "
                   "shuffled:SEED (deterministic)")
      ->capture_default_str();
  return {render, [o] { return run_render(*o); }};
}

}  // namespace pp5
