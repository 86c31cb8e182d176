#include "models/gp/expressions.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/gp/accurate_expressions.hpp"
#include "models/gp/sphere.hpp"

namespace pp5 {

namespace {

using E = Expression;
using F = ExpressionForm;

bool fits(std::int64_t v, int bits) {
  const std::int64_t limit = std::int64_t{1} << (bits - 1);
  return v >= -limit && v < limit;
}

// Edge e of the snapped triangle (SetupContext::edge), with the top-left rule.
template <int e>
bool edge(const SetupContext& c, QuadraticCoefficients& out) {
  return c.edge(e, 0, true, out);
}

bool depth(const SetupContext& c, QuadraticCoefficients& out) {
  return c.plane({c.depth(0), c.depth(1), c.depth(2)}, out);
}

// Depth's plane with the frame's threshold folded into its constant term, -1 (depth minus
// the threshold) or +1 (plus it): a firmware compares depth with z +- threshold in one qcmp
// instead of forming z +- threshold per pixel. The value leaves the depth range near the near
// (far) plane: a program compares it with a field one bit wider and signed.
template <int sign>
bool depth_threshold(const SetupContext& c, QuadraticCoefficients& out) {
  if (!depth(c, out)) return false;
  const std::int64_t threshold = (*c.frame)[static_cast<int>(Parameter::threshold)];
  out.F += sign * threshold * static_cast<std::int64_t>(c.f_scale);
  return fits(out.F, c.params.coefficient_bits);
}

bool eye_depth(const SetupContext& c, QuadraticCoefficients& out) {
  // Eye-space depth mapped linearly from [near, far] to the depth range, then a plane
  // through the three vertices in screen space: exact at the vertices, but eye depth is not
  // affine in screen space under perspective, so inside the triangle it is not the
  // surface's true eye depth (no perspective correction).
  const double near = static_cast<double>(c.camera.near_plane);
  const double span = static_cast<double>(c.camera.far_plane) - near;
  auto eye = [&](int k) {
    const double v = (c.triangle.v[k].eye_depth - near) / span;
    return std::clamp(v * c.depth_max, 0.5, c.depth_max - 1.5);
  };
  return c.plane({eye(0), eye(1), eye(2)}, out);
}

// Colours 0..255, clamped half a unit inside so that floor() stays in range.
double colour(double v) { return std::clamp(v * 255.0, 0.5, 255.49); }

template <int channel>
bool lit_colour(const SetupContext& c, QuadraticCoefficients& out) {
  const auto& v = c.triangle.v;
  return c.plane({colour(v[0].lit_color[channel]), colour(v[1].lit_color[channel]),
                  colour(v[2].lit_color[channel])},
                 out);
}

template <int channel>
bool base_colour(const SetupContext& c, QuadraticCoefficients& out) {
  const auto& v = c.triangle.v;
  return c.plane({colour(v[0].base_color[channel]), colour(v[1].base_color[channel]),
                  colour(v[2].base_color[channel])},
                 out);
}

template <int axis>
bool normal(const SetupContext& c, QuadraticCoefficients& out) {
  const auto& v = c.triangle.v;
  return c.plane({127.0 * v[0].normal[axis], 127.0 * v[1].normal[axis], 127.0 * v[2].normal[axis]},
                 out);
}

template <int channel>
bool flat_colour(const SetupContext& c, QuadraticCoefficients& out) {
  out = c.constant(std::clamp(c.triangle.flat_color[channel], 0.0, 1.0) * 255.0);
  return true;
}

// The depth plane's gradient along x (axis 0) or y (axis 1), in depth units per pixel,
// quantised for the firmware: units of 2^kSlopeShift, clamped to +-kSlopeLimit.
template <int axis>
bool slope(const SetupContext& c, QuadraticCoefficients& out) {
  const auto g = c.gradient({c.depth(0), c.depth(1), c.depth(2)});
  const double v = axis == 0 ? g.first : g.second;
  out = c.constant(std::clamp(std::nearbyint(std::ldexp(v, -kSlopeShift)),
                              -static_cast<double>(kSlopeLimit), static_cast<double>(kSlopeLimit)));
  return true;
}

bool opacity(const SetupContext& c, QuadraticCoefficients& out) {
  // Opacity 0..256 (256 = opaque), clamped like a colour so that floor() stays in range.
  auto o = [&](int k) { return std::clamp(c.triangle.v[k].opacity * 256.0, 0.5, 256.49); };
  return c.plane({o(0), o(1), o(2)}, out);
}

// A sphere's quadratics (models/gp/sphere.hpp): the conic at its scale 2^conic_shift, depth
// and normals at 2^fraction_bits, all rounded about the anchor pixel. A triangle has no
// sphere: asked for one of these (a caller setting a triangle up with every procedure's
// expressions), it gets zero; the Machine lets no triangle procedure use them.
bool sphere_inside(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.conic, std::ldexp(1.0, s.conic_shift), s.x0, s.y0, c.params, out);
}

bool sphere_depth(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.depth, c.f_scale, s.x0, s.y0, c.params, out);
}

