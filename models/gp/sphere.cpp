#include "models/gp/sphere.hpp"

#include <algorithm>
#include <cmath>

#include "models/gp/expressions.hpp"

namespace pp5 {

namespace {

// The least-squares fit of a quadratic over fixed points of the unit disc: the centre, 6 at
// radius 0.55 and 6 at 0.92 (turned by 30 degrees): the 6 x 13 matrix taking the values at
// the points to the coefficients of 1, u, v, u^2, uv, v^2. The points are fixed, so the
// matrix is a table the GP's code carries (computed here once).
constexpr int kSamples = 13;
struct FitTable {
  std::array<std::array<double, 2>, kSamples> points{};
  std::array<std::array<double, kSamples>, 6> solve{};
  double overshoot = 1;
};

std::array<double, 6> basis(double u, double v) { return {1.0, u, v, u * u, u * v, v * v}; }

FitTable make_fit_table() {
  FitTable t;
  const double pi = 3.14159265358979323846;
  t.points[0] = {0.0, 0.0};
  for (int k = 0; k < 6; ++k) {
    const double a = pi * k / 3.0;
    const double b = a + pi / 6.0;
    t.points[1 + k] = {0.55 * std::cos(a), 0.55 * std::sin(a)};
    t.points[7 + k] = {0.92 * std::cos(b), 0.92 * std::sin(b)};
  }
  // Normal equations N = B^T B (6 x 6), then solve = N^-1 B^T by Gauss-Jordan.
  std::array<std::array<double, 12>, 6> m{};
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      double s = 0;
      for (const auto& p : t.points) s += basis(p[0], p[1])[i] * basis(p[0], p[1])[j];
      m[i][j] = s;
    }
    m[i][6 + i] = 1.0;
  }
  for (int col = 0; col < 6; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 6; ++r) {
      if (std::fabs(m[r][col]) > std::fabs(m[pivot][col])) pivot = r;
    }
    std::swap(m[col], m[pivot]);
    const double inv = 1.0 / m[col][col];
    for (double& x : m[col]) x *= inv;
    for (int r = 0; r < 6; ++r) {
      if (r == col) continue;
      const double f = m[r][col];
      for (int j = 0; j < 12; ++j) m[r][j] -= f * m[col][j];
    }
  }
  for (int i = 0; i < 6; ++i) {
    for (int s = 0; s < kSamples; ++s) {
      double v = 0;
      const auto b = basis(t.points[s][0], t.points[s][1]);
      for (int j = 0; j < 6; ++j) v += m[i][6 + j] * b[j];
      t.solve[i][s] = v;
    }
  }
  // The fit's largest overshoot of a unit normal: the length of the fitted (u, v,
  // sqrt(1 - u^2 - v^2)) (the normal seen in parallel projection) over a fine grid of the
  // disc (1.056 for this pattern: the fit of sqrt(1 - rho^2) is 5.6% high at the centre).
  std::array<std::array<double, 6>, 3> g{};
  for (int axis = 0; axis < 3; ++axis) {
    for (int i = 0; i < 6; ++i) {
      for (int k = 0; k < kSamples; ++k) {
        const double u = t.points[k][0], v = t.points[k][1];
        const double n[3] = {u, v, std::sqrt(std::max(0.0, 1.0 - u * u - v * v))};
        g[axis][i] += t.solve[i][k] * n[axis];
      }
    }
  }
  t.overshoot = 1.0;
  for (int i = -100; i <= 100; ++i) {
    for (int j = -100; j <= 100; ++j) {
      const double u = i / 100.0, v = j / 100.0;
      if (u * u + v * v > 1.0) continue;
      const auto b = basis(u, v);
      double len2 = 0;
      for (int axis = 0; axis < 3; ++axis) {
        double x = 0;
        for (int k = 0; k < 6; ++k) x += g[axis][k] * b[k];
        len2 += x * x;
      }
      t.overshoot = std::max(t.overshoot, std::sqrt(len2));
    }
  }
  return t;
}

const FitTable& fit_table() {
  static const FitTable table = make_fit_table();
  return table;
}

// q(dx', dy') about the conic's centre, rewritten about the anchor: dx' = dx - sx.
CentredQuadratic shift(const CentredQuadratic& q, double sx, double sy) {
  CentredQuadratic r = q;
  r.d = q.d - 2 * q.a * sx - q.b * sy;
  r.e = q.e - q.b * sx - 2 * q.c * sy;
  r.f = q.at(-sx, -sy);
  return r;
}

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

}  // namespace

