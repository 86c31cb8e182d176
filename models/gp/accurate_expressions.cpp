#include "models/gp/accurate_expressions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <tuple>

namespace pp5 {

namespace {

// A mesh vertex projected as GeometryEngine::transform projects it (the same arithmetic, so
// the same doubles): pixel-index coordinates (u, w), depth units z, and whether it lies
// inside the view volume.
struct Projected {
  double u = 0, w = 0, z = 0;
  bool inside = false;
};

struct Projector {
  glm::dmat4 view;
  glm::dmat4 projection;
  const SetupContext& c;

  explicit Projector(const SetupContext& context) : c(context) {
    const float aspect =
        static_cast<float>(c.params.screen_width) / static_cast<float>(c.params.screen_height);
    view = glm::dmat4(view_matrix(c.camera));
    projection = glm::dmat4(projection_matrix(c.camera, aspect));
  }

  Projected operator()(std::uint32_t index) const {
    const glm::dvec4 e = view * glm::dvec4(glm::dvec3(c.mesh->vertices[index].position), 1.0);
    const glm::dvec4 clip = projection * e;
    Projected p;
    p.inside = clip.w + clip.x >= 0 && clip.w - clip.x >= 0 && clip.w + clip.y >= 0 &&
               clip.w - clip.y >= 0 && clip.w + clip.z >= 0 && clip.w - clip.z >= 0;
    if (!p.inside) return p;
    const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
    p.u = (ndc.x * 0.5 + 0.5) * c.params.screen_width - 0.5;
    p.w = (0.5 - ndc.y * 0.5) * c.params.screen_height - 0.5;
    const double depth = std::clamp(ndc.z * 0.5 + 0.5, 0.0, 1.0);
    p.z = std::clamp(depth * c.depth_max, 0.5, c.depth_max - 1.5);
    return p;
  }
};

// The plane z = a u + b w + k through three projected vertices; false if they are collinear
// on the screen.
struct Plane {
  double a = 0, b = 0, k = 0;
  double at(double u, double w) const { return a * u + b * w + k; }
};
// Its coefficients are kept to the GP's arithmetic (gp_round), as the side test's difference
// of two planes then is.
bool plane_through(const GeometryParams& params, const Projected& p0, const Projected& p1,
                   const Projected& p2, Plane& out) {
  const double det = (p1.u - p0.u) * (p2.w - p0.w) - (p2.u - p0.u) * (p1.w - p0.w);
  if (!(std::fabs(det) > 1e-9)) return false;
  out.a = gp_round(((p1.z - p0.z) * (p2.w - p0.w) - (p2.z - p0.z) * (p1.w - p0.w)) / det, params);
  out.b = gp_round(((p2.z - p0.z) * (p1.u - p0.u) - (p1.z - p0.z) * (p2.u - p0.u)) / det, params);
  out.k = gp_round(p0.z - out.a * p0.u - out.b * p0.w, params);
  return true;
}

bool fits(double v, int bits) { return std::fabs(v) < std::ldexp(1.0, bits - 1); }

}  // namespace

static_assert(std::tuple_size<decltype(SetupCounts::sides)>::value ==
                  static_cast<std::size_t>(SideKind::count),
              "SetupCounts::sides has one counter per SideKind");

const char* side_kind_name(SideKind kind) {
  switch (kind) {
    case SideKind::plane:
      return "plane";
    case SideKind::boundary:
      return "boundary";
    case SideKind::non_manifold:
      return "non_manifold";
    case SideKind::clipped:
      return "clipped";
    case SideKind::degenerate:
      return "degenerate";
    case SideKind::coplanar:
      return "coplanar";
    case SideKind::count:
      break;
  }
  return "?";
}

namespace {

// The most fraction bits (at most kMaxBits) with which a*u + b*w + k, rounded, neither overflows
// a coefficient nor wraps the evaluator's sum anywhere on the screen; and the largest error
// that rounding makes anywhere on the screen, in the function's units.
constexpr int kMaxBits = 48;
int fitting_bits(const SetupContext& c, const Plane& d, double& rounding) {
  const int cb = c.params.coefficient_bits;
  const int rb = std::min(c.params.result_bits, cb);
  const double width = c.params.screen_width;
  const double height = c.params.screen_height;
  const double slack = 0.5 * (width + height + 1.0) + 2.0;
  const double reach = std::fabs(d.a) * width + std::fabs(d.b) * height + std::fabs(d.k);
  int bits = kMaxBits;
  while (bits > -64 && !(fits(std::ldexp(reach, bits) + slack, rb) &&
                         fits(std::ldexp(std::fabs(d.k), bits) + 2.0, cb)))
    --bits;
  rounding = std::ldexp(slack, -bits);
  return bits;
}

// sign * (d - tie) in the evaluator's integers, d scaled by 2^bits, each coefficient kept to
// the GP's arithmetic before the tie-break (which then decides a centre exactly on the line).
QuadraticCoefficients fixed(const GeometryParams& params, const Plane& d, int bits, int sign,
                            std::int64_t tie) {
  auto keep = [&](double v) {
    return static_cast<std::int64_t>(
        gp_round(static_cast<__int128>(std::nearbyint(std::ldexp(v, bits))), params));
  };
  const std::int64_t A = keep(d.a), B = keep(d.b), C = keep(d.k);
  return QuadraticCoefficients::linear(sign * A, sign * B, sign * C - tie);
}

}  // namespace

SidePlane side_plane(const SetupContext& c, int e) {
  SidePlane r;
  const int f = c.triangle.source;
  const int n = c.adjacency->across(f, e);
  const glm::uvec3 tf = c.mesh->triangles[static_cast<std::size_t>(f)];
  const Projector project(c);
  Projected pf[3], pn[3];
  // A piece of a clipped triangle: its edges are not the mesh's (transform clips only a
  // triangle with a vertex outside the view volume; a whole one keeps the mesh's order).
  r.kind = SideKind::clipped;
  r.snapped = true;
  for (int k = 0; k < 3; ++k) {
    pf[k] = project(tf[k]);
    if (!pf[k].inside) return r;
  }
  glm::uvec3 tn{0, 0, 0};
  if (n >= 0) {
    tn = c.mesh->triangles[static_cast<std::size_t>(n)];
    for (int k = 0; k < 3; ++k) {
      pn[k] = project(tn[k]);
      if (!pn[k].inside) return r;
    }
  }
  r.snapped = false;
  const std::uint32_t p = tf[e];
  const std::uint32_t q = tf[(e + 1) % 3];
  const Projected& cf = pf[(e + 2) % 3];
  int third = -1;  // the neighbour's corner off the shared edge
  for (int k = 0; k < 3 && n >= 0 && third < 0; ++k) {
    if (tn[k] != p && tn[k] != q) third = k;
  }

  // The fallback: the unsnapped edge's own line, oriented by the vertex indices so that both
  // triangles of the edge form the same function, then turned to point inside.
  auto edge_line = [&](SideKind why) {
    r.kind = why;
    const Projected& a = p < q ? pf[e] : pf[(e + 1) % 3];
    const Projected& b = p < q ? pf[(e + 1) % 3] : pf[e];
    Plane line{gp_round(-(b.w - a.w), c.params), gp_round(b.u - a.u, c.params), 0.0};
    line.k = gp_round(-(line.a * a.u + line.b * a.w), c.params);
    const double at_f = line.at(cf.u, cf.w);
    r.sign = at_f < 0 ? -1 : 1;
    r.silhouette = third >= 0 && (line.at(pn[third].u, pn[third].w) < 0 ? -1 : 1) == r.sign;
    const std::int64_t tie = (third >= 0 && !r.silhouette && f > n) ? 1 : 0;
    double rounding = 0;
    r.fraction_bits = fitting_bits(c, line, rounding);
    r.coefficients = fixed(c.params, line, r.fraction_bits, r.sign, tie);
    return r;
  };
  if (n == MeshAdjacency::kBoundary) return edge_line(SideKind::boundary);
  if (n == MeshAdjacency::kNonManifold) return edge_line(SideKind::non_manifold);
  Plane zf, zn;
  if (third < 0 || !plane_through(c.params, pf[0], pf[1], pf[2], zf) ||
      !plane_through(c.params, pn[0], pn[1], pn[2], zn))
    return edge_line(SideKind::degenerate);
  // D = Z - Z_n, formed so that the neighbour, asking about the same edge, gets exactly the
  // negated coefficients and values (IEEE subtraction and products are sign-symmetric).
  const Plane d{gp_round(zf.a - zn.a, c.params), gp_round(zf.b - zn.b, c.params),
                gp_round(zf.k - zn.k, c.params)};
  const Projected& cn = pn[third];
  const double at_f = d.at(cf.u, cf.w);
  const double at_n = d.at(cn.u, cn.w);
  double rounding = 0;
  const int bits = fitting_bits(c, d, rounding);
  // D is small where the planes nearly coincide, and then it is mostly the double-precision
  // error of the two planes themselves: a plane of a face nearly edge-on to the eye is
  // ill-conditioned (its gradient is huge), and D of two such coplanar faces is noise. The
  // bound 2^-30 of the planes' magnitude over the screen is generous in double (2^-52);
  // with the GP's arithmetic at n significant bits (gp.significand_bits) each plane
  // coefficient and each difference carries 2^-n, so the bound is 2^-(n - 3) when that is
  // larger (a careful set-up program sizes its tolerance to its own arithmetic).
  const double width = c.params.screen_width;
  const double height = c.params.screen_height;
  const double noise =
      std::ldexp(std::fabs(zf.a) * width + std::fabs(zf.b) * height + std::fabs(zf.k) +
                     std::fabs(zn.a) * width + std::fabs(zn.b) * height + std::fabs(zn.k),
                 -std::min(30, c.params.significand_bits - 3));
  const double error = rounding + noise;
  // The error moves the crossing line by at most error / |grad D| pixels: planes too nearly
  // coplanar to place it within kLineTolerance are classified by the edge's line instead (the
  // same line, where the planes are exact), and so are third vertices too close to call.
  const double grad = std::fabs(d.a) + std::fabs(d.b);
  if (!(grad * kLineTolerance > error) || !(std::fabs(at_f) > 4.0 * error) ||
      !(std::fabs(at_n) > 4.0 * error))
    return edge_line(SideKind::coplanar);

  r.kind = SideKind::plane;
  r.sign = at_f > 0 ? 1 : -1;
  // Both third vertices on the same side of the crossing line: the edge is a silhouette and
  // the faces overlap on the screen; both admit the same side, with the same tie-break.
  r.silhouette = (at_f > 0) == (at_n > 0);
  const std::int64_t tie = (!r.silhouette && f > n) ? 1 : 0;
  r.fraction_bits = bits;
  r.coefficients = fixed(c.params, d, bits, r.sign, tie);
  return r;
}

bool plane_depth_expression(const SetupContext& c, QuadraticCoefficients& out) {
  // The plane through the unsnapped vertices (pixel-index coordinates), anchored at vertex 0
  // like SetupContext::plane, with C formed in extended precision and wrapped the same way.
  std::array<double, 3> u{}, w{}, f{};
  for (int k = 0; k < 3; ++k) {
    u[k] = c.triangle.v[k].position.x - 0.5;
    w[k] = c.triangle.v[k].position.y - 0.5;
    f[k] = c.depth(k);
  }
  const double det = (u[1] - u[0]) * (w[2] - w[0]) - (u[2] - u[0]) * (w[1] - w[0]);
  if (!(std::fabs(det) > 0)) return false;
  const double a = ((f[1] - f[0]) * (w[2] - w[0]) - (f[2] - f[0]) * (w[1] - w[0])) / det;
  const double b = ((f[2] - f[0]) * (u[1] - u[0]) - (f[1] - f[0]) * (u[2] - u[0])) / det;
  const int cb = c.params.coefficient_bits;
  const double A0 = std::nearbyint(a * c.f_scale);
  const double B0 = std::nearbyint(b * c.f_scale);
  if (!(fits(A0, cb) && fits(B0, cb))) return false;
  // Kept to the GP's arithmetic (gp_round), C before it is reduced modulo the width.
  const auto A = static_cast<double>(gp_round(static_cast<__int128>(A0), c.params));
  const auto B = static_cast<double>(gp_round(static_cast<__int128>(B0), c.params));
  if (!(fits(A, cb) && fits(B, cb))) return false;
  const long double num = static_cast<long double>(f[0]) * c.f_scale -
                          static_cast<long double>(A) * u[0] - static_cast<long double>(B) * w[0];
  if (!(std::fabs(num) < std::ldexp(1.0L, 100))) return false;
  __int128 C = gp_round(static_cast<__int128>(std::nearbyintl(num)), c.params);
  const __int128 span = static_cast<__int128>(1) << cb;
  if (c.params.result_bits <= cb) {
    C = ((C % span) + span) % span;
    if (C >= span / 2) C -= span;
  }
  if (C >= span / 2 || C < -span / 2) return false;
  out = QuadraticCoefficients::linear(static_cast<std::int64_t>(A), static_cast<std::int64_t>(B),
                                      static_cast<std::int64_t>(C));
  return true;
}

bool wide_edge_expression(const SetupContext& c, int e, QuadraticCoefficients& out) {
  // Snapping moves each vertex by at most half a snapped unit in x and in y, so the unsnapped
  // edge lies within (|dx| + |dy|) / 2 value units of the snapped one (the edge function's
  // value is the distance times the edge's length in snapped units).
  const int b = (e + 1) % 3;
  const std::int64_t outward =
      (std::llabs(c.xs[b] - c.xs[e]) + std::llabs(c.ys[b] - c.ys[e]) + 1) / 2;
  return c.edge(e, outward, false, out);
}

bool side_expression(const SetupContext& c, int e, QuadraticCoefficients& out) {
  const SidePlane s = side_plane(c, e);
  if (c.counts) ++c.counts->sides[static_cast<std::size_t>(s.kind)];
  if (s.snapped) return c.edge(e, 0, true, out);
  out = s.coefficients;
  return true;
}

}  // namespace pp5
