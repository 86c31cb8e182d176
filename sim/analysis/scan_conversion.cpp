#include "sim/analysis/scan_conversion.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "models/display_list/mesh_adjacency.hpp"
#include "models/gp/expressions.hpp"
#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "sim/analysis/analysis_firmware.hpp"
#include "sim/analysis/extremes.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

const std::string kAccurateCoverageFirmware = coverage_firmware(
    "Coverage counter with accurate.pp5's tests: each triangle adds 1 to every pixel whose "
    "centre it owns by the enlarged area and the three side tests.",
    {"wide0", "wide1", "wide2", "side0", "side1", "side2"});

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A screen triangle's exact plane in double precision: depth z0 + a (x - p0.x) + b (y - p0.y)
// in depth units, and its coverage (edge functions oriented by the sign of det).
struct ExactPlane {
  glm::dvec2 p0, p1, p2;
  double det = 0, s = 1, z0 = 0, a = 0, b = 0;
  static std::optional<ExactPlane> of(const ScreenTriangle& t, double depth_max) {
    ExactPlane e;
    e.p0 = t.v[0].position, e.p1 = t.v[1].position, e.p2 = t.v[2].position;
    const glm::dvec2 p0 = e.p0, p1 = e.p1, p2 = e.p2;
    e.det = (p1.x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (p1.y - p0.y);
    if (!(std::fabs(e.det) > 0)) return std::nullopt;
    const double z0 = t.v[0].depth * depth_max, z1 = t.v[1].depth * depth_max,
                 z2 = t.v[2].depth * depth_max;
    e.z0 = z0;
    e.a = ((z1 - z0) * (p2.y - p0.y) - (z2 - z0) * (p1.y - p0.y)) / e.det;
    e.b = ((z2 - z0) * (p1.x - p0.x) - (z1 - z0) * (p2.x - p0.x)) / e.det;
    e.s = e.det > 0 ? 1.0 : -1.0;
    return e;
  }
  double depth(double x, double y) const { return z0 + a * (x - p0.x) + b * (y - p0.y); }
  bool covers(double cx, double cy) const {
    return s * ((p1.x - p0.x) * (cy - p0.y) - (p1.y - p0.y) * (cx - p0.x)) >= 0 &&
           s * ((p2.x - p1.x) * (cy - p1.y) - (p2.y - p1.y) * (cx - p1.x)) >= 0 &&
           s * ((p0.x - p2.x) * (cy - p2.y) - (p0.y - p2.y) * (cx - p2.x)) >= 0;
  }
};

// The exact picture: per pixel the frontmost depth, the first hidden one, and whether the
// centre is within max(1, E) of any triangle's edge.
struct Reference {
  int width = 0, height = 0;
  std::vector<double> front, hidden;
  std::vector<std::uint8_t> near_edge;
  // Per pixel, for the 2ME bound: whether the centre is within 2E of a boundary, silhouette
  // or clipped edge (where a misclassified centre changes layer, not plane), and the largest
  // depth gradient of the two faces of any shared edge within 2E.
  std::vector<std::uint8_t> layer_edge;
  std::vector<float> local_m;
  // For the translated-layer bound, per pixel with layer_edge set and covered (indexed by
  // layer_index): the exact front depth at each sample point of the disc of radius
  // kLayerReach E about the centre (infinity where no triangle covers it), and the largest
  // depth gradient of the triangles within E of the centre.
  std::vector<int> layer_index;
  std::vector<double> layer_front;
  std::vector<float> layer_m;
  int samples = 0;
  double M = 0;
};

// Sample offsets (in units of E) of the translated-layer disc: a grid of step 1/4 within
// kLayerReach, so that every point within E of the centre has a sample within sqrt(2)/8 E.
std::vector<glm::dvec2> layer_offsets() {
  std::vector<glm::dvec2> out;
  for (int j = -5; j <= 5; ++j) {
    for (int i = -5; i <= 5; ++i) {
      const glm::dvec2 o(i / 4.0, j / 4.0);
      if (glm::length(o) <= kLayerReach + 1e-9) out.push_back(o);
    }
  }
  return out;
}

double distance_to_segment(double px, double py, const glm::dvec2& a, const glm::dvec2& b) {
  const glm::dvec2 d = b - a;
  const double len2 = glm::dot(d, d);
  double t = len2 > 0 ? glm::dot(glm::dvec2(px, py) - a, d) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const glm::dvec2 q = a + d * t;
  return std::hypot(px - q.x, py - q.y);
}

// Calls visit(q) for every pixel whose centre lies within r of the segment a-b, once each,
// row by row. The centres within r form a capsule (the segment's band and a disc at each end),
// which is convex, so each row meets it in one interval: the row's candidates are that
// interval, widened by a pixel each way, and each is kept by the exact distance test. The
// work is the band's area, not its bounding box's (a long diagonal edge's box is mostly
// empty).
template <typename Visit>
void near_segment(const glm::dvec2& a, const glm::dvec2& b, double r, int width, int height,
                  Visit visit) {
  const int y_lo = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y) - r - 0.5)));
  const int y_hi = std::min(height - 1, static_cast<int>(std::ceil(std::max(a.y, b.y) + r)));
  const glm::dvec2 d = b - a;
  const double len = glm::length(d);
  // The band's corners: the segment moved by r along its normal, each way.
  const glm::dvec2 n = len > 0 ? glm::dvec2(-d.y, d.x) * (r / len) : glm::dvec2(0.0);
  const glm::dvec2 corner[4] = {a + n, b + n, b - n, a - n};
  for (int y = y_lo; y <= y_hi; ++y) {
    const double cy = y + 0.5;
    double lo = kInfinity, hi = -kInfinity;
    for (const glm::dvec2& c : {a, b}) {
      const double dy = cy - c.y;
      if (std::fabs(dy) > r) continue;
      const double w = std::sqrt(r * r - dy * dy);
      lo = std::min(lo, c.x - w);
      hi = std::max(hi, c.x + w);
    }
    for (int k = 0; k < 4; ++k) {
      const glm::dvec2 p = corner[k], q = corner[(k + 1) % 4];
      if ((p.y - cy) * (q.y - cy) > 0) continue;
      if (p.y == q.y) {
        lo = std::min({lo, p.x, q.x});
        hi = std::max({hi, p.x, q.x});
        continue;
      }
      const double x = p.x + (cy - p.y) * (q.x - p.x) / (q.y - p.y);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    if (lo > hi) continue;
    lo = std::clamp(lo, -2.0, width + 2.0);
    hi = std::clamp(hi, -2.0, width + 2.0);
    const int x_lo = std::max(0, static_cast<int>(std::floor(lo - 0.5)) - 1);
    const int x_hi = std::min(width - 1, static_cast<int>(std::ceil(hi - 0.5)) + 1);
    for (int x = x_lo; x <= x_hi; ++x) {
      if (distance_to_segment(x + 0.5, cy, a, b) <= r)
        visit(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + x);
    }
  }
}