template <int axis>
bool sphere_normal(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.normal[axis], c.f_scale, s.x0, s.y0, c.params, out);
}

bool sphere_depth_paraboloid(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.paraboloid, c.f_scale, s.x0, s.y0, c.params, out);
}

// The exact depth's parts (sphere_sqrt.pp5): the linear part and the radicand at 2^fraction_bits
// about the anchor, the root's shift a constant.
bool sphere_depth_base(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.depth_base, c.f_scale, s.x0, s.y0, c.params, out);
}

bool sphere_radicand(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  const ScreenSphere& s = *c.sphere;
  return sphere_fixed_point(s.radicand, c.f_scale, s.x0, s.y0, c.params, out);
}

bool sphere_root_shift(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  out = c.constant(c.sphere->root_shift);
  return true;
}

template <int channel>
bool sphere_colour(const SetupContext& c, QuadraticCoefficients& out) {
  if (c.sphere == nullptr) return (out = {}, true);
  out = c.constant(std::clamp(c.sphere->color[channel], 0.0, 1.0) * 255.0);
  return true;
}

// i860 operations of one expression's set-up (docs/timing.md):
// An edge: A = dy, B = -dx on integer positions; C = x0 y1 - x1 y0 (2 integer multiplies in
// the FP unit, 1 subtract); the top-left rule adjusts C (compare, branch, add).
constexpr OpCounts kEdgeCost{1 + 1, 2, 0, 0, 2 + 2, 1, 1};
// A linear attribute: d1 = a1 - a0, d2 = a2 - a0; A = (d1 ey2 - d2 ey1) / area and B
// likewise (3 multiplies, 1 subtract each); C = a0 - A x0 - B y0; scale to fixed point (3
// multiplies) and convert (3); clamp at the vertices (3 compares, 1 branch).
constexpr OpCounts kPlaneCost{2 + 1 + 1 + 2 + 3 + 3, 3 + 3 + 2 + 3, 3, 0, 2, 1, 1};
// Depth's plane offset by a frame parameter: the plane as `depth` (a program naming one of
// these also loads depth, whose plane the GP then has), and one integer add to its constant.
constexpr OpCounts kDepthOffsetCost{0, 0, 0, 0, 1, 0, 0};
// A constant: C = the face-lit value, converted to fixed point.
constexpr OpCounts kConstantCost{1, 1, 0, 0, 0, 0, 0};
// A depth slope is a constant, but it is the depth plane's gradient: the same work as a
// plane's A or B, quantised and clamped, so it costs what an attribute plane costs.
constexpr OpCounts kSlopeCost = kPlaneCost;
// A sphere's quadratic about its anchor (the conic, depth or a normal): its six coefficients
// scaled (6 multiplies) and converted (6), then expanded to the screen's origin in integers
// (the i860 multiplies integers in its FP unit: 10 multiplies; 10 integer adds), each
// wrapped to the coefficient width (6 integer masks).
constexpr OpCounts kSphereQuadraticCost{6, 6 + 10, 0, 0, 10 + 6, 0, 2};
// Depth also forms its six coefficients from the conic's: H / k (a reciprocal), 1 / sqrt(Qm)
// (a reciprocal square root), 8 multiplies and 4 adds.
constexpr OpCounts kSphereDepthCost{6 + 4 + 4, 16 + 8 + 10, 0, 0, 16, 0, 4};
// A normal component's least-squares fit: its 6 coefficients from the 13 fit points (78
// multiply-adds), rewritten from the disc's coordinates to pixels (10 multiplies, 4 adds)
// and about the anchor (6, 6), then as any quadratic.
// The exact depth's linear part: H / k (a reciprocal, 1 multiply), its three coefficients
// (3 multiplies), the half step 2^(n - 1) folded into the constant (1 add, 1 integer); scaled
// (3 multiplies) and converted (3), expanded to the screen's origin (2 multiplies, 2 integer
// adds) and wrapped (3 integer masks).
constexpr OpCounts kSphereDepthBaseCost{2 + 1 + 3, 5 + 1 + 3 + 3 + 2, 0, 0, 1 + 2 + 3, 0, 4};
// The radicand: (H / k)^2 (1 multiply), the shift n from the exponent of the relief (H / k)
// sqrt(Qm) (a reciprocal square root, 1 multiply; integer: 4, a compare and branch) and 4^-n
// folded into the scale (1 multiply), then the six coefficients as any sphere quadratic.
constexpr OpCounts kSphereRadicandCost{3 + 6, 8 + 16, 0, 0, 4 + 16, 1, 2 + 2};
constexpr OpCounts kSphereNormalCost{78 + 4 + 6 + 6, 78 + 10 + 6 + 16, 0, 0, 16, 0, 4};

