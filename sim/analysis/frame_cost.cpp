#include "sim/analysis/frame_cost.hpp"

#include <fmt/format.h>

#include "sim/simulation.hpp"

namespace pp5 {

std::string FrameCost::cells() const {
  return fmt::format("{} | {:.3f} | {:.1f}", renderer_cycles, frame_seconds * 1e3,
                     frame_seconds > 0 ? 1.0 / frame_seconds : 0.0);
}

FrameCost frame_cost(const MachineConfig& config, const Scene& scene, const Program& program,
                     int threads, RgbImage* image) {
  const FrameResult r = simulate_frame(config, scene, program, threads);
  if (image) *image = r.image.flat();
  return {r.stats.integer("renderers_total.busy_cycles"), r.stats.real("frame.simulated_seconds")};
}

}  // namespace pp5