double sphere_rounding_bound(double dx, double dy) {
  dx = std::fabs(dx);
  dy = std::fabs(dy);
  return 0.5 * (dx * dx + dx * dy + dy * dy + dx + dy + 1.0);
}

bool is_sphere_expression(Expression e) {
  return static_cast<int>(e) >= static_cast<int>(Expression::sphere_inside) &&
         static_cast<int>(e) <= static_cast<int>(Expression::sphere_root_shift);
}

SphereProjector::SphereProjector(const GeometryParams& params, const Camera& camera)
    : params_(params) {
  const float aspect =
      static_cast<float>(params.screen_width) / static_cast<float>(params.screen_height);
  view_ = glm::dmat4(view_matrix(camera));
  const glm::dmat4 p = glm::dmat4(projection_matrix(camera, aspect));
  near_ = camera.near_plane;
  far_ = camera.far_plane;
  const double w = params.screen_width;
  const double h = params.screen_height;
  // Screen x = (P00 x_e / t * 0.5 + 0.5) W at t = -z_e; pixel X's centre is at X + 0.5.
  ax_ = 2.0 / (w * p[0][0]);
  bx_ = (1.0 - w) / (w * p[0][0]);
  ay_ = -2.0 / (h * p[1][1]);
  by_ = (h - 1.0) / (h * p[1][1]);
  // depth01 = (ndc z + 1) / 2 with ndc z = -P22 + P32 / t: depth = G - H / t.
  depth_max_ = std::ldexp(1.0, params.depth_bits) - 1.0;
  g_ = depth_max_ * (0.5 - 0.5 * p[2][2]);
  h_ = -0.5 * p[3][2] * depth_max_;
}

