#pragma once
// Ground truth for intersection highlighting, computed on the CPU independently of the
// machine: the world-space segments where triangles of a scene cross, the parts of them
// that are visible (checked against a double-precision depth reference at each sample's
// exact screen position), their projection, and the pixels within delta of them. Then the
// accuracy of a set of flagged pixels against that truth.
//
// Contract:
//  - Triangles that share a vertex index are neighbours, not intersecting; coplanar pairs
//    are ignored (they have no intersection curve).
//  - A curve sample is visible when no third triangle covers its screen position nearer
//    than it (by more than 1e-7 of the depth range).
//  - A truth pixel is reachable when at least two drawable triangles cover its centre: a
//    depth-test highlighter compares a sample with another only where two surfaces reach the
//    same pixel, so a truth pixel reached by one surface (or none: the band of width delta
//    spills past the surfaces' outlines) cannot be flagged by any program. The share of
//    truth pixels that are reachable is the recall ceiling of the truth.
//  - Screen conventions are the GP's: pixel (X, Y) has its centre at (X + 0.5, Y + 0.5),
//    y down, depth in [0, 1] from the near to the far plane.
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct Segment3 {
  glm::dvec3 a, b;
  int first = 0, second = 0;  // the two triangles
};

// Every intersection segment of the mesh's triangles, in a deterministic order.
std::vector<Segment3> intersection_segments(const Mesh& mesh);

// The segment where two triangles cross; false if they do not (or only touch at a point,
// or are coplanar).
bool triangle_intersection(const glm::dvec3 (&p)[3], const glm::dvec3 (&q)[3], glm::dvec3& a,
                           glm::dvec3& b);

struct CurveSample {
  glm::dvec2 screen;        // pixel coordinates
  glm::dvec2 tangent;       // unit, in the screen
  std::size_t segment = 0;  // index into IntersectionTruth::curves
};

struct IntersectionTruth {
  int width = 0, height = 0;
  double delta = 0;                   // half-width, pixels
  std::size_t segments = 0;           // world-space intersection segments
  std::vector<Segment3> curves;       // those segments, in intersection_segments order
  std::size_t samples = 0;            // samples along them (on screen)
  std::vector<CurveSample> visible;   // the visible samples
  std::vector<std::uint8_t> mask;     // pixels within delta of a visible sample
  std::size_t pixels = 0;             // set bits of mask
  std::size_t reachable = 0;          // of those, pixels whose centre two or more triangles cover
  std::vector<std::uint8_t> reached;  // per pixel, 1 for those reachable truth pixels
};

// Samples every segment at `spacing` pixels on the screen. With visible_only false, hidden
// parts count too (the truth for transparency, where every intersection shows).
IntersectionTruth intersection_truth(const Scene& scene, int width, int height, double delta,
                                     double spacing = 0.25, bool visible_only = true);

struct Accuracy {
  std::size_t truth = 0, flagged = 0, hits = 0;
  double recall = 0;     // hits / truth
  double ceiling = 0;    // truth.reachable / truth: the highest recall any program can reach
  double precision = 0;  // hits / flagged
  // Width of the flagged curve across the true one, in pixels, measured at the visible
  // samples whose own pixel is flagged; `coverage` is the share of samples that are.
  double width_mean = 0, width_sd = 0, coverage = 0;
  std::size_t width_samples = 0;
};

Accuracy measure_accuracy(const IntersectionTruth& truth, const std::vector<std::uint8_t>& flagged);

// The flagged curve's width across each true segment separately (width_mean, width_sd,
// width_samples and coverage of each; the pixel counts are left 0), indexed like
// truth.curves: how the width changes along a scene, e.g. with distance from the eye.
std::vector<Accuracy> measure_width_by_segment(const IntersectionTruth& truth,
                                               const std::vector<std::uint8_t>& flagged);

// The frame darkened, with flagged pixels in the truth green, flagged pixels outside it red
// and missed truth pixels blue.
RgbImage overlay_image(const RgbImage& frame, const IntersectionTruth& truth,
                       const std::vector<std::uint8_t>& flagged);

// The truth alone: the frame darkened, truth pixels two or more triangles reach white, truth
// pixels no program can flag (one surface or none reaches them) orange.
RgbImage truth_image(const RgbImage& frame, const IntersectionTruth& truth);

// `left` and `right` side by side with a `gap`-pixel grey band between them (the taller one's
// height; the shorter one padded with grey below).
RgbImage side_by_side(const RgbImage& left, const RgbImage& right, int gap = 8);

}  // namespace pp5
