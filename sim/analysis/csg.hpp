#pragma once
// Parity and depth-interval applications (issue 15), measured against a CPU ray caster in
// double precision.
//
// Where each comes from in Rossignac's "Accurate scan conversion of triangulated surfaces"
// (seeds/rossignac-accurate-scanconversion.md): the point-in-primitive test by parity, the
// products of the disjunctive form and the epsilon tolerance (the point tested slightly
// behind the scan-converted one, figure 9.4, and the epsilon-regularisation it amounts to,
// figure 9.5) are section 9.2.3, Shading from CSG; cross-sections and interference are
// 9.2.4; the depth-interval buffer for transparency is 9.2.2.
//
// Point in solid by parity: the machine runs a program that defines `parity` (parity.pp5,
// parity_accurate.pp5) under the point-in-solid pass plan (models/gp/pass_plan.hpp); its
// `inside` field is read back (sim/analysis/field_render.hpp) and compared pixel by pixel
// with the ray caster.
//
// Contract:
//  - The ray caster casts, per pixel centre (X + 0.5, Y + 0.5), the ray from the eye through
//    it (the camera's own view and projection, in double) against every scene triangle
//    (Moller-Trumbore, double). The point is the nearest hit on a triangle in no solid; it is
//    inside solid s when an odd number of s's triangles are hit behind it. Background: no
//    point.
//  - A pixel is uncertain (not compared) when the classification, or whether there is a
//    point, changes at any of four centres offset by `margin` pixels (an edge of a face, of
//    the point surface or of the solid's outline passes nearby, or the point lies on the
//    solid's surface there), or a hit lies within 1e-9 of a triangle's edge in barycentric
//    terms. Elsewhere the machine must agree: the tests require it.
//  - Deterministic; no pixel value of the machine comes from here.
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/analysis/frame_cost.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

// Scenes made for the parity applications: a point surface in no solid and closed solids.
// make_parity_scene also takes "plane-slab" (a solid thinner than epsilon in depth, for
// epsilon-regularisation), which the default table leaves out.
std::vector<std::string> parity_scene_names();
Scene make_parity_scene(const std::string& name);

struct ParityReference {
  int width = 0, height = 0;
  std::vector<std::int8_t> inside;      // per pixel: -1 no point, 0 outside, 1 inside
  std::vector<std::uint8_t> uncertain;  // per pixel: 1 if not compared
};
ParityReference parity_reference(const MachineConfig& config, const Scene& scene,
                                 double margin = 0.75);

struct ParityMeasure {
  std::string scene, program;
  std::int64_t compared = 0;   // certain pixels
  std::int64_t points = 0;     // certain pixels with a point
  std::int64_t inside = 0;     // certain pixels the ray caster finds inside
  std::int64_t disagree = 0;   // certain pixels where the machine's `inside` differs
  std::int64_t uncertain = 0;  // pixels near an edge, not compared
  // Of those, where the machine differs from the ray through the centre itself (reported,
  // not required: a centre on a shared edge is where standard scan conversion miscounts).
  std::int64_t edge_disagree = 0;
  std::int64_t machine_inside = 0;  // certain pixels where the machine's `inside` is set
  std::int64_t lost = 0;            // of `disagree`, inside by the ray caster, not by the machine
  std::int64_t gained = 0;          // of `disagree`, inside by the machine only
  int passes = 0;
  int bits = 0;
  FrameCost cost;
  RgbImage image;       // the machine's image
  RgbImage difference;  // white: disagree; grey: uncertain; black: agree
};

// Renders `scene` with `program` (which must define `parity` and a field `inside`), reads
// back `inside` and compares it with the ray caster; runs the frame's timing for the passes,
// cycles and frame time.
ParityMeasure measure_parity(const MachineConfig& config, const Scene& scene,
                             const Program& program, int threads);

report::Table parity_table(const std::vector<ParityMeasure>& rows);

// Epsilon regularisation, the two methods on the same scenes (the parity scenes, the slab
// thinner than epsilon and "plane-in-box", points inside a thick solid within epsilon of its
// face): parity_epsilon (an erosion: inside at both z - epsilon and z + epsilon) and
// parity_behind (Rossignac's test at z + epsilon, figure 9.4), beside exact parity. The table
// splits the disagreements into points lost and points gained.
std::vector<std::string> epsilon_scene_names();
report::Table epsilon_table(const std::vector<ParityMeasure>& rows);

// Interference of an assembly's first two solids (interference.pp5 under the same pass plan):
// the machine's flag, lo and hi fields read back; the truth is the ray caster's: a pixel
// interferes where the intersection of the two solids has a surface on its ray. Pixels
// where the truth changes within `margin` are not compared. `truth`, `flagged` and
// `disagree` count the compared pixels only (the same set); `flagged_uncertain` counts the
// machine's flags among the pixels not compared.
std::vector<std::string> interference_scene_names();  // also made by make_parity_scene
struct InterferenceMeasure {
  std::string scene, program;
  std::int64_t compared = 0, truth = 0, flagged = 0, disagree = 0, uncertain = 0;
  std::int64_t flagged_uncertain = 0;
  double lo = 0, hi = 0;  // the depth range of every flagged pixel's overlap, 0 near .. 1 far
  int passes = 0, bits = 0;
  FrameCost cost;
  RgbImage image, difference;
};
InterferenceMeasure measure_interference(const MachineConfig& config, const Scene& scene,
                                         const Program& program, int threads, double margin = 0.75);
