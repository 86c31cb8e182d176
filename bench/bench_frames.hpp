#pragma once
// What the encoder benchmarks share: the frame they encode, the clock they read and their
// timing loop.
#include <benchmark/benchmark.h>

#include <cstddef>
#include <ctime>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/machine_plan.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace pp5::bench {

// The default torus at `word` (1280 x 1024, phong), as the frame buffer holds it.
inline FrameImage torus_word_frame() {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"fidelity.pixels=word"});
  const Scene scene = make_builtin_scene("torus");
  const Program program = assemble_file(
      std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5", assembler_options(config));
  return simulate_frame(config, scene, program, 2).image;
}

// This thread's processor time, in seconds: the machine is shared, and the encoders are
// single-threaded.
inline double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// Per iteration, the new encoder and then the reference, each timed on this thread's clock:
// their mean milliseconds and the bytes each gave last.
struct EncoderTimes {
  double new_ms = 0, ref_ms = 0;
  std::size_t new_bytes = 0, ref_bytes = 0;
};

template <class New, class Ref>
EncoderTimes time_encoders(benchmark::State& state, New encode_new, Ref encode_ref) {
  double t_new = 0, t_ref = 0;
  EncoderTimes times;
  for (auto _ : state) {
    double t0 = thread_cpu_seconds();
    const std::string a = encode_new();
    t_new += thread_cpu_seconds() - t0;
    t0 = thread_cpu_seconds();
    const std::string b = encode_ref();
    t_ref += thread_cpu_seconds() - t0;
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
    times.new_bytes = a.size();
    times.ref_bytes = b.size();
  }
  const double n = static_cast<double>(state.iterations());
  times.new_ms = t_new / n * 1e3;
  times.ref_ms = t_ref / n * 1e3;
  return times;
}

}  // namespace pp5::bench
