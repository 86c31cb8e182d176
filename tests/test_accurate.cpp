// Accurate scan conversion (Rossignac, 9.4): the GP's side planes (models/gp/
// accurate_expressions.hpp), accurate.pp5 against phong.pp5 on the provoking scene and on a
// curved closed mesh (sim/analysis/scan_conversion.hpp), and edges without one neighbour.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "common/read_file.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/display_list/mesh_adjacency.hpp"
#include "models/gp/accurate_expressions.hpp"
#include "models/gp/geometry.hpp"
#include "sim/analysis/extremes.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/analysis/scan_conversion.hpp"
#include "sim/scene/scene.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

MachineConfig machine(int subpixel_bits, int significand_bits = 62) {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=2", "renderer.count=2",
              "gp.subpixel_bits=" + std::to_string(subpixel_bits),
              "gp.significand_bits=" + std::to_string(significand_bits)});
  return config;
}

ScanConversionReport measure(const MachineConfig& config, const Scene& scene) {
  return measure_scan_conversion(config, scene, test::load_program("phong", config),
                                 test::load_program("accurate", config), 2);
}

// Every edge's side plane as each of its two triangles computes it.
struct Sides {
  std::vector<std::array<SidePlane, 3>> of;
};
Sides side_planes(const MachineConfig& config, const Scene& scene, const MeshAdjacency& adjacency) {
  const GeometryParams params = geometry_params(config);
  const GeometryEngine geometry(params, scene);
  Sides s;
  s.of.resize(scene.mesh.triangles.size());
  std::vector<ScreenTriangle> pieces;
  SetupCounts counts;
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    pieces.clear();
    geometry.transform(i, pieces, counts);
    REQUIRE(pieces.size() == 1);  // the built-in scenes are framed whole
    SetupContext c{params, scene.camera, pieces[0]};
    c.adjacency = &adjacency;
    c.mesh = &scene.mesh;
    c.depth_max = std::ldexp(1.0, params.depth_bits) - 1.0;
    for (int e = 0; e < 3; ++e)
      s.of[static_cast<std::size_t>(i)][static_cast<std::size_t>(e)] = side_plane(c, e);
  }
  return s;
}

// Per pixel, the number of unsnapped screen triangles containing its centre, or -1 where the
// centre lies within 2^-10 pixel of a triangle's edge line (too close to call).
std::vector<int> exact_coverage(const MachineConfig& config, const Scene& scene) {
  const GeometryEngine geometry(geometry_params(config), scene);
  const int w = config.screen.width, h = config.screen.height;
  std::vector<int> count(static_cast<std::size_t>(w) * h, 0);
  std::vector<ScreenTriangle> pieces;
  SetupCounts counts;
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    geometry.transform(i, pieces, counts);
  }
  for (const ScreenTriangle& t : pieces) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const glm::dvec2 c(x + 0.5, y + 0.5);
        int inside = 0, close = 0;
        double area = 0;
        for (int e = 0; e < 3; ++e) {
          const glm::dvec2 a = t.v[e].position, b = t.v[(e + 1) % 3].position;
          area += a.x * b.y - b.x * a.y;
        }
        for (int e = 0; e < 3; ++e) {
          const glm::dvec2 a = t.v[e].position, b = t.v[(e + 1) % 3].position;
          const double cross =
              ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)) * (area > 0 ? 1.0 : -1.0);
          const double distance = cross / glm::length(b - a);
          if (distance > 0) ++inside;
          if (std::fabs(distance) < 1.0 / 1024) ++close;
        }
        int& n = count[static_cast<std::size_t>(y) * w + x];
        if (n < 0) continue;
        if (close > 0 && inside + close >= 3) {
          n = -1;
        } else if (inside == 3) {
          ++n;
        }
      }
    }
  }
  return count;
}

