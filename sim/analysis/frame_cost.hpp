#pragma once
// What one frame of an application costs on the machine: the last columns of the tables of
// `pp5sim csg` (parity, interference, CSG rendering, transparency, cross-sections).
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/frame_buffer/image.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct FrameCost {
  std::int64_t renderer_cycles = 0;  // the Renderers' busy array cycles, all regions
  double frame_seconds = 0;          // simulated
};

// A table's three cost columns, "Renderer cycles", "frame ms" and "frames/s" (`prefix`
// before the first heading: "unpruned: "), and a cost's cells for them, appended to a row.
void add_cost_columns(std::vector<report::Column>& columns, const std::string& prefix = {});
void add_cost_cells(std::vector<report::Cell>& row, const FrameCost& cost);

// One frame of `scene` through `program` (simulate_frame); its image into `image` if given.
FrameCost frame_cost(const MachineConfig& config, const Scene& scene, const Program& program,
                     int threads, RgbImage* image = nullptr);

}  // namespace pp5