Reference reference(const MachineConfig& config, const Scene& scene, double E) {
  const GeometryEngine geometry(geometry_params(config), scene);
  Reference r;
  r.width = config.screen.width;
  r.height = config.screen.height;
  const std::size_t n = static_cast<std::size_t>(r.width) * r.height;
  r.front.assign(n, kInfinity);
  r.hidden.assign(n, kInfinity);
  std::vector<int> owner(n, -1);
  const double depth_max = std::ldexp(1.0, config.gp.depth_bits) - 1.0;
  std::vector<ScreenTriangle> pieces;
  SetupCounts counts;
  // The reference projects the scene itself, from the camera's view and projection in double
  // (no code of the GP's transform): a triangle wholly inside the view volume is one piece.
  // Only a triangle the view volume clips is taken from the GP's transform, which clips it.
  const float aspect = static_cast<float>(config.screen.width) / static_cast<float>(r.height);
  const glm::dmat4 view_projection =
      glm::dmat4(projection_matrix(scene.camera, aspect)) * glm::dmat4(view_matrix(scene.camera));
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    ScreenTriangle t;
    t.source = i;
    bool inside = true;
    for (int k = 0; k < 3 && inside; ++k) {
      const glm::dvec3 p(
          scene.mesh.vertices[scene.mesh.triangles[static_cast<std::size_t>(i)][k]].position);
      const glm::dvec4 c = view_projection * glm::dvec4(p, 1.0);
      inside = c.w > 0 && std::fabs(c.x) <= c.w && std::fabs(c.y) <= c.w && std::fabs(c.z) <= c.w;
      if (!inside) break;
      const glm::dvec3 ndc = glm::dvec3(c) / c.w;
      t.v[static_cast<std::size_t>(k)].position = {(ndc.x * 0.5 + 0.5) * r.width,
                                                   (0.5 - ndc.y * 0.5) * r.height};
      t.v[static_cast<std::size_t>(k)].depth = std::clamp(ndc.z * 0.5 + 0.5, 0.0, 1.0);
    }
    if (inside) {
      pieces.push_back(t);
    } else {
      geometry.transform(i, pieces, counts);
    }
  }
  // Per scene triangle: its one whole piece, or -1 if it was clipped into several or away.
  std::vector<int> whole(scene.mesh.triangles.size(), -1);
  std::vector<int> piece_count(scene.mesh.triangles.size(), 0);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const auto source = static_cast<std::size_t>(pieces[k].source);
    if (++piece_count[source] == 1) whole[source] = static_cast<int>(k);
  }
  for (std::size_t t = 0; t < whole.size(); ++t) {
    if (piece_count[t] != 1) whole[t] = -1;
  }
  std::vector<double> gradient(pieces.size(), 0.0);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const std::optional<ExactPlane> plane = ExactPlane::of(pieces[k], depth_max);
    if (!plane) continue;
    const glm::dvec2 p0 = plane->p0, p1 = plane->p1, p2 = plane->p2;
    gradient[k] = std::hypot(plane->a, plane->b);
    r.M = std::max(r.M, gradient[k]);
    const int x_lo = std::max(0, static_cast<int>(std::floor(std::min({p0.x, p1.x, p2.x}))));
    const int x_hi =
        std::min(r.width - 1, static_cast<int>(std::ceil(std::max({p0.x, p1.x, p2.x}))));
    const int y_lo = std::max(0, static_cast<int>(std::floor(std::min({p0.y, p1.y, p2.y}))));
    const int y_hi =
        std::min(r.height - 1, static_cast<int>(std::ceil(std::max({p0.y, p1.y, p2.y}))));
    for (int y = y_lo; y <= y_hi; ++y) {
      const double cy = y + 0.5;
      for (int x = x_lo; x <= x_hi; ++x) {
        const double cx = x + 0.5;
        if (!plane->covers(cx, cy)) continue;
        const double z = plane->depth(cx, cy);
        const std::size_t q = static_cast<std::size_t>(y) * r.width + x;
        if (z < r.front[q]) {
          r.hidden[q] = r.front[q];
          r.front[q] = z;
          owner[q] = static_cast<int>(k);
        } else if (z < r.hidden[q]) {
          r.hidden[q] = z;
        }
      }
    }
  }
  // The bound's terms at each covered centre, from its front triangle F: a centre within 2E
  // of an edge of F that is a boundary, a silhouette or clipped may change layer; one within
  // 2E of a shared edge may take the neighbour's plane, and one within 2E of a corner any
  // plane of the triangles around that corner.
  const MeshAdjacency adjacency = build_mesh_adjacency(scene.mesh);
  std::vector<std::vector<int>> around(scene.mesh.vertices.size());
  for (std::size_t t = 0; t < scene.mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) around[scene.mesh.triangles[t][k]].push_back(static_cast<int>(t));
  }
  const double reach = 2.0 * E;
  r.layer_edge.assign(n, 0);
  r.local_m.assign(n, 0.0f);
  auto side = [](const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) > 0;
  };
  auto gradient_of = [&](int triangle) {
    const int k = whole[static_cast<std::size_t>(triangle)];
    return k >= 0 ? gradient[static_cast<std::size_t>(k)] : kInfinity;
  };
  // Whether the edge of piece k is a silhouette (both faces on one side of it on the screen),
  // a boundary, or an edge of a clipped triangle: any of them may hand a centre to another
  // layer, whichever triangle is in front there.
  auto layer_changing = [&](std::size_t k, int e) {
    const ScreenTriangle& t = pieces[k];
    const int f = t.source;
    const int nb = adjacency.across(f, e);
    const int nk = nb >= 0 ? whole[static_cast<std::size_t>(nb)] : -1;
    if (whole[static_cast<std::size_t>(f)] < 0 || nk < 0) return true;
    const glm::uvec3 tf = scene.mesh.triangles[static_cast<std::size_t>(f)];
    const glm::uvec3 tn = scene.mesh.triangles[static_cast<std::size_t>(nb)];
    int third = 0;
    while (tn[third] == tf[e] || tn[third] == tf[(e + 1) % 3]) ++third;
    const glm::dvec2 a = t.v[e].position, b = t.v[(e + 1) % 3].position;
    return side(a, b, t.v[(e + 2) % 3].position) ==
           side(a, b, pieces[static_cast<std::size_t>(nk)].v[third].position);
  };
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    for (int e = 0; e < 3; ++e) {
      if (!layer_changing(k, e)) continue;
      near_segment(pieces[k].v[e].position, pieces[k].v[(e + 1) % 3].position, reach, r.width,
                   r.height, [&](std::size_t q) { r.layer_edge[q] = 1; });
    }
  }
  for (std::size_t q = 0; q < n; ++q) {
    if (owner[q] < 0) continue;
    const ScreenTriangle& t = pieces[static_cast<std::size_t>(owner[q])];
    const int f = t.source;
    const glm::uvec3 tf = scene.mesh.triangles[static_cast<std::size_t>(f)];
    const double cx = static_cast<double>(q % static_cast<std::size_t>(r.width)) + 0.5;
    const double cy = static_cast<double>(q / static_cast<std::size_t>(r.width)) + 0.5;
    double m = gradient[static_cast<std::size_t>(owner[q])];
    bool layer = false;
    for (int e = 0; e < 3; ++e) {
      const glm::dvec2 a = t.v[e].position, b = t.v[(e + 1) % 3].position;
      if (whole[static_cast<std::size_t>(f)] < 0) {
        layer = true;
        break;
      }
      if (std::hypot(cx - a.x, cy - a.y) <= reach) {
        for (int g : around[tf[e]]) m = std::max(m, gradient_of(g));
      }
      if (distance_to_segment(cx, cy, a, b) > reach) continue;
      const int nb = adjacency.across(f, e);
      const int nk = nb >= 0 ? whole[static_cast<std::size_t>(nb)] : -1;
      if (nk < 0) {
        layer = true;
        continue;
      }
      const glm::uvec3 tn = scene.mesh.triangles[static_cast<std::size_t>(nb)];
      int third = 0;
      while (tn[third] == tf[e] || tn[third] == tf[(e + 1) % 3]) ++third;
      // The faces on one side of the edge on the screen: a silhouette.
      if (side(a, b, t.v[(e + 2) % 3].position) ==
          side(a, b, pieces[static_cast<std::size_t>(nk)].v[third].position))
        layer = true;
      m = std::max(m, gradient[static_cast<std::size_t>(nk)]);
    }
    if (layer) r.layer_edge[q] = 1;
    r.local_m[q] = static_cast<float>(m);
  }
  // Edge pixels: centres within max(1, E) of an edge of any triangle drawn, not only the front
  // one's: a hidden triangle's (the programs classify centres there too) and a nearer one's
  // that passes beside the centre (its rounded edge may claim it), each edge's band rasterised.
  r.near_edge.assign(n, 0);
  const double edge_reach = std::max(1.0, E);
  for (const ScreenTriangle& t : pieces) {
    for (int e = 0; e < 3; ++e) {
      near_segment(t.v[e].position, t.v[(e + 1) % 3].position, edge_reach, r.width, r.height,
                   [&](std::size_t q) { r.near_edge[q] = 1; });
    }
  }
  // The translated-layer samples and gradients, over the covered pixels near a layer edge.
  const std::vector<glm::dvec2> offsets = layer_offsets();
  r.samples = static_cast<int>(offsets.size());
  r.layer_index.assign(n, -1);
  int layers = 0;
  for (std::size_t q = 0; q < n; ++q) {
    if (r.layer_edge[q] && owner[q] >= 0) r.layer_index[q] = layers++;
  }
  r.layer_front.assign(static_cast<std::size_t>(layers) * offsets.size(), kInfinity);
  r.layer_m.assign(static_cast<std::size_t>(layers), 0.0f);
  const double rho = kLayerReach * E;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const ScreenTriangle& t = pieces[k];
    const std::optional<ExactPlane> plane = ExactPlane::of(t, depth_max);
    if (!plane) continue;
    const glm::dvec2 p0 = plane->p0, p1 = plane->p1, p2 = plane->p2;
    auto inside = [&](double cx, double cy) { return plane->covers(cx, cy); };
    const int x_lo =
        std::max(0, static_cast<int>(std::floor(std::min({p0.x, p1.x, p2.x}) - rho - 1)));
    const int x_hi =
        std::min(r.width - 1, static_cast<int>(std::ceil(std::max({p0.x, p1.x, p2.x}) + rho)));
    const int y_lo =
        std::max(0, static_cast<int>(std::floor(std::min({p0.y, p1.y, p2.y}) - rho - 1)));
    const int y_hi =
        std::min(r.height - 1, static_cast<int>(std::ceil(std::max({p0.y, p1.y, p2.y}) + rho)));
    for (int y = y_lo; y <= y_hi; ++y) {
      for (int x = x_lo; x <= x_hi; ++x) {
        const std::size_t q = static_cast<std::size_t>(y) * r.width + x;
        const int li = r.layer_index[q];
        if (li < 0) continue;
        const double cx = x + 0.5, cy = y + 0.5;
        double d = inside(cx, cy) ? 0.0 : kInfinity;
        for (int e = 0; e < 3 && d > 0; ++e)
          d = std::min(d, distance_to_segment(cx, cy, t.v[e].position, t.v[(e + 1) % 3].position));
        if (d > rho) continue;
        if (d <= E)
          r.layer_m[static_cast<std::size_t>(li)] =
              std::max(r.layer_m[static_cast<std::size_t>(li)], static_cast<float>(gradient[k]));
        for (std::size_t o = 0; o < offsets.size(); ++o) {
          const double sx = cx + offsets[o].x * E, sy = cy + offsets[o].y * E;
          if (!inside(sx, sy)) continue;
          double& f = r.layer_front[static_cast<std::size_t>(li) * offsets.size() + o];
          f = std::min(f, plane->depth(sx, sy));
        }
      }
    }
  }
  return r;
}

