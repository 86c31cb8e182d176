// The CPU side of visible_surface.hpp: projection, the exact reference, scan-line, Warnock,
// and the comparison of visibility images.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "sim/analysis/visible_surface.hpp"

namespace pp5 {

namespace {

// A polygon ready for pixel work: edges as signed distances (inside >= 0) and the depth
// plane z = zx x + zy y + z0.
struct Prepared {
  std::vector<glm::dvec3> edge;  // (a, b, c): a x + b y + c, unit (a, b), >= 0 inside
  double zx = 0, zy = 0, z0 = 0;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  int id = -1;
  const ScreenPolygon* source = nullptr;
  bool valid = false;
  double depth(double x, double y) const { return zx * x + zy * y + z0; }
  // The least signed distance of (x, y) to the edges: >= 0 inside.
  double inside(double x, double y) const {
    double m = std::numeric_limits<double>::infinity();
    for (const glm::dvec3& e : edge) m = std::min(m, e.x * x + e.y * y + e.z);
    return m;
  }
};

Prepared prepare(const ScreenPolygon& p) {
  Prepared r;
  r.id = p.source;
  r.source = &p;
  const std::size_t n = p.v.size();
  double area2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3& a = p.v[i];
    const glm::dvec3& b = p.v[(i + 1) % n];
    area2 += a.x * b.y - b.x * a.y;
  }
  if (n < 3 || std::abs(area2) < 1e-12) return r;
  const double sigma = area2 > 0 ? 1.0 : -1.0;
  r.x0 = r.x1 = p.v[0].x;
  r.y0 = r.y1 = p.v[0].y;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3& a = p.v[i];
    const glm::dvec3& b = p.v[(i + 1) % n];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len == 0) continue;
    // With y down and counter-clockwise area positive, inside lies to the left of a -> b.
    const double ea = -sigma * (b.y - a.y) / len, eb = sigma * (b.x - a.x) / len;
    r.edge.emplace_back(ea, eb, -(ea * a.x + eb * a.y));
    r.x0 = std::min(r.x0, a.x);
    r.x1 = std::max(r.x1, a.x);
    r.y0 = std::min(r.y0, a.y);
    r.y1 = std::max(r.y1, a.y);
  }
  // The depth plane through the first three vertices, solved in screen space.
  const glm::dvec3 &a = p.v[0], &b = p.v[1], &c = p.v[2];
  const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
  if (std::abs(det) < 1e-12) return r;
  r.zx = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / det;
  r.zy = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / det;
  r.z0 = a.z - r.zx * a.x - r.zy * a.y;
  r.valid = true;
  return r;
}

std::vector<Prepared> prepare_all(const std::vector<ScreenPolygon>& polygons) {
  std::vector<Prepared> out;
  out.reserve(polygons.size());
  for (const ScreenPolygon& p : polygons) {
    Prepared q = prepare(p);
    if (q.valid) out.push_back(std::move(q));
  }
  return out;
}

// Pixel index range [lo, hi] whose centres X + 0.5 lie in [a, b].
void pixel_range(double a, double b, int limit, int& lo, int& hi) {
  lo = std::max(0, static_cast<int>(std::ceil(a - 0.5)));
  hi = std::min(limit - 1, static_cast<int>(std::floor(b - 0.5)));
}

}  // namespace

std::vector<ScreenPolygon> project_scene(const MachineConfig& config, const Scene& scene) {
  const GeometryEngine geometry(geometry_params(config), scene);
  std::vector<ScreenPolygon> out;
  std::vector<ScreenTriangle> pieces;
  SetupCounts counts;
  for (int t = 0; t < static_cast<int>(scene.mesh.triangles.size()); ++t) {
    pieces.clear();
    geometry.transform(t, pieces, counts);
    if (pieces.empty()) continue;
    // transform() makes a fan around the polygon's first vertex: join it back.
    ScreenPolygon p;
    p.source = t;
    auto point = [](const ScreenVertex& v) { return glm::dvec3(v.position, v.depth); };
    p.v = {point(pieces[0].v[0]), point(pieces[0].v[1])};
    p.w = {pieces[0].v[0].eye_depth, pieces[0].v[1].eye_depth};
    for (const ScreenTriangle& s : pieces) {
      p.v.push_back(point(s.v[2]));
      p.w.push_back(s.v[2].eye_depth);
    }
    out.push_back(std::move(p));
  }
  return out;
}

