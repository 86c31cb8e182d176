#include "sim/analysis/intersections.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace pp5 {

namespace {

// Where the triangle's edges cross the plane with signed vertex distances d: the points and
// their parameters along `dir`.
bool plane_interval(const glm::dvec3 (&p)[3], const double (&d)[3], const glm::dvec3& dir,
                    double& lo, double& hi, glm::dvec3& plo, glm::dvec3& phi) {
  std::array<glm::dvec3, 4> pts;
  int n = 0;
  for (int k = 0; k < 3 && n < 4; ++k) {
    const int j = (k + 1) % 3;
    if (d[k] == 0) pts[n++] = p[k];
    if ((d[k] < 0 && d[j] > 0) || (d[k] > 0 && d[j] < 0)) {
      pts[n++] = p[k] + (p[j] - p[k]) * (d[k] / (d[k] - d[j]));
    }
  }
  if (n == 0) return false;
  lo = hi = glm::dot(pts[0], dir);
  plo = phi = pts[0];
  for (int k = 1; k < n; ++k) {
    const double t = glm::dot(pts[k], dir);
    if (t < lo) lo = t, plo = pts[k];
    if (t > hi) hi = t, phi = pts[k];
  }
  return true;
}

struct Projector {
  glm::dmat4 m;
  int width, height;
  // Screen x, y (pixels) and depth in [0, 1]; w <= 0 (behind the eye) gives false.
  bool operator()(const glm::dvec3& p, glm::dvec3& s) const {
    const glm::dvec4 c = m * glm::dvec4(p, 1.0);
    if (c.w <= 0) return false;
    const glm::dvec3 ndc = glm::dvec3(c) / c.w;
    s = {(ndc.x * 0.5 + 0.5) * width, (0.5 - ndc.y * 0.5) * height, ndc.z * 0.5 + 0.5};
    return true;
  }
};

}  // namespace

bool triangle_intersection(const glm::dvec3 (&p)[3], const glm::dvec3 (&q)[3], glm::dvec3& a,
                           glm::dvec3& b) {
  const glm::dvec3 np = glm::cross(p[1] - p[0], p[2] - p[0]);
  const glm::dvec3 nq = glm::cross(q[1] - q[0], q[2] - q[0]);
  double dp[3], dq[3];
  for (int k = 0; k < 3; ++k) {
    dp[k] = glm::dot(nq, p[k] - q[0]);
    dq[k] = glm::dot(np, q[k] - p[0]);
  }
  auto one_side = [](const double(&d)[3]) {
    return (d[0] > 0 && d[1] > 0 && d[2] > 0) || (d[0] < 0 && d[1] < 0 && d[2] < 0);
  };
  if (one_side(dp) || one_side(dq)) return false;
  const glm::dvec3 dir = glm::cross(np, nq);
  if (glm::dot(dir, dir) <= 1e-24 * glm::dot(np, np) * glm::dot(nq, nq)) return false;  // coplanar
  double plo, phi, qlo, qhi;
  glm::dvec3 pa, pb, qa, qb;
  if (!plane_interval(p, dp, dir, plo, phi, pa, pb)) return false;
  if (!plane_interval(q, dq, dir, qlo, qhi, qa, qb)) return false;
  const double lo = std::max(plo, qlo);
  const double hi = std::min(phi, qhi);
  if (!(lo < hi)) return false;
  a = plo >= qlo ? pa : qa;
  b = phi <= qhi ? pb : qb;
  return true;
}

