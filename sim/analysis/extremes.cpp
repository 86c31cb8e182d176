#include "sim/analysis/extremes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/analysis/analysis_firmware.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

const std::string kCoverageFirmware =
    coverage_firmware("Coverage counter: each triangle adds 1 to every pixel whose centre it owns.",
                      {"edge0", "edge1", "edge2"});

namespace {

constexpr int kScreen = 256;

MachineConfig small_machine(const MachineConfig& base) {
  MachineConfig c = base;
  c.set({"screen.width=256", "screen.height=256", "renderer.count=2", "gp.count=2"});
  return c;
}

// A scene seen by a camera at the origin looking down -z with a 90-degree field of view, so
// that a point at screen pixel position (X, Y) and view distance d is easy to place.
struct ViewScene {
  Scene scene;
  int width, height;
  ViewScene(int w, int h) : width(w), height(h) {
    scene.name = "extremes";
    scene.camera = Camera{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90.0f, 1.0f, 100.0f};
    scene.ambient = 1.0f;
    scene.lights = {Light{{0, 0, 1}, 0.0f, 0.0f, 1.0f}};
    scene.background = glm::vec3(0);
  }
  // Screen position (pixels, y down) at view distance d.
  glm::vec3 at(double x, double y, double d) const {
    const double aspect = static_cast<double>(width) / height;
    return glm::vec3(static_cast<float>((2.0 * x / width - 1.0) * d * aspect),
                     static_cast<float>((1.0 - 2.0 * y / height) * d), static_cast<float>(-d));
  }
  void triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 color = glm::vec3(1)) {
    const auto base = static_cast<unsigned>(scene.mesh.vertices.size());
    // Counter-clockwise seen from the camera is clockwise on a y-down screen; winding does
    // not matter to the firmware (no culling), so keep the order given.
    for (glm::vec3 p : {a, b, c}) scene.mesh.vertices.push_back({p, glm::vec3(0, 0, 1), color});
    scene.mesh.triangles.emplace_back(base, base + 1, base + 2);
  }
};

// A deterministic generator for jitter (a 64-bit LCG), so that every run sees the same scene.
struct Lcg {
  std::uint64_t s;
  double next() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(s >> 11) / 9007199254740992.0;
  }
};

Program assemble_text(const char* text, const char* name, const MachineConfig& config) {
  return assemble(text, name, assembler_options(config));
}

struct Drawn {
  RgbImage image;
  std::uint64_t overflow = 0;
};

Drawn draw_flat(const MachineConfig& config, const Scene& scene, int threads) {
  // Z-buffered, one constant colour per triangle; with ambient 1 and no diffuse or specular
  // light the colour is the material's. The z field is as wide as the depth expression.
  const std::string source = zbuffer_colour_firmware("Flat z-buffer (pp5sim extremes)",
                                                     config.gp.depth_bits, "depth", "flat");
  const Program program = assemble(source, "extremes-flat", assembler_options(config));
  const FrameResult r = simulate_frame(config, scene, program, threads);
  return {r.image.flat(),
          static_cast<std::uint64_t>(r.stats.integer("setup.coefficient_overflow"))};
}

std::string counts_text(const CoverageCheck& c) {
  return fmt::format("{} missing, {} extra among {} pixels with a definite answer", c.missing,
                     c.extra, c.certain);
}

ExtremeCase coverage_case(std::string name, std::string expected, const MachineConfig& config,
                          const Scene& scene, int threads) {
  const Coverage cov = coverage_counts(config, scene, threads);
  const CoverageCheck check = check_coverage(config, scene, cov);
  std::uint64_t covered = 0;
  for (auto c : cov.count) covered += c > 0;
  ExtremeCase out{std::move(name), std::move(expected), "", false};
  out.observed = fmt::format(
      "{}; {} pixels covered; set-up dropped {} zero-area, {} without a "
      "pixel centre",
      counts_text(check), covered, cov.degenerate, cov.no_pixels);
  out.pass = check.missing == 0 && check.extra == 0 && check.certain > 0;
  return out;
}

// Depth of screen triangle `t` at pixel centre (px, py), from the plane through its vertices.
double plane_depth(const ScreenTriangle& t, double px, double py) {
  const glm::dvec2 a = t.v[0].position, b = t.v[1].position, c = t.v[2].position;
  const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
  const double u = ((px - a.x) * (c.y - a.y) - (c.x - a.x) * (py - a.y)) / det;
  const double v = ((b.x - a.x) * (py - a.y) - (px - a.x) * (b.y - a.y)) / det;
  return t.v[0].depth + u * (t.v[1].depth - t.v[0].depth) + v * (t.v[2].depth - t.v[0].depth);
}