std::uint64_t triangle_cycles(const Program& program, const MachineConfig& config) {
  const TimingParams timing = timing_params(config);
  const OwnedValues none{};
  const PacketValues values(none);
  std::uint64_t cycles = 0;
  for (const Instruction& ins : program.procedure(Procedure::triangle).code)
    cycles += static_cast<std::uint64_t>(instruction_cost(ins, timing, values).count);
  return cycles;
}

ScanConversionMethod measure(const MachineConfig& config, const Scene& scene,
                             const Program& program, const std::string& coverage_source,
                             const Reference& ref, double E, bool closed, int threads) {
  ScanConversionMethod m;
  m.program = program.name;
  const FieldDecl* z_decl = program.find_field("z");
  if (z_decl == nullptr || z_decl->width < config.gp.depth_bits) {
    throw std::invalid_argument(fmt::format(
        "{}: scan conversion is measured on a program's 'z' field, at least gp.depth_bits = {} "
        "wide",
        program.name, config.gp.depth_bits));
  }
  // Parity first: on a closed mesh a centre covered an odd number of times lies in a crack or
  // an overlap of the program's own tiling (rounded edge lines that no longer meet in one
  // point at a vertex), where neither bound applies; those pixels are counted there.
  std::vector<std::uint8_t> odd;
  if (closed) {
    const Program counter =
        assemble(coverage_source, program.name + "-coverage", assembler_options(config));
    const FieldFrame coverage = render_field(config, scene, counter, "count", threads);
    m.parity_errors = 0;
    odd.reserve(coverage.values.size());
    for (std::uint64_t c : coverage.values) {
      m.parity_errors += static_cast<std::int64_t>(c & 1);
      odd.push_back(static_cast<std::uint8_t>(c & 1));
    }
  }
  const FieldFrame frame = render_field(config, scene, program, "z", threads);
  m.image = frame.image;
  const std::uint64_t cleared = (std::uint64_t{1} << z_decl->width) - 1;
  const std::size_t n = frame.values.size();
  m.shows_hidden.assign(n, 0);
  double sum = 0;
  for (std::size_t q = 0; q < n; ++q) {
    if (ref.front[q] == kInfinity) continue;
    if (frame.values[q] == cleared) {
      ++m.missing;
      continue;
    }
    const double z = static_cast<double>(frame.values[q]);
    const double error = std::fabs(z - ref.front[q]);
    if (ref.near_edge[q]) {
      ++m.edge_pixels;
      sum += error;
      m.edge_max_error = std::max(m.edge_max_error, error);
      if (!odd.empty() && odd[q]) {
        // A crack or an overlap: in parity_errors, in neither bound.
      } else if (!ref.layer_edge[q]) {
        m.shared_edge_max_error = std::max(m.shared_edge_max_error, error);
        m.bound_ratio = std::max(m.bound_ratio, error / (2.0 * ref.local_m[q] * E));
      } else {
        // Against the exact picture moved by at most kLayerReach E: the nearest of its
        // sampled depths.
        const auto li = static_cast<std::size_t>(ref.layer_index[q]);
        double moved = kInfinity;
        for (int o = 0; o < ref.samples; ++o) {
          const double f = ref.layer_front[li * static_cast<std::size_t>(ref.samples) +
                                           static_cast<std::size_t>(o)];
          if (f != kInfinity) moved = std::min(moved, std::fabs(z - f));
        }
        ++m.layer_pixels;
        m.layer_max_error = std::max(m.layer_max_error, moved);
        m.layer_bound_ratio = std::max(
            m.layer_bound_ratio, moved / (ref.layer_m[li] * kLayerReach * E + kDepthResolution));
      }
    } else {
      m.interior_max_error = std::max(m.interior_max_error, error);
    }
    const double hidden = ref.hidden[q];
    if (hidden != kInfinity && hidden - ref.front[q] > kDepthResolution &&
        z - ref.front[q] > hidden - z) {
      ++m.show_through;
      m.shows_hidden[q] = 1;
    }
  }
  m.edge_mean_error = m.edge_pixels > 0 ? sum / static_cast<double>(m.edge_pixels) : 0.0;

  m.triangle_cycles = triangle_cycles(program, config);
  m.bits = program.bits_used();
  m.packet_words =
      packet_words(program.procedure(Procedure::triangle).expressions,
                   coefficient_words(config.evaluator.coefficient_bits, config.ring.word_bits));
  const FrameResult r = simulate_frame(config, scene, program, threads);
  double clocks = 0;
  for (std::size_t g = 0; g < r.stats.elements("gp"); ++g)
    clocks += static_cast<double>(r.stats.integer(fmt::format("gp.{}.busy_clocks", g)));
  m.gp_clocks_per_triangle = scene.mesh.triangles.empty()
                                 ? 0.0
                                 : clocks / static_cast<double>(scene.mesh.triangles.size());
  m.frame_seconds = r.stats.real("frame.simulated_seconds");
  return m;
}

}  // namespace