report::Table interference_table(const std::vector<InterferenceMeasure>& rows);

// The CPU ray caster of a CSG expression (Scene::csg over Scene::solids), double precision:
// along the ray origin + t direction (t > 0), every hit of every solid's triangles in order;
// each solid's membership starts from the parity of all its hits (the origin's side) and
// toggles at each; the visible surface is the first hit where the expression's membership
// turns from outside to inside. t = -1 and solid = -1 when the ray meets none.
struct CsgSurface {
  double t = -1;
  int solid = -1;
  int triangle = -1;
};
CsgSurface csg_first_surface(const Scene& scene, glm::dvec3 origin, glm::dvec3 direction);

// Per pixel centre, the solid whose surface is visible in the CSG result (-1: background),
// with the camera's own rays.
std::vector<int> csg_reference(const MachineConfig& config, const Scene& scene);

// CSG rendering (csg.pp5 under the CSG pass plan, models/gp/pass_plan.hpp): the machine's
// result depth `z` (0xFFFFFF: background) read back and compared per pixel with the ray
// caster's first surface of the same expression on the same meshes, its depth taken to the
// GP's depth units (screen z, 0 near .. 2^gp.depth_bits - 1 far).
//
// Contract:
//  - A pixel is uncertain (not compared) when, at any of four centres offset by `margin`
//    pixels, the visible solid changes or its face is one with no vertex in common with the
//    centre's (an outline nearby: of the result, of the seam of two solids, or of one part of
//    a solid over another).
//  - Elsewhere it disagrees when one side shows a surface and the other not, or the machine's
//    depth differs from the ray caster's by more than the tolerance: 2 units (the floor of
//    the interpolated depth and the rounding of its coefficients) plus what the surface's
//    depth changes over half a sub-pixel step in x and in y (the GP snaps vertices to
//    1/2^gp.subpixel_bits of a pixel, moving the plane by up to that), the slope taken from
//    the ray caster's depths at the offset centres, the steeper side in each direction (at a
//    crease the pixel may belong to either face).
//  - Exact only for convex solids: a non-convex literal's nearest surface may be discarded
//    where a farther one is visible (the scene "pair-minus-bar" shows it).
std::vector<std::string> csg_scene_names();  // also made by make_parity_scene
// CSG scenes whose solids include quadric spheres (Solid::first_sphere..last_sphere), drawn by
// programs that define sphere_surface and sphere_parity.
std::vector<std::string> csg_quadric_scene_names();
struct CsgMeasure {
  std::string scene, program, expression;
  std::int64_t compared = 0;      // certain pixels
  std::int64_t surface = 0;       // certain pixels where the ray caster finds a surface
  std::int64_t disagree = 0;      // certain pixels where coverage or depth differs
  std::int64_t coverage = 0;      // of those, where one shows a surface and the other not
  std::int64_t uncertain = 0;     // pixels near an outline, not compared
  double median_depth_error = 0;  // depth units, over agreeing covered pixels
  double max_depth_error = 0;
  int passes = 0, bits = 0;
  FrameCost cost;
  RgbImage image, difference;  // difference: white disagree, grey uncertain
};
CsgMeasure measure_csg(const MachineConfig& config, const Scene& scene, const Program& program,
                       int threads, double margin = 0.75);
report::Table csg_render_table(const std::vector<CsgMeasure>& rows);

// Goldfeather's pruning (models/gp/pass_plan.hpp) measured: the plan's passes with and
// without it, and the machine's result depth `z` rendered both ways, compared pixel by
// pixel (they must not differ). The CSG scenes and "box-minus-apart", where a bar apart from
// the box is subtracted from it and intersected with the ball (both pruned away).
std::vector<std::string> csg_pruning_scene_names();  // made by make_parity_scene
struct CsgPruning {
  std::string scene, program, expression, pruned_expression;
  int passes_whole = 0, passes_pruned = 0;
  std::int64_t surface = 0;    // pixels where the unpruned plan leaves a surface
  std::int64_t differing = 0;  // pixels whose `z` differs between the two
  FrameCost cost_whole, cost_pruned;
};
CsgPruning measure_csg_pruning(const MachineConfig& config, const Scene& scene,
                               const Program& program, int threads);
report::Table csg_pruning_table(const std::vector<CsgPruning>& rows);

// Cross-sections with capping (section.pp5 under the point-in-solid pass plan): a scene of
// one quad in no solid (the cutting plane) and one closed solid. The truth is the ray
// caster's first surface of the solid intersected with the half-space behind the plane (the
// quad swept away from the eye: section_truth), compared as measure_csg compares (coverage
// and depth of the machine's `z`), and the cap: the machine's `inside` against where the
// truth shows the plane's face.
std::vector<std::string> section_scene_names();  // made by make_parity_scene
Scene section_truth(const Scene& drawn);
struct SectionMeasure {
  CsgMeasure surface;
  std::int64_t cap = 0;           // compared pixels where the ray caster shows the cap
  std::int64_t cap_disagree = 0;  // compared pixels where the machine's `inside` differs
};
SectionMeasure measure_section(const MachineConfig& config, const Scene& scene,
                               const Program& program, int threads, double margin = 0.75);
report::Table section_table(const std::vector<SectionMeasure>& rows);

}  // namespace pp5