constexpr std::array<ExpressionEntry, static_cast<int>(Expression::count)> kRegistry = {{
    {E::edge0, F::linear, kEdgeCost, false, edge<0>},
    {E::edge1, F::linear, kEdgeCost, false, edge<1>},
    {E::edge2, F::linear, kEdgeCost, false, edge<2>},
    {E::depth, F::linear, kPlaneCost, false, depth},
    {E::red, F::linear, kPlaneCost, false, lit_colour<0>},
    {E::green, F::linear, kPlaneCost, false, lit_colour<1>},
    {E::blue, F::linear, kPlaneCost, false, lit_colour<2>},
    {E::nx, F::linear, kPlaneCost, false, normal<0>},
    {E::ny, F::linear, kPlaneCost, false, normal<1>},
    {E::nz, F::linear, kPlaneCost, false, normal<2>},
    {E::flat_red, F::constant, kConstantCost, false, flat_colour<0>},
    {E::flat_green, F::constant, kConstantCost, false, flat_colour<1>},
    {E::flat_blue, F::constant, kConstantCost, false, flat_colour<2>},
    {E::base_red, F::linear, kPlaneCost, false, base_colour<0>},
    {E::base_green, F::linear, kPlaneCost, false, base_colour<1>},
    {E::base_blue, F::linear, kPlaneCost, false, base_colour<2>},
    {E::slope_x, F::constant, kSlopeCost, false, slope<0>},
    {E::slope_y, F::constant, kSlopeCost, false, slope<1>},
    {E::eye_depth, F::linear, kPlaneCost, false, eye_depth},
    {E::opacity, F::linear, kPlaneCost, false, opacity},
    {E::plane_depth, F::linear, kPlaneDepthCost, false, plane_depth_expression},
    {E::wide0, F::linear, kWideEdgeCost, false, wide_edge<0>, true},
    {E::wide1, F::linear, kWideEdgeCost, false, wide_edge<1>, true},
    {E::wide2, F::linear, kWideEdgeCost, false, wide_edge<2>, true},
    {E::side0, F::linear, kSideCost, true, side<0>},
    {E::side1, F::linear, kSideCost, true, side<1>},
    {E::side2, F::linear, kSideCost, true, side<2>},
    {E::sphere_inside, F::quadratic, kSphereQuadraticCost, false, sphere_inside},
    {E::sphere_depth, F::quadratic, kSphereDepthCost, false, sphere_depth},
    {E::sphere_nx, F::quadratic, kSphereNormalCost, false, sphere_normal<0>},
    {E::sphere_ny, F::quadratic, kSphereNormalCost, false, sphere_normal<1>},
    {E::sphere_nz, F::quadratic, kSphereNormalCost, false, sphere_normal<2>},
    {E::sphere_red, F::constant, kConstantCost, false, sphere_colour<0>},
    {E::sphere_green, F::constant, kConstantCost, false, sphere_colour<1>},
    {E::sphere_blue, F::constant, kConstantCost, false, sphere_colour<2>},
    {E::sphere_depth_paraboloid, F::quadratic, kSphereDepthCost, false, sphere_depth_paraboloid},
    {E::sphere_depth_base, F::linear, kSphereDepthBaseCost, false, sphere_depth_base},
    {E::sphere_radicand, F::quadratic, kSphereRadicandCost, false, sphere_radicand},
    {E::sphere_root_shift, F::constant, kConstantCost, false, sphere_root_shift},
    {E::depth_minus_threshold, F::linear, kDepthOffsetCost, false, depth_threshold<-1>, false,
     true},
    {E::depth_plus_threshold, F::linear, kDepthOffsetCost, false, depth_threshold<+1>, false, true},
}};

