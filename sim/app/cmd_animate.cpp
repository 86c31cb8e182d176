// pp5sim animate: the frames of an animation (sim/animation.hpp) in one persisting session,
// one PNG each, an animated GIF, frames.csv, the regions heat map summed over the frames and
// a timeline over all of them.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/machine.hpp"
#include "sim/animation.hpp"
#include "sim/animation_report.hpp"
#include "sim/app/commands.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/image/region_map.hpp"
#include "sim/frame_encoder.hpp"
#include "sim/output/output_set.hpp"
#include "sim/output/report_html.hpp"
#include "sim/simulation.hpp"
#include "sim/timeline_file.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

struct AnimateOptions {
  std::string scene_name = "torus";
  std::string firmware;
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir;
  int threads = default_threads();
  int frames = 0;
  double fps = 0;
  std::vector<int> tessellation;
  bool no_timeline = false;
  bool report = false;  // also OUT/report.html (sim/animation_report.hpp)
};

// frames.csv: one row per frame. Units are in the column names.
const char* const kFramesCsvHeader =
    "frame,animation_seconds,start_ms,frame_ms,end_ms,latency_ms,frames_per_second,"
    "triangles_per_second,"
    "primitives_per_second,bottleneck,gp_utilisation_max,renderer_utilisation_max,"
    "ring_utilisation,pixel_memory_bits_used,primitives_dropped,renderer_busy_cycles,host_ms\n";

std::string frames_csv_row(int k, double fps, const FrameResult& r) {
  const Statistics& s = r.stats;
  const double start_seconds = s.real("frame.start_seconds");
  const double end_seconds = s.real("frame.end_seconds");
  const double t = r.frame_seconds;
  const std::int64_t primitives = s.integer("frame.triangles") + s.integer("frame.spheres");
  const std::int64_t dropped =
      s.integer("setup.clipped_away") + s.integer("setup.degenerate") +
      s.integer("setup.no_pixel_centres") + s.integer("setup.coefficient_overflow") +
      s.integer("setup.sphere_behind_eye") + s.integer("setup.sphere_near_plane") +
      s.integer("setup.sphere_far_plane");
  std::uint64_t busy = 0;
  for (const RegionLoad& l : r.regions) busy += l.busy_cycles;
  return fmt::format(
      "{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.3f},{:.1f},{:.1f},{},{:.6f},{:.6f},{:.6f},{},{},{},"
      "{:.3f}\n",
      k, k / fps, start_seconds * 1e3, t * 1e3, end_seconds * 1e3,
      (end_seconds - start_seconds) * 1e3, t > 0 ? 1.0 / t : 0.0, r.triangles_per_second,
      t > 0 ? static_cast<double>(primitives) / t : 0.0, s.text("timing.bottleneck"),
      s.real("timing.gp_utilisation_max"), s.real("timing.renderer_utilisation_max"),
      s.real("timing.ring_utilisation"), s.integer("pixel_memory.used"), dropped, busy,
      s.real("host.seconds") * 1e3);
}

// `j` as the value of a key at depth `depth` of a document nlohmann::json dumps with an
// indent of 1: its lines after the first indented by `depth` more spaces (a string holds no
// newline: dump escapes it).
std::string indented_json(const nlohmann::json& j, int depth) {
  const std::string text = j.dump(1);
  const std::string indent = "\n" + std::string(static_cast<std::size_t>(depth), ' ');
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (char ch : text) {
    if (ch == '\n') {
      out += indent;
    } else {
      out.push_back(ch);
    }
  }
  return out;
}