bool SphereProjector::project(const Sphere& sphere, int index, ScreenSphere& out,
                              SetupCounts& counts, bool far) const {
  const glm::dvec3 c = glm::dvec3(view_ * glm::dvec4(glm::dvec3(sphere.center), 1.0));
  const double r = sphere.radius;
  const double tc = -c.z;  // view-axis distance of the centre
  if (tc + r <= 0) {
    ++counts.sphere_behind;
    return false;
  }
  if (tc + r <= near_ || tc - r >= far_) {
    ++counts.clipped_away;
    return false;
  }
  if (tc - r <= near_) {
    ++counts.sphere_near;
    return false;
  }
  if (tc + r >= far_) {
    ++counts.sphere_far;
    return false;
  }
  out.source = index;
  out.far = far;
  out.centre = c;
  out.radius = r;
  out.color = glm::dvec3(sphere.color);
  const double k = glm::dot(c, c) - r * r;  // > 0: the sphere lies beyond the near plane

  // Anchor: the pixel the centre projects to (clamped to a range the integer expansion holds).
  const double px = (-c.x / c.z - bx_) / ax_;
  const double py = (-c.y / c.z - by_) / ay_;
  const double lim = 1 << 20;
  out.x0 = std::llround(std::clamp(px, -lim, lim));
  out.y0 = std::llround(std::clamp(py, -lim, lim));
  const glm::dvec3 d0 = ray(static_cast<double>(out.x0), static_cast<double>(out.y0));
  // d.c = l0 + lx dx + ly dy; |d|^2 = |d0|^2 + 2 d0x ax dx + ax^2 dx^2 + (same in y).
  const double lx = ax_ * c.x, ly = ay_ * c.y, l0 = glm::dot(d0, c);
  CentredQuadratic& q = out.conic;
  q.a = lx * lx - k * ax_ * ax_;
  q.b = 2 * lx * ly;
  q.c = ly * ly - k * ay_ * ay_;
  q.d = 2 * lx * l0 - 2 * k * d0.x * ax_;
  q.e = 2 * ly * l0 - 2 * k * d0.y * ay_;
  q.f = l0 * l0 - k * glm::dot(d0, d0);
  // Centre of the ellipse: the gradient vanishes. a, c < 0 and 4ac - b^2 > 0 for a sphere in
  // front of the eye.
  const double det = 4 * q.a * q.c - q.b * q.b;
  if (!(q.a < 0 && det > 0)) {
    ++counts.sphere_near;
    return false;
  }
  out.centre_x = (q.b * q.e - 2 * q.c * q.d) / det;
  out.centre_y = (q.b * q.d - 2 * q.a * q.e) / det;
  out.q_max = q.f + 0.5 * (q.d * out.centre_x + q.e * out.centre_y);
  if (!(out.q_max > 0)) {
    ++counts.no_pixels;
    return false;
  }
  // Half extents of {Q >= 0}: sqrt(Qm (-M)^-1_ii), M = [[a, b/2], [b/2, c]].
  const double dm = q.a * q.c - 0.25 * q.b * q.b;
  const double hw = std::sqrt(out.q_max * -q.c / dm);
  const double hh = std::sqrt(out.q_max * -q.a / dm);
  const double cx = static_cast<double>(out.x0) + out.centre_x;
  const double cy = static_cast<double>(out.y0) + out.centre_y;
  const double big = 1e9;
  out.x_min = static_cast<int>(std::clamp(std::ceil(cx - hw), 0.0, big));
  out.x_max = static_cast<int>(std::clamp(std::floor(cx + hw), -1.0, params_.screen_width - 1.0));
  out.y_min = static_cast<int>(std::clamp(std::ceil(cy - hh), 0.0, big));
  out.y_max = static_cast<int>(std::clamp(std::floor(cy + hh), -1.0, params_.screen_height - 1.0));
  if (out.x_min > out.x_max || out.y_min > out.y_max) {
    ++counts.no_pixels;
    return false;
  }

  // The conic's scale: the largest 2^s with |2^s Q| <= 2^(R - 3) on every pixel of every
  // region it is binned to. Q is concave there: its maximum is Qm, its minimum over the
  // rectangle at a corner.
  const int rw = params_.region_width, rh = params_.region_height;
  const double rx0 = static_cast<double>(floor_div(out.x_min, rw) * rw);
  const double ry0 = static_cast<double>(floor_div(out.y_min, rh) * rh);
  const double rx1 = static_cast<double>(floor_div(out.x_max, rw) * rw + rw - 1);
  const double ry1 = static_cast<double>(floor_div(out.y_max, rh) * rh + rh - 1);
  double largest = out.q_max;
  for (double x : {rx0, rx1}) {
    for (double y : {ry0, ry1}) {
      largest = std::max(largest,
                         -q.at(x - static_cast<double>(out.x0), y - static_cast<double>(out.y0)));
    }
  }
  int exponent = 0;
  std::frexp(largest, &exponent);  // largest < 2^exponent
  out.conic_shift = params_.result_bits - 3 - exponent;

  // Depth: G - (H / k)(d.c + Q / sqrt(Qm) + sqrt(Qm) / 8); the far hemisphere's has the
  // square root's line subtracted (1/t = (d.c - sqrt(Q)) / k), with the same error bound.
  const double s = std::sqrt(out.q_max);
  const double hk = h_ / k;
  const double root = far ? -1.0 : 1.0;
  CentredQuadratic& z = out.depth;
  z.a = -hk * root * q.a / s;
  z.b = -hk * root * q.b / s;
  z.c = -hk * root * q.c / s;
  z.d = -hk * (lx + root * q.d / s);
  z.e = -hk * (ly + root * q.e / s);
  z.f = g_ - hk * (l0 + root * (q.f / s + s / 8.0));
  out.depth_approximation_bound = hk * s / 8.0;
  // Pixel-Planes 4's paraboloid: the line through the square root's ends, Q / sqrt(Qm), exact
  // at the outline (Q = 0) and at the conic's centre (Q = Qm), too deep by up to sqrt(Qm) / 4
  // (at Q = Qm / 4): the same line as above without the minimax offset sqrt(Qm) / 8.
  out.paraboloid = z;
  out.paraboloid.f = g_ - hk * (l0 + root * q.f / s);
  // The exact depth, G - (H / k) d.c -+ (H / k) sqrt(Q), for a square root in pixel memory
  // (sphere_sqrt.pp5): the radicand (H / k)^2 Q / 4^n, with the least n that keeps its root
  // (at most (H / k) sqrt(Qm) / 2^n, the relief at the conic's centre) below 2^13 - 1, so
  // that 13 root bits and 26 radicand bits hold it; the firmware subtracts the truncated
  // root times 2^n from the linear part, which has half a root step and half a unit (for its
  // own floor) folded in so that both truncations err either way.
  const double relief = hk * s;
  const double root_limit = std::ldexp(1.0, kSphereRootBits) - 2.0;
  int root_shift = 0;
  while (std::ldexp(relief, -root_shift) > root_limit) ++root_shift;
  out.root_shift = root_shift;
  const double p = hk * hk * std::ldexp(1.0, -2 * root_shift);
  out.radicand = CentredQuadratic{p * q.a, p * q.b, p * q.c, p * q.d, p * q.e, p * q.f};
  out.depth_base = CentredQuadratic{
      0, 0, 0, -hk * lx, -hk * ly, g_ - hk * l0 - root * std::ldexp(1.0, root_shift - 1) + 0.5};
  const double ex = std::max(std::fabs(out.x_min - static_cast<double>(out.x0)),
                             std::fabs(out.x_max - static_cast<double>(out.x0)));
  const double ey = std::max(std::fabs(out.y_min - static_cast<double>(out.y0)),
                             std::fabs(out.y_max - static_cast<double>(out.y0)));
  out.depth_bound = out.depth_approximation_bound +
                    sphere_rounding_bound(ex, ey) / std::ldexp(1.0, params_.fraction_bits) + 1.0;
  // The approximation must stay inside the depth range, as a triangle's clamped vertices do.
  if (depth_at(tc - r) - out.depth_bound < 0.5) {
    ++counts.sphere_near;
    return false;
  }
  if (depth_at(tc + r) + out.depth_bound > depth_max_ - 1.5) {
    ++counts.sphere_far;
    return false;
  }

  // Normals: the exact normal at the 13 fit points of the ellipse, fitted in the disc's
  // coordinates u = R (p - centre), R the Cholesky factor of -M / Qm, then rewritten in
  // pixels about the anchor.
  const double n11 = -q.a / out.q_max, n12 = -0.5 * q.b / out.q_max, n22 = -q.c / out.q_max;
  const double r11 = std::sqrt(n11), r12 = n12 / r11;
  const double r22 = std::sqrt(std::max(n22 - r12 * r12, 1e-300));
  const FitTable& table = fit_table();
  // N.L must stay below 2^14 with |L| = 127 (phong's `dot[13:6]`): a fitted vector of length
  // up to 16383 / 127 = 129 is allowed, so the fit is scaled by 129 / (127 overshoot).
  const double normal_scale = 127.0 * std::min(1.0, 16383.0 / (127.0 * 127.0) / table.overshoot);
  std::array<glm::dvec3, kSamples> values{};
  for (int i = 0; i < kSamples; ++i) {
    const double u = table.points[i][0], v = table.points[i][1];
    const double dy = out.centre_y + v / r22;
    const double dx = out.centre_x + (u - r12 * v / r22) / r11;
    const glm::dvec3 d = ray(static_cast<double>(out.x0) + dx, static_cast<double>(out.y0) + dy);
    const double dc = glm::dot(d, c);
    const double disc = std::max(0.0, dc * dc - k * glm::dot(d, d));
    // The far hit's normal is turned to the eye: the wall of the cavity a complemented
    // sphere leaves. k / (dc - sqrt) as (dc + sqrt) / |d|^2, which does not cancel.
    const double t = far ? (dc + std::sqrt(disc)) / glm::dot(d, d) : k / (dc + std::sqrt(disc));
    values[i] = normal_scale * (far ? c - t * d : t * d - c) / r;
  }
  for (int axis = 0; axis < 3; ++axis) {
    std::array<double, 6> g{};
    for (int j = 0; j < 6; ++j) {
      for (int i = 0; i < kSamples; ++i) g[j] += table.solve[j][i] * values[i][axis];
    }
    // u = r11 dx' + r12 dy', v = r22 dy' about the centre.
    CentredQuadratic n;
    n.a = g[3] * r11 * r11;
    n.b = 2 * g[3] * r11 * r12 + g[4] * r11 * r22;
    n.c = g[3] * r12 * r12 + g[4] * r12 * r22 + g[5] * r22 * r22;
    n.d = g[1] * r11;
    n.e = g[1] * r12 + g[2] * r22;
    n.f = g[0];
    out.normal[static_cast<std::size_t>(axis)] = shift(n, out.centre_x, out.centre_y);
  }
  return true;
}

