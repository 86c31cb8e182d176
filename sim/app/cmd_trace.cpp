// pp5sim trace: record per-pixel traces of a frame and inspect them (see traces/README.md).
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/animation.hpp"
#include "sim/app/commands.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "sim/trace/inspect.hpp"
#include "sim/trace/recorder.hpp"
#include "sim/trace/snapshot.hpp"
#include "sim/trace/trace_file.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// What to simulate: the same choices as `pp5sim render`.
struct RunOptions {
  std::string scene_name = "torus";
  std::string firmware;  // empty: the scene file's "firmware", else phong
  std::string config_path;
  std::vector<std::string> sets;
  int threads = default_threads();
  std::vector<int> tessellation;
  int frame = -1;  // --frame K: frame K of the scene's animation (pp5sim animate)
  int animation_frames = 0;

  void add(CLI::App& c) {
    c.add_option("--frame", frame,
                 "Frame K of the scene's animation, as 'pp5sim animate' draws it: frames 0 .. K "
                 "(and K+1, which overlaps it) run overlapped, timing only but frame K, which "
                 "this command looks at")
        ->check(CLI::Range(0, 100000));
    c.add_option("--animation-frames", animation_frames,
                 "Frames of that animation (animate's --frames) [the scene file's, else 24]")
        ->check(CLI::Range(1, 100000));
    c.add_option("-s,--scene", scene_name,
                 "Scene: a built-in name (pp5sim scenes), a mesh file or a scene file")
        ->capture_default_str();
    c.add_option("-f,--firmware", firmware, firmware_help());
    add_config_options(c, config_path, sets);
    c.add_option("-j,--threads", threads, "Host threads (the trace is identical for any number)")
        ->check(CLI::Range(1, 256));
    c.add_option("--tessellation", tessellation, "Tessellation U V of the torus or sphere")
        ->expected(2);
  }
  SceneOptions scene_options() const {
    SceneOptions so;
    if (tessellation.size() == 2) {
      so.tessellation_u = tessellation[0];
      so.tessellation_v = tessellation[1];
    }
    return so;
  }
  std::optional<Animation> animation() const {
    if (frame < 0) {
      if (animation_frames > 0) throw std::runtime_error("--animation-frames needs --frame");
      return std::nullopt;
    }
    AnimationOptions ao;
    ao.scene = scene_options();
    ao.frames = animation_frames;
    return load_animation(scene_name, ao);
  }
  // The scene looked at: the built-in or file, or frame K of its animation.
  Scene scene() const {
    if (const auto a = animation()) return a->scene(frame);
    return load_scene(scene_name, scene_options());
  }
  // The frame looked at, with `observe` on its Renderers: one frame, or frame K of the
  // animation as `pp5sim animate` draws it: frames 0 .. K overlapped in one session
  // (Session::run_frames), frames 0 .. K-1 timing only.
  FrameResult simulate(const MachineConfig& config, const Scene& scene, const Program& program,
                       const std::function<BoardObserver*(int renderer)>& observe) const {
    const auto a = animation();
    if (!a) return simulate_frame(config, scene, program, threads, observe);
    if (config.fidelity.timing != MachineConfig::Fidelity::Timing::event) {
      throw std::invalid_argument(
          "traces and snapshots need fidelity.timing=event (the analytic model runs no events "
          "and records no start cycles)");
    }
    if (config.fidelity.pixels == MachineConfig::Fidelity::Pixels::none)
      throw std::invalid_argument("an observer of the boards needs fidelity.pixels=bit or word");
    // Frame K + 1 as well, when the animation has it: its set-up overlaps frame K (frame K + 2
    // begins only once every Renderer has finished K + 1).
    const auto first = std::make_shared<const Scene>(a->scene(0));
    Session session(config, first, std::shared_ptr<const Program>(&program, [](const Program*) {}),
                    threads);
    const int count = frame + 1 < a->frames() ? frame + 2 : frame + 1;
    FrameResult out;
    session.run_frames(
        count,
        [&out, this](int k, FrameResult& r) {
          if (k == frame) out = std::move(r);
        },
        true,
        [&a, &scene, &first, this](int k) {
          if (k == 0) return first;
          return std::make_shared<const Scene>(k == frame ? scene : a->scene(k));
        },
        nullptr, ObservedFrame{frame, observe});
    return out;
  }
};