ScanConversionReport measure_scan_conversion(const MachineConfig& config, const Scene& scene,
                                             const Program& standard, const Program& accurate,
                                             int threads) {
  ScanConversionReport report;
  report.scene = scene.name;
  report.triangles = scene.mesh.triangles.size();
  const MeshAdjacency adjacency = build_mesh_adjacency(scene.mesh);
  report.edges = adjacency.edges;
  report.boundary_edges = adjacency.boundary_edges;
  report.non_manifold_edges = adjacency.non_manifold_edges;
  report.closed = adjacency.closed() && !scene.mesh.triangles.empty();

  // The accurate set-up's classification of every edge of every whole or clipped piece.
  const GeometryParams params = geometry_params(config);
  const GeometryEngine geometry(params, scene);
  std::vector<ScreenTriangle> pieces;
  SetupCounts counts;
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    pieces.clear();
    geometry.transform(i, pieces, counts);
    for (const ScreenTriangle& t : pieces) {
      SetupContext c{params, scene.camera, t};
      c.adjacency = &adjacency;
      c.mesh = &scene.mesh;
      c.depth_max = std::ldexp(1.0, params.depth_bits) - 1.0;
      for (int e = 0; e < 3; ++e) ++report.sides[static_cast<int>(side_plane(c, e).kind)];
    }
  }

  // E: the snap's share, and the edge coefficients' rounding: at most 2^-n (|A| x + |B| y +
  // |C|) / |(A, B)| pixels at pixel (x, y), where |A x + B y| / |(A, B)| <= |(x, y)| and
  // |C| / |(A, B)| <= |(u, w)| of the edge's first vertex: so 2^-n 2 R, R the farthest pixel
  // or vertex from the origin.
  report.E_snap = std::sqrt(2.0) * std::ldexp(1.0, -(config.gp.subpixel_bits + 1));
  if (config.gp.significand_bits < 62) {
    double R = std::hypot(config.screen.width, config.screen.height);
    for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
      pieces.clear();
      geometry.transform(i, pieces, counts);
      for (const ScreenTriangle& t : pieces) {
        for (const ScreenVertex& v : t.v)
          R = std::max(R, std::hypot(std::fabs(v.position.x) + 1, std::fabs(v.position.y) + 1));
      }
    }
    report.E_edge = std::ldexp(2.0 * R, -config.gp.significand_bits);
  }
  report.E = report.E_snap + report.E_edge;
  const Reference ref = reference(config, scene, report.E);
  report.M = ref.M;
  report.standard =
      measure(config, scene, standard, kCoverageFirmware, ref, report.E, report.closed, threads);
  report.accurate = measure(config, scene, accurate, kAccurateCoverageFirmware, ref, report.E,
                            report.closed, threads);

  // Accurate's image at half brightness; red where the two images differ, yellow where the
  // standard one shows a hidden surface.
  report.marked = report.accurate.image;
  const std::size_t n = report.marked.rgb.size() / 3;
  for (std::size_t q = 0; q < n; ++q) {
    std::uint8_t* px = &report.marked.rgb[q * 3];
    const std::uint8_t* s = &report.standard.image.rgb[q * 3];
    const bool differs = px[0] != s[0] || px[1] != s[1] || px[2] != s[2];
    if (differs) ++report.differing;
    if (report.standard.shows_hidden[q]) {
      px[0] = 255, px[1] = 230, px[2] = 0;
    } else if (differs) {
      px[0] = 255, px[1] = 0, px[2] = 0;
    } else {
      for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>(px[c] / 2);
    }
  }
  return report;
}