// Signed distances of a point to the three edges, positive inside (either winding).
std::array<double, 3> edge_distances(const ScreenTriangle& t, double px, double py) {
  const glm::dvec2 a = t.v[0].position, b = t.v[1].position, c = t.v[2].position;
  const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
  const double s = area >= 0 ? 1.0 : -1.0;
  std::array<double, 3> d{};
  const glm::dvec2 p(px, py);
  const glm::dvec2 v[3] = {a, b, c};
  for (int e = 0; e < 3; ++e) {
    const glm::dvec2 p0 = v[e], p1 = v[(e + 1) % 3];
    const glm::dvec2 dir = p1 - p0;
    const double len = glm::length(dir);
    const double cross = dir.x * (p.y - p0.y) - dir.y * (p.x - p0.x);
    d[e] = len > 0 ? s * cross / len : 0.0;
  }
  return d;
}

// Screen triangles of every scene triangle, as the GP projects them.
std::vector<ScreenTriangle> project(const MachineConfig& config, const Scene& scene) {
  GeometryEngine geometry(geometry_params(config), scene);
  std::vector<ScreenTriangle> out;
  SetupCounts counts;
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    geometry.transform(i, out, counts);
  }
  return out;
}

// Two planes drawn red then blue: pixels where the nearer one (by more than `tolerance`
// z-units in the reference) did not win, and pixels too close to call.
struct Visibility {
  std::uint64_t wrong = 0, close = 0, checked = 0;
};
Visibility check_two_planes(const MachineConfig& config, const Scene& scene, const Drawn& drawn,
                            double tolerance) {
  const std::vector<ScreenTriangle> tris = project(config, scene);
  Visibility v;
  const double eps = std::ldexp(1.0, -config.gp.subpixel_bits);
  const double units = std::ldexp(1.0, config.gp.depth_bits) - 1.0;
  const int w = config.screen.width, h = config.screen.height;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double px = x + 0.5, py = y + 0.5;
      // The nearest triangle certainly covering the pixel, per colour.
      double best[2] = {1e300, 1e300};
      for (const ScreenTriangle& t : tris) {
        const auto d = edge_distances(t, px, py);
        if (std::min({d[0], d[1], d[2]}) <= eps) continue;
        const int which = t.flat_color.b > t.flat_color.r ? 1 : 0;
        best[which] = std::min(best[which], plane_depth(t, px, py) * units);
      }
      if (best[0] > 1e299 || best[1] > 1e299) continue;
      const auto* p = &drawn.image.rgb[(static_cast<std::size_t>(y) * w + x) * 3];
      if (std::abs(best[0] - best[1]) <= tolerance) {
        ++v.close;
        continue;
      }
      ++v.checked;
      const bool blue_nearer = best[1] < best[0];
      const bool blue_drawn = p[2] > p[0];
      if (blue_nearer != blue_drawn) ++v.wrong;
    }
  }
  return v;
}

ExtremeCase depth_precision_case(const MachineConfig& config, int threads) {
  (void)threads;
  const int n = config.gp.depth_bits;
  const int need = depth_fraction_bits_needed(config.screen.width, config.screen.height);
  ExtremeCase out;
  out.name = "depth precision";
  out.expected = fmt::format(
      "an {}-bit z-buffer on a {}-pixel screen needs {} + log2(2 x {}) = {} bits of running "
      "depth ({} fraction bits): error at most 1 z-unit with {} fraction bits, more with fewer",
      n, std::max(config.screen.width, config.screen.height), n,
      std::max(config.screen.width, config.screen.height), n + need, need, need);
  std::string rows;
  std::int64_t at_need = 0, worst_fewer = 0;
  bool fits = true;
  for (int f = std::max(0, need - 4); f <= need + 1; ++f) {
    if (n + f + 2 > config.evaluator.result_bits || n + f + 2 > config.evaluator.coefficient_bits) {
      fits = false;
      continue;
    }
    const std::int64_t e = depth_precision_error(config, n, f);
    rows += fmt::format("{}{} bits: {}", rows.empty() ? "" : ", ", f, e);
    if (f == need) at_need = e;
    if (f < need) worst_fewer = std::max(worst_fewer, e);
  }
  out.observed = fmt::format(
      "max error in z-units by fraction bits: {}; configured "
      "evaluator.fraction_bits = {}",
      rows, config.evaluator.fraction_bits);
  if (!fits) out.observed += " (some widths exceed the evaluator's and were skipped)";
  // The model's property (enough fraction bits give at most 1 z-unit, fewer give more) and
  // this machine's: the configured fraction bits must be enough for its screen.
  const bool enough = config.evaluator.fraction_bits >= need;
  if (!enough) {
    out.observed += fmt::format(
        "; with {} fraction bits this machine's depth errs by up to {} z-units (fewer than the "
        "{} needed)",
        config.evaluator.fraction_bits,
        depth_precision_error(config, n, config.evaluator.fraction_bits), need);
  }
  out.pass = at_need <= 1 && worst_fewer > 1 && enough;
  return out;
}

}  // namespace

