// The analytic timing model against the event model: the work it sums is exactly the event
// model's (packets, GP geometry clocks, Renderer busy cycles), the image it lets the boards
// draw is the same, and its frame time over a grid of machines (GP and Renderer counts, ring
// channels, programs) stays within a measured bound, asserted here as a regression bound.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

FrameResult run(MachineConfig config, const char* timing, const char* pixels, const Scene& scene,
                const Program& program) {
  config.set({std::string("fidelity.timing=") + timing, std::string("fidelity.pixels=") + pixels});
  return simulate_frame(config, scene, program, 2);
}

}  // namespace

TEST_CASE("analytic timing sums exactly the event model's work", "[analytic]") {
  const Scene scene = make_builtin_scene("torus");
  // 8 GPs share the torus's 8,192 triangles evenly; 7 end their blocks between the set-up
  // summary's checkpoints, and a narrower screen clips and culls (setup counts not zero).
  for (const char* gps : {"gp.count=8", "gp.count=7"}) {
    MachineConfig config = MachineConfig::defaults();
    config.set(
        std::vector<std::string>{"screen.width=640", "screen.height=512", gps, "renderer.count=4"});
    if (std::string(gps) == "gp.count=7")
      config.set(std::vector<std::string>{"screen.width=500", "gp.cull_back_faces=1"});
    for (const char* name : {"phong", "threshold", "transparent"}) {
      INFO("program " << name << ", " << gps);
      const Program program = test::load_program(name, config);
      const FrameResult event = run(config, "event", "none", scene, program);
      const FrameResult analytic = run(config, "analytic", "none", scene, program);
      const Statistics& e = event.stats;
      const Statistics& a = analytic.stats;
      CHECK(a.integer("setup.packets") == e.integer("setup.packets"));
      CHECK(a.integer("setup.coefficient_overflow") == e.integer("setup.coefficient_overflow"));
      CHECK(a.integer("setup.culled") == e.integer("setup.culled"));
      CHECK(a.integer("setup.clipped_away") == e.integer("setup.clipped_away"));
      CHECK(a.integer("renderers_total.busy_cycles") == e.integer("renderers_total.busy_cycles"));
      CHECK(a.integer("ring.words") == e.integer("ring.words"));
      CHECK(a.integer("ring.messages") == e.integer("ring.messages"));
      for (int k = 0; k < config.gp.count; ++k) {
        const std::string p = fmt::format("gp.{}.", k);
        CHECK(a.integer(p + "geometry_clocks") == e.integer(p + "geometry_clocks"));
        CHECK(a.integer(p + "busy_clocks") == e.integer(p + "busy_clocks"));
        CHECK(a.integer(p + "messages") == e.integer(p + "messages"));
      }
      // Static balancing: the same regions on the same Renderers, so the same cycles each.
      for (int k = 0; k < config.renderer.count; ++k) {
        const std::string p = fmt::format("renderer.{}.", k);
        CHECK(a.integer(p + "busy_cycles") == e.integer(p + "busy_cycles"));
        CHECK(a.integer(p + "regions") == e.integer(p + "regions"));
      }
      // Region by region (regions.png's heat map), the same cycles on the same Renderer.
      REQUIRE(analytic.regions.size() == event.regions.size());
      for (const RegionLoad& load : analytic.regions) {
        const auto same =
            std::find_if(event.regions.begin(), event.regions.end(),
                         [&](const RegionLoad& l) { return l.region == load.region; });
        REQUIRE(same != event.regions.end());
        CHECK(same->renderer == load.renderer);
        CHECK(same->busy_cycles == load.busy_cycles);
      }
      // The closed form's terms add up to the frame time.
      CHECK(a.real("frame.simulated_seconds") ==
            Approx(a.real("analytic.fill_seconds") + a.real("analytic.busiest_seconds") +
                   a.real("analytic.drain_seconds")));
    }
  }
}