ReferenceImage exact_reference(const std::vector<ScreenPolygon>& polygons, int width, int height,
                               int subpixel_bits, int depth_bits) {
  const double margin = std::ldexp(1.0, -subpixel_bits);
  // Two depths closer than the machine's arithmetic can order: 16 units of its depth, plus
  // what snapping the vertices by up to `margin` moves each plane at the pixel.
  const double unit_slack = 16.0 * std::ldexp(1.0, -depth_bits);
  const double inf = std::numeric_limits<double>::infinity();
  const auto pixels = static_cast<std::size_t>(width) * height;
  ReferenceImage r;
  r.width = width;
  r.height = height;
  r.id.assign(pixels, -1);
  r.uncertain.assign(pixels, 0);
  std::vector<double> best(pixels, inf), certain1(pixels, inf), certain2(pixels, inf),
      maybe(pixels, inf), slack1(pixels, 0), slack2(pixels, 0);
  for (const ScreenPolygon& poly : polygons) {
    const Prepared p = prepare(poly);
    if (!p.valid) continue;
    const double slack = unit_slack + 2.0 * margin * (std::abs(p.zx) + std::abs(p.zy));
    int x_lo, x_hi, y_lo, y_hi;
    pixel_range(p.x0 - margin, p.x1 + margin, width, x_lo, x_hi);
    pixel_range(p.y0 - margin, p.y1 + margin, height, y_lo, y_hi);
    for (int y = y_lo; y <= y_hi; ++y) {
      for (int x = x_lo; x <= x_hi; ++x) {
        const double cx = x + 0.5, cy = y + 0.5;
        const double m = p.inside(cx, cy);
        if (m <= -margin) continue;
        const double z = p.depth(cx, cy);
        const std::size_t k = static_cast<std::size_t>(y) * width + x;
        // The ray through the centre: the nearest polygon whose closed interior it meets.
        if (m >= 0 && (z < best[k] || (z == best[k] && p.id < r.id[k]))) {
          best[k] = z;
          r.id[k] = p.id;
        }
        if (m >= margin) {
          if (z < certain1[k]) {
            certain2[k] = certain1[k];
            slack2[k] = slack1[k];
            certain1[k] = z;
            slack1[k] = slack;
          } else if (z < certain2[k]) {
            certain2[k] = z;
            slack2[k] = slack;
          }
        } else {
          maybe[k] = std::min(maybe[k], z - slack);
        }
      }
    }
  }
  for (std::size_t k = 0; k < pixels; ++k) {
    // Near an edge of a polygon that could be the nearest, or two nearest depths too close
    // for the machine's depth arithmetic to order as the reference does.
    if (maybe[k] < inf && maybe[k] < certain1[k] + slack1[k]) r.uncertain[k] = 1;
    if (certain2[k] < inf && certain2[k] - certain1[k] < slack1[k] + slack2[k]) r.uncertain[k] = 1;
  }
  return r;
}