int depth_fraction_bits_needed(int screen_width, int screen_height) {
  const int k = std::max(screen_width, screen_height);
  int bits = 0;
  while ((1LL << bits) < 2LL * k) ++bits;
  return bits;
}

std::int64_t depth_precision_error(const MachineConfig& config, int depth_bits, int fraction_bits) {
  MachineConfig c = config;
  RendererBoardParams params = board_params(c);
  params.timing.fraction_bits = fraction_bits;
  AssemblerOptions options = assembler_options(c);
  const std::string source = fmt::format(
      "field z {}\nfield red 8\noutput red red red\nproc triangle\n  eall\n  qload z, depth\nend\n",
      depth_bits);
  const Program program = assemble(source, "depth-probe", options);
  // A plane rising by about 0.4 of the depth range across each axis, with gradients 1/3 of a
  // unit of 2^-f away from the nearest representable value: the worst steady rounding.
  const double range = std::ldexp(1.0, depth_bits);
  const int w = c.screen.width, h = c.screen.height;
  const double a = std::floor(0.4 * range / w) + 1.0 / 3.0;
  const double b = std::floor(0.4 * range / h) + 1.0 / 3.0;
  const double z0 = std::floor(0.1 * range) + 1.0 / 3.0;
  const double scale = std::ldexp(1.0, fraction_bits);
  OwnedValues values;
  values.expressions[static_cast<int>(Expression::depth)] = QuadraticCoefficients::linear(
      std::llround(a * scale), std::llround(b * scale), std::llround(z0 * scale));
  RendererBoard board(params);
  // The region holding the screen's far corner, where the error has grown the most.
  const int rw = c.renderer.region_width, rh = c.renderer.region_height;
  const int x0 = (w - 1) / rw * rw, y0 = (h - 1) / rh * rh;
  board.begin_region(x0, y0);
  board.run(program.procedure(Procedure::triangle), values);
  const FieldDecl* decl = program.find_field("z");
  const Field z{decl->lo, decl->width, false};
  std::int64_t worst = 0;
  for (int p = 0; p < rw * rh; ++p) {
    const int x = x0 + p % rw, y = y0 + p / rw;
    if (x >= w || y >= h) continue;
    const double exact = z0 + a * x + b * y;
    const auto got = static_cast<std::int64_t>(board.array().read(p, z));
    worst = std::max(worst, std::abs(got - static_cast<std::int64_t>(std::floor(exact))));
  }
  return worst;
}

bool is_closed(const Mesh& mesh) {
  std::map<std::pair<unsigned, unsigned>, int> edges;
  for (const auto& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      unsigned a = t[e], b = t[(e + 1) % 3];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
  }
  if (edges.empty()) return false;
  for (const auto& [edge, n] : edges) {
    if (n != 2) return false;
  }
  return true;
}

Coverage coverage_counts(const MachineConfig& config, const Scene& scene, int threads) {
  const Program program = assemble_text(kCoverageFirmware.c_str(), "coverage", config);
  const FrameResult r = simulate_frame(config, scene, program, threads);
  Coverage c;
  c.width = r.image.width();
  c.height = r.image.height();
  c.count.resize(static_cast<std::size_t>(c.width) * c.height);
  for (std::size_t p = 0; p < c.count.size(); ++p) c.count[p] = r.image.flat().rgb[p * 3];
  auto count = [&r](const char* name) {
    return static_cast<std::uint64_t>(r.stats.integer(std::string("setup.") + name));
  };
  c.overflow = count("coefficient_overflow");
  c.degenerate = count("degenerate");
  c.no_pixels = count("no_pixel_centres");
  c.clipped_away = count("clipped_away");
  return c;
}