// Two surfaces facing the eye along -z, a 90-degree field of view on 256 x 256, so that a
// point (x, y, -d) lands on pixel ((x / d + 1) 128, (1 - y / d) 128): a square at depth 2
// over pixels 32 .. 224 (two triangles, its diagonal from (32, 224) to (224, 32)) and,
// optionally, a triangle at depth 4 wholly behind it, over (64, 192), (192, 192), (128, 64).
Scene occluded_triangle_scene(bool with_hidden) {
  Scene scene;
  scene.name = "occluded-triangle";
  scene.camera = {{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90.0f, 0.5f, 20.0f};
  scene.lights = {default_light(scene.camera)};
  scene.background = glm::vec3(0.0f);
  auto vertex = [&](float x, float y, float z) {
    scene.mesh.vertices.push_back({{x, y, z}, {0, 0, 1}, {0.8f, 0.8f, 0.8f}});
  };
  vertex(-1.5f, -1.5f, -2), vertex(1.5f, -1.5f, -2), vertex(1.5f, 1.5f, -2),
      vertex(-1.5f, 1.5f, -2);
  scene.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  if (with_hidden) {
    vertex(-2, -2, -4), vertex(2, -2, -4), vertex(0, 2, -4);
    scene.mesh.triangles.push_back({4, 5, 6});
  }
  return scene;
}

// The distance from c to the segment a-b, written out for the test.
double segment_gap(glm::dvec2 c, glm::dvec2 a, glm::dvec2 b) {
  const double t = std::clamp(glm::dot(c - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
  return glm::length(c - (a + t * (b - a)));
}

}  // namespace

TEST_CASE("accurate: the two triangles of an edge get opposite side planes", "[accurate]") {
  const MachineConfig config = machine(4);
  const Scene scene = make_builtin_scene("sphere");
  const MeshAdjacency adjacency = build_mesh_adjacency(scene.mesh);
  const Sides s = side_planes(config, scene, adjacency);
  int planes = 0, silhouettes = 0;
  for (int t = 0; t < static_cast<int>(scene.mesh.triangles.size()); ++t) {
    for (int e = 0; e < 3; ++e) {
      const SidePlane& a = s.of[static_cast<std::size_t>(t)][static_cast<std::size_t>(e)];
      const int n = adjacency.across(t, e);
      REQUIRE(n >= 0);  // closed
      int f = 0;
      while (adjacency.across(n, f) != t) ++f;
      const SidePlane& b = s.of[static_cast<std::size_t>(n)][static_cast<std::size_t>(f)];
      INFO("triangle " << t << " edge " << e << ", neighbour " << n << " edge " << f);
      REQUIRE(a.kind == b.kind);
      if (a.kind != SideKind::plane) continue;
      ++planes;
      CHECK(a.fraction_bits == b.fraction_bits);
      CHECK(a.silhouette == b.silhouette);
      // K (D - t) and K' (-D - t'): an interior edge has K = K' and t + t' = 1, so that every
      // integer value of D is owned by exactly one of them; a silhouette K = -K', t = t' = 0.
      const QuadraticCoefficients& p = a.coefficients;
      const QuadraticCoefficients& q = b.coefficients;
      if (a.silhouette) {
        ++silhouettes;
        CHECK(a.sign == -b.sign);
        CHECK(p.D == q.D);
        CHECK(p.E == q.E);
        CHECK(p.F == q.F);
      } else {
        CHECK(a.sign == b.sign);
        CHECK(p.D == -q.D);
        CHECK(p.E == -q.E);
        CHECK(p.F + q.F == -1);
      }
    }
  }
  // The sphere's faces are curved enough that most edges use the neighbour's plane, and its
  // outline is made of silhouette edges.
  CHECK(planes > 3 * static_cast<int>(scene.mesh.triangles.size()) / 2);
  CHECK(silhouettes > 0);
}

TEST_CASE(
    "accurate: on the folded slab the standard program shows the hidden back, accurate never does",
    "[accurate]") {
  // Two sub-pixel bits: vertices snapped to a quarter pixel, so E = 0.18 pixel.
  const MachineConfig config = machine(2);
  const Scene scene = make_builtin_scene("folded-slab");
  const ScanConversionReport r = measure(config, scene);
  REQUIRE(r.closed);
  CHECK(r.standard.show_through > 0);
  CHECK(r.accurate.show_through == 0);
  // The paper's bound on the standard program's error where a centre can only change plane,
  // not layer, for this round-off; far larger errors where it changes layer.
  CHECK(r.standard.bound_ratio <= 1.0);
  CHECK(r.standard.shared_edge_max_error > 1000.0);
  CHECK(r.standard.edge_max_error > 2.0 * r.standard.shared_edge_max_error);
  // Accurate's depth is its own plane at every pixel it owns: within the z-buffer's floor()
  // and the plane's rounding.
  CHECK(r.accurate.edge_max_error <= kDepthResolution);
  CHECK(r.accurate.interior_max_error <= kDepthResolution);
  CHECK(r.standard.parity_errors == 0);
  CHECK(r.accurate.parity_errors == 0);
  CHECK(r.accurate.missing == 0);
}

TEST_CASE("accurate: edge pixels are near any triangle's edge, a hidden one's too", "[accurate]") {
  // The square alone, then with the triangle behind it: the hidden triangle's edges add
  // every covered centre within max(1, E) = 1 pixel of them (E = 0.044 at 4 sub-pixel bits)
  // not already within 1 pixel of the square's edges. Counted here by brute force over every
  // centre (no centre lies within 1e-3 pixel of distance 1 from these edges, so the float
  // projection cannot move one across). Counting only the front triangle's edges (the
  // earlier definition) adds none.
  const MachineConfig config = machine(4);
  const ScanConversionReport front = measure(config, occluded_triangle_scene(false));
  const ScanConversionReport both = measure(config, occluded_triangle_scene(true));
  REQUIRE(front.E < 1.0);
  using P = glm::dvec2;
  const std::vector<std::array<P, 2>> square = {{P(32, 224), P(224, 224)},
                                                {P(224, 224), P(224, 32)},
                                                {P(224, 32), P(32, 32)},
                                                {P(32, 32), P(32, 224)},
                                                {P(32, 224), P(224, 32)}};
  const std::vector<std::array<P, 2>> hidden = {
      {P(64, 192), P(192, 192)}, {P(192, 192), P(128, 64)}, {P(128, 64), P(64, 192)}};
  auto near = [](P c, const std::vector<std::array<P, 2>>& edges) {
    for (const auto& e : edges) {
      if (segment_gap(c, e[0], e[1]) <= 1.0) return true;
    }
    return false;
  };
  std::uint64_t square_edge = 0, hidden_only = 0;
  for (int y = 32; y < 224; ++y) {
    for (int x = 32; x < 224; ++x) {
      const P c(x + 0.5, y + 0.5);
      if (near(c, square)) {
        ++square_edge;
      } else if (near(c, hidden)) {
        ++hidden_only;
      }
    }
  }
  REQUIRE(hidden_only > 700);  // about twice the hidden triangle's perimeter of 414 pixels
  for (const ScanConversionMethod* m : {&front.standard, &front.accurate}) {
    CHECK(m->missing == 0);
    CHECK(m->edge_pixels == square_edge);
  }
  for (const ScanConversionMethod* m : {&both.standard, &both.accurate}) {
    CHECK(m->missing == 0);
    CHECK(m->edge_pixels == square_edge + hidden_only);
    CHECK(m->show_through == 0);
  }
}

TEST_CASE("accurate: coarse edge coefficients make the standard program misclassify (9.3.3)",
          "[accurate]") {
  // The vertices at the default sixteenth of a pixel; the edge coefficients kept to 10
  // significant bits, so the sent edges move by up to E_edge = 2^-10 2 R pixels (R the
  // farthest pixel from the origin, 362 on 256 x 256), 0.71: far more than the snap's 0.044.
  const MachineConfig exact = machine(4);
  const MachineConfig coarse = machine(4, 10);
  const Scene scene = make_builtin_scene("folded-slab");
  const ScanConversionReport e = measure(exact, scene);
  const ScanConversionReport c = measure(coarse, scene);
  REQUIRE(c.closed);
  CHECK(e.E_edge == 0.0);
  CHECK(c.E_edge > 4.0 * c.E_snap);
  // The standard program draws more centres with the wrong plane, so more hidden surface
  // shows through and the largest shared-edge error grows.
  CHECK(c.standard.show_through > e.standard.show_through);
  CHECK(c.standard.shared_edge_max_error > e.standard.shared_edge_max_error);
  // Still within the bounds for the configured round-off: 2ME where a centre changes plane,
  // M (5/4) E + 2 against the exact picture moved by 5E/4 where it changes layer.
  CHECK(c.standard.bound_ratio <= 1.0);
  CHECK(c.standard.layer_bound_ratio <= 1.0);
  // Rounding is symmetric, so a shared edge's two functions stay exact negatives; but the
  // three rounded lines of the edges around a vertex no longer meet in one point, so the
  // standard tiling has cracks and overlaps there (odd coverage on a closed mesh), which
  // exact coefficients do not. Those pixels are in neither bound (parity_errors counts them).
  CHECK(e.standard.parity_errors == 0);
  CHECK(c.standard.parity_errors > 0);
  // The GP's arithmetic rounds the accurate program's side tests and planes too
  // (gp.significand_bits reaches every value it sends): at 10 bits it is no longer exact, and
  // it loses its guarantee (its depth error exceeds the z-buffer's resolution).
  CHECK(e.accurate.edge_max_error <= kDepthResolution);
  CHECK(c.accurate.edge_max_error > 100.0 * kDepthResolution);
}

TEST_CASE("accurate: at the i860's single precision the accurate program still wins",
          "[accurate]") {
  // 24 significant bits for every value the GP sends (edges, planes, side tests): the
  // accurate program's error grows from the z-buffer's resolution but stays far below the
  // standard program's, and no hidden surface shows through it.
  const MachineConfig single = machine(4, 24);
  for (const char* name : {"folded-slab", "torus"}) {
    INFO(name);
    const ScanConversionReport r = measure(single, make_builtin_scene(name));
    REQUIRE(r.closed);
    CHECK(r.standard.show_through > 0);
    CHECK(r.accurate.show_through == 0);
    CHECK(r.accurate.parity_errors == 0);
    CHECK(r.accurate.edge_max_error < 100.0 * kDepthResolution);
    CHECK(100.0 * r.accurate.edge_max_error < r.standard.shared_edge_max_error);
  }
}

TEST_CASE("accurate: neither ingredient alone, both together, remove the edge error",
          "[accurate]") {
  // The ablation of pp5sim scanconvert --ablation: the standard program with its depth drawn
  // through the unsnapped vertices, and the accurate program's classification with the
  // snapped vertices' depth. Only the two together keep every edge pixel on its own plane.
  const MachineConfig config = machine(4);
  const AssemblerOptions options = assembler_options(config);
  const std::string dir = std::string(PP5_SOURCE_DIR) + "/firmware/programs/";
  const Program phong = test::load_program("phong", config);
  const Program accurate = test::load_program("accurate", config);
  auto text = [&](const char* name) {
    return read_regular_file(dir + name + ".pp5", kMaxProgramBytes, "a firmware program");
  };
  const Program phong_unsnapped =
      with_depth_expression(phong, text("phong"), "depth", "plane_depth", options);
  const Program accurate_snapped =
      with_depth_expression(accurate, text("accurate"), "plane_depth", "depth", options);
  CHECK_THROWS_WITH(with_depth_expression(phong, text("phong"), "plane_depth", "depth", options),
                    Catch::Contains("no line 'qcmp.lt z, plane_depth'"));
  for (const char* name : {"folded-slab", "torus"}) {
    INFO(name);
    const Scene scene = make_builtin_scene(name);
    const ScanConversionReport a =
        measure_scan_conversion(config, scene, phong, accurate_snapped, 2);
    const ScanConversionReport b =
        measure_scan_conversion(config, scene, phong_unsnapped, accurate, 2);
    // Unsnapped planes alone: the interior is exact, the edges are not.
    CHECK(b.standard.interior_max_error <= a.standard.interior_max_error);
    CHECK(b.standard.edge_max_error > 1000.0 * kDepthResolution);
    // Neighbour planes alone: the snapped plane's error stays, inside and at the edges.
    CHECK(a.accurate.edge_max_error > 1000.0 * kDepthResolution);
    CHECK(a.accurate.interior_max_error > 100.0 * kDepthResolution);
    // Both: the z-buffer's resolution everywhere, nothing hidden shows.
    CHECK(b.accurate.edge_max_error <= kDepthResolution);
    CHECK(b.accurate.show_through == 0);
    CHECK(a.accurate.show_through + b.standard.show_through > 0);
    // The table's column: the share of the accurate set-up's edge tests that fall back to
    // the edge's own line (most of the folded slab's, a third of the closed torus's, whose
    // every edge has a neighbour: its own line where the planes are nearly coplanar).
    const std::uint64_t own = b.sides[static_cast<int>(SideKind::boundary)] +
                              b.sides[static_cast<int>(SideKind::non_manifold)] +
                              b.sides[static_cast<int>(SideKind::degenerate)] +
                              b.sides[static_cast<int>(SideKind::coplanar)];
    std::uint64_t all = 0;
    for (std::uint64_t n : b.sides) all += n;
    REQUIRE(all > 0);
    const double share = static_cast<double>(own) / static_cast<double>(all);
    CHECK((std::string(name) == "torus" ? share < 0.5 : share > 0.5));
    const std::string table = format_scan_conversion_ablation({{a, b}});
    CHECK_THAT(table, Catch::Contains(fmt::format("{:.1f}% ({} of {})", 100 * share, own, all)));
  }
}

TEST_CASE("accurate: the standard program's worst error is within the bound at each round-off",
          "[accurate]") {
  // Configured round-offs: the snap alone (a quarter pixel), and the GP's arithmetic at IEEE
  // single on the sixteenth-pixel snap. (The paper's bound counts the edges' round-off only;
  // below about 16 significant bits the planes' own rounding, which the GP's arithmetic
  // applies too, exceeds it: README's scan conversion table by precision.)
  const auto [subpixel_bits, edge_bits] = GENERATE(std::make_pair(2, 62), std::make_pair(4, 24));
  INFO("gp.subpixel_bits = " << subpixel_bits << ", gp.significand_bits = " << edge_bits);
  const MachineConfig config = machine(subpixel_bits, edge_bits);
  for (const char* name : {"folded-slab", "torus"}) {
    INFO(name);
    const ScanConversionReport r = measure(config, make_builtin_scene(name));
    CHECK(r.E == r.E_snap + r.E_edge);
    // Centres that change plane: within 2ME, and the error is real (not a vacuous bound).
    CHECK(r.standard.bound_ratio <= 1.0);
    CHECK(r.standard.shared_edge_max_error > 10.0 * kDepthResolution);
    // Centres that change layer: within M (5/4) E + 2 of the exact picture moved by 5E/4,
    // though their plain error (against the unmoved picture) is the gap between layers.
    CHECK(r.standard.layer_pixels > 0);
    CHECK(r.standard.layer_bound_ratio <= 1.0);
    CHECK(r.standard.edge_max_error > r.standard.layer_max_error);
    CHECK(r.accurate.edge_max_error < 100.0 * kDepthResolution);
  }
}

TEST_CASE("accurate: a finely tessellated sphere, at the default round-off", "[accurate]") {
  const MachineConfig config = machine(4);
  SceneOptions options;
  options.tessellation_u = 128;
  options.tessellation_v = 64;
  const Scene scene = make_builtin_scene("sphere", options);
  const ScanConversionReport r = measure(config, scene);
  REQUIRE(r.closed);
  CHECK(r.accurate.show_through == 0);
  CHECK(r.standard.bound_ratio <= 1.0);
  CHECK(r.accurate.edge_max_error <= kDepthResolution);
  CHECK(r.accurate.edge_max_error < r.standard.edge_max_error);
  CHECK(r.accurate.parity_errors == 0);
}

TEST_CASE("accurate: boundary and non-manifold edges are classified by their own lines",
          "[accurate]") {
  // Three triangles hinged on one edge {0, 1} (non-manifold), each with two boundary edges,
  // facing the camera at different slopes, and a fourth sharing a proper edge {1, 2} with the
  // first.
  Scene scene = make_builtin_scene("two-triangles");
  Mesh mesh;
  const glm::vec3 colour(0.8f, 0.6f, 0.4f);
  for (const glm::vec3 p :
       {glm::vec3(0, -1, 0), glm::vec3(0, 1, 0), glm::vec3(1.2f, 0.2f, 0.3f),
        glm::vec3(-1, 0.1f, 0.5f), glm::vec3(0.9f, -0.9f, -0.6f), glm::vec3(1.4f, 1.1f, 0.1f)})
    mesh.vertices.push_back({p, {0, 0, 1}, colour});
  mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 5, 2}};
  compute_smooth_normals(mesh);
  scene.mesh = mesh;
  scene.name = "hinge";
  scene.camera = frame_mesh(scene.mesh, glm::vec3(0.2f, 0.3f, 1.0f), 40.0f);
  // Exact, and at the i860's single precision (24 significant bits for every value sent, the
  // side tests' planes included).
  const int edge_bits = GENERATE(62, 24);
  INFO("gp.significand_bits = " << edge_bits);
  const MachineConfig config = machine(4, edge_bits);
  const MeshAdjacency adjacency = build_mesh_adjacency(scene.mesh);
  CHECK(adjacency.non_manifold_edges == 1);
  CHECK(adjacency.boundary_edges == 7);
  const Sides s = side_planes(config, scene, adjacency);
  CHECK(s.of[0][0].kind == SideKind::non_manifold);
  CHECK(s.of[1][0].kind == SideKind::non_manifold);
  CHECK(s.of[2][0].kind == SideKind::non_manifold);
  CHECK(s.of[3][2].kind == SideKind::plane);
  CHECK(s.of[0][2].kind == SideKind::boundary);
  // Coverage counted by firmware with accurate.pp5's tests equals the exact count of
  // unsnapped triangles containing each centre, wherever the centre is not within 2^-10 pixel
  // of an edge's line; the standard program's (snapped edges) does not.
  const std::vector<int> exact = exact_coverage(config, scene);
  const FieldFrame standard =
      render_field(config, scene,
                   assemble(kCoverageFirmware, "coverage", assembler_options(config)), "count", 1);
  const FieldFrame accurate = render_field(
      config, scene,
      assemble(kAccurateCoverageFirmware, "accurate-coverage", assembler_options(config)), "count",
      1);
  std::uint64_t covered = 0, wrong_standard = 0, wrong_accurate = 0;
  for (std::size_t q = 0; q < exact.size(); ++q) {
    if (exact[q] < 0) continue;
    covered += static_cast<std::uint64_t>(exact[q]);
    wrong_standard += standard.values[q] != static_cast<std::uint64_t>(exact[q]) ? 1 : 0;
    wrong_accurate += accurate.values[q] != static_cast<std::uint64_t>(exact[q]) ? 1 : 0;
  }
  CHECK(covered > 1000);
  CHECK(wrong_accurate == 0);
  CHECK(wrong_standard > 0);
}

