// Host cost of regions that no primitive touches. The same scene (a sphere of 3,968
// triangles, filling one 128 x 128 region) is rendered with the Phong firmware on a 128 x 128
// screen and in the top-left region of a 4096 x 4096 screen (1,024 regions, 1,023 of them
// empty). Each empty region's stream (clear, shade) runs once per board and is reused, so the
// big screen should cost about what the small one does: BM_OneRegionRatio prints the ratio,
// measured in one run (BM_OneRegionScene the two times and where they went). The simulated
// timing still charges every region's real work, so the counter sim_ms is the 4096 x 4096
// machine's frame time.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/simulation.hpp"

namespace {

// A sphere that a camera at the origin sees inside screen pixels [8, 120] of a square screen
// `width` pixels wide, i.e. within the top-left region and nowhere else, at any width. The
// field of view is narrow (2 degrees) so that perspective does not stretch the sphere near
// the screen's corner: it is the same 112-pixel disc on every screen.
pp5::Scene sphere_in_first_region(int width) {
  pp5::Scene scene = pp5::make_builtin_scene("sphere");
  const pp5::BoundingSphere b = pp5::bounding_sphere(scene.mesh);
  const double fov_degrees = 2.0;
  const double d = 100.0;                                           // view distance of the centre
  const double half = d * std::tan(glm::radians(fov_degrees / 2));  // half the screen there
  const double pixel = 2.0 * half / width;  // world size of a pixel at that distance
  const double radius = 56.0 * pixel;       // 112 pixels across
  const double cx = -half + 64.0 * pixel, cy = half - 64.0 * pixel;
  for (pp5::Vertex& v : scene.mesh.vertices) {
    v.position = glm::vec3((v.position - b.center) / b.radius * static_cast<float>(radius) +
                           glm::vec3(static_cast<float>(cx), static_cast<float>(cy), -d));
  }
  scene.camera =
      pp5::Camera{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, static_cast<float>(fov_degrees), 50.0f, 200.0f};
  scene.lights = {pp5::default_light(scene.camera)};
  return scene;
}

// The one-region scene's machine, scene and program on a `width` x `width` screen.
struct OneRegion {
  explicit OneRegion(int width)
      : config(screen(width)),
        scene(sphere_in_first_region(width)),
        program(pp5::assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5",
                                   pp5::assembler_options(config))) {}
  static pp5::MachineConfig screen(int width) {
    pp5::MachineConfig c = pp5::MachineConfig::defaults();
    c.set(std::vector<std::string>{"screen.width=" + std::to_string(width),
                                   "screen.height=" + std::to_string(width)});
    return c;
  }
  pp5::MachineConfig config;
  pp5::Scene scene;
  pp5::Program program;
};

void BM_OneRegionScene(benchmark::State& state) {
  const OneRegion one(static_cast<int>(state.range(0)));
  const pp5::MachineConfig& config = one.config;
  const pp5::Scene& scene = one.scene;
  const pp5::Program& program = one.program;
  double sim_seconds = 0;
  double timing_ms = 0;
  double pixel_ms = 0;
  for (auto _ : state) {
    const pp5::FrameResult r = pp5::simulate_frame(config, scene, program, 1);
    sim_seconds = r.frame_seconds;
    timing_ms += r.stats.real("host.timing_seconds") * 1e3;
    pixel_ms += r.stats.real("host.pixel_seconds") * 1e3;
    benchmark::DoNotOptimize(r.image);
  }
  state.counters["regions"] = config.regions();
  state.counters["sim_ms"] = sim_seconds * 1e3;
  // Where the host time went, per frame: the SystemC timing pass and the pixel pass.
  state.counters["timing_ms"] = timing_ms / static_cast<double>(state.iterations());
  state.counters["pixel_ms"] = pixel_ms / static_cast<double>(state.iterations());
}
BENCHMARK(BM_OneRegionScene)->Arg(128)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();

// The figure itself, measured in one run: each iteration renders the scene on the small
// screen and then on the big one, alternately, so that a change in the host's load between
// two benchmarks does not enter the ratio. Counters: big_over_small (the target is 1.2 or
// less), and each screen's least frame time.
void BM_OneRegionRatio(benchmark::State& state) {
  const OneRegion small(128), big(4096);
  double small_sum = 0, big_sum = 0;
  double small_least = 1e30, big_least = 1e30;
  for (auto _ : state) {
    for (const OneRegion* one : {&small, &big}) {
      const auto t0 = std::chrono::steady_clock::now();
      const pp5::FrameResult r = pp5::simulate_frame(one->config, one->scene, one->program, 1);
      benchmark::DoNotOptimize(r.image);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      (one == &small ? small_sum : big_sum) += s;
      double& least = one == &small ? small_least : big_least;
      least = std::min(least, s);
    }
  }
  state.counters["big_over_small"] = small_sum > 0 ? big_sum / small_sum : 0;
  state.counters["small_least_ms"] = small_least * 1e3;
  state.counters["big_least_ms"] = big_least * 1e3;
}
BENCHMARK(BM_OneRegionRatio)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