CoverageCheck check_coverage(const MachineConfig& config, const Scene& scene,
                             const Coverage& coverage) {
  const int w = coverage.width, h = coverage.height;
  std::vector<int> lo(static_cast<std::size_t>(w) * h, 0), hi(lo.size(), 0);
  const double eps = std::ldexp(1.0, -config.gp.subpixel_bits);
  for (const ScreenTriangle& t : project(config, scene)) {
    double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
    for (const auto& v : t.v) {
      x_lo = std::min(x_lo, v.position.x);
      x_hi = std::max(x_hi, v.position.x);
      y_lo = std::min(y_lo, v.position.y);
      y_hi = std::max(y_hi, v.position.y);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(x_lo - 1)));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(x_hi + 1)));
    const int y0 = std::max(0, static_cast<int>(std::floor(y_lo - 1)));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(y_hi + 1)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const auto d = edge_distances(t, x + 0.5, y + 0.5);
        const double m = std::min({d[0], d[1], d[2]});
        const std::size_t p = static_cast<std::size_t>(y) * w + x;
        if (m > eps) ++lo[p];
        if (m >= -eps) ++hi[p];
      }
    }
  }
  CoverageCheck check;
  for (std::size_t p = 0; p < lo.size(); ++p) {
    if (lo[p] == hi[p]) ++check.certain;
    // Counts are kept modulo 256 by the 8-bit counter.
    const int got = coverage.count[p];
    if (got < (lo[p] & 255) && lo[p] < 256) ++check.missing;
    if (got > hi[p]) ++check.extra;
  }
  return check;
}

