#pragma once
// Standard against accurate scan conversion (Rossignac, sections 9.3 and 9.4), measured on a
// scene: how far the depth each program leaves in its z-buffer is from the exact depth of the
// true surface at the pixel centre, where a hidden surface shows through, whether parity
// holds across a closed mesh, and what the fix costs.
//
// Every depth examined comes out of firmware executing on the pixel array: the programs'
// own `z` field, read back (render_field). Parity is counted by firmware too: a program per
// method that adds 1 to a per-pixel counter for every triangle that owns the centre, with that
// method's tests (the snapped edges; the enlarged area and the side tests). The reference is
// computed in double precision from the projected, unsnapped triangles, projected by the
// reference itself from the camera's view and projection matrices (it shares no code with the
// GP's transform); only a triangle the view volume clips is taken, clipped, from the GP's
// transform (the built-in scenes have none).
//
// Contract (the terms of the report):
//  - Exact depth at pixel (X, Y): the smallest depth, in depth units (0 .. 2^gp.depth_bits - 1),
//    of the unsnapped screen triangles containing the centre (X + 0.5, Y + 0.5); the next
//    larger depth of another triangle there is the first hidden surface.
//  - An edge pixel: one whose centre is within max(1, E) pixels of an edge of any triangle
//    drawn (E below): the front triangle there, a hidden one, or one that passes beside the
//    centre without covering it (a nearer face's silhouette, whose rounded edge may claim the
//    centre). Each edge's band is rasterised row by row. Errors are |z - exact| over edge
//    pixels that both the reference and the program cover; interior pixels (the rest) are
//    reported separately.
//  - A hidden surface shows through at a covered pixel when a hidden surface lies more than
//    kDepthResolution units behind the front one and the program's z is nearer to the hidden
//    depth than to the front one.
//  - Parity errors: pixels covered an odd number of times, counted only on a closed mesh
//    (every edge shared by two triangles); -1 for an open one.
//  - The paper's bound, in our terms. E: the farthest the edge the GP sends lies from the true
//    one, E_snap + E_edge pixels. E_snap = sqrt(2) 2^-(gp.subpixel_bits + 1) (each vertex
//    moves by at most half a snapped unit in x and in y; the paper's E is along x only).
//    E_edge = 2^-n 2 R with n = gp.significand_bits (0 at 62): rounding A, B and C to n
//    significant bits changes A x + B y + C by at most 2^-n (|A| x + |B| y + |C|), which is at
//    most 2^-n 2 R |(A, B)|, R the farthest screen pixel or triangle vertex from the origin. M: the
//    larger depth gradient (depth units per pixel, Euclidean, the paper's dZ/dX in any direction)
//    of the two faces of a shared edge. A centre handed to the wrong one of two faces sharing an
//    edge lies at most E from it, where their planes differ by at most 2ME. It holds where the two
//    faces lie on opposite sides of the edge on the screen; across a boundary or silhouette edge a
//    misclassified centre changes layer (the paper's figure 9.10, bottom row), and the error
//    is the gap between the layers. So the bound is checked at edge pixels within 2E of no
//    silhouette, boundary or clipped edge of any triangle, with M the largest gradient of the
//    front face and of the faces across its edges or around its corners within 2E (local);
//    report.M is the scene's largest gradient, for scale.
//  - Across a silhouette, boundary or clipped edge the paper (9.3.3, figure 9.10 bottom row)
//    says a misclassified centre yields "a slightly translated layer": its depth is that of a
//    surface moved by at most E. So at the edge pixels within 2E of such an edge (the layer
//    pixels) the error is measured against the exact picture moved by at most kLayerReach E:
//    the smallest |z - front(p)| over points p on a grid of step E/4 within kLayerReach E of
//    the centre (front(p) the exact front depth there). A triangle that claims a centre it
//    does not contain lies within E of it, and its plane changes by at most M E over that
//    distance, so the bound is M kLayerReach E + kDepthResolution, M the steepest triangle
//    within E of the centre.
//  - Both bounds assume the program's tiling has no crack: rounded edge coefficients move the
//    three lines at a vertex independently, so they no longer meet in one point, and a centre
//    there may be owned by no triangle of a surface (the layer behind shows) or by two. On a
//    closed mesh such centres are covered an odd number of times: they are counted in
//    parity_errors and left out of both bounds (their errors stay in the max and interior
//    columns). On an open mesh they cannot be told apart and are not left out.
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/gp/accurate_expressions.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

// Depth units within which a rendered depth counts as the surface's own (the z-buffer keeps
// floor() of the value, and the planes are rounded to evaluator.fraction_bits).
inline constexpr double kDepthResolution = 2.0;
// The radius, in units of E, of the disc over which the translated-layer error is sampled.
inline constexpr double kLayerReach = 1.25;