IdImage scanline_visible(const std::vector<ScreenPolygon>& polygons, int width, int height,
                         ScanlineWork& work) {
  const std::vector<Prepared> prep = prepare_all(polygons);
  IdImage img;
  img.width = width;
  img.height = height;
  img.id.assign(static_cast<std::size_t>(width) * height, -1);
  // The edge table: each non-horizontal edge filed under the first scan line whose centre
  // it spans; active while y + 0.5 lies in [y_lo, y_hi).
  struct Edge {
    double x;     // at the current scan line's centre
    double dxdy;  // x step per scan line (edge coherence)
    int last;     // last scan line
    int polygon;  // index into prep
  };
  std::vector<std::vector<Edge>> table(static_cast<std::size_t>(height));
  for (int i = 0; i < static_cast<int>(prep.size()); ++i) {
    const ScreenPolygon* src = prep[i].source;
    const std::size_t n = src->v.size();
    for (std::size_t e = 0; e < n; ++e) {
      glm::dvec3 a = src->v[e], b = src->v[(e + 1) % n];
      if (a.y == b.y) continue;
      if (a.y > b.y) std::swap(a, b);
      const int first = std::max(0, static_cast<int>(std::ceil(a.y - 0.5)));
      const int last = std::min(height - 1, static_cast<int>(std::ceil(b.y - 0.5)) - 1);
      if (first > last) continue;
      const double dxdy = (b.x - a.x) / (b.y - a.y);
      table[first].push_back({a.x + (first + 0.5 - a.y) * dxdy, dxdy, last, i});
      ++work.edges;
    }
  }
  std::vector<Edge> active;
  std::vector<std::pair<double, int>> crossings;
  std::vector<int> inside_count(prep.size(), 0);
  std::vector<int> open;
  for (int y = 0; y < height; ++y) {
    const double cy = y + 0.5;
    active.erase(
        std::remove_if(active.begin(), active.end(), [y](const Edge& e) { return e.last < y; }),
        active.end());
    active.insert(active.end(), table[y].begin(), table[y].end());
    crossings.clear();
    for (const Edge& e : active) crossings.emplace_back(e.x, e.polygon);
    std::sort(crossings.begin(), crossings.end());
    work.crossings += crossings.size();
    open.clear();
    int* row = img.id.data() + static_cast<std::size_t>(y) * width;
    // Resolves [xl, xr) for the open polygons, splitting where the two candidates cross.
    std::function<void(double, double, int)> resolve = [&](double xl, double xr, int level) {
      int lo, hi;
      pixel_range(xl, xr, width, lo, hi);
      if (xr - 0.5 == hi) --hi;  // half-open: a centre at xr belongs to the next span
      if (lo > hi || open.empty()) return;
      ++work.spans;
      const double a = lo + 0.5, b = hi + 0.5;
      int front_a = open[0], front_b = open[0];
      for (int p : open) {
        work.depth_comparisons += 2;
        if (prep[p].depth(a, cy) < prep[front_a].depth(a, cy)) front_a = p;
        if (prep[p].depth(b, cy) < prep[front_b].depth(b, cy)) front_b = p;
      }
      if (front_a == front_b || level > 32) {
        if (front_a == front_b) {
          for (int x = lo; x <= hi; ++x) row[x] = prep[front_a].id;
        } else {
          for (int x = lo; x <= hi; ++x) {
            int f = open[0];
            for (int p : open) {
              if (prep[p].depth(x + 0.5, cy) < prep[f].depth(x + 0.5, cy)) f = p;
            }
            row[x] = prep[f].id;
          }
        }
        return;
      }
      // The two fronts cross inside the span: split it where their depths are equal.
      const double da = prep[front_a].depth(a, cy) - prep[front_b].depth(a, cy);
      const double db = prep[front_a].depth(b, cy) - prep[front_b].depth(b, cy);
      double xs = a + (b - a) * da / (da - db);
      if (!(xs > a && xs <= b)) xs = 0.5 * (a + b);
      ++work.splits;
      resolve(std::max(xl, a - 0.5), xs, level + 1);
      resolve(xs, xr, level + 1);
    };
    double x_prev = 0;
    for (const auto& [x, p] : crossings) {
      resolve(x_prev, x, 0);
      x_prev = x;
      if (++inside_count[p] % 2 == 1) {
        open.push_back(p);
      } else {
        open.erase(std::find(open.begin(), open.end(), p));
      }
    }
    for (int p : open) inside_count[p] = 0;
    for (Edge& e : active) e.x += e.dxdy;
  }
  return img;
}

