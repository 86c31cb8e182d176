#pragma once
// Visible-surface determination beside the machine's z-buffer: CPU references (an exact
// per-pixel-centre ray cast, a scan-line span algorithm with an active edge table, and
// Warnock's area subdivision with the slides' simple cases), and the comparison of the
// machine's z-buffer, painter's (depth sort on the GPs, models/gp/depth_sort.hpp), bad and
// correct perspective depth and back-face removal against the exact reference.
//
// The machine's images are visibility images: every triangle's three vertices carry its
// index + 1 in 24 bits as an unlit colour (base_red/green/blue), and in-code firmware loads
// that colour where the triangle wins; so the visible triangle of every pixel comes out of
// micro-instructions executing on the pixel memory, and decoding the frame gives it back.
// The same runs with the shaded programs (gouraud.pp5, painter.pp5) give the Renderer
// cycles, the bits and the frame time; their visibility logic is the same instructions.
//
// Contract:
//  - Polygons are the scene's triangles after the GP's own transform and clipping
//    (GeometryEngine::transform, in double, not snapped): one convex polygon per scene
//    triangle (a clipped triangle's fan joined back). Pixel (X, Y) samples (X + 0.5, Y + 0.5).
//  - The exact reference takes at each pixel centre the polygon with the least screen depth
//    among those whose closed interior holds the centre. A pixel is uncertain when the
//    machine may legitimately differ: a centre within 2^-subpixel_bits of an edge of a
//    polygon that could be nearest there (vertex snapping moves edges by less), or two
//    nearest depths within 16 units of 2^-depth_bits. Differences are counted on the other
//    pixels only; the uncertain ones are counted apart.
//  - Scan-line and Warnock agree with the reference on every certain pixel of any scene
//    (they resolve interpenetration exactly); the tests check it.
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "common/statistics.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/frame_buffer/image.hpp"
#include "models/gp/depth_sort.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

// A scene triangle after projection: a convex polygon in screen space (x, y pixels, y down;
// z the screen depth, 0 near .. 1 far).
struct ScreenPolygon {
  std::vector<glm::dvec3> v;
  std::vector<double> w;  // each vertex's clip w (eye depth): screen coordinates x w are
                          // affine in the world point, which is what splitting needs
  int source = 0;         // the scene triangle
};

// The scene's triangles through the machine's transform and clipping (with
// gp.cull_back_faces as configured); dropped triangles make no polygon.
std::vector<ScreenPolygon> project_scene(const MachineConfig& config, const Scene& scene);

// The visible scene triangle per pixel, -1 for background; row-major.
struct IdImage {
  int width = 0, height = 0;
  std::vector<int> id;
};

struct ReferenceImage : IdImage {
  std::vector<std::uint8_t> uncertain;
};
ReferenceImage exact_reference(const std::vector<ScreenPolygon>& polygons, int width, int height,
                               int subpixel_bits, int depth_bits);

// Work of the scan-line algorithm: edges entered in the edge table, edge crossings sorted,
// spans resolved, depth comparisons, spans split where two polygons cross in depth.
struct ScanlineWork {
  std::uint64_t edges = 0, crossings = 0, spans = 0, depth_comparisons = 0, splits = 0;
};
IdImage scanline_visible(const std::vector<ScreenPolygon>& polygons, int width, int height,
                         ScanlineWork& work);

// Work of Warnock's algorithm: areas examined, and how many each simple case settled.
struct WarnockWork {
  std::uint64_t areas = 0, empty = 0, single = 0, surrounding = 0, front_surrounding = 0,
                pixels = 0;
  int max_level = 0;
};
IdImage warnock_visible(const std::vector<ScreenPolygon>& polygons, int width, int height,
                        WarnockWork& work);

// An image against the reference, on its certain pixels.
struct Difference {
  std::uint64_t differing = 0;  // certain pixels whose visible triangle differs
  std::uint64_t uncertain = 0;  // uncertain pixels that differ (not counted above)
  std::uint64_t regions = 0;    // regions (region_width x region_height) with a difference
  int densest_region = -1;      // row-major region index, -1 if none
  std::uint64_t densest = 0;    // differing pixels in it
};
Difference compare_visibility(const IdImage& image, const ReferenceImage& reference,
                              int region_width, int region_height);
