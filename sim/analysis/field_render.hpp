#pragma once
// The functional half of a frame with one firmware field read back: the GP's set-up
// (every primitive through its kind, models/gp/primitive_kind.hpp) feeds every region's
// packets, in display-list order, to a RendererBoard
// that executes the program's region stream on its pixel array, exactly as execute_pixels
// (models/renderer/execute_pixels.hpp) does; afterwards the value of a named field (an intersection
// flag, say) is read from every pixel. The analysis of intersection highlighting compares that
// field with the truth.
//
// Contract: no value is computed here but by the firmware; the readout is the same scalar
// access the frame buffer's output path uses. Deterministic for any thread count.
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct FieldFrame {
  RgbImage image;                     // the program's output fields
  std::vector<std::uint64_t> values;  // the field, row-major, width * height
  std::uint64_t packets = 0;          // triangle packets sent to regions
};

// Throws std::invalid_argument if `field` is not a field of `program`.
FieldFrame render_field(const MachineConfig& config, const Scene& scene, const Program& program,
                        const std::string& field, int threads);

}  // namespace pp5
