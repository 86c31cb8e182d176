#pragma once
// Numerical stability at the extremes: what the machine does with depth precision,
// coefficient overflow, triangles edge-on to the screen, slivers, sub-pixel triangles, huge
// coordinates, nearly parallel and coincident planes, both ends of the depth range, and the
// ownership of pixel centres along shared edges.
//
// Every pixel value examined here comes out of firmware executing on the PixelArray: coverage
// is counted by a program that adds 1 to a per-pixel counter for every triangle whose three
// edge tests pass (kCoverageFirmware), visibility by the flat z-buffer program, depth by a
// program that loads the depth expression into an N-bit field. The references they are
// checked against are computed in double precision from the projected (unsnapped) triangles.
//
// Contract of the coverage reference: snapping moves a vertex by at most 2^-(subpixel_bits+1)
// in x and y, so a pixel centre farther than 2^-subpixel_bits inside every edge of a triangle
// must be covered by it, and one farther than that outside any edge must not be.
#include <cstdint>
#include <string>
#include <vector>

#include "models/config/machine_config.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct ExtremeCase {
  std::string name;
  std::string expected;
  std::string observed;
  bool pass = false;
};

// The synthetic cases, on a 256 x 256 screen of `config`'s machine (its bit widths, sub-pixel
// snapping and evaluator kept, so 'what if' settings show their effect).
std::vector<ExtremeCase> synthetic_extreme_cases(const MachineConfig& config, int threads);
// The checks that apply to any scene: set-up drops, coverage against the reference, parity
// across a closed mesh, and the depth precision of the configured screen.
std::vector<ExtremeCase> scene_extreme_cases(const MachineConfig& config, const Scene& scene,
                                             int threads);
// The cases as a report (sim/output/report.hpp): a table of result, case, expected and
// observed, and a note counting them.
report::Report extremes_report(const std::vector<ExtremeCase>& cases);
// The report as the terminal shows it: one block per case, with PASS or FAIL, then the count.
std::string format_extremes(const std::vector<ExtremeCase>& cases);

// Building blocks, exposed for the tests.

// The firmware that counts, per pixel, the triangles covering its centre (in the red output).
extern const std::string kCoverageFirmware;

// Per-pixel coverage counts of `scene` (row-major, width * height), executed on the machine.
struct Coverage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> count;
  std::uint64_t overflow = 0, degenerate = 0, no_pixels = 0, clipped_away = 0;
};
Coverage coverage_counts(const MachineConfig& config, const Scene& scene, int threads);

// Pixels where the coverage contradicts the reference: missing (a certain-inside triangle did
// not count) and extra (counted by a triangle whose centre is certainly outside).
struct CoverageCheck {
  std::uint64_t missing = 0, extra = 0, certain = 0;  // certain: pixels with a definite answer
};
CoverageCheck check_coverage(const MachineConfig& config, const Scene& scene,
                             const Coverage& coverage);

// Whether every edge of the mesh is shared by exactly two triangles.
bool is_closed(const Mesh& mesh);

// The fraction bits an N-bit z-buffer needs in its running depth on a screen whose larger side
// is K pixels: ceil(log2(2K)), so N + log2(2K) bits in all.
int depth_fraction_bits_needed(int screen_width, int screen_height);
// The largest |z - floor(exact depth)| in z-units over the screen's far-corner region, for a
// depth plane with a badly rounded gradient (1/3 of a unit of 2^-f per pixel) anchored at the
// origin, loaded into a `depth_bits` field with `fraction_bits` fraction bits.
std::int64_t depth_precision_error(const MachineConfig& config, int depth_bits, int fraction_bits);

}  // namespace pp5