std::vector<ExtremeCase> synthetic_extreme_cases(const MachineConfig& base, int threads) {
  const MachineConfig config = small_machine(base);
  std::vector<ExtremeCase> cases;
  cases.push_back(depth_precision_case(base, threads));

  {  // Coefficient width: a steep plane far from the screen's origin, and one too steep.
    ViewScene v(kScreen, kScreen);
    // Edge-on at x = 230: a depth gradient of about 2^37 per pixel (with fraction bits), so
    // its constant term is far beyond 40 bits while every value inside it is in range.
    v.triangle(v.at(230.3, 40.0, 1.5), v.at(230.7, 220.0, 1.5), v.at(230.4, 130.0, 90.0));
    v.triangle(v.at(20.0, 20.0, 5.0), v.at(60.0, 20.0, 5.0), v.at(20.0, 60.0, 5.0));
    const Drawn wide = draw_flat(config, v.scene, threads);
    std::uint64_t wide_drawn = 0;
    for (int y = 0; y < kScreen; ++y) {
      for (int x = 200; x < kScreen; ++x) {
        wide_drawn += wide.image.rgb[3 * (static_cast<std::size_t>(y) * kScreen + x)] > 0;
      }
    }
    // Narrower with the same depth span, until the gradient itself does not fit the
    // coefficients (a sixteenth of a pixel with the defaults: about 2^42 per pixel). With
    // fewer fraction bits or wider coefficients even the thinnest triangle the GP can snap
    // (two sub-pixel steps across a pixel centre) may fit: then no triangle can overflow and
    // there is nothing to drop.
    Drawn steep;
    double width = 0;
    for (int k = 1; k <= config.gp.subpixel_bits && steep.overflow == 0; ++k) {
      width = 2 * std::ldexp(1.0, -k);
      ViewScene w(kScreen, kScreen);
      w.triangle(w.at(230.5 - width / 2, 40.0, 1.5), w.at(230.5 + width / 2, 220.0, 1.5),
                 w.at(230.5 - width / 2, 130.0, 90.0));
      steep = draw_flat(config, w.scene, threads);
    }
    std::uint64_t steep_drawn = 0;
    for (std::uint8_t b : steep.image.rgb) steep_drawn += b > 0;
    ExtremeCase c;
    c.name = "coefficient width";
    c.expected = fmt::format(
        "a triangle edge-on to the screen at x = 230 has a constant term far beyond the {0}-bit "
        "coefficients; sent modulo 2^{0}, which the evaluator's wrapping sums make exact, it is "
        "drawn and nothing is dropped. A triangle so thin that its depth gradient itself does "
        "not fit is dropped and counted in stats.json setup.coefficient_overflow and the render "
        "summary, never drawn with wrapped values",
        config.evaluator.coefficient_bits);
    c.observed = fmt::format("steep triangle: {} dropped, {} pixels drawn right of x = 200; ",
                             wide.overflow, wide_drawn);
    c.observed += steep.overflow > 0
                      ? fmt::format("too steep ({} pixel wide): {} dropped, {} pixels drawn", width,
                                    steep.overflow, steep_drawn)
                      : fmt::format(
                            "no triangle is too steep on this machine: even one {} pixel wide "
                            "(the thinnest that {} sub-pixel bits snap) has a gradient that fits",
                            width, config.gp.subpixel_bits);
    c.pass = wide.overflow == 0 && wide_drawn > 0 && steep.overflow <= 1 &&
             (steep.overflow == 0 || steep_drawn == 0);
    cases.push_back(c);
  }

  {  // Edge-on: a triangle whose plane nearly contains the view direction.
    ViewScene v(kScreen, kScreen);
    v.triangle(v.at(100.3, 40.0, 1.5), v.at(100.7, 220.0, 1.5), v.at(100.4, 130.0, 90.0));
    v.triangle(v.at(160.0, 40.0, 2.0), v.at(160.0, 220.0, 80.0), v.at(163.0, 130.0, 2.0));
    ExtremeCase c = coverage_case(
        "nearly perpendicular to the screen",
        "triangles edge-on to the screen cover exactly the pixel centres inside them; where the "
        "depth gradient does not fit the coefficients, the triangle is dropped and counted",
        config, v.scene, threads);
    const Drawn d = draw_flat(config, v.scene, threads);
    c.observed += fmt::format("; with depth (flat firmware): {} dropped for coefficient overflow",
                              d.overflow);
    cases.push_back(c);
  }

  {  // Slivers: long, far thinner than a pixel, at many angles.
    ViewScene v(kScreen, kScreen);
    for (int k = 0; k < 48; ++k) {
      const double angle = 3.14159265358979 * k / 48.0;
      const double cx = 128 + 3 * std::cos(angle * 7), cy = 128 + 3 * std::sin(angle * 5);
      const glm::dvec2 dir(std::cos(angle), std::sin(angle)), side(-dir.y, dir.x);
      const glm::dvec2 a = glm::dvec2(cx, cy) - 110.0 * dir, b = glm::dvec2(cx, cy) + 110.0 * dir;
      const glm::dvec2 m = glm::dvec2(cx, cy) + (0.002 + 0.01 * (k % 5)) * side;
      v.triangle(v.at(a.x, a.y, 5), v.at(b.x, b.y, 5), v.at(m.x, m.y, 5));
    }
    cases.push_back(coverage_case("slivers",
                                  "48 triangles 220 pixels long and 0.002 to 0.042 pixels wide "
                                  "cover only pixel centres inside them, and none is lost "
                                  "to overflow",
                                  config, v.scene, threads));
  }

  {  // Sub-pixel triangles at jittered positions.
    ViewScene v(kScreen, kScreen);
    Lcg rng{12345};
    for (int k = 0; k < 600; ++k) {
      const double x = 8 + 240 * rng.next(), y = 8 + 240 * rng.next(), s = 0.1 + 0.8 * rng.next();
      v.triangle(v.at(x, y, 4), v.at(x + s, y + s * rng.next(), 4),
                 v.at(x + s * rng.next(), y + s, 4));
    }
    cases.push_back(coverage_case("sub-pixel triangles",
                                  "600 triangles 0.1 to 0.9 pixels across: each covers a pixel "
                                  "only if it contains the pixel's centre (most cover none)",
                                  config, v.scene, threads));
  }

  {  // Huge coordinates: a quad reaching a million pixels beyond the screen, clipped by the GP.
    ViewScene v(kScreen, kScreen);
    const double far = 1e6;
    v.triangle(v.at(-far, -far, 3), v.at(far, -far * 0.999, 3), v.at(far, far, 3));
    v.triangle(v.at(-far, -far, 3), v.at(far, far, 3), v.at(-far * 1.001, far, 3));
    ExtremeCase c = coverage_case(
        "huge coordinates",
        "two triangles with vertices 10^6 pixels off screen, sharing a diagonal through it, "
        "are clipped and cover every pixel exactly once",
        config, v.scene, threads);
    const Coverage cov = coverage_counts(config, v.scene, threads);
    std::uint64_t not_one = 0;
    for (auto n : cov.count) not_one += n != 1;
    c.observed += fmt::format("; {} pixels not covered exactly once", not_one);
    c.pass = c.pass && not_one == 0;
    cases.push_back(c);
  }

  {  // Shared edges: a jittered grid of 392 triangles, and a fan meeting at a pixel centre.
    ViewScene v(kScreen, kScreen);
    Lcg rng{777};
    const int n = 14;
    std::vector<glm::vec3> grid;
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        const bool border = i == 0 || j == 0 || i == n || j == n;
        const double jx = border ? 0 : (rng.next() - 0.5) * 9,
                     jy = border ? 0 : (rng.next() - 0.5) * 9;
        grid.push_back(v.at(16 + 16.0 * i + jx, 16 + 16.0 * j + jy, 3 + 0.05 * i));
      }
    }
    Scene& s = v.scene;
    const auto base = static_cast<unsigned>(s.mesh.vertices.size());
    for (const glm::vec3& p : grid)
      s.mesh.vertices.push_back({p, glm::vec3(0, 0, 1), glm::vec3(1)});
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const unsigned a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        s.mesh.triangles.emplace_back(a, b, d);
        s.mesh.triangles.emplace_back(a, d, c);
      }
    }
    const Coverage cov = coverage_counts(config, s, threads);
    std::uint64_t gaps = 0, doubles = 0;
    // The grid's outline is the square [16, 240]: centres inside are covered exactly once.
    for (int y = 0; y < kScreen; ++y) {
      for (int x = 0; x < kScreen; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const bool inside = px > 16.1 && px < 239.9 && py > 16.1 && py < 239.9;
        const bool outside = px < 15.9 || px > 240.1 || py < 15.9 || py > 240.1;
        const int got = cov.count[static_cast<std::size_t>(y) * kScreen + x];
        if (inside && got == 0) ++gaps;
        if (got > 1 || (outside && got > 0)) ++doubles;
      }
    }
    ExtremeCase c;
    c.name = "shared edges across a mesh";
    c.expected =
        "a jittered grid of 392 triangles sharing edges and vertices: every pixel centre inside "
        "it is owned by exactly one triangle (no gap, none drawn twice), so parity is exact";
    c.observed = fmt::format("{} gaps, {} pixels drawn twice or outside", gaps, doubles);
    c.pass = gaps == 0 && doubles == 0;
    cases.push_back(c);

    ViewScene fan(kScreen, kScreen);
    const glm::dvec2 centre(128.5, 128.5);  // exactly a pixel centre
    const int spokes = 64;
    for (int k = 0; k < spokes; ++k) {
      const double a0 = 6.283185307179586 * k / spokes, a1 = 6.283185307179586 * (k + 1) / spokes;
      fan.triangle(fan.at(centre.x, centre.y, 4),
                   fan.at(centre.x + 100 * std::cos(a0), centre.y + 100 * std::sin(a0), 4),
                   fan.at(centre.x + 100 * std::cos(a1), centre.y + 100 * std::sin(a1), 4));
    }
    const Coverage fc = coverage_counts(config, fan.scene, threads);
    std::uint64_t fan_gaps = 0, fan_doubles = 0;
    for (int y = 0; y < kScreen; ++y) {
      for (int x = 0; x < kScreen; ++x) {
        const double r = glm::length(glm::dvec2(x + 0.5, y + 0.5) - centre);
        const int got = fc.count[static_cast<std::size_t>(y) * kScreen + x];
        if (r < 99 && got != 1) ++fan_gaps;
        if (got > 1) ++fan_doubles;
      }
    }
    ExtremeCase f;
    f.name = "fan meeting at a pixel centre";
    f.expected =
        "64 triangles meeting at the centre of pixel (128, 128): that pixel, and every "
        "other inside the fan, is owned by exactly one triangle";
    f.observed = fmt::format(
        "{} pixels inside not covered exactly once, {} drawn twice; the "
        "centre pixel counted {}",
        fan_gaps, fan_doubles, fc.count[128 * kScreen + 128]);
    f.pass = fan_gaps == 0 && fan_doubles == 0;
    cases.push_back(f);
  }

  {  // Nearly parallel planes crossing each other, drawn red then blue.
    ViewScene v(kScreen, kScreen);
    const glm::vec3 red(1, 0, 0), blue(0, 0, 1);
    const double d = 10.0, tilt = 1.2e-4;  // about +-20 z-units apart at the screen's sides
    auto quad = [&](double d_left, double d_right, glm::vec3 color) {
      v.triangle(v.at(8, 8, d_left), v.at(248, 8, d_right), v.at(248, 248, d_right), color);
      v.triangle(v.at(8, 8, d_left), v.at(248, 248, d_right), v.at(8, 248, d_left), color);
    };
    quad(d, d, red);
    quad(d - tilt, d + tilt, blue);
    const Drawn drawn = draw_flat(config, v.scene, threads);
    const Visibility vis = check_two_planes(config, v.scene, drawn, 2.0);
    ExtremeCase c;
    c.name = "nearly parallel planes";
    c.expected =
        "two planes crossing at a shallow angle (about 20 z-units apart at the sides): "
        "wherever they differ by more than 2 z-units the nearer one is visible";
    c.observed = fmt::format(
        "{} of {} decided pixels show the farther plane; {} pixels within 2 "
        "z-units (either may win)",
        vis.wrong, vis.checked, vis.close);
    c.pass = vis.wrong == 0 && vis.checked > 0;
    cases.push_back(c);
  }

  {  // Coincident planes: the same triangle twice.
    ViewScene v(kScreen, kScreen);
    const glm::vec3 a = v.at(20, 30, 3), b = v.at(230, 50, 7), c3 = v.at(90, 240, 5);
    v.triangle(a, b, c3, glm::vec3(1, 0, 0));
    v.triangle(a, b, c3, glm::vec3(0, 0, 1));
    const Drawn drawn = draw_flat(config, v.scene, threads);
    const Coverage cov = coverage_counts(config, v.scene, threads);
    std::uint64_t red = 0, blue = 0, covered = 0;
    for (std::size_t p = 0; p < cov.count.size(); ++p) {
      if (cov.count[p] == 0) continue;
      ++covered;
      red += drawn.image.rgb[p * 3] > 128;
      blue += drawn.image.rgb[p * 3 + 2] > 128;
    }
    ExtremeCase c;
    c.name = "coincident planes";
    c.expected =
        "the same triangle drawn twice (red, then blue) computes identical depths, so "
        "the strict z test keeps the first everywhere: no stitching";
    c.observed = fmt::format("{} covered pixels: {} red, {} blue", covered, red, blue);
    c.pass = covered > 0 && red == covered && blue == 0;
    cases.push_back(c);
  }

  {  // Both ends of the depth range.
    ViewScene v(kScreen, kScreen);
    // Depth is 1 - (n / d)(f - d) / (f - n) of the range: about 17 z-units from the near end and
    // 170 from the far end (perspective compresses depth there; closer is clipped).
    const double n = 1.0 + 1e-6, f = 99.9;
    // Overlapping: the far one drawn last must stay behind; beside it a far one alone.
    v.triangle(v.at(20, 20, n), v.at(120, 20, n), v.at(20, 200, n), glm::vec3(1, 0, 0));
    v.triangle(v.at(10, 10, f), v.at(130, 10, f), v.at(10, 220, f), glm::vec3(0, 0, 1));
    v.triangle(v.at(140, 20, f), v.at(240, 20, f), v.at(240, 200, f), glm::vec3(0, 0, 1));
    const Drawn drawn = draw_flat(config, v.scene, threads);
    const Visibility vis = check_two_planes(config, v.scene, drawn, 0.5);
    // Every pixel certainly inside the lone far triangle must be drawn (beat the cleared z).
    const std::vector<ScreenTriangle> tris = project(config, v.scene);
    const double eps = std::ldexp(1.0, -config.gp.subpixel_bits);
    std::uint64_t far_missing = 0, far_inside = 0;
    for (int y = 0; y < kScreen; ++y) {
      for (int x = 0; x < kScreen; ++x) {
        const auto d = edge_distances(tris.back(), x + 0.5, y + 0.5);
        if (std::min({d[0], d[1], d[2]}) <= eps) continue;
        ++far_inside;
        far_missing += drawn.image.rgb[(static_cast<std::size_t>(y) * kScreen + x) * 3 + 2] < 128;
      }
    }
    ExtremeCase c;
    c.name = "depth at both ends of its range";
    c.expected =
        "a triangle at the near plane hides one at the far plane drawn after it, and a "
        "triangle at the far plane still beats the cleared depth: no wrap-around";
    c.observed = fmt::format(
        "{} of {} overlapping pixels show the far triangle; {} of {} pixels "
        "of the lone far triangle not drawn; {} dropped for overflow",
        vis.wrong, vis.checked, far_missing, far_inside, drawn.overflow);
    c.pass = vis.wrong == 0 && vis.checked > 0 && far_missing == 0 && far_inside > 0;
    cases.push_back(c);
  }
  return cases;
}

