// Frames in sequence against single frames, on the built-in torus at 1280 x 1024 (8,192
// triangles, phong, the default machine), 2 host threads, frame.png encoded for every frame.
// One run times kFrames single frames (simulate_frame: a SystemC context and a Machine made and
// freed per frame, as `pp5sim render` does) and then kFrames frames of one Session (one
// context and one Machine for all of them), and reports:
//   single_over_simulated   host seconds per single frame / the simulated frame period
//   session_over_simulated  host seconds per session frame / the simulated frame period
//   session_over_single     the two host times' ratio (below 1: the session is faster)
// at the fidelity level given as the argument (0: word, 1: bit).
//
// BM_OverlappedFrames: the real-time targets. A kOverlapped-frame animation as `pp5sim
// animate` draws it (sim/animation.hpp: every frame's scene made first, as animate does,
// outside the time), overlapped in one Session (Session::run_frames: a GP sets up frame n + 1
// while the Renderers draw frame n; the run streams, the kernel simulating later frames while
// a helper thread executes a frame's pixels), every frame's frame.png encoded and the frame
// added to the animated GIF in on_frame, as animate does,
// 2 host threads, and reports
//   host_over_period  host seconds per frame / the simulated sustained frame period
//   target            the target for that ratio (real time: 1)
//   met               1 if host_over_period <= target
// for 0: the torus turning in 4-space (animate's default scene) at word (target 1), 1: the
// same at bit (1.5), 2: the 3,200-atom molecule turning about its vertical axis at word (2).
#include <benchmark/benchmark.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/machine_plan.hpp"
#include "sim/animation.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/frame_encoder.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace {

constexpr int kFrames = 10;

void BM_FramesInSequence(benchmark::State& state) {
  pp5::MachineConfig config = pp5::MachineConfig::defaults();
  config.set(std::vector<std::string>{state.range(0) == 0 ? "fidelity.pixels=word"
                                                          : "fidelity.pixels=bit"});
  const auto scene = std::make_shared<const pp5::Scene>(pp5::make_builtin_scene("torus"));
  const auto program = std::make_shared<const pp5::Program>(
      pp5::assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5",
                         pp5::assembler_options(config)));
  auto seconds_since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  double single = 0, session = 0, simulated = 0;
  for (auto _ : state) {
    auto t0 = std::chrono::steady_clock::now();
    for (int f = 0; f < kFrames; ++f) {
      const pp5::FrameResult r = pp5::simulate_frame(config, *scene, *program, 2);
      const std::string png = pp5::encode_png(r.image);
      benchmark::DoNotOptimize(png.data());
      simulated = r.frame_seconds;
    }
    single += seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    pp5::Session run(config, scene, program, 2);
    for (int f = 0; f < kFrames; ++f) {
      const pp5::FrameResult r = run.frame();
      const std::string png = pp5::encode_png(r.image);
      benchmark::DoNotOptimize(png.data());
    }
    session += seconds_since(t0);
  }
  const double frames = static_cast<double>(state.iterations()) * kFrames;
  state.counters["sim_ms"] = simulated * 1e3;
  state.counters["single_over_simulated"] = single / frames / simulated;
  state.counters["session_over_simulated"] = session / frames / simulated;
  state.counters["session_over_single"] = session / single;
}

BENCHMARK(BM_FramesInSequence)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

constexpr int kOverlapped = 100;

void BM_OverlappedFrames(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  pp5::MachineConfig config = pp5::MachineConfig::defaults();
  config.set(std::vector<std::string>{which == 1 ? "fidelity.pixels=bit" : "fidelity.pixels=word"});
  pp5::AnimationOptions options;
  options.frames = kOverlapped;
  const pp5::Animation animation = pp5::load_animation(which == 2 ? "molecule" : "torus", options);
  const std::vector<std::shared_ptr<const pp5::Scene>> scenes =
      pp5::animation_scenes(animation, config);
  const auto program = std::make_shared<const pp5::Program>(
      pp5::assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5",
                         pp5::assembler_options(config)));
  const double target = which == 0 ? 1.0 : which == 1 ? 1.5 : 2.0;
  double host = 0, period = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    pp5::Session run(config, scenes.front(), program, 2);
    std::size_t bytes = 0;
    pp5::FrameEncoder encoder(4, [&bytes](pp5::EncodedFrame& e) {
      bytes += e.png.size() + e.gif.size();
      benchmark::DoNotOptimize(e.png.data());
    });
    const pp5::RunSummary& s = run.run_frames(
        kOverlapped, [&encoder](int k, pp5::FrameResult& r) { encoder.add(k, std::move(r.image)); },
        true, [&scenes](int k) { return scenes[static_cast<std::size_t>(k)]; });
    const std::string trailer = encoder.finish();
    benchmark::DoNotOptimize(trailer.data());
    benchmark::DoNotOptimize(bytes);
    period = s.sustained_frame_seconds;
    host += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const double per_frame = host / (static_cast<double>(state.iterations()) * kOverlapped);
  state.counters["period_ms"] = period * 1e3;
  state.counters["host_ms_per_frame"] = per_frame * 1e3;
  state.counters["host_over_period"] = per_frame / period;
  state.counters["target"] = target;
  state.counters["met"] = per_frame / period <= target ? 1 : 0;
}

BENCHMARK(BM_OverlappedFrames)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