Program with_depth_expression(const Program& program, const std::string& source,
                              const std::string& from, const std::string& to,
                              const AssemblerOptions& options) {
  std::string text = source;
  for (const std::string& op : {std::string("qcmp.lt z, "), std::string("qload z, ")}) {
    const std::string line = op + from + "\n";
    const std::size_t at = text.find("proc triangle");
    const std::size_t end = text.find("\nend", at);
    const std::size_t hit = at == std::string::npos ? at : text.find(line, at);
    if (hit == std::string::npos || hit > end) {
      throw std::invalid_argument(
          fmt::format("program '{}': its triangle procedure has no line '{}{}' to ablate",
                      program.name, op, from));
    }
    text.replace(hit, line.size(), op + to + "\n");
  }
  Program out = assemble(text, program.name + " (" + to + ")", options);
  return out;
}

report::Table scan_conversion_ablation_table(const std::vector<ScanConversionAblation>& rows) {
  using namespace report;
  Table t;
  t.id = "scanconvert-ablation";
  t.columns = {
      text_column("scene"),
      text_column("classification", "How a pixel is classified inside or outside a triangle"),
      text_column("depth plane", "The vertices the depth plane is drawn through"),
      integer_column("edge px", "pixels", "Covered pixels within max(1, E) of any triangle's edge"),
      headed(real_column("max error", "depth units", 0, "Largest depth error at edge pixels"),
             "max error"),
      headed(real_column("mean error", "depth units", 2, "Mean depth error at edge pixels"),
             "mean error"),
      headed(real_column("shared-edge max", "depth units", 0,
                         "Largest depth error at edge pixels within 2E of no silhouette, boundary "
                         "or clipped edge"),
             "shared-edge max"),
      headed(real_column("layer-edge max", "depth units", 0,
                         "Largest depth error near a silhouette, boundary or clipped edge"),
             "layer-edge max"),
      headed(real_column("interior max", "depth units", 0,
                         "Largest depth error at the other covered pixels"),
             "interior max"),
      integer_column("hidden shows", "pixels", "Pixels where a hidden surface shows"),
      headed(integer_column("parity errors", "pixels",
                            "Pixels of odd coverage on a closed mesh ('open': not closed)"),
             "parity errors", Align::right),
      headed(real_column("edge tests by the edge's own line", "%", 1,
                         "The accurate set-up's edge tests that fall back to the unsnapped "
                         "edge's own line, of every edge test it sent"),
             "edge tests by the edge's own line", Align::right),
      integer_column("cycles/tri", "array cycles", "Array cycles of one triangle invocation"),
      headed(real_column("GP clocks/tri", "i860 clocks", 0,
                         "i860 clocks over the GPs per scene triangle"),
             "GP clocks/tri"),
      integer_column("words/packet", "ring words", "Ring words of one triangle packet"),
  };
  for (auto& c : t.columns) {
    if (c.heading.empty()) c.heading = c.name;
  }
  // The share of the accurate set-up's edge tests that fall back to the unsnapped edge's own
  // line (no neighbour, non-manifold, edge-on, coplanar), of every edge test it sent; the
  // standard program tests every edge by its snapped line.
  auto own_line = [](const ScanConversionReport& r) {
    std::uint64_t all = 0, own = 0;
    for (int k = 0; k < static_cast<int>(SideKind::count); ++k) {
      const std::uint64_t n = r.sides[static_cast<std::size_t>(k)];
      all += n;
      const auto kind = static_cast<SideKind>(k);
      if (kind != SideKind::plane && kind != SideKind::clipped) own += n;
    }
    if (all == 0) return Cell::missing();
    const double share = 100.0 * static_cast<double>(own) / all;
    return Cell::shown_as(share, fmt::format("{:.1f}% ({} of {})", share, own, all));
  };
  for (const ScanConversionAblation& r : rows) {
    const struct {
      const ScanConversionMethod* m;
      const char* edges;
      const char* plane;
      Cell own;
    } lines[] = {{&r.a.standard, "snapped edges", "snapped vertices", Cell::missing()},
                 {&r.b.standard, "snapped edges", "unsnapped vertices", Cell::missing()},
                 {&r.a.accurate, "neighbour planes", "snapped vertices", own_line(r.a)},
                 {&r.b.accurate, "neighbour planes", "unsnapped vertices", own_line(r.b)}};
    bool first = true;
    for (const auto& l : lines) {
      const ScanConversionMethod& m = *l.m;
      t.add_row(
          {first ? r.a.scene : std::string(), l.edges, l.plane, m.edge_pixels, m.edge_max_error,
           m.edge_mean_error, m.shared_edge_max_error, m.layer_max_error, m.interior_max_error,
           m.show_through,
           m.parity_errors < 0 ? Cell::shown_as(Cell::missing(), "open") : Cell(m.parity_errors),
           l.own, m.triangle_cycles, m.gp_clocks_per_triangle, m.packet_words});
      first = false;
    }
  }
  return t;
}