// Agreeing pixels grey (shaded by triangle), differing certain pixels red, differing
// uncertain pixels dim yellow, background black.
RgbImage difference_image(const IdImage& image, const ReferenceImage& reference);

// The scene with every triangle on its own three vertices, coloured by index + 1 (24 bits
// over red, green, blue: (k + 0.5) / 255 per channel), triangles in `order` (scene indices;
// empty keeps the scene's order) and a black background.
Scene visibility_scene(const Scene& scene, const std::vector<int>& order);
// The visible triangle of every pixel of a frame of a visibility_scene.
IdImage decode_visibility(const RgbImage& frame);

// In-code firmware of the visibility runs (every pixel value comes from these).
extern const char* const kVisibilityZbufferFirmware;   // z-buffer on screen depth (correct)
extern const char* const kVisibilityEyeDepthFirmware;  // eye depth linear in screen (bad)
extern const char* const kVisibilityPainterFirmware;   // no depth: last drawn wins

// One algorithm's row of the comparison.
struct AlgorithmRow {
  std::string name;
  Difference difference;
  std::string bits;                    // pixel-memory bits, or what the CPU reference keeps
  double gp_clocks_per_primitive = 0;  // 0: not run on the GPs
  std::uint64_t renderer_cycles = 0;   // 0: not run on the Renderers
  double primitives_per_second = 0;    // projected for the machine; 0 for CPU references
  std::string work;                    // the algorithm's own counts
  RgbImage image;                      // the difference image
};

// How painter's runs (docs/timing.md "Depth sort"). The defaults are the slides' order
// (their drawing algorithm removes back faces, then sorts), over the whole screen, costed from
// the sort's own operation counts: gp.overhead_factor was fitted to the transform loop's
// uncounted work (traversal, PPHIGS state, the OS), which a sort over records already in
// memory does not do, so it is not applied unless asked for.
struct PainterOptions {
  bool remove_back_faces = true;  // false: every face is sorted and drawn (two-sided)
  bool overhead_factor = false;   // true: the sort's clocks x gp.overhead_factor too
  // A pair no test orders: split one polygon by the other's plane (Newell, Newell and
  // Sancha) and insert the pieces into the order (or sort again: insert_pieces), up to this
  // many rounds; then halve pieces at their siblings' vertices (no T-junctions); 0 leaves
  // such pairs in far-depth order.
  int split_rounds = 8;
  // Splitting inserts the pieces into the order (only the pairs that touch a piece, or a
  // polygon moved since, checked again: depth_sort_insert); false sorts every polygon again
  // each round (the former behaviour).
  bool insert_pieces = true;
  // The projection test's containment step: the centroid against every edge (the default),
  // or the slides' centre against the containing rectangle.
  Containment containment = Containment::edges;
};

// One way of running the sort and what it costs on the GPs: the slowest GP's prepare, the
// merge on GP 0 with the runs' and the order's ring transfers, the slowest GP's checks.
struct SortCost {
  std::string label;
  bool back_faces_removed = true;
  bool per_region = false;  // each region's bin sorted on its own (cost only: see below)
  bool overhead_factor = false;
  std::uint64_t polygons = 0;
  std::uint64_t pairs_checked = 0;
  double prepare_seconds = 0, merge_seconds = 0, transfer_seconds = 0, check_seconds = 0;
  double seconds() const {
    return prepare_seconds + merge_seconds + transfer_seconds + check_seconds;
  }
};