struct ScanConversionMethod {
  std::string program;
  std::uint64_t edge_pixels = 0;  // edge pixels covered by reference and program
  double edge_max_error = 0;      // depth units
  double edge_mean_error = 0;     // depth units
  double interior_max_error = 0;  // depth units, the other covered pixels
  // Over edge pixels within 2E of no silhouette, boundary or clipped edge (a centre there can
  // change plane, not layer): the largest error, and the largest error / (2 M E) with M the
  // larger gradient of the faces of the front face's shared edges there (the paper's bound;
  // 1 = at the bound).
  double shared_edge_max_error = 0;
  double bound_ratio = 0;
  // Over the layer pixels (edge pixels within 2E of a silhouette, boundary or clipped edge):
  // how many, the largest error against the exact picture moved by at most kLayerReach E, and
  // the largest error / (M kLayerReach E + kDepthResolution) (1 = at the bound).
  std::uint64_t layer_pixels = 0;
  double layer_max_error = 0;
  double layer_bound_ratio = 0;
  std::uint64_t show_through = 0;   // pixels where a hidden surface shows
  std::uint64_t missing = 0;        // covered in the reference, z never written
  std::int64_t parity_errors = -1;  // odd coverage on a closed mesh; -1 if not closed
  // Cost.
  std::uint64_t triangle_cycles = 0;  // array cycles of one `triangle` invocation
  int bits = 0;                       // pixel-memory bits the program uses
  double gp_clocks_per_triangle = 0;  // i860 clocks summed over the GPs / scene triangles
  std::uint64_t packet_words = 0;     // ring words of one triangle packet
  double frame_seconds = 0;           // simulated frame time
  RgbImage image;
  std::vector<std::uint8_t> shows_hidden;  // per pixel, 1 where a hidden surface shows
};

struct ScanConversionReport {
  std::string scene;
  std::uint64_t triangles = 0;
  bool closed = false;
  std::uint64_t edges = 0, boundary_edges = 0, non_manifold_edges = 0;
  // How the accurate program's GP set-up classified each edge of each drawn triangle
  // (SideKind order): the neighbour's plane, or why the snapped edge was used instead.
  std::array<std::uint64_t, static_cast<int>(SideKind::count)> sides{};
  double M = 0, E = 0;            // see the contract; the bound is 2 M E
  double E_snap = 0, E_edge = 0;  // E's two parts: the vertex snap, the edge rounding
  ScanConversionMethod standard, accurate;
  std::uint64_t differing = 0;  // pixels whose colour differs between the two
  RgbImage marked;              // accurate's image, dimmed, with the differing pixels marked
};

// Measures `standard` (phong.pp5) and `accurate` (accurate.pp5) on `scene` with `config`'s
// machine. Both programs must have a 24-bit or wider `z` field holding the depth.
ScanConversionReport measure_scan_conversion(const MachineConfig& config, const Scene& scene,
                                             const Program& standard, const Program& accurate,
                                             int threads);

// The table, one row per scene and method (sim/output/report.hpp).
report::Table scan_conversion_table(const std::vector<ScanConversionReport>& reports);

// The two programs measured at each precision of the GP's arithmetic: one row per significand
// width, scene and method (the scene named on every row), with the accuracy columns of
// scan_conversion_table (not the cost, which precision does not change).
struct ScanConversionAtPrecision {
  int significand_bits = 62;  // gp.significand_bits (62: exact)
  std::vector<ScanConversionReport> reports;
};
report::Table scan_conversion_precision_table(const std::vector<ScanConversionAtPrecision>& runs);

// The ablation of accurate scan conversion's two ingredients, each alone: the standard
// program with its depth drawn through the unsnapped vertices (plane_depth instead of depth),
// and the accurate program's classification (enlarged area and side tests) with the snapped
// vertices' depth (depth instead of plane_depth). Made from the two programs' text by
// replacing the depth expression of the triangle procedure's z-buffer test and load
// (`qcmp.lt z, E` and `qload z, E`); throws std::invalid_argument naming the program when
// either line is missing.
Program with_depth_expression(const Program& program, const std::string& source,
                              const std::string& from, const std::string& to,
                              const AssemblerOptions& options);
// Per scene, four rows: standard; snapped edges with unsnapped planes; the accurate program's
// classification over snapped planes; the full accurate program. `a` measured (standard,
// accurate with snapped planes), `b` (standard with unsnapped planes, accurate).
struct ScanConversionAblation {
  ScanConversionReport a, b;
};
report::Table scan_conversion_ablation_table(const std::vector<ScanConversionAblation>& rows);
std::string format_scan_conversion_ablation(const std::vector<ScanConversionAblation>& rows);

// The firmware that counts, per pixel, the triangles that own its centre by accurate.pp5's
// tests (the enlarged area and the three side tests), in the red output.
extern const std::string kAccurateCoverageFirmware;

}  // namespace pp5