int run_animate(AnimateOptions o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  const bool pixels = config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
  const bool event = config.fidelity.timing == MachineConfig::Fidelity::Timing::event;
  AnimationOptions ao;
  if (o.tessellation.size() == 2) {
    ao.scene.tessellation_u = o.tessellation[0];
    ao.scene.tessellation_v = o.tessellation[1];
  }
  ao.frames = o.frames;
  ao.fps = o.fps;
  const Animation animation = load_animation(o.scene_name, ao);
  const int frames = animation.frames();
  // Every frame's scene, made and checked before anything runs: a bad frame stops the run
  // before any output. Only frame 0's is kept: each later frame's is made again as it runs,
  // so that a long animation holds no more than the frames in flight.
  const std::shared_ptr<const Scene> first_scene = check_animation_scenes(animation, config);
  const Scene& first = *first_scene;
  auto program = std::make_shared<const Program>(
      assemble_file(firmware_for(o.firmware, first), assembler_options(config)));
  if (o.out_dir.empty()) o.out_dir = default_output_folder(animation.name() + "-animation");
  const bool replacing = prepare_output_folder(o.out_dir, "--out");
  const fs::path dir(o.out_dir);

  std::cout << fmt::format(
      "pp5sim: animation of scene '{}' ({} triangles, {} spheres), {}: {} "
      "frames at {:g} frames/s, firmware {}\n",
      animation.name(), first.mesh.triangles.size(), first.spheres.size(), animation.motion(),
      frames, animation.fps(), program->name);
  // Every output is staged as a file as soon as it is made (StagedOutputs: a staging folder
  // of this run's inside OUT), and all move into place at the end, or none: memory stays
  // flat however many frames.
  StagedOutputs outputs;
  Session session(config, first_scene, program, o.threads);
  const bool record_timeline = event && !o.no_timeline;
  std::optional<TimelineFile> timeline;
  if (record_timeline) timeline.emplace(outputs, (dir / "timeline.json").string());
  session.stream_timeline(timeline ? &*timeline : nullptr);
  StagedFile csv(outputs, (dir / "frames.csv").string());
  csv.write(kFramesCsvHeader);
  // stats.json, as nlohmann::json's dump(1) of {"frames": [...], "summary": {...}} writes it,
  // a frame at a time.
  StagedFile stats(outputs, (dir / "stats.json").string());
  stats.write("{\n \"frames\": [");
  std::optional<StagedFile> gif_file;
  if (pixels) gif_file.emplace(outputs, (dir / "animation.gif").string());
  std::vector<std::string> staged_pngs;  // for the report, read back at the end
  // Each frame's PNG and its part of the GIF are encoded on a helper thread while the
  // simulation goes on (FrameEncoder), and staged here, in frame order, as they come back:
  // the GIF is written out as it goes, and at most a few frames' images are held.
  FrameEncoder encoder(
      std::max(2, static_cast<int>(std::lround(100.0 / animation.fps()))), [&](EncodedFrame& e) {
        const std::string staged =
            outputs.add((dir / fmt::format("frame-{:04d}.png", e.frame)).string(), e.png);
        if (o.report) staged_pngs.push_back(staged);
        gif_file->write(e.gif);
      });
  std::map<int, RegionLoad> summed;  // by region
  FrameResult last;
  AnimationReportInput report_in;
  std::vector<std::pair<double, double>> frame_spans;  // per frame: start and end, seconds
  // The frames overlapped, as the machine ran them (Session::run_frames): each frame's GPs
  // set up its own scene while the Renderers still draw the frame before.
  auto on_frame = [&](int k, FrameResult& r) {
    csv.write(frames_csv_row(k, animation.fps(), r));
    const double start = r.stats.real("frame.start_seconds");
    const double end = r.stats.real("frame.end_seconds");
    if (record_timeline) frame_spans.emplace_back(start, end);  // 16 bytes a frame
    stats.write((k == 0 ? "\n  " : ",\n  ") + indented_json(r.stats_json, 2));
    if (pixels) encoder.add(k, r.image);  // the last frame's image is kept below (last)
    // The report's row (about 100 bytes a frame, kept for its table).
    AnimationFrameRow row;
    row.start_seconds = start;
    row.frame_seconds = r.frame_seconds;
    row.triangles_per_second = r.triangles_per_second;
    row.bottleneck = r.stats.text("timing.bottleneck");
    row.gp_utilisation_max = r.stats.real("timing.gp_utilisation_max");
    row.renderer_utilisation_max = r.stats.real("timing.renderer_utilisation_max");
    row.ring_utilisation = r.stats.real("timing.ring_utilisation");
    for (const RegionLoad& l : r.regions) row.renderer_busy_cycles += l.busy_cycles;
    if (o.report) report_in.frames.push_back(row);
    for (const RegionLoad& l : r.regions) {
      auto [it, added] = summed.try_emplace(l.region, l);
      if (!added) {
        it->second.busy_cycles += l.busy_cycles;
        it->second.renderer = l.renderer;  // the last frame's Renderer
      }
    }
    std::cout << fmt::format("frame {}: {:.3f} ms simulated, latency {:.3f} ms, {}-bound\n", k,
                             r.frame_seconds * 1e3, (end - start) * 1e3,
                             r.stats.text("timing.bottleneck"));
    last = std::move(r);
  };
  session.run_frames(frames, on_frame, pixels,
                     [&](int k) { return k == 0 ? first_scene : animation_scene(animation, k); });
  csv.close();
  const RunSummary& summary = session.summary();
  nlohmann::json summary_json = summary.statistics().to_json();
  summary_json.update({{"frames", summary.frames},
                       {"simulated_seconds", summary.simulated_seconds},
                       {"mean_frame_seconds", summary.mean_frame_seconds()},
                       {"shortest_frame_seconds", summary.shortest_frame_seconds},
                       {"longest_frame_seconds", summary.longest_frame_seconds},
                       {"fps", animation.fps()},
                       {"motion", animation.motion()}});
  stats.write("\n ],\n \"summary\": " + indented_json(summary_json, 1) + "\n}\n");
  stats.close();
  if (pixels) {
    gif_file->write(encoder.finish());
    gif_file->close();
    if (o.report)
      report_in.gif = read_staged(gif_file->staged_path(), (dir / "animation.gif").string());
  }
  std::vector<RegionLoad> loads;
  for (const auto& [region, load] : summed) loads.push_back(load);
  if (!loads.empty()) {
    const RegionHeatMap map(last.image, loads);
    std::string png = encode_png(map.width(), map.height(),
                                 [&map](int y, std::uint8_t* row) { map.row(y, row); });
    if (o.report) report_in.regions_png = png;
    outputs.add((dir / "regions.png").string(), png);
  }
  outputs.add((dir / "config.json").string(), config.to_json().dump(2) + "\n");
  if (record_timeline) {
    // One more track: the frames themselves, each a slice from its start to its end.
    constexpr int kFramesPid = 5;
    constexpr auto after = TimelineStream::Part::arrivals;  // after the run's own events
    timeline->add(after, {{"ph", "M"},
                          {"name", "process_name"},
                          {"pid", kFramesPid},
                          {"tid", 0},
                          {"args", {{"name", "Animation frames"}}}});
    timeline->add(after, {{"ph", "M"},
                          {"name", "process_sort_index"},
                          {"pid", kFramesPid},
                          {"tid", 0},
                          {"args", {{"sort_index", -1}}}});
    // Two frames are in flight at once: even frames on one row, odd on the other, each from
    // its first set-up on a GP to its last region in the frame buffer.
    for (int row = 0; row < 2; ++row) {
      timeline->add(after, {{"ph", "M"},
                            {"name", "thread_name"},
                            {"pid", kFramesPid},
                            {"tid", row},
                            {"args", {{"name", row == 0 ? "even frames" : "odd frames"}}}});
    }
    for (std::size_t k = 0; k < frame_spans.size(); ++k) {
      timeline->add(after, {{"ph", "X"},
                            {"name", fmt::format("frame {}", k)},
                            {"pid", kFramesPid},
                            {"tid", static_cast<int>(k & 1)},
                            {"ts", frame_spans[k].first * 1e6},
                            {"dur", (frame_spans[k].second - frame_spans[k].first) * 1e6}});
    }
    timeline->finish();
  }
  if (o.report) {
    report_in.title = fmt::format("animation of scene '{}' ({} triangles, {} spheres), firmware {}",
                                  animation.name(), first.mesh.triangles.size(),
                                  first.spheres.size(), fs::path(program->name).stem().string());
    report_in.subtitle = fmt::format("{}: {} frames", animation.motion(), frames);
    report_in.config = &config;
    report_in.summary = summary;
    report_in.fps = animation.fps();
    report_in.timeline = timeline ? &timeline->busy() : nullptr;
    // The report holds every frame's image (a self-contained page): read back from the
    // staged files now, not kept during the run.
    for (std::size_t k = 0; k < staged_pngs.size(); ++k) {
      report_in.frame_pngs.push_back(
          read_staged(staged_pngs[k], (dir / fmt::format("frame-{:04d}.png", k)).string()));
    }
    outputs.add((dir / "report.html").string(), report::html(animation_report(report_in)));
  }
  outputs.commit();
  // What an earlier run into this folder left and this run did not write is not this run's:
  // its report, GIF, heat map, timeline, and frames beyond this run's.
  {
    std::error_code ignored;
    if (!o.report) fs::remove(dir / "report.html", ignored);
    if (!pixels) fs::remove(dir / "animation.gif", ignored);
    if (loads.empty()) fs::remove(dir / "regions.png", ignored);
    if (!record_timeline) fs::remove(dir / "timeline.json", ignored);
    const int kept = pixels ? frames : 0;
    std::vector<fs::path> stale;
    for (const auto& entry : fs::directory_iterator(dir, ignored)) {
      const std::string name = entry.path().filename().string();
      if (name.size() == 14 && name.rfind("frame-", 0) == 0 && name.compare(10, 4, ".png") == 0 &&
          std::all_of(name.begin() + 6, name.begin() + 10,
                      [](char ch) { return ch >= '0' && ch <= '9'; }) &&
          std::stoi(name.substr(6, 4)) >= kept) {
        stale.push_back(entry.path());
      }
    }
    for (const fs::path& p : stale) fs::remove(p, ignored);
  }

  std::cout << summary.text() << summary.sustained_text();
  std::cout << fmt::format(
      "{} {}{}/frames.csv, {}/stats.json, {}/config.json{}{}\n",
      replacing ? "wrote (replacing the previous run's)" : "wrote",
      pixels ? fmt::format("{0}/frame-0000.png .. frame-{1:04d}.png, {0}/animation.gif, ",
                           o.out_dir, frames - 1)
             : "",
      o.out_dir, o.out_dir, o.out_dir,
      loads.empty() ? "" : fmt::format(", {}/regions.png (summed over the frames)", o.out_dir),
      record_timeline ? fmt::format(", {}/timeline.json (open it in ui.perfetto.dev)", o.out_dir)
                      : "");
  if (o.report) std::cout << fmt::format("wrote {}/report.html\n", o.out_dir);
  return 0;
}

}  // namespace

