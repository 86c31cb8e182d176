// Spheres drawn with the evaluator's quadratic terms (models/gp/sphere.hpp): the firmware's
// coverage against the exact outline at every pixel centre, its depth against the stated
// bound, spheres and triangles in one z-buffer, and the extremes, each counted.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "models/gp/sphere.hpp"
#include "models/machine.hpp"
#include "sim/analysis/spheres.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/scene/sphere_scenes.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

MachineConfig small(std::vector<std::string> more = {}) {
  MachineConfig config = MachineConfig::defaults();
  more.insert(more.begin(), {"screen.width=256", "screen.height=256"});
  config.set(more);
  return config;
}

// The GP's view of every sphere of the scene (dropped ones absent).
std::vector<ScreenSphere> project_all(const MachineConfig& config, const Scene& scene,
                                      SetupCounts& counts) {
  const SphereProjector projector(geometry_params(config), scene.camera);
  std::vector<ScreenSphere> out;
  for (std::size_t k = 0; k < scene.spheres.size(); ++k) {
    ScreenSphere s;
    if (projector.project(scene.spheres[k], static_cast<int>(k), s, counts)) out.push_back(s);
  }
  return out;
}

// A pixel where some sphere's scaled conic lies within the fixed-point rounding bound of 0:
// there the integer conic, not the real one, decides (models/gp/sphere.hpp).
bool ambiguous(const std::vector<ScreenSphere>& spheres, int x, int y) {
  for (const ScreenSphere& s : spheres) {
    const double dx = x - static_cast<double>(s.x0), dy = y - static_cast<double>(s.y0);
    const double q = std::ldexp(s.conic.at(dx, dy), s.conic_shift);
    if (std::fabs(q) <= sphere_rounding_bound(dx, dy) + 1.0) return true;
  }
  return false;
}

struct CoverageCheck {
  std::uint64_t covered = 0, wrong = 0, ambiguous = 0;
};

// Coverage of the firmware against the ray cast at every pixel centre.
CoverageCheck check_coverage(const MachineConfig& config, const Scene& scene) {
  SetupCounts counts;
  const auto screen = project_all(config, scene, counts);
  const RayCast truth = ray_cast(config, scene);
  const DrawnSpheres drawn = draw_spheres(config, scene, test::load_program("phong", config), 2);
  CoverageCheck c;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      const bool exact = truth.what[i] >= 0;
      c.covered += exact;
      if (exact == (drawn.covered[i] != 0)) continue;
      if (ambiguous(screen, x, y)) {
        ++c.ambiguous;
      } else {
        ++c.wrong;
      }
    }
  }
  return c;
}

Scene camera_scene(std::vector<Sphere> spheres, float near_plane = 1.0f, float far_plane = 100.0f) {
  Scene scene;
  scene.name = "test-spheres";
  scene.spheres = std::move(spheres);
  scene.camera = {{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 40.0f, near_plane, far_plane};
  scene.lights = {default_light(scene.camera)};
  scene.background = glm::vec3(0.0f);
  return scene;
}

}  // namespace

TEST_CASE("sphere coverage equals the exact outline at every pixel centre", "[spheres]") {
  const MachineConfig config = small();
  for (const char* name : {"spheres", "molecule"}) {
    INFO(name);
    const CoverageCheck c = check_coverage(config, make_builtin_scene(name));
    REQUIRE(c.covered > 1000);
    CHECK(c.wrong == 0);
    // Pixel centres within the rounding bound of an outline: none expected at 40 bits.
    CHECK(c.ambiguous == 0);
  }
}

