#include "models/evaluator/linear_band.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>

namespace pp5 {

bool one_interval(Compare cond) {
  return cond == Compare::lt || cond == Compare::le || cond == Compare::gt || cond == Compare::ge;
}

bool fits_64(const QuadraticCoefficients& c, int y0, int x0, int width, int height) {
  using i128 = __int128;
  const i128 limit = i128(1) << 61;
  auto small = [&](i128 v) { return v > -limit && v < limit; };
  const i128 ey = i128(c.E) * (std::abs(y0) + height);
  const i128 dx = i128(c.D) * (std::abs(x0) + width);
  auto magnitude = [](i128 v) { return v < 0 ? -v : v; };
  return small(magnitude(c.F) + magnitude(ey) + magnitude(dx));
}

// The region's rectangle of pixel centres clipped by each test's half-plane
// (Sutherland-Hodgman), each half-plane widened by half a pixel so that rounding cannot lose a
// pixel on its edge, and a row more each way. In doubles: a test's value at the region's
// origin is formed exactly in 64 bits (its terms are below 2^61: fits_64), and rounding it errs
// by 2^-53 of it, which is a tiny part of a pixel where the edge crosses the region (there it
// is at most the gradient times the region's size) and cannot turn the sign of a value far
// from zero.
void linear_row_band(const LinearTest* tests, std::size_t n, int x0, int y0, int width, int height,
                     int& lo, int& hi) {
  using R = double;
  struct Point {
    R x, y;
  };
  std::array<Point, 4 + 2 * kMaxBandTests> poly{}, next{};
  std::size_t m = 4;
  poly[0] = {0, 0};
  poly[1] = {R(width - 1), 0};
  poly[2] = {R(width - 1), R(height - 1)};
  poly[3] = {0, R(height - 1)};
  n = std::min(n, kMaxBandTests);  // each cut adds at most one vertex; the rest only narrow
  for (std::size_t k = 0; k < n && m > 0; ++k) {
    const QuadraticCoefficients& c = tests[k].c;
    if (c.D == 0 && c.E == 0) continue;  // all or nothing: left to the rows
    // h(x, y) >= 0 on the side where the test can hold: g = D (x0 + x) + E (y0 + y) + F,
    // its sign turned for lt and le, widened by half a pixel.
    const R sign = (tests[k].cond == Compare::lt || tests[k].cond == Compare::le) ? -1 : 1;
    const R a = sign * R(c.D), b = sign * R(c.E);
    const std::int64_t at_origin = c.D * x0 + c.E * y0 + c.F;  // exact: below 3 x 2^61
    const R d = sign * R(at_origin) + R(0.5) * (std::fabs(R(c.D)) + std::fabs(R(c.E)));
    auto h = [&](const Point& p) { return a * p.x + b * p.y + d; };
    std::size_t out = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const Point& p = poly[i];
      const Point& q = poly[(i + 1) % m];
      const R hp = h(p), hq = h(q);
      if (hp >= 0) next[out++] = p;
      if ((hp >= 0) != (hq >= 0)) {
        const R t = hp / (hp - hq);
        next[out++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
      }
    }
    poly = next;
    m = out;
  }
  if (m == 0) {
    lo = hi + 1;  // no row
    return;
  }
  R ymin = poly[0].y, ymax = poly[0].y;
  for (std::size_t i = 1; i < m; ++i)
    ymin = std::min(ymin, poly[i].y), ymax = std::max(ymax, poly[i].y);
  if (!std::isfinite(ymin) || !std::isfinite(ymax)) return;
  lo = std::max(lo, static_cast<int>(std::floor(ymin)) - 1);
  hi = std::min(hi, static_cast<int>(std::ceil(ymax)) + 1);
}

}  // namespace pp5
