// Numerical stability at the extremes (sim/analysis/extremes.hpp): every case states what is
// expected and checks it on pixels produced by firmware running on the pixel array.
#include <catch2/catch.hpp>

#include "sim/analysis/extremes.hpp"
#include "sim/scene/scene_loader.hpp"

using namespace pp5;

namespace {

MachineConfig small(int width, int height) {
  MachineConfig c = MachineConfig::defaults();
  c.set(std::vector<std::string>{"screen.width=" + std::to_string(width),
                                 "screen.height=" + std::to_string(height), "renderer.count=2",
                                 "gp.count=2"});
  return c;
}

}  // namespace

TEST_CASE("an N-bit z-buffer on a K-pixel screen needs N + log2(2K) bits of running depth",
          "[extremes]") {
  CHECK(depth_fraction_bits_needed(1280, 1024) == 12);
  CHECK(depth_fraction_bits_needed(256, 256) == 9);
  CHECK(depth_fraction_bits_needed(4096, 64) == 13);
  for (int width : {256, 1280}) {
    INFO("screen width " << width);
    const MachineConfig c = small(width, width == 256 ? 256 : 1024);
    const int need = depth_fraction_bits_needed(c.screen.width, c.screen.height);
    // Within the z-buffer's resolution with enough bits...
    CHECK(depth_precision_error(c, 24, need) <= 1);
    CHECK(depth_precision_error(c, 24, need + 1) <= 1);
    // ... and off by several z-units with four fewer.
    CHECK(depth_precision_error(c, 24, need - 4) > 1);
    CHECK(depth_precision_error(c, 24, need - 4) >= depth_precision_error(c, 24, need - 2));
  }
}

TEST_CASE("every synthetic extreme case behaves as stated", "[extremes]") {
  const auto cases = synthetic_extreme_cases(MachineConfig::defaults(), 2);
  REQUIRE(cases.size() >= 11);
  for (const ExtremeCase& c : cases) {
    INFO(c.name << "\n  expected: " << c.expected << "\n  observed: " << c.observed);
    CHECK(c.pass);
  }
}

TEST_CASE("whole closed meshes: coverage matches the reference and parity is even", "[extremes]") {
  const MachineConfig c = small(512, 384);
  for (const char* name : {"sphere", "torus"}) {
    INFO(name);
    const Scene scene = load_scene(name);
    REQUIRE(is_closed(scene.mesh));
    const Coverage cov = coverage_counts(c, scene, 2);
    const CoverageCheck check = check_coverage(c, scene, cov);
    CHECK(check.missing == 0);
    CHECK(check.extra == 0);
    CHECK(check.certain > 100000);
    std::uint64_t odd = 0, covered = 0;
    for (auto n : cov.count) {
      odd += n & 1;
      covered += n > 0;
    }
    CHECK(odd == 0);
    CHECK(covered > 10000);
  }
}

TEST_CASE("the scene report fails what is wrong and names it", "[extremes]") {
  MachineConfig c = small(256, 256);
  c.set(std::vector<std::string>{"evaluator.fraction_bits=6"});
  const auto cases = scene_extreme_cases(c, load_scene("two-triangles"), 1);
  bool depth_failed = false;
  for (const ExtremeCase& k : cases) {
    if (k.name == "scene: depth precision of this machine") depth_failed = !k.pass;
  }
  CHECK(depth_failed);
  // An open mesh is not held to the parity rule, and the report says so.
  const auto open = scene_extreme_cases(small(256, 256), load_scene("two-triangles"), 1);
  CHECK(open[2].observed.find("not checked") != std::string::npos);
  CHECK_FALSE(is_closed(load_scene("two-triangles").mesh));
}

TEST_CASE("with too few fraction bits, depth precision fails and no other case does",
          "[extremes]") {
  // Issue 18: with 8 fraction bits the depth-precision case passed while reporting errors of
  // 3 z-units, and the coefficient-width case failed because its too-steep triangle fits.
  MachineConfig c = small(1280, 1024);
  c.set("evaluator.fraction_bits=8");
  for (const ExtremeCase& e : synthetic_extreme_cases(c, 2)) {
    INFO(e.name << ": " << e.observed);
    if (e.name == "depth precision") {
      CHECK_FALSE(e.pass);
      CHECK_THAT(e.observed, Catch::Contains("errs by up to 3 z-units"));
    } else {
      CHECK(e.pass);
    }
    if (e.name == "coefficient width") {
      CHECK_THAT(e.observed, Catch::Contains("no triangle is too steep on this machine"));
    }
  }
}
