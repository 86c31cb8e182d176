#pragma once
// What one frame of an application costs on the machine: the last columns of the tables of
// `pp5sim csg` (parity, interference, CSG rendering, transparency, cross-sections).
#include <cstdint>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/frame_buffer/image.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct FrameCost {
  std::int64_t renderer_cycles = 0;  // the Renderers' busy array cycles, all regions
  double frame_seconds = 0;          // simulated
  // The table cells "cycles | frame ms | frames/s" (no outer bars).
  std::string cells() const;
};

// One frame of `scene` through `program` (simulate_frame); its image into `image` if given.
FrameCost frame_cost(const MachineConfig& config, const Scene& scene, const Program& program,
                     int threads, RgbImage* image = nullptr);

}  // namespace pp5