TEST_CASE("accurate: the expressions in the registry", "[accurate]") {
  ExpressionSet sides, wide;
  sides.set(static_cast<int>(Expression::side0));
  wide.set(static_cast<int>(Expression::wide1));
  CHECK(needs_adjacency(sides));
  CHECK_FALSE(widens_bounds(sides));
  CHECK(widens_bounds(wide));
  CHECK_FALSE(needs_adjacency(wide));
  // accurate.pp5 sends the enlarged edges, the sides and its own depth plane instead of the
  // snapped edges and depth: three linear expressions more than phong.
  const MachineConfig config = machine(4);
  const Program phong = test::load_program("phong", config);
  const Program accurate = test::load_program("accurate", config);
  CHECK(packet_words(accurate.procedure(Procedure::triangle).expressions, 2) ==
        packet_words(phong.procedure(Procedure::triangle).expressions, 2) + 3 * 3 * 2);
  CHECK(accurate.bits_used() == phong.bits_used());
}

TEST_CASE("accurate: edge coefficients kept to n significant bits", "[accurate]") {
  CHECK(round_significand(0b101101, 62) == 0b101101);
  // The GP's arithmetic on reals and wide integers: the same rounding.
  GeometryParams p3;
  p3.significand_bits = 3;
  CHECK(gp_round(11.0, p3) == 12.0);  // 1011: to 110 x 2
  CHECK(gp_round(13.0, p3) == 12.0);  // 1101: a tie (110.1), to even
  CHECK(gp_round(-11.0, p3) == -12.0);
  CHECK(gp_round(0.15625, p3) == 0.15625);  // 101 x 2^-5 already fits
  CHECK(gp_round(static_cast<__int128>(0b101101) << 70, p3) == static_cast<__int128>(0b110) << 73);
  CHECK(gp_round(0.1, GeometryParams{}) == 0.1);  // 62 bits: exact
  CHECK(round_significand(0b101101, 3) == 0b110000);
  CHECK(round_significand(-0b101101, 3) == -0b110000);
  CHECK(round_significand(0b101000, 3) == 0b101000);
  CHECK(round_significand(0b100100, 2) == 0b100000);  // a tie, to even
  CHECK(round_significand(0b101100, 2) == 0b110000);  // a tie, to even
  CHECK(round_significand((std::int64_t{1} << 40) + 12345, 20) == std::int64_t{1} << 40);
  // The key is declared with its range: below 4 or above 62 it is refused, by name.
  MachineConfig config = MachineConfig::defaults();
  for (const char* bad : {"gp.edge_significand_bits=3", "gp.edge_significand_bits=63"}) {
    try {
      config.set(bad);
      FAIL("accepted: " << bad);
    } catch (const ConfigError& e) {
      CHECK(std::string(e.what()).find("gp.edge_significand_bits") != std::string::npos);
    }
  }
  // The rounding is in the coefficients the GP sends: a coarse setting changes the edge
  // expressions of most triangles of the sphere, and the two triangles of every edge still get
  // exactly opposite functions (so a centre is owned by exactly one of them), or on a
  // silhouette the same one.
  const Scene scene = make_builtin_scene("sphere");
  const MeshAdjacency adjacency = build_mesh_adjacency(scene.mesh);
  ExpressionSet needed;
  for (Expression e : {Expression::edge0, Expression::edge1, Expression::edge2})
    needed.set(static_cast<int>(e));
  auto edges = [&](const MachineConfig& c) {
    const GeometryEngine geometry(geometry_params(c), scene);
    std::vector<std::array<QuadraticCoefficients, 3>> out(scene.mesh.triangles.size());
    std::vector<ScreenTriangle> pieces;
    SetupCounts counts;
    for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
      pieces.clear();
      geometry.transform(i, pieces, counts);
      REQUIRE(pieces.size() == 1);
      SetupResult r;
      if (!geometry.setup(pieces[0], needed, r, counts)) continue;  // no pixel centre
      for (int e = 0; e < 3; ++e)
        out[static_cast<std::size_t>(i)][static_cast<std::size_t>(e)] =
            r.values.expressions[static_cast<std::size_t>(Expression::edge0) +
                                 static_cast<std::size_t>(e)];
    }
    return out;
  };
  const auto exact = edges(machine(4));
  const auto coarse = edges(machine(4, 8));
  int changed = 0, opposite = 0;
  for (int t = 0; t < static_cast<int>(scene.mesh.triangles.size()); ++t) {
    for (int e = 0; e < 3; ++e) {
      const QuadraticCoefficients& p =
          coarse[static_cast<std::size_t>(t)][static_cast<std::size_t>(e)];
      const QuadraticCoefficients& x =
          exact[static_cast<std::size_t>(t)][static_cast<std::size_t>(e)];
      if (p.D != x.D || p.E != x.E || p.F != x.F) ++changed;
      // Kept to 8 bits; C then less 1 by the top-left rule on some edges.
      CHECK(round_significand(p.D, 8) == p.D);
      CHECK(round_significand(p.E, 8) == p.E);
      CHECK((round_significand(p.F, 8) == p.F || round_significand(p.F + 1, 8) == p.F + 1));
      if (x.D == 0 && x.E == 0) continue;  // not set up
      const int n = adjacency.across(t, e);
      REQUIRE(n >= 0);
      int f = 0;
      while (adjacency.across(n, f) != t) ++f;
      const QuadraticCoefficients& xq =
          exact[static_cast<std::size_t>(n)][static_cast<std::size_t>(f)];
      if (xq.D == 0 && xq.E == 0) continue;
      const QuadraticCoefficients& q =
          coarse[static_cast<std::size_t>(n)][static_cast<std::size_t>(f)];
      if (x.D == -xq.D && x.E == -xq.E) {
        // Opposite sides on the screen: exact negatives, the top-left rule's 1 taken from C of
        // exactly one of the two; so still after rounding.
        ++opposite;
        CHECK(p.D == -q.D);
        CHECK(p.E == -q.E);
        CHECK(p.F + q.F == -1);
      } else {
        // A silhouette (both faces on one side): the same function, rounded the same.
        REQUIRE((x.D == xq.D && x.E == xq.E && x.F == xq.F));
        CHECK((p.D == q.D && p.E == q.E && p.F == q.F));
      }
    }
  }
  CHECK(changed > 3 * static_cast<int>(scene.mesh.triangles.size()) / 2);
  CHECK(opposite > 3 * static_cast<int>(scene.mesh.triangles.size()) / 2);
}