IdImage warnock_visible(const std::vector<ScreenPolygon>& polygons, int width, int height,
                        WarnockWork& work) {
  const std::vector<Prepared> prep = prepare_all(polygons);
  IdImage img;
  img.width = width;
  img.height = height;
  img.id.assign(static_cast<std::size_t>(width) * height, -1);
  enum class Relation { disjoint, surrounding, intersecting, contained };
  // The area is the rectangle of its pixel centres.
  auto relate = [&](const Prepared& p, double ax0, double ay0, double ax1, double ay1) {
    if (p.x1 < ax0 || p.x0 > ax1 || p.y1 < ay0 || p.y0 > ay1) return Relation::disjoint;
    bool all_in = true;
    for (const glm::dvec3& e : p.edge) {
      const double f[4] = {e.x * ax0 + e.y * ay0 + e.z, e.x * ax1 + e.y * ay0 + e.z,
                           e.x * ax0 + e.y * ay1 + e.z, e.x * ax1 + e.y * ay1 + e.z};
      const bool out = f[0] < 0 && f[1] < 0 && f[2] < 0 && f[3] < 0;
      if (out) return Relation::disjoint;
      if (f[0] < 0 || f[1] < 0 || f[2] < 0 || f[3] < 0) all_in = false;
    }
    if (all_in) return Relation::surrounding;
    if (p.x0 >= ax0 && p.x1 <= ax1 && p.y0 >= ay0 && p.y1 <= ay1) return Relation::contained;
    return Relation::intersecting;
  };
  auto fill = [&](int x0, int y0, int x1, int y1, int id) {
    for (int y = y0; y < y1; ++y)
      std::fill(img.id.begin() + static_cast<std::ptrdiff_t>(y) * width + x0,
                img.id.begin() + static_cast<std::ptrdiff_t>(y) * width + x1, id);
  };
  std::function<void(int, int, int, int, const std::vector<int>&, int)> area =
      [&](int x0, int y0, int x1, int y1, const std::vector<int>& candidates, int level) {
        ++work.areas;
        work.max_level = std::max(work.max_level, level);
        const double ax0 = x0 + 0.5, ay0 = y0 + 0.5, ax1 = x1 - 0.5, ay1 = y1 - 0.5;
        std::vector<int> present, surrounding;
        for (int p : candidates) {
          const Relation r = relate(prep[p], ax0, ay0, ax1, ay1);
          if (r == Relation::disjoint) continue;
          present.push_back(p);
          if (r == Relation::surrounding) surrounding.push_back(p);
        }
        // All polygons disjoint from the area: background.
        if (present.empty()) {
          ++work.empty;
          return;
        }
        // One intersecting or contained polygon: background, then the polygon's part.
        if (present.size() == 1 && surrounding.empty()) {
          ++work.single;
          const Prepared& p = prep[present[0]];
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
              if (p.inside(x + 0.5, y + 0.5) >= 0)
                img.id[static_cast<std::size_t>(y) * width + x] = p.id;
          return;
        }
        // A single surrounding polygon and nothing else.
        if (present.size() == 1) {
          ++work.surrounding;
          fill(x0, y0, x1, y1, prep[present[0]].id);
          return;
        }
        // A surrounding polygon nearer at the four corners than every other polygon's
        // plane is anywhere over the area (a plane's extremes are at the corners).
        for (int s : surrounding) {
          const Prepared& ps = prep[s];
          const double far = std::max(
              {ps.depth(ax0, ay0), ps.depth(ax1, ay0), ps.depth(ax0, ay1), ps.depth(ax1, ay1)});
          bool front = true;
          for (int p : present) {
            if (p == s) continue;
            const Prepared& q = prep[p];
            const double near = std::min(
                {q.depth(ax0, ay0), q.depth(ax1, ay0), q.depth(ax0, ay1), q.depth(ax1, ay1)});
            if (!(far < near)) {
              front = false;
              break;
            }
          }
          if (front) {
            ++work.front_surrounding;
            fill(x0, y0, x1, y1, ps.id);
            return;
          }
        }
        // At the resolution of the display: the nearest polygon through the pixel centre.
        if (x1 - x0 == 1 && y1 - y0 == 1) {
          ++work.pixels;
          double best = std::numeric_limits<double>::infinity();
          int id = -1;
          for (int p : present) {
            const Prepared& q = prep[p];
            if (q.inside(ax0, ay0) < 0) continue;
            const double z = q.depth(ax0, ay0);
            if (z < best || (z == best && q.id < id)) {
              best = z;
              id = q.id;
            }
          }
          img.id[static_cast<std::size_t>(y0) * width + x0] = id;
          return;
        }
        const int xm = x1 - x0 > 1 ? (x0 + x1) / 2 : x1;
        const int ym = y1 - y0 > 1 ? (y0 + y1) / 2 : y1;
        area(x0, y0, xm, ym, present, level + 1);
        if (xm < x1) area(xm, y0, x1, ym, present, level + 1);
        if (ym < y1) area(x0, ym, xm, y1, present, level + 1);
        if (xm < x1 && ym < y1) area(xm, ym, x1, y1, present, level + 1);
      };
  std::vector<int> all(prep.size());
  for (std::size_t i = 0; i < prep.size(); ++i) all[i] = static_cast<int>(i);
  area(0, 0, width, height, all, 0);
  return img;
}