std::vector<Segment3> intersection_segments(const Mesh& mesh) {
  const int n = static_cast<int>(mesh.triangles.size());
  std::vector<glm::dvec3> lo(n), hi(n);
  for (int i = 0; i < n; ++i) {
    lo[i] = hi[i] = glm::dvec3(mesh.vertices[mesh.triangles[i][0]].position);
    for (int k = 1; k < 3; ++k) {
      const glm::dvec3 v(mesh.vertices[mesh.triangles[i][k]].position);
      lo[i] = glm::min(lo[i], v);
      hi[i] = glm::max(hi[i], v);
    }
  }
  // Sweep along x: each triangle meets only those whose x-extents overlap its own.
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return lo[a].x < lo[b].x || (lo[a].x == lo[b].x && a < b); });
  std::vector<Segment3> out;
  for (int oi = 0; oi < n; ++oi) {
    const int i = order[oi];
    const glm::uvec3 ti = mesh.triangles[i];
    glm::dvec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = glm::dvec3(mesh.vertices[ti[k]].position);
    for (int oj = oi + 1; oj < n && lo[order[oj]].x <= hi[i].x; ++oj) {
      const int j = order[oj];
      if (lo[j].y > hi[i].y || hi[j].y < lo[i].y || lo[j].z > hi[i].z || hi[j].z < lo[i].z)
        continue;
      const glm::uvec3 tj = mesh.triangles[j];
      bool shared = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) shared = shared || ti[a] == tj[b];
      if (shared) continue;
      glm::dvec3 q[3];
      for (int k = 0; k < 3; ++k) q[k] = glm::dvec3(mesh.vertices[tj[k]].position);
      Segment3 s;
      if (triangle_intersection(p, q, s.a, s.b)) {
        s.first = std::min(i, j);
        s.second = std::max(i, j);
        out.push_back(s);
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const Segment3& x, const Segment3& y) {
    return x.first < y.first || (x.first == y.first && x.second < y.second);
  });
  return out;
}