struct VisibleSceneReport {
  std::string scene;
  std::uint64_t triangles = 0;
  std::uint64_t polygons = 0;      // after the transform (dropped ones removed)
  std::vector<AlgorithmRow> rows;  // z-buffer, painter's, scan-line, Warnock
  PainterOptions painter_options;
  // Splitting: the rounds run, the triangles split, the pieces drawn in their place, and the
  // pairs the first sort could not order.
  int split_rounds = 0;
  std::uint64_t split_triangles = 0;
  std::uint64_t pieces = 0;
  std::uint64_t unresolved_before_split = 0;
  std::uint64_t t_junctions = 0;  // siblings halved at a piece's vertex on their edge
  DepthSortResult sort;
  std::vector<GpClocks> sort_clocks;  // per GP: prepare + its share of the checks
  GpClocks merge_clocks{};
  double sort_seconds = 0;  // the sort painter's ran with (painter_options), transfers included:
                            // the closed form (max prepare + merge + transfers + max checks)
  // The same sort as the GPs ran it in the painter's frame (each GP's phases and the ring's
  // messages simulated): when its last GP finished, from the frame's start; and that frame's
  // time, which includes it.
  double sort_simulated_seconds = 0;
  double painter_frame_seconds = 0;
  std::uint64_t zbuffer_ring_words = 0, painter_ring_words = 0;  // ring.words of the two frames
  std::uint64_t pairs_rechecked = 0;  // pairs the split pieces were checked against
  // The sort's cost under every combination of the choices (back faces removed or kept,
  // whole screen or per region bin, overhead factor or not): the range it spans.
  std::vector<SortCost> sort_costs;
  // Perspective depth: visibility with eye depth interpolated linearly (bad) against
  // screen depth (correct); pixels whose visible triangle flips between the two.
  Difference bad_depth;  // against the reference
  std::uint64_t flips = 0;
  RgbImage flip_image;
  // Back-face removal with the z-buffer.
  std::uint64_t culled = 0;
  std::uint64_t renderer_cycles_culled = 0;
  Difference culled_difference;
  RgbImage zbuffer_frame, painter_frame;  // the shaded frames
};

// Runs every algorithm on `scene`. `zbuffer` and `painter` are the shaded programs
// (gouraud.pp5 and painter.pp5) whose runs give cycles, bits and frame time.
VisibleSceneReport analyse_visible_surfaces(const MachineConfig& config, const Scene& scene,
                                            const Program& zbuffer, const Program& painter,
                                            int threads,
                                            const PainterOptions& painter_options = {});
// Painter's against the z-buffer on the timing model alone (no pixels, `config`'s
// fidelity.timing): the z-buffer's frame (`zbuffer`, back faces as `config` says), and
// painter's frame (`painter`, in the sorted order, pieces split as `options` says) plus the
// sort's time (whole screen, or `per_region` bins; own counts or x the factor).
// Whole screen, the GPs run the sort inside painter's frame (Scene::depth_sort), so the
// frame time includes it (simulated_sort_seconds: when the last GP's sort ended) and
// sort_seconds is 0; per region bin, or at a level that does not simulate the GPs' phases
// (fidelity.timing=analytic), the closed form is added (sort_seconds).
struct PainterTiming {
  double zbuffer_seconds = 0;
  double painter_frame_seconds = 0;
  double sort_seconds = 0;  // added to the frame
  double simulated_sort_seconds = 0;
  double closed_form_sort_seconds = 0;
  double painter_seconds() const { return painter_frame_seconds + sort_seconds; }
};
PainterTiming painter_against_zbuffer(const MachineConfig& config, const Scene& scene,
                                      const Program& zbuffer, const Program& painter,
                                      const PainterOptions& options, bool per_region);

// The comparison table and the per-scene notes (markdown).
// The reports as a statistics registry (frozen), written as visible.json: per scene
// (scene.N.*) its name, triangles, the depth sort's (scene.N.depth_sort.*, registered by
// register_depth_sort_statistics), each algorithm's differing and uncertain pixels, regions,
// Renderer cycles, GP clocks per primitive and primitives per second, the perspective flips
// and back-face removal.
Statistics visible_statistics(const std::vector<VisibleSceneReport>& reports);
// The comparison table (`config` gives the region size the clusters are counted in), the
// per-scene notes (a Markdown list), and the two as Markdown, the table first.
report::Table visible_table(const std::vector<VisibleSceneReport>& reports,
                            const MachineConfig& config);
std::string visible_notes(const std::vector<VisibleSceneReport>& reports);
std::string format_visible_report(const std::vector<VisibleSceneReport>& reports,
                                  const MachineConfig& config);

}  // namespace pp5
