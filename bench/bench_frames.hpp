#pragma once
// What the encoder benchmarks share: the frame they encode and the clock they read.
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

}  // namespace pp5::bench