IntersectionTruth intersection_truth(const Scene& scene, int width, int height, double delta,
                                     double spacing, bool visible_only) {
  IntersectionTruth t;
  t.width = width;
  t.height = height;
  t.delta = delta;
  const Mesh& mesh = scene.mesh;
  const double aspect = static_cast<double>(width) / height;
  const Projector project{glm::dmat4(projection_matrix(scene.camera, static_cast<float>(aspect))) *
                              glm::dmat4(view_matrix(scene.camera)),
                          width, height};

  // The depth reference: every triangle in screen space, binned into 16-pixel cells.
  constexpr int kCell = 16;
  const int cx = (width + kCell - 1) / kCell, cy = (height + kCell - 1) / kCell;
  const int n = static_cast<int>(mesh.triangles.size());
  std::vector<std::array<glm::dvec3, 3>> screen(n);
  std::vector<bool> drawable(n, true);
  std::vector<std::vector<int>> cells(static_cast<std::size_t>(cx) * cy);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      drawable[i] = drawable[i] &&
                    project(glm::dvec3(mesh.vertices[mesh.triangles[i][k]].position), screen[i][k]);
    }
    if (!drawable[i]) continue;
    double x0 = screen[i][0].x, x1 = x0, y0 = screen[i][0].y, y1 = y0;
    for (int k = 1; k < 3; ++k) {
      x0 = std::min(x0, screen[i][k].x), x1 = std::max(x1, screen[i][k].x);
      y0 = std::min(y0, screen[i][k].y), y1 = std::max(y1, screen[i][k].y);
    }
    const int a0 = std::max(0, static_cast<int>(std::floor(x0 / kCell)));
    const int a1 = std::min(cx - 1, static_cast<int>(std::floor(x1 / kCell)));
    const int b0 = std::max(0, static_cast<int>(std::floor(y0 / kCell)));
    const int b1 = std::min(cy - 1, static_cast<int>(std::floor(y1 / kCell)));
    for (int b = b0; b <= b1; ++b)
      for (int a = a0; a <= a1; ++a) cells[static_cast<std::size_t>(b) * cx + a].push_back(i);
  }
  // Barycentric coordinates of (x, y) in screen triangle k; false if degenerate.
  auto barycentric = [&](int k, double x, double y, double& l0, double& l1, double& l2) {
    const auto& v = screen[k];
    const double det =
        (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (v[1].y - v[0].y);
    if (det == 0) return false;
    l1 = ((x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (y - v[0].y)) / det;
    l2 = ((v[1].x - v[0].x) * (y - v[0].y) - (x - v[0].x) * (v[1].y - v[0].y)) / det;
    l0 = 1.0 - l1 - l2;
    return true;
  };
  auto hidden = [&](const glm::dvec3& s, int first, int second) {
    const int a = static_cast<int>(std::floor(s.x / kCell));
    const int b = static_cast<int>(std::floor(s.y / kCell));
    if (a < 0 || b < 0 || a >= cx || b >= cy) return true;
    for (int k : cells[static_cast<std::size_t>(b) * cx + a]) {
      if (k == first || k == second) continue;
      double l0, l1, l2;
      if (!barycentric(k, s.x, s.y, l0, l1, l2)) continue;
      if (l0 < 0 || l1 < 0 || l2 < 0) continue;
      const auto& v = screen[k];
      const double z = l0 * v[0].z + l1 * v[1].z + l2 * v[2].z;  // affine in screen space
      if (z < s.z - 1e-7) return true;
    }
    return false;
  };

  const std::vector<Segment3> segments = intersection_segments(mesh);
  t.segments = segments.size();
  t.curves = segments;
  t.mask.assign(static_cast<std::size_t>(width) * height, 0);
  const int reach = static_cast<int>(std::ceil(delta)) + 1;
  for (std::size_t index = 0; index < segments.size(); ++index) {
    const Segment3& seg = segments[index];
    glm::dvec3 sa, sb;
    if (!project(seg.a, sa) || !project(seg.b, sb)) continue;
    const glm::dvec2 d(sb.x - sa.x, sb.y - sa.y);
    const double length = glm::length(d);
    if (length == 0) continue;
    const glm::dvec2 tangent = d / length;
    const int steps = std::max(1, static_cast<int>(std::ceil(length / spacing)));
    for (int k = 0; k <= steps; ++k) {
      glm::dvec3 s;
      if (!project(glm::mix(seg.a, seg.b, static_cast<double>(k) / steps), s)) continue;
      ++t.samples;
      if (s.x < 0 || s.y < 0 || s.x >= width || s.y >= height) continue;
      if (visible_only && hidden(s, seg.first, seg.second)) continue;
      t.visible.push_back({{s.x, s.y}, tangent, index});
      const int px = static_cast<int>(std::floor(s.x)), py = static_cast<int>(std::floor(s.y));
      for (int y = std::max(0, py - reach); y <= std::min(height - 1, py + reach); ++y) {
        for (int x = std::max(0, px - reach); x <= std::min(width - 1, px + reach); ++x) {
          const double ex = x + 0.5 - s.x, ey = y + 0.5 - s.y;
          if (ex * ex + ey * ey <= delta * delta)
            t.mask[static_cast<std::size_t>(y) * width + x] = 1;
        }
      }
    }
  }
  t.pixels = static_cast<std::size_t>(std::count(t.mask.begin(), t.mask.end(), 1));
  // The recall ceiling: truth pixels whose centre at least two triangles cover.
  t.reached.assign(t.mask.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!t.mask[static_cast<std::size_t>(y) * width + x]) continue;
      const double px = x + 0.5, py = y + 0.5;
      int surfaces = 0;
      for (int k : cells[static_cast<std::size_t>(y / kCell) * cx + x / kCell]) {
        double l0, l1, l2;
        if (barycentric(k, px, py, l0, l1, l2) && l0 >= 0 && l1 >= 0 && l2 >= 0 && ++surfaces == 2)
          break;
      }
      t.reachable += surfaces >= 2;
      t.reached[static_cast<std::size_t>(y) * width + x] = surfaces >= 2;
    }
  }
  return t;
}

namespace {

bool flagged_at(const IntersectionTruth& truth, const std::vector<std::uint8_t>& flagged,
                glm::dvec2 s) {
  const int x = static_cast<int>(std::floor(s.x)), y = static_cast<int>(std::floor(s.y));
  if (x < 0 || y < 0 || x >= truth.width || y >= truth.height) return false;
  return flagged[static_cast<std::size_t>(y) * truth.width + x] != 0;
}

// Width across the curve at one sample: walk along its normal, both ways, in quarter-pixel
// steps while the pixels are flagged. False if the sample's own pixel is not flagged.
bool width_at(const IntersectionTruth& truth, const std::vector<std::uint8_t>& flagged,
              const CurveSample& s, double& w) {
  constexpr double kStep = 0.25;
  constexpr int kMaxSteps = 256;
  if (!flagged_at(truth, flagged, s.screen)) return false;
  const glm::dvec2 normal(-s.tangent.y, s.tangent.x);
  w = kStep;
  for (int dir = -1; dir <= 1; dir += 2) {
    for (int k = 1;
         k <= kMaxSteps && flagged_at(truth, flagged, s.screen + normal * (dir * k * kStep)); ++k)
      w += kStep;
  }
  return true;
}

struct WidthSum {
  double sum = 0, sum2 = 0;
  std::size_t n = 0, samples = 0;
  void finish(Accuracy& a) const {
    a.width_samples = n;
    if (n) {
      a.width_mean = sum / n;
      a.width_sd = std::sqrt(std::max(0.0, sum2 / n - a.width_mean * a.width_mean));
    }
    a.coverage = samples ? static_cast<double>(n) / samples : 0;
  }
};

}  // namespace