constexpr bool in_enum_order() {
  for (std::size_t k = 0; k < kRegistry.size(); ++k) {
    if (static_cast<std::size_t>(kRegistry[k].id) != k) return false;
  }
  return true;
}

}  // namespace

namespace {

// |v| of a 128-bit integer, and the bit width of a magnitude.
unsigned __int128 magnitude128(__int128 v) {
  return v < 0 ? 0 - static_cast<unsigned __int128>(v) : static_cast<unsigned __int128>(v);
}
int width128(unsigned __int128 m) {
  const auto hi = static_cast<std::uint64_t>(m >> 64);
  if (hi != 0) return 128 - __builtin_clzll(hi);
  const auto lo = static_cast<std::uint64_t>(m);
  return lo == 0 ? 0 : 64 - __builtin_clzll(lo);
}

__int128 round_significand128(__int128 v, int bits) {
  if (bits >= 62 || v == 0) return v;
  const unsigned __int128 m = magnitude128(v);
  const int width = width128(m);
  if (width <= bits) return v;
  const int drop = width - bits;
  const unsigned __int128 unit = static_cast<unsigned __int128>(1) << drop;
  unsigned __int128 q = m >> drop;
  const unsigned __int128 r = m & (unit - 1);
  if (r > unit / 2 || (r == unit / 2 && (q & 1) != 0)) ++q;
  const auto rounded = static_cast<__int128>(q << drop);
  return v < 0 ? -rounded : rounded;
}

}  // namespace

std::int64_t round_significand(std::int64_t v, int bits) {
  return static_cast<std::int64_t>(round_significand128(v, bits));
}

__int128 gp_round(__int128 v, const GeometryParams& params) {
  return round_significand128(v, params.significand_bits);
}

double gp_round(double v, const GeometryParams& params) {
  const int bits = params.significand_bits;
  if (bits >= 62 || v == 0 || !std::isfinite(v)) return v;
  int e = 0;
  const double m = std::frexp(v, &e);  // v = m 2^e, 0.5 <= |m| < 1
  // Nearest, ties to even (the default rounding mode), at `bits` bits of m.
  return std::ldexp(std::nearbyint(std::ldexp(m, bits)), e - bits);
}

const char* expression_form_name(ExpressionForm form) {
  switch (form) {
    case F::constant:
      return "constant";
    case F::linear:
      return "linear";
    case F::quadratic:
      return "quadratic";
  }
  return "?";
}

int coefficients(ExpressionForm form) {
  switch (form) {
    case F::constant:
      return 1;
    case F::linear:
      return 3;
    case F::quadratic:
      return 6;
  }
  return 6;
}

