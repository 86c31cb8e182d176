#include "sim/analysis/transparency.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

// A screen triangle's planes: barycentric weights of a screen point, and the depth, colour
// and opacity they interpolate.
struct Planes {
  std::array<glm::dvec2, 3> p;
  std::array<double, 3> depth;
  std::array<glm::dvec3, 3> colour;  // 0..255
  std::array<double, 3> opacity;     // 0..1
  double area2 = 0;
  glm::dvec2 depth_gradient;  // d(depth)/dx, d(depth)/dy

  explicit Planes(const ScreenTriangle& t) {
    for (int k = 0; k < 3; ++k) {
      p[k] = t.v[k].position;
      depth[k] = t.v[k].depth;
      colour[k] = t.v[k].lit_color * 255.0;
      opacity[k] = t.v[k].opacity;
    }
    area2 = cross(p[1] - p[0], p[2] - p[0]);
    if (area2 != 0) {
      const glm::dvec2 a = p[1] - p[0], b = p[2] - p[0];
      const double da = depth[1] - depth[0], db = depth[2] - depth[0];
      depth_gradient = {(da * b.y - db * a.y) / area2, (db * a.x - da * b.x) / area2};
    }
  }
  static double cross(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }
  // Barycentric weights at q; all >= 0 inside the closed triangle.
  std::array<double, 3> weights(glm::dvec2 q) const {
    return {cross(p[1] - q, p[2] - q) / area2, cross(p[2] - q, p[0] - q) / area2,
            cross(p[0] - q, p[1] - q) / area2};
  }
};

struct Layer {
  double depth;
  glm::dvec3 colour;
  double opacity;
  int plane;  // index into the planes
};

}  // namespace

TransparencyReference transparency_reference(const MachineConfig& config, const Scene& scene,
                                             double margin) {
  const GeometryEngine geometry(geometry_params(config), scene);
  std::vector<Planes> planes;
  {
    std::vector<ScreenTriangle> pieces;
    SetupCounts counts;
    for (int t = 0; t < static_cast<int>(scene.mesh.triangles.size()); ++t) {
      pieces.clear();
      geometry.transform(t, pieces, counts);
      for (const ScreenTriangle& s : pieces) {
        Planes p(s);
        if (p.area2 != 0) planes.push_back(p);
      }
    }
  }
  TransparencyReference ref;
  ref.width = config.screen.width;
  ref.height = config.screen.height;
  const auto pixels = static_cast<std::size_t>(ref.width) * static_cast<std::size_t>(ref.height);
  // The layers at every centre, and the layer counts at the four offset centres.
  std::vector<std::vector<Layer>> at(pixels);
  std::array<std::vector<int>, 4> counts;
  const std::array<glm::dvec2, 4> offsets = {glm::dvec2(margin, 0), glm::dvec2(-margin, 0),
                                             glm::dvec2(0, margin), glm::dvec2(0, -margin)};
  for (auto& c : counts) c.assign(pixels, 0);
  for (int i = 0; i < static_cast<int>(planes.size()); ++i) {
    const Planes& p = planes[static_cast<std::size_t>(i)];
    double x0 = p.p[0].x, x1 = x0, y0 = p.p[0].y, y1 = y0;
    for (const glm::dvec2& v : p.p) {
      x0 = std::min(x0, v.x), x1 = std::max(x1, v.x);
      y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
    }
    const int xa = std::max(0, static_cast<int>(std::floor(x0 - margin - 0.5)));
    const int xb = std::min(ref.width - 1, static_cast<int>(std::ceil(x1 + margin - 0.5)));
    const int ya = std::max(0, static_cast<int>(std::floor(y0 - margin - 0.5)));
    const int yb = std::min(ref.height - 1, static_cast<int>(std::ceil(y1 + margin - 0.5)));
    for (int y = ya; y <= yb; ++y) {
      for (int x = xa; x <= xb; ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * ref.width + x;
        const glm::dvec2 c(x + 0.5, y + 0.5);
        const auto w = p.weights(c);
        if (w[0] >= 0 && w[1] >= 0 && w[2] >= 0) {
          Layer l{0, glm::dvec3(0), 0, i};
          for (int v = 0; v < 3; ++v) {
            l.depth += w[v] * p.depth[v];
            l.colour += w[v] * p.colour[v];
            l.opacity += w[v] * p.opacity[v];
          }
          l.colour = glm::clamp(l.colour, 0.0, 255.0);
          l.opacity = std::clamp(l.opacity, 0.0, 1.0);
          at[k].push_back(l);
        }
        for (int o = 0; o < 4; ++o) {
          const auto wo = p.weights(c + offsets[static_cast<std::size_t>(o)]);
          if (wo[0] >= 0 && wo[1] >= 0 && wo[2] >= 0) ++counts[static_cast<std::size_t>(o)][k];
        }
      }
    }
  }
  ref.rgb.assign(pixels * 3, 0);
  ref.layers.assign(pixels, 0);
  ref.uncertain.assign(pixels, 0);
  const glm::dvec3 background = glm::dvec3(scene.background) * 255.0;
  for (std::size_t k = 0; k < pixels; ++k) {
    std::vector<Layer>& ls = at[k];
    std::sort(ls.begin(), ls.end(), [](const Layer& a, const Layer& b) {
      return a.depth != b.depth ? a.depth < b.depth : a.plane < b.plane;
    });
    glm::dvec3 acc(0);
    double t = 1;
    for (const Layer& l : ls) {
      acc += l.colour * l.opacity * t;
      t *= 1 - l.opacity;
    }
    acc += background * t;
    for (int c = 0; c < 3; ++c) ref.rgb[k * 3 + static_cast<std::size_t>(c)] = acc[c];
    ref.layers[k] = static_cast<std::uint8_t>(std::min<std::size_t>(ls.size(), 255));
    bool uncertain = false;
    for (const auto& c : counts) uncertain = uncertain || c[k] != static_cast<int>(ls.size());
    // Two depth planes meeting within `margin` of the centre: the difference of two affine
    // functions is zero within that distance when its value is below margin times its
    // gradient's length.
    for (std::size_t a = 0; a + 1 < ls.size() && !uncertain; ++a) {
      for (std::size_t b = a + 1; b < ls.size() && !uncertain; ++b) {
        const glm::dvec2 g = planes[static_cast<std::size_t>(ls[a].plane)].depth_gradient -
                             planes[static_cast<std::size_t>(ls[b].plane)].depth_gradient;
        uncertain = std::abs(ls[b].depth - ls[a].depth) <= margin * glm::length(g) + 1e-12;
      }
    }
    ref.uncertain[k] = uncertain ? 1 : 0;
  }
  return ref;
}