Difference compare_visibility(const IdImage& image, const ReferenceImage& reference,
                              int region_width, int region_height) {
  Difference d;
  const int rx = (reference.width + region_width - 1) / region_width;
  const int ry = (reference.height + region_height - 1) / region_height;
  std::vector<std::uint64_t> per_region(static_cast<std::size_t>(rx) * ry, 0);
  for (int y = 0; y < reference.height; ++y) {
    for (int x = 0; x < reference.width; ++x) {
      const std::size_t k = static_cast<std::size_t>(y) * reference.width + x;
      if (image.id[k] == reference.id[k]) continue;
      if (reference.uncertain[k]) {
        ++d.uncertain;
        continue;
      }
      ++d.differing;
      ++per_region[static_cast<std::size_t>(y / region_height) * rx + x / region_width];
    }
  }
  for (std::size_t r = 0; r < per_region.size(); ++r) {
    if (per_region[r] == 0) continue;
    ++d.regions;
    if (per_region[r] > d.densest) {
      d.densest = per_region[r];
      d.densest_region = static_cast<int>(r);
    }
  }
  return d;
}

RgbImage difference_image(const IdImage& image, const ReferenceImage& reference) {
  RgbImage out;
  out.width = reference.width;
  out.height = reference.height;
  out.rgb.assign(static_cast<std::size_t>(out.width) * out.height * 3, 0);
  for (std::size_t k = 0; k < reference.id.size(); ++k) {
    std::uint8_t* px = &out.rgb[3 * k];
    if (image.id[k] != reference.id[k]) {
      px[0] = reference.uncertain[k] ? 110 : 255;
      px[1] = reference.uncertain[k] ? 110 : 30;
      px[2] = reference.uncertain[k] ? 0 : 30;
    } else if (reference.id[k] >= 0) {
      const auto g =
          static_cast<std::uint8_t>(60 + (static_cast<unsigned>(reference.id[k]) * 37u) % 80u);
      px[0] = px[1] = px[2] = g;
    }
  }
  return out;
}

Scene visibility_scene(const Scene& scene, const std::vector<int>& order) {
  Scene s = scene;
  s.mesh.vertices.clear();
  s.mesh.triangles.clear();
  std::vector<int> sequence = order;
  if (sequence.empty()) {
    for (int t = 0; t < static_cast<int>(scene.mesh.triangles.size()); ++t) sequence.push_back(t);
  }
  for (int t : sequence) {
    const unsigned id = static_cast<unsigned>(t) + 1;
    const glm::vec3 colour((static_cast<float>(id & 0xFF) + 0.5f) / 255.0f,
                           (static_cast<float>((id >> 8) & 0xFF) + 0.5f) / 255.0f,
                           (static_cast<float>((id >> 16) & 0xFF) + 0.5f) / 255.0f);
    const auto base = static_cast<unsigned>(s.mesh.vertices.size());
    for (int k = 0; k < 3; ++k) {
      Vertex v = scene.mesh.vertices[scene.mesh.triangles[static_cast<std::size_t>(t)][k]];
      v.color = colour;
      s.mesh.vertices.push_back(v);
    }
    s.mesh.triangles.emplace_back(base, base + 1, base + 2);
  }
  s.background = glm::vec3(0.0f);
  return s;
}

IdImage decode_visibility(const RgbImage& frame) {
  IdImage img;
  img.width = frame.width;
  img.height = frame.height;
  img.id.resize(static_cast<std::size_t>(frame.width) * frame.height);
  for (std::size_t k = 0; k < img.id.size(); ++k) {
    const unsigned id =
        frame.rgb[3 * k] | (frame.rgb[3 * k + 1] << 8) | (frame.rgb[3 * k + 2] << 16);
    img.id[k] = static_cast<int>(id) - 1;
  }
  return img;
}

}  // namespace pp5
