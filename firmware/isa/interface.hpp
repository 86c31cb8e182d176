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
// (multipass algorithms such as depth peeling). Numbered in the order they were added (trace
// files store the number), not the order they run in.
enum class Procedure { clear, triangle, pass, shade, light, count };
inline constexpr const char* kProcedureNames[] = {"clear", "triangle", "pass", "shade", "light"};
inline constexpr const char* kProcedureMeaning[] = {
    "once per region, before any primitive (initialise every pixel)",
    "once per triangle binned to the region, with the triangle's expressions",
    "once per region after each pass but the last (programs with `option passes N`)",
    "once per region, after all primitives and lights (deferred shading)",
    ("once per region and scene light, after the last pass's triangles and before shade, "
     "with that light's light_*, half_*, diffuse and specular (deferred lighting)"),
};
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
  count
};

// Depth slopes are sent as constants in units of 2^kSlopeShift depth units per pixel, clamped
// to a signed 16-bit range: steeper planes (near edge-on) saturate rather than wrap.
inline constexpr int kSlopeShift = 6;
inline constexpr int kSlopeLimit = 32767;
struct ExpressionInfo {
  const char* name;
  const char* meaning;
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
    {"flat_red", "red of the triangle lit with its face normal, 0..255, constant"},
    {"flat_green", "face-lit green, 0..255, constant"},
    {"flat_blue", "face-lit blue, 0..255, constant"},
    {"base_red", "unlit material red, 0..255, interpolated (for deferred shading)"},
    {"base_green", "unlit material green, 0..255, interpolated"},
    {"base_blue", "unlit material blue, 0..255, interpolated"},
    {"slope_x",
     "the depth plane's d(depth)/dx, depth units per pixel / 64, clamped to +-32767, constant "
     "(intersection width, epsilon)"},
    {"slope_y", "d(depth)/dy (y down), same units, constant"},
    {"eye_depth",
     "eye-space depth (distance along the view axis), 0 at the near plane to 2^gp.depth_bits - "
     "1 at the far plane, interpolated linearly in screen space through the three vertices: "
     "not perspective-correct (threshold_eyez)"},
    {"opacity", "the material's opacity, 0..256 (256 = opaque), interpolated (transparent)"},
};
static_assert(sizeof(kExpressions) / sizeof(kExpressions[0]) ==
              static_cast<std::size_t>(Expression::count));

// Constants of the frame, sent with every packet's procedure and usable as an operand.
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
  count
};
struct FrameParameterInfo {
  const char* name;
  const char* meaning;
};
inline constexpr FrameParameterInfo kParameters[] = {
    {"light_x",
     "eye-space unit vector toward the light, x times 127: the scene's first light, or in the "
     "`light` procedure the light it runs for"},
    {"light_y", "light direction y times 127"},
    {"light_z", "light direction z times 127"},
    {"half_x", "eye-space half vector (light + view, normalised), x times 127"},
    {"half_y", "half vector y times 127"},
    {"half_z", "half vector z times 127"},
    {"ambient", "ambient reflection, 0..255 (255 = 1.0)"},
    {"diffuse", "diffuse reflection, 0..255 (of the light bound: see the `light` procedure)"},
    {"specular", "specular reflection, 0..255 (of the light bound)"},
    {"background_red", "background red, 0..255"},
    {"background_green", "background green, 0..255"},
    {"background_blue", "background blue, 0..255"},
    {"highlight_red", "intersection highlight red, 0..255 (default 255)"},
    {"highlight_green", "highlight green, 0..255 (default 230)"},
    {"highlight_blue", "highlight blue, 0..255 (default 0)"},
    {"highlight_opacity", "highlight opacity, 0..256 (256 = opaque, the default)"},
    {"highlight_keep", "derived: 256 - highlight_opacity, the weight of the surface colour"},
    {"threshold",
     "threshold program: flag where |depth - stored depth| < threshold, depth units (default "
     "32768)"},
    {"delta", "half-width of fixed-width curves (epsilon programs), 1/16 pixel (default 24)"},
    {"epsilon_scale",
     "derived: (delta/16)^2 * 4^6, so that dz^2 < epsilon_scale * |slope difference|^2 with slopes "
     "in units of 64 depth units per pixel"},
    {"silhouette",
     "silhouette remedy: ignore the flag where the frontmost |normal z| * 127 < silhouette "
     "(default 0: off)"},
    {"surface_opacity",
     "opacity of every surface in the transparency programs, 0..256 (default 128)"},
    {"surface_keep", "derived: 256 - surface_opacity"},
    {"normal_epsilon_scale",
     "derived: (delta/16)^2 * S^2 / 256, S = depth units per pixel per unit of eye-space slope at "
     "the camera's target distance (epsilon_normal: slopes recovered from normals)"},
};

// Frame parameters computed from others: an override of their sources recomputes them.
inline constexpr Parameter kDerivedParameters[] = {
    Parameter::highlight_keep, Parameter::epsilon_scale, Parameter::surface_keep,
    Parameter::normal_epsilon_scale};

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