bool sphere_fixed_point(const CentredQuadratic& q, double scale, std::int64_t x0, std::int64_t y0,
                        const GeometryParams& params, QuadraticCoefficients& out) {
  using i128 = __int128;
  const double v[6] = {q.a * scale, q.b * scale, q.c * scale,
                       q.d * scale, q.e * scale, q.f * scale};
  i128 r[6];
  for (int k = 0; k < 6; ++k) {
    if (!std::isfinite(v[k]) || std::fabs(v[k]) > 1e36) return false;
    // The GP's arithmetic (gp_round) keeps n significant bits of each coefficient about the
    // anchor, and of each expanded to the screen's origin (before the reduction modulo the
    // coefficient width).
    r[k] = gp_round(static_cast<i128>(std::nearbyint(v[k])), params);
  }
  const i128 X = x0, Y = y0;
  // a dx^2 + b dx dy + c dy^2 + d dx + e dy + f with dx = X - x0, expanded exactly.
  i128 c6[6] = {r[0],
                r[1],
                r[2],
                r[3] - 2 * r[0] * X - r[1] * Y,
                r[4] - r[1] * X - 2 * r[2] * Y,
                r[5] + r[0] * X * X + r[1] * X * Y + r[2] * Y * Y - r[3] * X - r[4] * Y};
  const int cb = params.coefficient_bits;
  const i128 span = static_cast<i128>(1) << cb;
  std::int64_t o[6];
  for (int k = 0; k < 6; ++k) {
    i128 x = gp_round(c6[k], params);
    if (params.result_bits <= cb) {
      x = ((x % span) + span) % span;
      if (x >= span / 2) x -= span;
    }
    if (x >= span / 2 || x < -span / 2) return false;
    o[k] = static_cast<std::int64_t>(x);
  }
  out.A = o[0];
  out.B = o[1];
  out.C = o[2];
  out.D = o[3];
  out.E = o[4];
  out.F = o[5];
  return true;
}