std::vector<ExtremeCase> scene_extreme_cases(const MachineConfig& config, const Scene& scene,
                                             int threads) {
  std::vector<ExtremeCase> cases;
  const Drawn drawn = draw_flat(config, scene, threads);
  {
    ExtremeCase c;
    c.name = "scene: coefficient overflow";
    c.expected =
        "every triangle's depth, colour and edge coefficients fit "
        "evaluator.coefficient_bits; any that does not is counted, never silent";
    c.observed = fmt::format(
        "{} of {} triangles dropped for coefficient overflow (with the flat "
        "firmware's expressions)",
        drawn.overflow, scene.mesh.triangles.size());
    if (drawn.overflow > 0) {
      c.observed +=
          ": a triangle nearly edge-on to the screen has a depth gradient A or B too large "
          "for the coefficient width (the constant term is sent modulo 2^coefficient_bits, "
          "which is exact, but the gradient itself must fit); each leaves a hole. More "
          "evaluator.coefficient_bits (with result_bits), or fewer gp.depth_bits, would keep them";
    }
    c.pass = drawn.overflow == 0;
    cases.push_back(c);
  }
  const Coverage cov = coverage_counts(config, scene, threads);
  const CoverageCheck check = check_coverage(config, scene, cov);
  cases.push_back({"scene: coverage",
                   "every pixel centre certainly inside a triangle is counted by it and none "
                   "certainly outside is",
                   counts_text(check), check.missing == 0 && check.extra == 0});
  if (is_closed(scene.mesh)) {
    std::uint64_t odd = 0, covered = 0;
    for (auto n : cov.count) {
      odd += n & 1;
      covered += n > 0;
    }
    cases.push_back(
        {"scene: parity across the closed mesh",
         "every edge is shared by two triangles, so every pixel is covered an even number of "
         "times (each ray enters and leaves): shared edges own each centre exactly once",
         fmt::format("{} of {} covered pixels have an odd count", odd, covered),
         odd == 0 && cov.clipped_away == 0});
  } else {
    cases.push_back({"scene: parity across the closed mesh",
                     "applies only to closed meshes (every edge shared by two triangles)",
                     "the mesh is open or non-manifold: not checked", true});
  }
  const int need = depth_fraction_bits_needed(config.screen.width, config.screen.height);
  cases.push_back(
      {"scene: depth precision of this machine",
       fmt::format("evaluator.fraction_bits >= log2(2 x {}) = {} for a {}-bit z-buffer",
                   std::max(config.screen.width, config.screen.height), need, config.gp.depth_bits),
       fmt::format("evaluator.fraction_bits = {}", config.evaluator.fraction_bits),
       config.evaluator.fraction_bits >= need});
  return cases;
}

