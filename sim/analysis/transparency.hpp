#pragma once
// Multipass transparency (transparent.pp5, front to back; transparent_interval.pp5, back to
// front with Rossignac's depth-interval buffer, section 9.2.2) against a CPU ground truth:
// every layer at the pixel centre, sorted by depth and composited in double precision.
//
// Contract:
//  - The layers at pixel (X, Y) are the scene's triangles after the GP's own transform,
//    lighting and clipping (GeometryEngine::transform, in double, not snapped) whose closed
//    screen interior holds the centre (X + 0.5, Y + 0.5). Each carries its screen depth, its
//    vertex-lit colour (0..255) and opacity (0..1), interpolated linearly in screen space
//    (Gouraud, as the GP's planes are), colour and opacity clamped to their ranges.
//  - The reference colour is sum_i c_i op_i prod_{j<i} (1 - op_j) + background
//    prod_j (1 - op_j), nearest layer first, on the 0..255 scale of the frame buffer.
//  - A pixel is uncertain (not compared) when the number of layers differs at any of four
//    centres offset by `margin` pixels (an outline nearby), or two of its layers' depth
//    planes meet within `margin` pixels of the centre (their order may swap; a centre on an
//    edge two triangles share is one such).
//  - Elsewhere it differs when a channel of the machine's frame is off the reference by more
//    than kTransparencyTolerance levels.
//  - Deterministic; no pixel value of the machine comes from here.
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/frame_buffer/image.hpp"
#include "sim/analysis/frame_cost.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

// Levels of 255 a channel may be off: the firmware floors each layer's colour, each
// compositing product and the output (about one level), plus the snapped, fixed-point planes.
inline constexpr double kTransparencyTolerance = 3.0;

struct TransparencyReference {
  int width = 0, height = 0;
  std::vector<double> rgb;              // per pixel, three channels, 0..255
  std::vector<std::uint8_t> layers;     // per pixel, the layers at the centre (255 at most)
  std::vector<std::uint8_t> uncertain;  // per pixel, 1 if not compared
};
TransparencyReference transparency_reference(const MachineConfig& config, const Scene& scene,
                                             double margin = 0.75);

struct TransparencyMeasure {
  std::string scene, program;
  int layers = 0;               // the program's passes: the layers it composites
  std::int64_t compared = 0;    // certain pixels
  std::int64_t covered = 0;     // certain pixels with at least one layer
  std::int64_t too_many = 0;    // certain pixels with more layers than `layers`
  int most = 0;                 // the most layers at a certain pixel
  std::int64_t differ = 0;      // certain pixels off the reference by more than the tolerance
  std::int64_t uncertain = 0;   // not compared
  double max_error = 0;         // levels, over the certain pixels
  double max_error_within = 0;  // levels, over the certain pixels with at most `layers` layers
  int bits = 0;
  FrameCost cost;
  RgbImage image, difference;  // difference: white differs, grey uncertain
};
// Renders `scene` with `program` (a transparency program: `option passes layers`, or any
// pass count), compares its frame with the reference and runs the frame's timing.
TransparencyMeasure measure_transparency(const MachineConfig& config, const Scene& scene,
                                         const Program& program, int threads);
report::Table transparency_table(const std::vector<TransparencyMeasure>& rows);

}  // namespace pp5