TEST_CASE("sphere depth stays within the stated bound of the exact sphere", "[spheres]") {
  const MachineConfig config = small();
  const Scene scene = make_builtin_scene("spheres");
  SetupCounts counts;
  const auto screen = project_all(config, scene, counts);
  REQUIRE(screen.size() == scene.spheres.size());
  const RayCast truth = ray_cast(config, scene);
  const DrawnSpheres drawn = draw_spheres(config, scene, test::load_program("phong", config), 2);
  double worst_ratio = 0, worst = 0;
  std::uint64_t checked = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      if (truth.what[i] < 0 || drawn.covered[i] == 0) continue;
      // The drawn depth is the least of the covering spheres' approximations, the truth the
      // least of their exact depths: they differ by at most the largest of their bounds.
      double bound = 0;
      for (const ScreenSphere& s : screen) {
        if (sphere_depth_at(config, scene, s.source, x, y) < 1e300) {
          bound = std::max(bound, s.depth_bound);
        }
      }
      const double error = std::fabs(static_cast<double>(drawn.z[i]) - truth.depth[i]);
      INFO("pixel " << x << ", " << y);
      REQUIRE(error <= bound);
      worst = std::max(worst, error);
      worst_ratio = std::max(worst_ratio, error / bound);
      ++checked;
    }
  }
  REQUIRE(checked > 1000);
  // The bound is tight: the worst pixel reaches a good part of it.
  CHECK(worst_ratio > 0.5);
  WARN("sphere depth: worst error " << worst << " depth units, " << worst_ratio
                                    << " of its pixel's bound");
}

TEST_CASE("spheres and triangles share one z-buffer, z-correct against a ray cast", "[spheres]") {
  const MachineConfig config = small();
  const Scene scene = make_builtin_scene("spheres-and-triangles");
  REQUIRE_FALSE(scene.mesh.triangles.empty());
  REQUIRE_FALSE(scene.spheres.empty());
  SetupCounts counts;
  const auto screen = project_all(config, scene, counts);
  double sphere_bound = 0;
  for (const ScreenSphere& s : screen) sphere_bound = std::max(sphere_bound, s.depth_bound);
  const RayCast truth = ray_cast(config, scene);
  const DrawnSpheres drawn = draw_spheres(config, scene, test::load_program("phong", config), 2);
  const std::vector<int> shown = shown_spheres(config, scene, {}, 2);
  std::uint64_t spheres_seen = 0, triangles_seen = 0, triangles_lost = 0;
  double worst_triangle = 0;
  for (int y = 1; y + 1 < truth.height; ++y) {
    for (int x = 1; x + 1 < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      // Away from the scene's silhouette, where snapped triangle edges may move coverage.
      bool inside = true;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          inside = inside && truth.what[i + static_cast<std::size_t>(dy * truth.width + dx)] != -1;
        }
      }
      if (!inside) continue;
      INFO("pixel " << x << ", " << y << " shows " << truth.what[i] << ", the firmware "
                    << shown[i]);
      REQUIRE(drawn.covered[i] == 1);
      const double error = std::fabs(static_cast<double>(drawn.z[i]) - truth.depth[i]);
      // The ray cast sees the same triangle at the pixel and its eight neighbours (away from
      // its edges, where the snapped edges may hand a centre to its neighbour).
      bool one_triangle = truth.what[i] < -1;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          one_triangle =
              one_triangle &&
              truth.what[i + static_cast<std::size_t>(dy * truth.width + dx)] == truth.what[i];
        }
      }
      if (one_triangle && shown[i] == -2) {
        // A triangle shown where the ray cast sees a triangle: the triangle's tolerance, not the
        // spheres' bound. The plane depth is rounded at 12 fraction bits (a few units) and runs
        // through vertices snapped by up to 2^-(subpixel_bits + 1) pixel in x and in y, which
        // moves it by up to that times its gradient (taken from the ray cast's neighbours),
        // doubled for margin.
        const double gx = std::fabs(truth.depth[i + 1] - truth.depth[i - 1]) / 2.0;
        const double gy = std::fabs(truth.depth[i + static_cast<std::size_t>(truth.width)] -
                                    truth.depth[i - static_cast<std::size_t>(truth.width)]) /
                          2.0;
        const double tolerance = 8.0 + (gx + gy) * std::ldexp(1.0, -config.gp.subpixel_bits);
        INFO("triangle tolerance " << tolerance);
        REQUIRE(error <= tolerance);
        worst_triangle = std::max(worst_triangle, error);
        ++triangles_seen;
      } else if (truth.what[i] < -1 && shown[i] == -2) {
        REQUIRE(error <= sphere_bound + 8.0);  // a triangle's edge
      } else if (truth.what[i] < -1) {
        // A sphere's approximate depth in front of the visible triangle: counted below.
        ++triangles_lost;
      } else {
        REQUIRE(error <= sphere_bound + 8.0);
        ++spheres_seen;
      }
    }
  }
  CHECK(spheres_seen > 1000);
  CHECK(triangles_seen > 1000);
  // Where a sphere passes through a triangle, its quadratic depth (up to sphere_bound off)
  // may win pixels the triangle owns: few, next to the intersection curves (1 at 256 x 256).
  WARN("triangle pixels a sphere covers wrongly: " << triangles_lost << "; worst triangle error "
                                                   << worst_triangle << " of bound "
                                                   << sphere_bound);
  CHECK(worst_triangle < sphere_bound / 100.0);
  CHECK(triangles_lost <= 10);
}