std::optional<trace::Pixel> pixel_option(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const trace::Rect r = trace::parse_rect(text, "--pixel");
  if (r.width != 1 || r.height != 1) throw std::runtime_error("--pixel: expected X,Y");
  return trace::Pixel{r.x, r.y};
}

struct RecordOptions {
  RunOptions run;
  std::vector<std::string> pixels, rects, fields;
  std::vector<int> regions;
  std::string instructions, primitives, frames;
  std::string out;
};

int run_record(const RecordOptions& o) {
  const MachineConfig config = load_config(o.run.config_path, o.run.sets);
  if (refuse_below_bit_level(config, "pp5sim trace record")) return 2;
  const Scene scene = o.run.scene();
  const Program program =
      assemble_file(firmware_for(o.run.firmware, scene), assembler_options(config));
  trace::Selection sel;
  for (const auto& p : o.pixels) {
    const trace::Rect r = trace::parse_rect(p, "--pixel");
    if (r.width != 1 || r.height != 1) throw std::runtime_error("--pixel: expected X,Y");
    sel.rects.push_back(r);
  }
  for (const auto& r : o.rects) sel.rects.push_back(trace::parse_rect(r, "--rect"));
  sel.regions = o.regions;
  sel.fields = o.fields;
  if (!o.instructions.empty())
    sel.instructions = trace::parse_range(o.instructions, "--instructions");
  if (!o.primitives.empty()) sel.primitives = trace::parse_range(o.primitives, "--primitives");
  if (!o.frames.empty()) sel.frames = trace::parse_range(o.frames, "--frames");
  trace::Recorder recorder(config, scene, program, sel, std::max(0, o.run.frame));
  const std::string out =
      o.out.empty() ? (fs::path("out") / scene.name / "trace.pp5t").string() : o.out;
  if (fs::path(out).has_parent_path()) fs::create_directories(fs::path(out).parent_path());

  for (int k = 0; k < config.renderer.count; ++k) recorder.observer(k);
  const FrameResult result =
      o.run.simulate(config, scene, program, [&](int k) { return recorder.observer(k); });
  recorder.write(out);
  std::uint64_t count = 0;
  const auto bytes = recorder.records(count).size();
  std::cout << fmt::format(
      "pp5sim: traced {} pixel(s) of scene '{}' ({} triangles), firmware {}: {} records, {} "
      "bytes\n",
      recorder.pixel_count(), scene.name, scene.mesh.triangles.size(), program.name, count, bytes);
  if (recorder.pixel_count() == 1) {
    const auto& rects = sel.rects;
    if (!rects.empty()) {
      const std::uint8_t* c = result.image.pixel(rects[0].x, rects[0].y);
      std::cout << fmt::format("frame colour of pixel {},{}: ({}, {}, {})\n", rects[0].x,
                               rects[0].y, c[0], c[1], c[2]);
    }
  }
  std::cout << fmt::format("wrote {}\n", out);
  return 0;
}

std::string default_vcd_name(const std::string& trace_path) {
  return (fs::path(trace_path).replace_extension(".vcd")).string();
}

}  // namespace