std::string format_scan_conversion_ablation(const std::vector<ScanConversionAblation>& rows) {
  return report::markdown(scan_conversion_ablation_table(rows));
}

report::Table scan_conversion_table(const std::vector<ScanConversionReport>& reports) {
  using namespace report;
  Table t;
  t.id = "scanconvert";
  t.columns = {
      text_column("scene"),
      text_column("method", "standard (phong) or accurate"),
      left_aligned(integer_column("edge px", "pixels",
                                  "Covered pixels within max(1, E) of any triangle's edge")),
      left_aligned(
          real_column("max error", "depth units", 0, "Largest depth error at edge pixels")),
      left_aligned(real_column("mean error", "depth units", 2, "Mean depth error at edge pixels")),
      left_aligned(
          real_column("shared-edge max", "depth units", 0,
                      "Largest depth error at edge pixels within 2E of no silhouette, boundary or "
                      "clipped edge")),
      left_aligned(real_column(
          "/ 2ME", "", 3, "The shared-edge error over the paper's bound 2 M E (1: at the bound)")),
      left_aligned(real_column("layer-edge max", "depth units", 0,
                               "Largest depth error near a silhouette, boundary or clipped edge")),
      left_aligned(
          real_column("/ ME", "", 3, "The layer-edge error over its bound (1: at the bound)")),
      left_aligned(real_column("interior max", "depth units", 0,
                               "Largest depth error at the other covered pixels")),
      left_aligned(integer_column("hidden shows", "pixels", "Pixels where a hidden surface shows")),
      left_aligned(integer_column("parity errors", "pixels",
                                  "Pixels of odd coverage on a closed mesh ('open': not closed)")),
      left_aligned(
          integer_column("cycles/tri", "array cycles", "Array cycles of one triangle invocation")),
      left_aligned(integer_column("bits", "bits", "Pixel-memory bits the program uses")),
      left_aligned(real_column("GP clocks/tri", "i860 clocks", 0,
                               "i860 clocks over the GPs per scene triangle")),
      left_aligned(
          integer_column("words/packet", "ring words", "Ring words of one triangle packet")),
      left_aligned(real_column("frame ms", "ms", 2, "Simulated frame time")),
  };
  for (const ScanConversionReport& r : reports) {
    for (const ScanConversionMethod* m : {&r.standard, &r.accurate}) {
      const bool first = m == &r.standard;
      t.add_row(
          {first ? r.scene : std::string(), first ? "standard" : "accurate", m->edge_pixels,
           m->edge_max_error, m->edge_mean_error, m->shared_edge_max_error, m->bound_ratio,
           m->layer_max_error, m->layer_bound_ratio, m->interior_max_error, m->show_through,
           m->parity_errors < 0 ? Cell::shown_as(Cell::missing(), "open") : Cell(m->parity_errors),
           m->triangle_cycles, m->bits, m->gp_clocks_per_triangle, m->packet_words,
           m->frame_seconds * 1e3});
    }
  }
  return t;
}