namespace {

// A reciprocal or reciprocal square root: a seed and two Newton-Raphson steps (as i860.cpp).
constexpr OpCounts kReciprocal{2, 5, 0, 0, 0, 0, 1};

bool any_normal(const GpWorkload& w) {
  return w.expressions.test(static_cast<int>(Expression::sphere_nx)) ||
         w.expressions.test(static_cast<int>(Expression::sphere_ny)) ||
         w.expressions.test(static_cast<int>(Expression::sphere_nz));
}

}  // namespace

OpCounts sphere_operations(const GpWorkload& w, int setups, int regions) {
  // Fetch centre, radius and colour (7 loads), loop counter and branch.
  OpCounts c{0, 0, 7, 0, 4, 2, 0};
  // Centre to eye space (3 x 4 affine: 9 multiplies, 9 adds); the four range tests against
  // the eye, near and far planes (4 compares, 4 branches).
  c += OpCounts{9 + 4, 9, 0, 0, 0, 4, 1};
  if (setups == 0) return c;
  // A sphere of a solid has two set-ups (its near and far hemispheres) sharing the projection
  // (everything up to the depth range checks); each has its own normal fit, expressions and
  // packet.
  OpCounts s;
  // k = |c|^2 - r^2 (4, 3); the anchor: project the centre (reciprocal, 2 multiplies, 2 adds,
  // 2 conversions); d0, l0 and |d0|^2 (4 + 3 + 3 multiplies, 2 + 2 + 2 adds); the conic about
  // the anchor: a..f (14 multiplies, 5 adds).
  s += OpCounts{3 + 4 + 6 + 5, 4 + 2 + 10 + 14, 0, 0, 2, 0, 3} + kReciprocal;
  // Its centre and maximum: the 2x2 determinant and solve (7 multiplies, 3 adds, a
  // reciprocal), Qm (2, 2); half extents (2 multiplies, 2 reciprocal square roots, 2 more);
  // the bounding box (4 adds, 4 conversions, 4 clamps), its region rectangle (4 integer
  // shifts), four corners of Q (4 x (5 multiplies, 5 adds)), the exponent of the largest
  // (integer: 3).
  s += OpCounts{3 + 2 + 4 + 4 + 4 + 20, 7 + 2 + 4 + 20, 0, 0, 4 + 4 + 3, 6, 4} + kReciprocal * 3;
  // Depth range checks: two depths at t = tc -+ r (2 reciprocals, 2 multiplies, 2 adds,
  // 2 compares, 2 branches).
  s += OpCounts{4, 2, 0, 0, 0, 2, 0} + kReciprocal * 2;
  c += s;
  s = OpCounts{};
  if (any_normal(w)) {
    // The Cholesky factor of the ellipse (3 multiplies, 1 add, 2 reciprocal square roots),
    // then per fit point: its pixel position (4, 3), the ray (2, 2), d.c and |d|^2 (6, 4), the
    // square root and t (reciprocal square root and reciprocal, 2 multiplies, 2 adds), the
    // normal (t d - c) / r (6, 3): a table of 13.
    s += OpCounts{1, 3, 0, 0, 0, 0, 1} + kReciprocal * 2;
    s += (OpCounts{3 + 2 + 4 + 2 + 3, 4 + 2 + 6 + 2 + 6, 2, 0, 0, 0, 2} + kReciprocal * 2) *
         kSamples;
  }
  for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
    if (w.expressions.test(e)) s += I860Work::expression_setup(static_cast<Expression>(e));
  }
  s += I860Work::pack(w);
  c += s * static_cast<std::uint64_t>(setups);
  c += I860Work::bin_region() * static_cast<std::uint64_t>(regions);
  return c;
}

}  // namespace pp5
