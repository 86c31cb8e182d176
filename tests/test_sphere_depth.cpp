// The sphere depth methods beside the quadric (sim/analysis/sphere_depth_methods.hpp): the
// exact depth by a bit-serial square root in pixel memory (sphere_sqrt.pp5) and Pixel-Planes
// 4's paraboloid (sphere_pp4.pp5), each against the ray cast; and the unshaded programs that
// read which primitive each pixel shows.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "models/gp/sphere.hpp"
#include "models/machine.hpp"
#include "sim/analysis/sphere_depth_methods.hpp"
#include "sim/analysis/spheres.hpp"
#include "sim/scene/sphere_scenes.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

MachineConfig small_depth_config() {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  return config;
}

std::vector<ScreenSphere> project_depth_spheres(const MachineConfig& config, const Scene& scene) {
  const SphereProjector projector(geometry_params(config), scene.camera);
  SetupCounts counts;
  std::vector<ScreenSphere> out;
  for (std::size_t k = 0; k < scene.spheres.size(); ++k) {
    ScreenSphere s;
    if (projector.project(scene.spheres[k], static_cast<int>(k), s, counts)) out.push_back(s);
  }
  return out;
}

std::string program_path(const char* name) { return test::kProgramsDir + name + ".pp5"; }

}  // namespace

TEST_CASE("the square root in pixel memory draws each sphere's depth to half a root step",
          "[spheres]") {
  // sphere_sqrt.pp5 subtracts 2^n floor(sqrt(P)) from the linear part, which holds half a root
  // step: the error is at most 2^(n-1) + 1/2, plus the radicand's fixed-point rounding (dP,
  // at most sqrt(dP) root steps where the radicand is small, at the rim) and the linear
  // part's. The four spheres have reliefs of millions of depth units (the quadric errs by up
  // to 459,581); every pixel here must be within its covering spheres' bound.
  const MachineConfig config = small_depth_config();
  // The molecule's 3,200 small atoms take the small shifts, the four spheres the large ones:
  // between them every bit of the four-stage shifter is exercised (checked below).
  const char* name = GENERATE("spheres", "molecule");
  INFO(name);
  const Scene scene = make_builtin_scene(name);
  const auto screen = project_depth_spheres(config, scene);
  REQUIRE(screen.size() > 0);
  const RayCast truth = ray_cast(config, scene);
  const DrawnSpheres drawn =
      draw_spheres(config, scene, test::load_program("sphere_sqrt", config), 2);
  const double f = std::ldexp(1.0, config.evaluator.fraction_bits);
  double worst = 0;
  std::uint64_t checked = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      if (truth.what[i] < 0 || drawn.covered[i] == 0) continue;
      double bound = 0;
      for (const ScreenSphere& s : screen) {
        if (!(sphere_depth_at(config, scene, s.source, x, y) < 1e300)) continue;
        const double dx = x - static_cast<double>(s.x0), dy = y - static_cast<double>(s.y0);
        const double dp = sphere_rounding_bound(dx, dy) / f + 1.0;
        const double step = std::ldexp(1.0, s.root_shift);
        bound = std::max(bound, step / 2 + step * std::sqrt(dp) + 2.0);
      }
      const double error = std::fabs(static_cast<double>(drawn.z[i]) - truth.depth[i]);
      INFO("pixel " << x << ", " << y << ": drawn " << drawn.z[i] << ", exact " << truth.depth[i]);
      REQUIRE(error <= bound);
      worst = std::max(worst, error);
      ++checked;
    }
  }
  REQUIRE(checked > 10000);
  int largest_shift = 0, shift_bits = 0;
  for (const ScreenSphere& s : screen) {
    largest_shift = std::max(largest_shift, s.root_shift);
    shift_bits |= s.root_shift;
  }
  WARN(name << ": square root in pixel memory: worst depth error " << worst
            << " units, largest shift " << largest_shift << ", shift bits used " << shift_bits);
  // The error is the root step's, not less: the truncation is real.
  CHECK(worst > std::ldexp(1.0, largest_shift - 2));
  // Every stage of the shifter is used by one scene or the other.
  static int bits_seen = 0;
  bits_seen |= shift_bits;
  if (std::string(name) == "molecule") CHECK(bits_seen == 15);
}