report::Report extremes_report(const std::vector<ExtremeCase>& cases) {
  using namespace report;
  Table t;
  t.id = "extremes";
  t.columns = {text_column("result", "PASS or FAIL"), text_column("case"),
               text_column("expected", "What a correct machine does"),
               text_column("observed", "What the firmware, executing on the pixel arrays, did")};
  int failed = 0;
  for (const ExtremeCase& c : cases) {
    t.add_row({c.pass ? "PASS" : "FAIL", c.name, c.expected, c.observed});
    failed += !c.pass;
  }
  Report r;
  r.title = "pp5sim extremes: numerical stability at the extremes";
  Section& s = r.add_section("cases", "Cases");
  s.blocks.push_back(t);
  s.blocks.push_back(Note{
      failed ? Note::Level::warning : Note::Level::info,
      fmt::format("{} cases, {} passed, {} failed", cases.size(), cases.size() - failed, failed)});
  return r;
}

std::string format_extremes(const std::vector<ExtremeCase>& cases) {
  const report::Report r = extremes_report(cases);
  const auto& blocks = r.sections.at(0).blocks;
  return report::text_records(std::get<report::Table>(blocks.at(0)), 2) + "\n" +
         std::get<report::Note>(blocks.at(1)).text + "\n";
}

}  // namespace pp5