Command add_animate_command(CLI::App& app) {
  auto o = std::make_shared<AnimateOptions>();
  auto* c = app.add_subcommand(
      "animate",
      "Render the frames of an animated scene in one persisting simulation: a PNG per frame, "
      "an animated GIF, frames.csv, the summed regions heat map and a timeline");
  c->add_option("-s,--scene", o->scene_name,
                "torus (Banks' torus turning in 4-space), another built-in scene (turning about "
                "the vertical axis), or a scene file (.json) with an \"animation\" of keyframes "
                "(docs/reference/scene-files.md)")
      ->capture_default_str();
  c->add_option("-f,--firmware", o->firmware, firmware_help());
  add_config_options(*c, o->config_path, o->sets);
  add_fidelity_option(*c, o->sets);
  c->add_option("-n,--frames", o->frames,
                "Frames to render [the scene file's animation.frames, else 24]; a turn spans "
                "all of them")
      ->check(CLI::Range(1, 100000));
  c->add_option("--fps", o->fps, "Frames per second of the animation [animation.fps, else 12]")
      ->check(CLI::Range(0.1, 100.0));
  c->add_option("-o,--out", o->out_dir,
                "Output folder [out/SCENE-animation]: frame-NNNN.png, animation.gif, frames.csv, "
                "regions.png, stats.json, config.json, timeline.json");
  c->add_option("-j,--threads", o->threads, "Host threads (results are identical for any number)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  c->add_option("--tessellation", o->tessellation, "Tessellation U V of the torus or sphere")
      ->expected(2);
  c->add_flag("--no-timeline", o->no_timeline, "Do not record OUT/timeline.json");
  c->add_flag("--report", o->report,
              "Also write OUT/report.html: one self-contained page with the animation, every "
              "frame's figures and image, the summed heat map, the timeline and the configuration");
  return {c, [o] { return run_animate(*o); }};
}

}  // namespace pp5