std::pair<double, double> SetupContext::gradient(const std::array<double, 3>& f) const {
  return {((f[1] - f[0]) * (w[2] - w[0]) - (f[2] - f[0]) * (w[1] - w[0])) / det,
          ((f[2] - f[0]) * (u[1] - u[0]) - (f[1] - f[0]) * (u[2] - u[0])) / det};
}

bool SetupContext::plane(const std::array<double, 3>& f, QuadraticCoefficients& out) const {
  const int cb = params.coefficient_bits;
  const auto [a, b] = gradient(f);
  const double A = std::nearbyint(a * f_scale);
  const double B = std::nearbyint(b * f_scale);
  const double limit = std::ldexp(1.0, cb - 1);
  if (!(std::fabs(A) < limit && std::fabs(B) < limit)) return false;
  // The GP's arithmetic keeps params.significand_bits of each coefficient (gp_round). A and B
  // are whole and below 2^(cb - 1): with cb <= 64 (the configuration allows 62) converted
  // through 64 bits, exactly, rather than by the library's double to 128-bit conversion.
  const auto whole = [cb](double v) {
    return cb <= 64 ? static_cast<__int128>(static_cast<std::int64_t>(v))
                    : static_cast<__int128>(v);
  };
  const auto Ai = static_cast<std::int64_t>(gp_round(whole(A), params));
  const auto Bi = static_cast<std::int64_t>(gp_round(whole(B), params));
  if (!fits(Ai, cb) || !fits(Bi, cb)) return false;
  // C makes the value exact (to rounding) at the first vertex: C = f0 - A u0 - B v0, with
  // the products formed exactly in integers.
  const __int128 f0 = static_cast<__int128>(std::llround(f[0] * f_scale)) * scale;
  const __int128 num =
      f0 - static_cast<__int128>(Ai) * (xs[0] - half) - static_cast<__int128>(Bi) * (ys[0] - half);
  // Rounded to the nearest (halves away from zero) by a division that truncates toward zero;
  // scale is 2^subpixel_bits (GeometryEngine::setup), so by shifts (a 128-bit division is a
  // library call).
  if ((scale & (scale - 1)) != 0) throw std::logic_error("SetupContext: scale is not 2^n");
  const int shift = __builtin_ctzll(static_cast<unsigned long long>(scale));
  const __int128 rounded = num >= 0 ? num + scale / 2 : num - scale / 2;
  __int128 C = gp_round(rounded >= 0 ? rounded >> shift : -((-rounded) >> shift), params);
  // C is sent modulo 2^coefficient_bits when the evaluator's sums wrap at no more bits than
  // that: every pixel then still gets A x + B y + C exactly modulo 2^result_bits, and inside
  // the triangle, where the attribute lies within its range, that is its exact value. A
  // steep plane far from the screen's origin needs this: its C is far beyond the width
  // while the values it yields are not. (Edge functions are never wrapped: their sign
  // matters at every pixel.)
  const __int128 span = static_cast<__int128>(1) << cb;
  if (params.result_bits <= cb) {
    C &= span - 1;  // C modulo 2^cb, in [0, span): two's complement
    if (C >= span / 2) C -= span;
  }
  if (C >= span / 2 || C < -span / 2) return false;
  out = QuadraticCoefficients::linear(Ai, Bi, static_cast<std::int64_t>(C));
  return true;
}