TEST_CASE("the visible sphere where spheres meet, read from firmware, within a stated count",
          "[spheres]") {
  // The four interpenetrating spheres at 256 x 256: which primitive each pixel shows is read
  // from firmware (shown_spheres) and compared with the ray cast. The quadric's depth (a line
  // in Q: up to about an eighth of a sphere's depth extent off) shows the wrong sphere at
  // 141 of the 5,019 pixels where two spheres overlap and at 104 of the 375 pixels on the
  // intersection curves; a 64 x 32 tessellation at 6 and 5. Away from the overlaps every
  // pixel shows its sphere.
  const MachineConfig config = small();
  const Scene scene = make_builtin_scene("spheres");
  const RayCast truth = ray_cast(config, scene);
  const Program phong = test::load_program("phong", config);
  const std::vector<int> shown = shown_spheres(config, scene, {}, 2);
  const SphereAccuracy a =
      measure_spheres(config, scene, truth, draw_spheres(config, scene, phong, 2), shown);
  CHECK(a.overlap_pixels == 5019);
  CHECK(a.curve_pixels == 375);
  CHECK(a.overlap_shown_wrong <= 160);
  CHECK(a.overlap_shown_wrong >= 100);  // the depth approximation's cost is real
  CHECK(a.curve_shown_wrong <= 120);
  CHECK(a.curve_shown_wrong < a.overlap_shown_wrong);
  std::uint64_t single = 0, single_wrong = 0;
  for (std::size_t i = 0; i < shown.size(); ++i) {
    if (truth.what[i] < 0 || truth.spheres[i] != 1) continue;
    ++single;
    single_wrong += shown[i] != truth.what[i];
  }
  CHECK(single > 15000);
  CHECK(single_wrong == 0);
  // A fine tessellation of the same spheres, its triangles standing for their spheres.
  Scene tess = scene;
  tess.spheres.clear();
  append_tessellated_spheres(scene.spheres, 64, 32, tess.mesh);
  std::vector<int> stands_for;
  for (std::size_t k = 0; k < scene.spheres.size(); ++k)
    stands_for.insert(stands_for.end(), 2 * 64 * 31, static_cast<int>(k));
  const SphereAccuracy t =
      measure_spheres(config, scene, truth, draw_spheres(config, tess, phong, 2),
                      shown_spheres(config, tess, stands_for, 2));
  CHECK(t.overlap_shown_wrong <= 10);
  CHECK(t.curve_shown_wrong <= 10);
}