TEST_CASE("the square root shows the right sphere where spheres meet, the paraboloid errs more",
          "[spheres]") {
  // Which sphere each pixel shows, read from each program with its shading taken out: the
  // square root errs at no more than a few of the 5,019 overlap pixels and 375 curve pixels
  // (1 and 1 measured), the quadric at 141 and 104, Pixel-Planes 4's paraboloid (twice the
  // quadric's depth error, all of it too deep) at more.
  const MachineConfig config = small_depth_config();
  const Scene scene = make_builtin_scene("spheres");
  const RayCast truth = ray_cast(config, scene);
  auto accuracy = [&](const char* name) {
    const Program p = test::load_program(name, config);
    const Program unshaded = unshaded_program(program_path(name), config);
    return measure_spheres(config, scene, truth, draw_spheres(config, scene, p, 2),
                           shown_spheres_by(config, scene, {}, unshaded, 2));
  };
  const SphereAccuracy root = accuracy("sphere_sqrt");
  const SphereAccuracy quadric = accuracy("phong");
  const SphereAccuracy pp4 = accuracy("sphere_pp4");
  REQUIRE(root.overlap_pixels == 5019);
  REQUIRE(root.curve_pixels == 375);
  CHECK(root.overlap_shown_wrong <= 3);
  CHECK(root.curve_shown_wrong <= 3);
  CHECK(root.overlap_depth_wrong <= 3);
  CHECK(root.depth_max_error < 1000);
  // The unshaded phong reads what shown_spheres' own firmware reads: the same counts.
  const SphereAccuracy own = measure_spheres(
      config, scene, truth, draw_spheres(config, scene, test::load_program("phong", config), 2),
      shown_spheres(config, scene, {}, 2));
  CHECK(quadric.overlap_shown_wrong == own.overlap_shown_wrong);
  CHECK(quadric.curve_shown_wrong == own.curve_shown_wrong);
  CHECK(quadric.overlap_shown_wrong >= 100);
  // Pixel-Planes 4: the line through the ends errs twice as far as the minimax line.
  CHECK(pp4.depth_max_error > 1.8 * quadric.depth_max_error);
  CHECK(pp4.depth_max_error < 2.2 * quadric.depth_max_error);
  CHECK(pp4.overlap_shown_wrong > quadric.overlap_shown_wrong);
}

TEST_CASE("Pixel-Planes 4's paraboloid is never nearer than the sphere", "[spheres]") {
  // The line through the square root's ends lies below the root: the drawn depth is the
  // exact one or deeper, never nearer than the fixed-point rounding allows.
  const MachineConfig config = small_depth_config();
  const Scene scene = make_builtin_scene("spheres");
  const RayCast truth = ray_cast(config, scene);
  const DrawnSpheres drawn =
      draw_spheres(config, scene, test::load_program("sphere_pp4", config), 2);
  std::uint64_t checked = 0, deeper = 0;
  for (std::size_t i = 0; i < drawn.z.size(); ++i) {
    if (truth.what[i] < 0 || truth.spheres[i] != 1 || drawn.covered[i] == 0) continue;
    ++checked;
    const double d = static_cast<double>(drawn.z[i]) - truth.depth[i];
    INFO("pixel " << i);
    REQUIRE(d > -4.0);
    deeper += d > 1000.0;
  }
  REQUIRE(checked > 15000);
  CHECK(deeper > checked / 2);
}

TEST_CASE("unshaded programs: light and shade taken out, errors name the file and line",
          "[spheres]") {
  const std::string text =
      "field z 24\nfield red 8\noutput red red red\nproc clear\n  eall\nend\nproc light ; x\n"
      "  eall\nend\nproc sphere\n  eall\nend\nproc shade\n  mov red, 0\nend\n";
  const std::string out = unshaded_source(text, "t.pp5");
  CHECK(out.find("proc light") == std::string::npos);
  CHECK(out.find("proc shade") == std::string::npos);
  CHECK(out.find("mov red, 0") == std::string::npos);
  CHECK(out.find("proc sphere") != std::string::npos);
  CHECK(out.find("proc clear") != std::string::npos);
  REQUIRE_THROWS_WITH(unshaded_source("proc sphere\n  eall\n", "t.pp5"),
                      Catch::Contains("t.pp5:1") && Catch::Contains("no 'end'"));
  REQUIRE_THROWS_WITH(unshaded_source("proc clear\nend\n", "t.pp5"),
                      Catch::Contains("t.pp5") && Catch::Contains("no 'proc sphere'"));
  REQUIRE_THROWS_WITH(unshaded_program("no/such.pp5", small_depth_config()),
                      Catch::Contains("no/such.pp5"));
}