Command add_trace_command(CLI::App& app) {
  auto* t = app.add_subcommand(
      "trace",
      "Per-pixel traces: record a frame's effect on chosen pixels, then ask why a pixel has its "
      "value (see traces/README.md)");
  t->require_subcommand(1);
  auto runs = std::make_shared<std::vector<std::pair<CLI::App*, std::function<int()>>>>();

  auto ro = std::make_shared<RecordOptions>();
  auto* rec =
      t->add_subcommand("record",
                        "Simulate a frame and record the selected pixels' fields after every "
                        "micro-instruction that writes or changes them");
  ro->run.add(*rec);
  rec->add_option("-p,--pixel", ro->pixels, "A screen pixel X,Y (repeatable)");
  rec->add_option("--rect", ro->rects, "A screen rectangle X,Y,WIDTH,HEIGHT (repeatable)");
  rec->add_option("--region", ro->regions, "A whole 128 x 128 region by number (repeatable)");
  rec->add_option("--fields", ro->fields, "Fields to record, comma-separated [all]")
      ->delimiter(',');
  rec->add_option("--instructions", ro->instructions,
                  "Window of micro-instruction numbers on the pixel's Renderer, A:B (B excluded), "
                  "A:, :B or N");
  rec->add_option("--primitives", ro->primitives,
                  "Window of scene triangles A:B; clear and shade fall outside it");
  rec->add_option("--frames", ro->frames, "Window of frames A:B (a run renders frame 0)");
  rec->add_option("-o,--out", ro->out, "Trace file to write [out/SCENE/trace.pp5t]");
  runs->push_back({rec, [ro] { return run_record(*ro); }});

  auto file = std::make_shared<std::string>();
  auto file_b = std::make_shared<std::string>();
  auto pixel = std::make_shared<std::string>();
  auto fields = std::make_shared<std::vector<std::string>>();
  auto every = std::make_shared<bool>(false);
  auto out = std::make_shared<std::string>();

  auto* info = t->add_subcommand("info", "What a trace file holds: its header and record counts");
  info->add_option("trace", *file, "Trace file (.pp5t)")->required();
  runs->push_back({info, [file] {
                     const trace::Trace tr = trace::read_trace(*file);
                     nlohmann::json h = tr.header;
                     h.erase("config");
                     h["firmware"].erase("procedures");
                     std::cout << h.dump(2) << "\n";
                     std::cout << fmt::format("{} instruction records, {} value records\n",
                                              tr.events.size(), tr.values.size());
                     return 0;
                   }});

  auto* hist = t->add_subcommand("history", "A table of a pixel's fields over time");
  hist->add_option("trace", *file, "Trace file (.pp5t)")->required();
  hist->add_option("-p,--pixel", *pixel, "Pixel X,Y (needed if the trace holds several)");
  hist->add_option("--fields", *fields, "Only these fields, comma-separated")->delimiter(',');
  hist->add_flag("--all", *every, "Also list instructions that changed none of the fields");
  runs->push_back({hist, [=] {
                     const trace::Trace tr = trace::read_trace(*file);
                     std::cout << trace::history_report(
                         tr, trace::choose_pixel(tr, pixel_option(*pixel)), *fields, *every);
                     return 0;
                   }});

  auto* why =
      t->add_subcommand("why",
                        "Why a pixel has its value: each field's final value and the primitive and "
                        "instruction that last wrote it");
  why->add_option("trace", *file, "Trace file (.pp5t)")->required();
  why->add_option("-p,--pixel", *pixel, "Pixel X,Y (needed if the trace holds several)");
  runs->push_back({why, [=] {
                     const trace::Trace tr = trace::read_trace(*file);
                     std::cout << trace::why_report(tr,
                                                    trace::choose_pixel(tr, pixel_option(*pixel)));
                     return 0;
                   }});

  auto* diff = t->add_subcommand(
      "diff",
      "Compare two traces (two firmware programs or configurations) field by field, "
      "packet by packet, and show the first divergence");
  diff->add_option("a", *file, "First trace")->required();
  diff->add_option("b", *file_b, "Second trace")->required();
  diff->add_option("-p,--pixel", *pixel, "Only this pixel X,Y");
  runs->push_back({diff, [=] {
                     const trace::Trace a = trace::read_trace(*file);
                     const trace::Trace b = trace::read_trace(*file_b);
                     bool diverged = false;
                     std::cout << trace::diff_report(a, b, pixel_option(*pixel), diverged);
                     return 0;
                   }});

  auto* bitmap = t->add_subcommand(
      "bitmap", "Which bits of pixel memory each field occupies, and which changed in the trace");
  bitmap->add_option("trace", *file, "Trace file (.pp5t)")->required();
  runs->push_back({bitmap, [=] {
                     std::cout << trace::bitmap_report(trace::read_trace(*file));
                     return 0;
                   }});

  auto* v = t->add_subcommand(
      "vcd", "Export the selected pixels' fields and the instruction stream as VCD (GTKWave)");
  v->add_option("trace", *file, "Trace file (.pp5t)")->required();
  v->add_option("-o,--out", *out, "VCD file to write [the trace's name with .vcd]");
  runs->push_back({v, [=] {
                     const trace::Trace tr = trace::read_trace(*file);
                     const std::string path = out->empty() ? default_vcd_name(*file) : *out;
                     write_file_atomically(path, trace::vcd(tr));
                     std::cout << fmt::format("wrote {} (open it with: gtkwave {})\n", path, path);
                     return 0;
                   }});

  struct SnapOptions {
    RunOptions run;
    int region = -1;
    std::string pixel;
    std::int64_t after = -1;
    std::string out;
    std::vector<std::string> png;
    std::string from;
  };
  auto so = std::make_shared<SnapOptions>();
  auto* snap =
      t->add_subcommand("snapshot",
                        "Simulate a frame and save a region's whole pixel memory at a chosen point "
                        "(.pp5m), and chosen fields as PNG images");
  so->run.add(*snap);
  snap->add_option("--region", so->region, "Region number");
  snap->add_option("-p,--pixel", so->pixel, "Or: the region holding screen pixel X,Y");
  // -1 (the default) stands for the region's end; a negative number given is refused, not
  // taken as that.
  snap->add_option("--after", so->after,
                   "After this micro-instruction number of the region's Renderer [the region's "
                   "end]")
      ->check(CLI::NonNegativeNumber);
  snap->add_option("-o,--out", so->out, "Snapshot file [out/SCENE/region-R.pp5m]");
  snap->add_option("--png", so->png,
                   "Also write FIELD as OUT-FIELD.png (repeatable): 1-bit fields as masks, wider "
                   "ones as a grey ramp from the region's minimum to its maximum");
  snap->add_option("--from", so->from,
                   "Read this snapshot file instead of simulating (with --png: images of it)");
  runs->push_back(
      {snap, [so] {
         if (!so->from.empty()) {
           const trace::Snapshot s = trace::read_snapshot(so->from);
           for (const auto& f : so->png) trace::field_image(s, f);  // check names
           std::cout << fmt::format("{}: region {}, {}\n", so->from, s.region, s.point);
           for (const auto& f : so->png) {
             const std::string png =
                 fs::path(so->from).replace_extension("").string() + "-" + f + ".png";
             write_png(png, trace::field_image(s, f));
             std::cout << fmt::format("wrote {}\n", png);
           }
           return 0;
         }
         const MachineConfig config = load_config(so->run.config_path, so->run.sets);
         if (refuse_below_bit_level(config, "pp5sim trace snapshot")) return 2;
         int region = so->region;
         if (const auto p = pixel_option(so->pixel)) {
           if (p->first >= config.screen.width || p->second >= config.screen.height) {
             throw std::runtime_error(fmt::format("--pixel {}: outside the screen", so->pixel));
           }
           region = (p->second / config.renderer.region_height) * config.regions_x() +
                    p->first / config.renderer.region_width;
         }
         if (region < 0) throw std::runtime_error("snapshot: give --region or --pixel");
         const Scene scene = so->run.scene();
         const Program program =
             assemble_file(firmware_for(so->run.firmware, scene), assembler_options(config));
         std::optional<std::uint64_t> after;
         if (so->after >= 0) after = static_cast<std::uint64_t>(so->after);
         trace::SnapshotTaker taker(config, program, region, after);
         so->run.simulate(config, scene, program, [&](int k) { return taker.observer(k); });
         const trace::Snapshot& s = taker.snapshot();
         for (const auto& f : so->png) trace::field_image(s, f);  // check names
         const std::string path =
             so->out.empty()
                 ? (fs::path("out") / scene.name / fmt::format("region-{}.pp5m", region)).string()
                 : so->out;
         if (fs::path(path).has_parent_path()) {
           prepare_output_folder(fs::path(path).parent_path().string(), "--out");
         }
         // The snapshot and its images together, or none of them (sim/output).
         OutputSet outputs;
         outputs.add(path, trace::encode_snapshot(s));
         std::vector<std::string> pngs;
         for (const auto& f : so->png) {
           pngs.push_back((fs::path(path).replace_extension("").string()) + "-" + f + ".png");
           outputs.add(pngs.back(), encode_png(trace::field_image(s, f)));
         }
         outputs.commit();
         std::cout << fmt::format("wrote {} (region {}, {})\n", path, region, s.point);
         for (const std::string& png : pngs) std::cout << fmt::format("wrote {}\n", png);
         return 0;
       }});

  return {t, [runs] {
            for (const auto& [cmd, run] : *runs) {
              if (*cmd) return run();
            }
            return 1;
          }};
}

}  // namespace pp5