TEST_CASE("sphere extremes: near plane, behind the eye, far plane, clipped, counted", "[spheres]") {
  const MachineConfig config = small();
  const Scene scene = camera_scene({
      {{0, 0, 5}, 1, glm::vec3(1)},         // behind the eye
      {{0, 0, -1.5f}, 1, glm::vec3(1)},     // crossing the near plane (at 1)
      {{0, 0, -99.5f}, 1, glm::vec3(1)},    // crossing the far plane (at 100)
      {{0, 0, -0.2f}, 0.1f, glm::vec3(1)},  // between the eye and the near plane
      {{0, 0, -300}, 1, glm::vec3(1)},      // beyond the far plane
      {{0.3f, 0, -10}, 1, glm::vec3(1)},    // drawn
  });
  const FrameResult r = simulate_frame(config, scene, test::load_program("phong", config), 2);
  CHECK(r.stats.integer("setup.sphere_behind_eye") == 1);
  CHECK(r.stats.integer("setup.sphere_near_plane") == 1);
  CHECK(r.stats.integer("setup.sphere_far_plane") == 1);
  CHECK(r.stats.integer("setup.clipped_away") == 2);
  CHECK(r.stats.integer("setup.packets") >= 1);
}

TEST_CASE("sphere extremes: sub-pixel and larger than the screen, exact coverage", "[spheres]") {
  const MachineConfig config = small();
  SECTION("sub-pixel spheres") {
    std::vector<Sphere> tiny;
    for (int k = 0; k < 40; ++k) {
      tiny.push_back(
          {{-4.0f + 0.2f * k, 0.13f * (k % 7) - 0.4f, -30.0f}, 0.02f + 0.002f * k, glm::vec3(1)});
    }
    const CoverageCheck c = check_coverage(config, camera_scene(tiny));
    CHECK(c.wrong == 0);
    CHECK(c.ambiguous == 0);
    WARN("sub-pixel spheres cover " << c.covered << " pixel centres of 40 spheres");
  }
  SECTION("a sphere larger than the screen") {
    // Seen under 60 degrees through a 40-degree field of view: every pixel is inside.
    const Scene scene = camera_scene({{{0.2f, 0.1f, -20.0f}, 10.0f, glm::vec3(1)}});
    const CoverageCheck c = check_coverage(config, scene);
    CHECK(c.covered == 256u * 256u);
    CHECK(c.wrong == 0);
    CHECK(c.ambiguous == 0);
  }
  SECTION("a sphere so near that its depth bound leaves the depth range: dropped, counted") {
    const Scene scene = camera_scene({{{0.2f, 0.1f, -3.0f}, 2.9f, glm::vec3(1)}}, 0.05f, 10.0f);
    const FrameResult r = simulate_frame(config, scene, test::load_program("phong", config), 2);
    CHECK(r.stats.integer("setup.sphere_near_plane") + r.stats.integer("setup.sphere_far_plane") ==
          1);
    CHECK(r.stats.integer("setup.packets") == 0);
  }
}

TEST_CASE("sphere extremes: coefficients at the edge of evaluator.coefficient_bits", "[spheres]") {
  const Scene scene = make_builtin_scene("spheres");
  SECTION("narrow coefficients: the conic's scale shrinks, coverage still exact") {
    // 30 bits (the least a 16-bit depth buffer allows) leave the conic 2^27: pixels within
    // the rounding bound are counted, every other one is exact.
    const MachineConfig config =
        small({"gp.depth_bits=16", "evaluator.coefficient_bits=30", "evaluator.result_bits=30"});
    const CoverageCheck c = check_coverage(config, scene);
    CHECK(c.wrong == 0);
    WARN("30-bit coefficients: " << c.ambiguous << " pixel centres within the rounding bound of "
                                 << c.covered);
  }
  SECTION("a coefficient that cannot wrap and does not fit drops the sphere, counted") {
    SetupCounts counts;
    MachineConfig config = small();
    GeometryParams p = geometry_params(config);
    p.coefficient_bits = 24;
    p.result_bits = 40;  // the evaluator would not wrap at 24 bits: no modular sending
    const SphereProjector projector(p, scene.camera);
    ScreenSphere s;
    REQUIRE(projector.project(scene.spheres[0], 0, s, counts));
    QuadraticCoefficients q;
    CHECK_FALSE(sphere_fixed_point(s.conic, std::ldexp(1.0, s.conic_shift), s.x0, s.y0, p, q));
  }
}

