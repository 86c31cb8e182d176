#pragma once
// The contract between the Graphics Processors and Renderer firmware: which procedures a
// program may define, which per-primitive expressions the GP can compute for it, and which
// per-frame constants it sends. The assembler accepts only these names; the GP computes
// only the expressions that a program's procedures use.
#include <cstddef>
#include <iterator>
#include <string_view>

namespace pp5 {

// Procedures the Renderer runs for every region it renders: clear; the triangles; then
// `light` once per scene light; then shade. With `option passes N` the GPs send every
// region's triangles N times, and the Renderer runs `pass` between one pass and the next
// (multipass algorithms such as depth peeling); with `option passes PARAMETER` N is that
// frame parameter's value (`layers`), set at run time. Numbered in the order they were added (trace
// files store the number), not the order they run in.
enum class Procedure {
  clear,
  triangle,
  pass,
  shade,
  light,
  sphere,
  parity,
  surface,
  candidate,
  keep_inside,
  keep_outside,
  merge,
  next_layer,
  sphere_surface,
  sphere_parity,
  count
};
inline constexpr const char* kProcedureNames[] = {
    "clear",        "triangle", "pass",       "shade",          "light",
    "sphere",       "parity",   "surface",    "candidate",      "keep_inside",
    "keep_outside", "merge",    "next_layer", "sphere_surface", "sphere_parity"};
inline constexpr const char* kProcedureMeaning[] = {
    "once per region, before any primitive (initialise every pixel)",
    "once per triangle binned to the region, with the triangle's expressions",
    "once per region after each pass but the last (programs with `option passes N`)",
    "once per region, after all primitives and lights (deferred shading)",
    ("once per region and scene light, after the last pass's triangles and before shade, "
     "with that light's light_*, half_*, diffuse and specular (deferred lighting)"),
    "once per sphere binned to the region, with the sphere's expressions (sphere_*)",
    ("once per triangle of the solid a classification pass draws (the pass plan: point in "
     "solid, CSG), with the triangle's expressions; it may use only those `triangle` uses"),
    ("once per triangle of the CSG literal a surface pass draws (its front faces, or its back "
     "faces for a complemented solid), with the triangle's expressions; it may use only those "
     "`triangle` uses (CSG pass plan)"),
    "once per region before each CSG surface pass (reset the candidate surface)",
    ("once per region after the parity pass of a positive CSG literal: keep the candidate "
     "where the parity is odd (inside), clear the parity"),
    ("once per region after the parity pass of a complemented CSG literal: keep the candidate "
     "where the parity is even (outside), clear the parity"),
    ("once per region after a CSG literal's classification: a kept candidate nearer than the "
     "result replaces it"),
    ("once per region before each CSG surface pass after a literal's first (programs that "
     "peel: `layers` rounds per literal of a product of two or more): the candidate's depth "
     "becomes the layer the next one must lie behind, and the candidate is reset"),
    ("`surface` for a sphere of the CSG literal (its near hemisphere, or its far one for a "
     "complemented solid), with the sphere's expressions; it may use only those `sphere` uses"),
    ("`parity` for a sphere of the classifying solid (each of its two hemispheres), with the "
     "sphere's expressions; it may use only those `sphere` uses"),
};

// The procedure a packet runs in a planned pass whose packets run `planned` (parity or
// surface): a triangle's packet runs `planned` itself, a sphere's its sphere counterpart.
constexpr Procedure planned_procedure(Procedure planned, Procedure own) {
  if (own != Procedure::sphere) return planned;
  if (planned == Procedure::surface) return Procedure::sphere_surface;
  if (planned == Procedure::parity) return Procedure::sphere_parity;
  return planned;
}
static_assert(std::size(kProcedureNames) == static_cast<std::size_t>(Procedure::count));
static_assert(std::size(kProcedureMeaning) == static_cast<std::size_t>(Procedure::count));

// Expressions the GP can supply with a triangle packet. All are fixed point with
// evaluator.fraction_bits fraction bits and are evaluated at pixel centres.
enum class Expression {
  edge0,
  edge1,
  edge2,
  depth,
  red,
  green,
  blue,
  nx,
  ny,
  nz,
  flat_red,
  flat_green,
  flat_blue,
  base_red,
  base_green,
  base_blue,
  slope_x,
  slope_y,
  eye_depth,
  opacity,
  plane_depth,
  wide0,
  wide1,
  wide2,
  side0,
  side1,
  side2,
  sphere_inside,
  sphere_depth,
  sphere_nx,
  sphere_ny,
  sphere_nz,
  sphere_red,
  sphere_green,
  sphere_blue,
  sphere_depth_paraboloid,
  sphere_depth_base,
  sphere_radicand,
  sphere_root_shift,
  depth_minus_threshold,
  depth_plus_threshold,
  count
};

// Depth slopes are sent as constants in units of 2^kSlopeShift depth units per pixel, clamped
// to a signed 16-bit range: steeper planes (near edge-on) saturate rather than wrap.
inline constexpr int kSlopeShift = 6;
inline constexpr int kSlopeLimit = 32767;
// A sphere's exact depth is drawn in pixel memory as sphere_depth_base - 2^sphere_root_shift *
// floor(sqrt(sphere_radicand)); the GP picks the shift that keeps the square root below
// 2^kSphereRootBits, so the radicand fits 2 * kSphereRootBits bits (firmware sphere_sqrt.pp5).
inline constexpr int kSphereRootBits = 13;
struct ExpressionInfo {
  const char* name;
  const char* meaning;
  // One value per primitive (the GP sends it as one coefficient): besides `qload`, firmware
  // may name it where an instruction takes a constant (a 'V' operand), and the Renderer
  // broadcasts its integer part as it broadcasts a literal, without the evaluator.
  bool constant = false;
};
inline constexpr ExpressionInfo kExpressions[] = {
    {"edge0", "first edge function: >= 0 inside the triangle (top-left rule folded in)"},
    {"edge1", "second edge function"},
    {"edge2", "third edge function"},
    {"depth", "depth, 0 at the near plane to 2^gp.depth_bits - 1 at the far plane"},
    {"red", "vertex-lit red, 0..255, interpolated (Gouraud)"},
    {"green", "vertex-lit green, 0..255, interpolated"},
    {"blue", "vertex-lit blue, 0..255, interpolated"},
    {"nx", "eye-space normal x times 127, interpolated (Phong)"},
    {"ny", "eye-space normal y times 127, interpolated"},
    {"nz", "eye-space normal z times 127, interpolated"},
    {"flat_red", "red of the triangle lit with its face normal, 0..255, constant", true},
    {"flat_green", "face-lit green, 0..255, constant", true},
    {"flat_blue", "face-lit blue, 0..255, constant", true},
    {"base_red", "unlit material red, 0..255, interpolated (for deferred shading)"},
    {"base_green", "unlit material green, 0..255, interpolated"},
    {"base_blue", "unlit material blue, 0..255, interpolated"},
    {"slope_x",
     "the depth plane's d(depth)/dx, depth units per pixel / 64, clamped to +-32767, constant "
     "(intersection width, epsilon)",
     true},
    {"slope_y", "d(depth)/dy (y down), same units, constant", true},
    {"eye_depth",
     "eye-space depth (distance along the view axis), 0 at the near plane to 2^gp.depth_bits - "
     "1 at the far plane, interpolated linearly in screen space through the three vertices: "
     "not perspective-correct (threshold_eyez)"},
    {"opacity", "the material's opacity, 0..256 (256 = opaque), interpolated (transparent)"},
    {"plane_depth",
     "depth like `depth`, but the plane through the unsnapped vertices (the face's own plane, "
     "not the sub-pixel-snapped one): accurate scan conversion"},
    {"wide0",
     "first edge function moved outward by the vertex round-off: >= 0 on every pixel centre "
     "the unsnapped triangle may own (the enlarged area of accurate scan conversion)"},
    {"wide1", "second edge, moved outward by the vertex round-off"},
    {"wide2", "third edge, moved outward by the vertex round-off"},
    {"side0",
     "K0 (Z - Z0): >= 0 where this face's plane lies on the face's side of the plane of the "
     "neighbour across edge 0 (Rossignac); the unsnapped edge's own line where there is no "
     "usable neighbour (boundary, non-manifold, coplanar), the snapped edge on a clipped piece"},
    {"side1", "K1 (Z - Z1), the neighbour across edge 1"},
    {"side2", "K2 (Z - Z2), the neighbour across edge 2"},
    {"sphere_inside",
     "a sphere's outline: the exact screen conic of the cone from the eye tangent to it, >= 0 "
     "inside (quadratic; models/gp/sphere.hpp)"},
    {"sphere_depth",
     "a sphere's depth, as `depth`, quadratic: exact but for the square root of the conic, "
     "replaced by its minimax line (error bound in models/gp/sphere.hpp)"},
    {"sphere_nx", "a sphere's eye-space normal x times 127, least-squares quadratic"},
    {"sphere_ny", "a sphere's normal y times 127, least-squares quadratic"},
    {"sphere_nz", "a sphere's normal z times 127, least-squares quadratic"},
    {"sphere_red", "a sphere's unlit material red, 0..255, constant", true},
    {"sphere_green", "a sphere's material green, 0..255, constant", true},
    {"sphere_blue", "a sphere's material blue, 0..255, constant", true},
    {"sphere_depth_paraboloid",
     "a sphere's depth as Pixel-Planes 4 drew it, quadratic: the square root of the conic "
     "replaced by the line through its ends (a paraboloid exact at the outline and at the "
     "nearest point; error up to twice sphere_depth's, all on the far side)"},
    {"sphere_depth_base",
     "the linear part of a sphere's exact depth, depth units (linear): the depth is "
     "sphere_depth_base - 2^sphere_root_shift * floor(sqrt(sphere_radicand)) (its far "
     "hemisphere's, + instead of -); half a step of the root is folded in, so the truncated "
     "root errs by at most 2^(sphere_root_shift - 1) + 1/2 units either way"},
    {"sphere_radicand",
     "the conic scaled to depth units squared and divided by 4^sphere_root_shift, below "
     "2^26 inside the outline (quadratic): its square root, 13 bits, times "
     "2^sphere_root_shift is the depth below sphere_depth_base"},
    {"sphere_root_shift",
     "the least shift (0..15; 11 or less within the depth range) that keeps sqrt(sphere_radicand) "
     "below 2^13 - 1 over the "
     "sphere, constant",
     true},
    {"depth_minus_threshold",
     "depth - threshold (the frame parameter, folded into the plane's constant term by the GP): "
     "-threshold .. 2^gp.depth_bits - 1, negative near the near plane"},
    {"depth_plus_threshold", "depth + threshold, likewise: up to 2^gp.depth_bits - 1 + threshold"},
};
static_assert(sizeof(kExpressions) / sizeof(kExpressions[0]) ==
              static_cast<std::size_t>(Expression::count));

// Constants of the frame, sent with every packet's procedure and usable as an operand.
// Their names are declared here, for the assembler; unit, default, range, meaning and which
// are computed by the GP are declared once in the configuration table's `frame.` section
// (models/config/machine_config.cpp), which `pp5sim isa` and `pp5sim config --describe` show.
enum class Parameter {
  light_x,
  light_y,
  light_z,
  half_x,
  half_y,
  half_z,
  ambient,
  diffuse,
  specular,
  background_red,
  background_green,
  background_blue,
  highlight_red,
  highlight_green,
  highlight_blue,
  highlight_opacity,
  highlight_keep,
  threshold,
  delta,
  epsilon_scale,
  silhouette,
  surface_opacity,
  surface_keep,
  normal_epsilon_scale,
  layers,
  count
};
struct FrameParameterInfo {
  const char* name;
};
inline constexpr FrameParameterInfo kParameters[] = {
    {"light_x"},
    {"light_y"},
    {"light_z"},
    {"half_x"},
    {"half_y"},
    {"half_z"},
    {"ambient"},
    {"diffuse"},
    {"specular"},
    {"background_red"},
    {"background_green"},
    {"background_blue"},
    {"highlight_red"},
    {"highlight_green"},
    {"highlight_blue"},
    {"highlight_opacity"},
    {"highlight_keep"},
    {"threshold"},
    {"delta"},
    {"epsilon_scale"},
    {"silhouette"},
    {"surface_opacity"},
    {"surface_keep"},
    {"normal_epsilon_scale"},
    {"layers"},
};
static_assert(std::size(kParameters) == static_cast<std::size_t>(Parameter::count));
inline constexpr const char* parameter_name(Parameter k) {
  return kParameters[static_cast<int>(k)].name;
}

inline int expression_index(std::string_view name) {
  for (int i = 0; i < static_cast<int>(Expression::count); ++i) {
    if (name == kExpressions[i].name) return i;
  }
  return -1;
}
inline int parameter_index(std::string_view name) {
  for (int i = 0; i < static_cast<int>(Parameter::count); ++i) {
    if (name == kParameters[i].name) return i;
  }
  return -1;
}
inline int procedure_index(std::string_view name) {
  for (int i = 0; i < static_cast<int>(Procedure::count); ++i) {
    if (name == kProcedureNames[i]) return i;
  }
  return -1;
}

}  // namespace pp5