// Edge e runs from vertex e to vertex (e + 1) % 3: A x + B y + C >= 0 inside, on pixel
// indices, from the snapped vertices, so coefficients are exact integers and two triangles
// sharing the edge get exactly opposite functions; then rounded to the GP's edge precision.
bool SetupContext::edge(int e, std::int64_t outward, bool top_left_rule,
                        QuadraticCoefficients& out) const {
  const int a = e;
  const int b = (e + 1) % 3;
  const std::int64_t sigma = area2 > 0 ? 1 : -1;
  const std::int64_t dx = xs[b] - xs[a];
  const std::int64_t dy = ys[b] - ys[a];
  std::int64_t A = -sigma * dy * scale;
  std::int64_t B = sigma * dx * scale;
  std::int64_t C = sigma * (dx * (half - ys[a]) - dy * (half - xs[a])) + outward;
  // The GP keeps params.significand_bits of each coefficient (gp_round): the
  // line moves, by at most 2^-n (|A| x + |B| y + |C|) value units at pixel (x, y). Rounding
  // is symmetric about 0, so the neighbour's function stays exactly the negation. A line
  // moved outward (an enlarged area, which must hold every centre the unsnapped edge does)
  // is first moved out by that much more over the whole screen, then rounded.
  const int n = params.significand_bits;
  if (n < 62) {
    if (outward > 0) {
      const double u = std::ldexp(1.0, -n);
      double reach = u * (std::fabs(static_cast<double>(A)) * params.screen_width +
                          std::fabs(static_cast<double>(B)) * params.screen_height);
      reach += 2.0 * u * (std::fabs(static_cast<double>(C)) + reach) + 2.0;
      if (!(reach < std::ldexp(1.0, 61))) return false;
      C += static_cast<std::int64_t>(std::ceil(reach));
    }
    A = static_cast<std::int64_t>(gp_round(static_cast<__int128>(A), params));
    B = static_cast<std::int64_t>(gp_round(static_cast<__int128>(B), params));
    C = static_cast<std::int64_t>(gp_round(static_cast<__int128>(C), params));
  }
  // Top-left rule: a pixel centre exactly on the edge belongs to this triangle only if the
  // edge is a left edge (inside lies to its right) or a top edge.
  if (top_left_rule && !(A > 0 || (A == 0 && B > 0))) C -= 1;
  const int cb = params.coefficient_bits;
  if (!fits(A, cb) || !fits(B, cb) || !fits(C, cb)) return false;
  out = QuadraticCoefficients::linear(A, B, C);
  return true;
}

QuadraticCoefficients SetupContext::constant(double value) const {
  // A multiplication, not a shift: constants may be negative.
  return QuadraticCoefficients::constant(static_cast<std::int64_t>(gp_round(
      static_cast<__int128>(std::llround(value)) * (std::int64_t{1} << params.fraction_bits),
      params)));
}

double SetupContext::depth(int k) const {
  return std::clamp(triangle.v[k].depth * depth_max, 0.5, depth_max - 1.5);
}

const std::array<ExpressionEntry, static_cast<int>(Expression::count)>& expression_registry() {
  static_assert(in_enum_order(), "expression registry entries must follow the Expression enum");
  return kRegistry;
}

namespace {

// The expressions whose registry entry has a flag, as a set: asked of every triangle's set-up,
// so one AND rather than a walk of the registry.
template <bool ExpressionEntry::*flag>
const ExpressionSet& expressions_with() {
  static const ExpressionSet set = [] {
    ExpressionSet s;
    for (const ExpressionEntry& e : kRegistry) {
      if (e.*flag) s.set(static_cast<std::size_t>(e.id));
    }
    return s;
  }();
  return set;
}

}  // namespace

bool needs_adjacency(const ExpressionSet& set) {
  return (set & expressions_with<&ExpressionEntry::needs_adjacency>()).any();
}

bool needs_frame_parameters(const ExpressionSet& set) {
  return (set & expressions_with<&ExpressionEntry::reads_frame>()).any();
}

bool widens_bounds(const ExpressionSet& set) {
  return (set & expressions_with<&ExpressionEntry::widens>()).any();
}

int coefficient_words(int coefficient_bits, int word_bits) {
  return (coefficient_bits + word_bits - 1) / word_bits;
}

std::uint64_t packet_words(const ExpressionSet& set, int coefficient_words) {
  // A header word naming the procedure, then each expression's coefficients by its form.
  std::uint64_t n = 0;
  for (const ExpressionEntry& e : kRegistry) {
    if (set.test(static_cast<int>(e.id))) n += static_cast<std::uint64_t>(coefficients(e.form));
  }
  return 1 + n * static_cast<std::uint64_t>(coefficient_words);
}

}  // namespace pp5
