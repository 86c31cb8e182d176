#include "sim/analysis/frame_cost.hpp"

#include <fmt/format.h>

#include "sim/simulation.hpp"

namespace pp5 {

void add_cost_columns(std::vector<report::Column>& columns, const std::string& prefix) {
  using namespace report;
  columns.push_back(headed(integer_column("Renderer cycles", "array cycles",
                                          "The Renderers' busy array cycles, all regions"),
                           prefix + "Renderer cycles"));
  columns.push_back(headed(real_column("frame ms", "ms", 3, "Simulated frame time"), "frame ms"));
  columns.push_back(
      headed(real_column("frames/s", "frames/s", 1, "1 / the frame time"), "frames/s"));
}

void add_cost_cells(std::vector<report::Cell>& row, const FrameCost& cost) {
  row.emplace_back(cost.renderer_cycles);
  row.emplace_back(cost.frame_seconds * 1e3);
  row.emplace_back(cost.frame_seconds > 0 ? 1.0 / cost.frame_seconds : 0.0);
}

FrameCost frame_cost(const MachineConfig& config, const Scene& scene, const Program& program,
                     int threads, RgbImage* image) {
  const FrameResult r = simulate_frame(config, scene, program, threads);
  if (image) *image = r.image.flat();
  return {r.stats.integer("renderers_total.busy_cycles"), r.stats.real("frame.simulated_seconds")};
}

}  // namespace pp5