TransparencyMeasure measure_transparency(const MachineConfig& config, const Scene& scene,
                                         const Program& program, int threads) {
  TransparencyMeasure m;
  m.scene = scene.name;
  m.program = program.name;
  const FrameValues values = GeometryEngine(geometry_params(config), scene).frame_values();
  m.layers = program.pass_count(values.frame.parameters);
  m.bits = program.bits_used();
  m.cost = frame_cost(config, scene, program, threads, &m.image);
  const TransparencyReference ref = transparency_reference(config, scene);
  m.difference.width = ref.width;
  m.difference.height = ref.height;
  m.difference.rgb.assign(ref.rgb.size(), 0);
  for (std::size_t k = 0; k < ref.layers.size(); ++k) {
    std::uint8_t shade = 0;
    if (ref.uncertain[k]) {
      ++m.uncertain;
      shade = 96;
    } else {
      ++m.compared;
      m.covered += ref.layers[k] > 0;
      m.too_many += ref.layers[k] > m.layers;
      m.most = std::max(m.most, static_cast<int>(ref.layers[k]));
      double error = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        error = std::max(
            error, std::abs(static_cast<double>(m.image.rgb[k * 3 + c]) - ref.rgb[k * 3 + c]));
      }
      m.max_error = std::max(m.max_error, error);
      if (ref.layers[k] <= m.layers) m.max_error_within = std::max(m.max_error_within, error);
      if (error > kTransparencyTolerance) {
        ++m.differ;
        shade = 255;
      }
    }
    for (std::size_t c = 0; c < 3; ++c) m.difference.rgb[k * 3 + c] = shade;
  }
  return m;
}

report::Table transparency_table(const std::vector<TransparencyMeasure>& rows) {
  using namespace report;
  auto pixels = [](const std::string& heading, const std::string& description) {
    return headed(integer_column(heading, "pixels", description), heading);
  };
  Table t;
  t.id = "csg-transparency";
  t.columns = {
      headed(text_column("application"), "application"),
      headed(text_column("scene"), "scene"),
      headed(text_column("program"), "program"),
      headed(integer_column("layers (passes)", "layers", "The layers the program composites"),
             "layers (passes)"),
      pixels("pixels compared", "Pixels far from an outline"),
      pixels("with a surface", "Compared pixels with at least one layer"),
      headed(integer_column("with more layers than passes", "pixels",
                            "Compared pixels with more layers than the program composites (the "
                            "most layers at a pixel)"),
             "with more layers than passes (most)", Align::right),
      pixels(fmt::format("differing by more than {:g} of 255", kTransparencyTolerance),
             "Compared pixels off the reference by more than the tolerance"),
      headed(real_column("largest error", "levels of 255", 1, "Over the compared pixels"),
             "largest error"),
      headed(real_column("largest error where layers <= passes", "levels of 255", 1,
                         "Over the compared pixels with no more layers than passes"),
             "largest error where layers <= passes"),
      pixels("near an outline (not compared)", "Pixels near an outline"),
      headed(integer_column("bits", "bits", "Pixel-memory bits the program uses"), "bits")};
  add_cost_columns(t.columns);
  for (const TransparencyMeasure& m : rows) {
    std::vector<Cell> row = {"transparency",
                             m.scene,
                             m.program,
                             m.layers,
                             m.compared,
                             m.covered,
                             Cell::shown_as(m.too_many, fmt::format("{} ({})", m.too_many, m.most)),
                             m.differ,
                             m.max_error,
                             m.max_error_within,
                             m.uncertain,
                             m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

}  // namespace pp5