report::Table scan_conversion_precision_table(const std::vector<ScanConversionAtPrecision>& runs) {
  using namespace report;
  // The accuracy columns, as scan_conversion_table defines them, numbers right-aligned.
  static const char* const kKept[] = {
      "scene",           "method",         "edge px",      "max error",    "mean error",
      "shared-edge max", "layer-edge max", "interior max", "hidden shows", "parity errors"};
  const Table full = scan_conversion_table({});
  std::vector<std::size_t> kept;
  for (const char* name : kKept) {
    std::size_t k = 0;
    while (k < full.columns.size() && full.columns[k].name != name) ++k;
    if (k == full.columns.size())
      throw std::logic_error(fmt::format("scan_conversion_table has no column '{}'", name));
    kept.push_back(k);
  }
  Table t;
  t.id = "scanconvert-precision";
  t.columns.push_back(headed(integer_column("significand bits", "bits",
                                            "Significant bits of every value the GP computes "
                                            "(gp.significand_bits; 62: exact)"),
                             "significand bits"));
  for (std::size_t k : kept) {
    Column c = full.columns[k];
    c.align = Align::automatic;
    t.columns.push_back(std::move(c));
  }
  for (const ScanConversionAtPrecision& run : runs) {
    const Table one = scan_conversion_table(run.reports);
    for (std::size_t r = 0; r < one.rows.size(); ++r) {
      std::vector<Cell> row = {run.significand_bits};
      for (std::size_t k : kept) row.push_back(one.rows[r][k]);
      row[1] = run.reports[r / 2].scene;  // named on every row (the full table names it once)
      t.add_row(std::move(row));
    }
  }
  return t;
}

}  // namespace pp5