Accuracy measure_accuracy(const IntersectionTruth& truth,
                          const std::vector<std::uint8_t>& flagged) {
  Accuracy a;
  for (std::size_t p = 0; p < truth.mask.size(); ++p) {
    a.truth += truth.mask[p];
    a.flagged += flagged[p] != 0;
    a.hits += truth.mask[p] && flagged[p];
  }
  a.recall = a.truth ? static_cast<double>(a.hits) / a.truth : 0;
  a.ceiling = truth.pixels ? static_cast<double>(truth.reachable) / truth.pixels : 0;
  a.precision = a.flagged ? static_cast<double>(a.hits) / a.flagged : 0;
  WidthSum all;
  for (const CurveSample& s : truth.visible) {
    ++all.samples;
    double w = 0;
    if (!width_at(truth, flagged, s, w)) continue;
    all.sum += w;
    all.sum2 += w * w;
    ++all.n;
  }
  all.finish(a);
  return a;
}

std::vector<Accuracy> measure_width_by_segment(const IntersectionTruth& truth,
                                               const std::vector<std::uint8_t>& flagged) {
  std::vector<WidthSum> sums(truth.curves.size());
  for (const CurveSample& s : truth.visible) {
    WidthSum& sum = sums.at(s.segment);
    ++sum.samples;
    double w = 0;
    if (!width_at(truth, flagged, s, w)) continue;
    sum.sum += w;
    sum.sum2 += w * w;
    ++sum.n;
  }
  std::vector<Accuracy> out(sums.size());
  for (std::size_t i = 0; i < sums.size(); ++i) sums[i].finish(out[i]);
  return out;
}

RgbImage overlay_image(const RgbImage& frame, const IntersectionTruth& truth,
                       const std::vector<std::uint8_t>& flagged) {
  RgbImage out = frame;
  for (std::size_t p = 0; p < truth.mask.size(); ++p) {
    std::uint8_t* c = &out.rgb[p * 3];
    const bool t = truth.mask[p] != 0, f = flagged[p] != 0;
    if (t && f) {
      c[0] = 40, c[1] = 255, c[2] = 40;
    } else if (f) {
      c[0] = 255, c[1] = 40, c[2] = 40;
    } else if (t) {
      c[0] = 60, c[1] = 120, c[2] = 255;
    } else {
      for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(c[k] / 3);
    }
  }
  return out;
}

RgbImage truth_image(const RgbImage& frame, const IntersectionTruth& truth) {
  RgbImage out = frame;
  for (std::size_t p = 0; p < truth.mask.size(); ++p) {
    std::uint8_t* c = &out.rgb[p * 3];
    if (!truth.mask[p]) {
      for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(c[k] / 3);
    } else if (truth.reached[p]) {
      c[0] = 255, c[1] = 255, c[2] = 255;
    } else {
      c[0] = 255, c[1] = 150, c[2] = 0;
    }
  }
  return out;
}

RgbImage side_by_side(const RgbImage& left, const RgbImage& right, int gap) {
  RgbImage out;
  out.width = left.width + gap + right.width;
  out.height = std::max(left.height, right.height);
  out.rgb.assign(static_cast<std::size_t>(out.width) * out.height * 3, 128);
  auto blit = [&out](const RgbImage& image, int x0) {
    for (int y = 0; y < image.height; ++y) {
      std::copy_n(&image.rgb[static_cast<std::size_t>(y) * image.width * 3],
                  static_cast<std::size_t>(image.width) * 3,
                  &out.rgb[(static_cast<std::size_t>(y) * out.width + x0) * 3]);
    }
  };
  blit(left, 0);
  blit(right, left.width + gap);
  return out;
}

}  // namespace pp5