TEST_CASE("analytic timing counts each kind's packet words as the event model does", "[analytic]") {
  // Spheres alone, and spheres beside triangles: packets of different words. A small queue
  // splits the bins into many messages, and without double buffering every packet's
  // coefficient load is charged by its own words.
  for (const auto& [scene_name, program_name] : std::vector<std::pair<std::string, std::string>>{
           {"molecule", "threshold"}, {"spheres-and-triangles", "phong"}}) {
    INFO(scene_name << " " << program_name);
    MachineConfig config = MachineConfig::defaults();
    config.set(std::vector<std::string>{"screen.width=512", "screen.height=512", "gp.count=5",
                                        "renderer.count=3", "renderer.queue_words=160",
                                        "evaluator.double_buffered=0"});
    const Scene scene = make_builtin_scene(scene_name);
    const Program program = test::load_program(program_name, config);
    const FrameResult event = run(config, "event", "none", scene, program);
    const FrameResult analytic = run(config, "analytic", "none", scene, program);
    const Statistics& e = event.stats;
    const Statistics& a = analytic.stats;
    CHECK(a.integer("ring.words") == e.integer("ring.words"));
    CHECK(a.integer("ring.messages") == e.integer("ring.messages"));
    CHECK(a.integer("renderers_total.busy_cycles") == e.integer("renderers_total.busy_cycles"));
    for (int k = 0; k < config.gp.count; ++k) {
      const std::string p = fmt::format("gp.{}.", k);
      CHECK(a.integer(p + "messages") == e.integer(p + "messages"));
      CHECK(a.integer(p + "busy_clocks") == e.integer(p + "busy_clocks"));
    }
  }
}

TEST_CASE("analytic timing with word pixels draws the event model's image", "[analytic]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=4", "renderer.count=3",
              "renderer.balancing=dynamic"});
  for (const char* scene_name : {"torus", "crossing-quads"}) {
    const Scene scene = make_builtin_scene(scene_name);
    const Program program = test::load_program("phong", config);
    const FrameResult event = run(config, "event", "bit", scene, program);
    const FrameResult analytic = run(config, "analytic", "word", scene, program);
    INFO("scene " << scene_name);
    CHECK(analytic.image.flat().rgb == event.image.flat().rgb);
    // A window: only its regions are drawn, the others stay black.
    MachineConfig window = config;
    window.set({"fidelity.window_x=1", "fidelity.window_columns=1", "fidelity.window_rows=1"});
    const FrameResult corner = run(window, "analytic", "word", scene, program);
    for (int y = 0; y < 256; ++y) {
      for (int x = 0; x < 256; ++x) {
        const std::size_t p = (static_cast<std::size_t>(y) * 256 + x) * 3;
        const bool inside = x >= 128 && y < 128;
        for (int c = 0; c < 3; ++c) {
          if (inside) {
            REQUIRE(corner.image.flat().rgb[p + c] == event.image.flat().rgb[p + c]);
          } else {
            REQUIRE(corner.image.flat().rgb[p + c] == 0);
          }
        }
      }
    }
  }
}

TEST_CASE("analytic frame time within its measured bound over a grid of machines", "[analytic]") {
  // The bound is measured: the largest |analytic - event| / event over this grid, rounded up
  // (docs/timing.md "Analytic timing" gives the table). A change to either model that moves
  // the analytic error beyond it fails here and must say why.
  // Measured on this grid: worst 31.8% (phong, 32 GPs, 2 Renderers, 1 ring channel: the
  // ring and the Renderers take turns, the closed form overlaps them), mean 13.1%; the
  // bottleneck agrees at 44 of the 48 points. (29.4%, 12.9% and 42 before the event model's
  // GPs were woken nearest first, RegionScheduler, which moved that machine's frame 3.6%.)
  constexpr double kBound = 0.33;
  const Scene scene = make_builtin_scene("torus");
  double worst = 0, sum = 0;
  std::string worst_at;
  int agree = 0, points = 0;
  for (const char* program_name : {"phong", "threshold", "flat", "transparent"}) {
    for (int gps : {4, 32}) {
      for (int renderers : {2, 8, 16}) {
        for (int channels : {1, 8}) {
          MachineConfig config = MachineConfig::defaults();
          config.set({"screen.width=640", "screen.height=512", fmt::format("gp.count={}", gps),
                      fmt::format("renderer.count={}", renderers),
                      fmt::format("ring.channels={}", channels)});
          const Program program = test::load_program(program_name, config);
          const FrameResult event = run(config, "event", "none", scene, program);
          const FrameResult analytic = run(config, "analytic", "none", scene, program);
          const double error =
              std::abs(analytic.frame_seconds - event.frame_seconds) / event.frame_seconds;
          const std::string at = fmt::format("{} gps={} renderers={} channels={}", program_name,
                                             gps, renderers, channels);
          if (error > worst) worst = error, worst_at = at;
          sum += error;
          ++points;
          if (analytic.stats.text("timing.bottleneck") == event.stats.text("timing.bottleneck"))
            ++agree;
        }
      }
    }
  }
  INFO("worst error " << worst << " at " << worst_at << "; bottleneck agrees at " << agree << " of "
                      << points);
  WARN(fmt::format(
      "analytic frame time: worst error {:.2f}% ({}), mean {:.2f}%, bottleneck agrees at {} of {}",
      100 * worst, worst_at, 100 * sum / points, agree, points));
  CHECK(worst <= kBound);
}