TEST_CASE("molecule files: PDB and mmCIF through gemmi, bad files name file and line",
          "[spheres][molecule]") {
  const std::string dir = std::string(PP5_SOURCE_DIR) + "/tests/data/molecules/";
  const auto pdb = read_molecule_file(dir + "tripeptide.pdb");
  const auto cif = read_molecule_file(dir + "tripeptide.cif");
  REQUIRE(pdb.size() == cif.size());
  REQUIRE(pdb.size() > 10);
  for (std::size_t k = 0; k < pdb.size(); ++k) {
    CHECK(pdb[k].center.x == Approx(cif[k].center.x));
    CHECK(pdb[k].radius == cif[k].radius);
  }
  CHECK(element_style("C").radius == 1.70f);
  CHECK(element_style("o").radius == 1.52f);
  auto fails = [&](const std::string& file, const std::string& what) {
    INFO(file);
    try {
      read_molecule_file(dir + file);
      FAIL("no error");
    } catch (const SceneError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(what) != std::string::npos);
    }
  };
  fails("bad_coordinate.pdb", "bad_coordinate.pdb:3: y coordinate");
  fails("short_record.pdb", "short_record.pdb:2:");
  fails("no_atoms.pdb", "no atoms");
  // PDB's columns hold F8.3 decimals: an exponent is refused as the format's, not as far.
  fails("far_atom.pdb", "x coordinate '   1e+30' (columns 31-38) is not a decimal number");
  fails("bad_syntax.cif", "bad_syntax.cif");
  // gemmi 0.5 would overflow an int reading it (fuzzing found it); refused with its place.
  fails("long_seq_id.cif",
        "long_seq_id.cif:21: the value at column 22 starts with a number larger than 2147483647");
  // Real files: a modern wwPDB mmCIF (ten-digit deposition ids), a PDB with UTF-8 names in
  // its AUTHOR and REMARK records. Both hold the tripeptide.
  CHECK(read_molecule_file(dir + "modern_deposition.cif").size() == pdb.size());
  CHECK(read_molecule_file(dir + "utf8_remark.pdb").size() == pdb.size());
  // A hexadecimal float passed strtod and gemmi read it as 0.
  fails("hex_coordinate.pdb",
        "hex_coordinate.pdb:6: x coordinate '  0x1p3 ' (columns 31-38) is not a decimal number");
  fails("missing.pdb", "missing.pdb");
}

TEST_CASE("scene files hold spheres and molecules, errors name the key", "[spheres]") {
  const Scene s = parse_scene_json(
      R"({"spheres": [{"center": [0, 0, 0], "radius": 1, "color": [1, 0, 0]},
                      {"molecule": "tripeptide.pdb", "translate": [5, 0, 0], "scale": 0.5}]})",
      "inline.json", std::string(PP5_SOURCE_DIR) + "/tests/data/molecules");
  REQUIRE(s.spheres.size() > 2);
  CHECK(s.spheres[0].radius == 1.0f);
  CHECK(s.spheres[1].radius == Approx(0.5f * element_style("N").radius));
  try {
    parse_scene_json(R"({"spheres": [{"center": [0, 0, 0], "radius": -1}]})", "bad.json", ".");
    FAIL("no error");
  } catch (const SceneError& e) {
    CHECK(std::string(e.what()).find("bad.json: key 'spheres[0].radius'") != std::string::npos);
  }
}

TEST_CASE("a program must draw what the scene holds, with its kind's expressions", "[spheres]") {
  const MachineConfig config = small();
  const Scene scene = make_builtin_scene("spheres");
  try {
    simulate_frame(config, scene, test::load_program("gouraud", config), 1);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("defines no 'sphere' procedure") != std::string::npos);
  }
  const Program wrong =
      assemble("field z 24\nfield r 8\noutput r r r\nproc triangle\n  qload z, sphere_depth\nend\n",
               "wrong", assembler_options(config));
  try {
    simulate_frame(config, make_builtin_scene("two-triangles"), wrong, 1);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("uses expression 'sphere_depth', which the triangle kind "
                                     "does not supply") != std::string::npos);
  }
}
