// The analytic timing model against the event model: the work it sums is exactly the event
// model's (packets, GP geometry clocks, Renderer busy cycles), the image it lets the boards
// draw is the same, and its frame time on a held-out grid of machines meets the targets where
// it does (sim/analysis/analytic_validation.hpp), with the measured bound where it does not.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sim/analysis/analytic_validation.hpp"
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

// The analytic level against the event level on a held-out grid: machines drawn with a
// seeded generator over scenes, programs, screens and every timing knob, which the model was
// never adjusted on (sim/analysis/analytic_validation.hpp; it was adjusted on the 48-point
// torus grids and on the grids of seeds 0x3434 to 0x3440, each once held out). Targets
// (docs/timing.md): worst frame-time error at most 15%, Kendall tau at least 0.9. This grid
// (seed 0x3441, 120 machines) was chosen and committed before either model was run on it.
// Measured once, after that: mean 0.5%, worst 9.0% (dynamic; static 5.9%), bottleneck agrees
// at 117 of 120, tau 0.994; the other two, 0x3442 and 0x3443, worst 5.9% and 4.5% (tau 0.996,
// 0.997).
TEST_CASE("analytic frame time on the held-out grid: error, bottleneck and rank against events",
          "[analytic]") {
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return test::load_program(name, c);
  };
  const std::vector<GridMachine> grid = analytic_heldout_grid(120, kHeldOutSeed);
  REQUIRE(grid.size() >= 100);
  const AnalyticValidation v = validate_analytic("held-out", grid, load);
  WARN(fmt::format(
      "analytic on the held-out grid: mean {:.2f}%, worst {:.2f}% ({}), static "
      "balancing worst {:.2f}%, dynamic {:.2f}%, bottleneck {} of {}, tau {:.3f}; closed form "
      "mean {:.2f}%, worst {:.2f}%, tau {:.3f}",
      100 * v.mean_error, 100 * v.worst_error, v.worst_at, 100 * v.static_balancing.worst_error,
      100 * v.dynamic_balancing.worst_error, v.bottleneck_agree, v.points.size(), v.kendall_tau,
      100 * v.closed_form_mean_error, 100 * v.closed_form_worst_error, v.closed_form_tau));
  CHECK(v.static_balancing.machines + v.dynamic_balancing.machines ==
        static_cast<int>(v.points.size()));
  CHECK(v.kendall_tau >= 0.9);
  CHECK(v.worst_error <= 0.15);
  CHECK(v.mean_error <= 0.02);
  CHECK(v.bottleneck_agree >= static_cast<int>(v.points.size()) * 95 / 100);
  // The recurrence must beat the closed form it refines, on the same machines.
  CHECK(v.mean_error < v.closed_form_mean_error);
  CHECK(v.kendall_tau > v.closed_form_tau);
}

// Dynamic balancing on the grid the fix was derived on (seed 0x3434): a GP free for several
// Renderers' open stages serves the lowest stage, as GraphicsProcessor::run picks. Served in
// Renderer order instead, a Renderer holding a later region took the GP first, claimed the
// next region sooner, and a whole region moved: worst 22.0% there (folded-slab, 8 Renderers);
// in stage order 10.5%. With the event model's send order, arrival-order consumption and
// empty stages opening at their start the dynamic machines' worst is 12.4% (a ring-bound
// torus at 1280 x 1024 whose regions spread differently, 2.1% before), and in Renderer order
// 14.1%.
TEST_CASE("analytic dynamic balancing: a GP serves the lowest open stage", "[analytic]") {
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return test::load_program(name, c);
  };
  const AnalyticValidation v =
      validate_analytic("looked at", analytic_heldout_grid(120, kLookedAtSeed), load);
  REQUIRE(v.dynamic_balancing.machines > 40);
  CHECK(v.dynamic_balancing.worst_error <= 0.13);
  CHECK(v.dynamic_balancing.mean_error <= 0.025);
}

// The ring as the event model books it (Ring::reserve): in request order, on the channel that
// frees first, held from then until the message's last word. A Renderer that finishes empty
// regions quickly books each next one to start only when its interface has sent the one
// before, and holds a channel idle until then. The worst machines of the looked-at grids of
// seeds 0x3436 and 0x3437 (spheres-and-triangles, static and dynamic balancing, whose frame is
// the ring shipping mostly empty regions) were 23.2% and 34.1% under with calendars that
// filled those idle gaps; a GP's message waiting behind another GP's (a stage's messages
// sent in GP order) cost the dynamic one more.
TEST_CASE("analytic ring books regions as the event ring: idle gaps held", "[analytic]") {
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return test::load_program(name, c);
  };
  const std::vector<GridMachine> machines = {
      {"spheres-and-triangles",
       "threshold",
       {"screen.width=512", "screen.height=512", "gp.count=27", "renderer.count=14",
        "ring.channels=8", "renderer.queue_words=4096", "renderer.balancing=static",
        "renderer.overlap_shipping=1", "ring.hop_latency_cycles=0", "evaluator.double_buffered=0",
        "gp.code=assembly"}},
      {"spheres-and-triangles",
       "phong",
       {"screen.width=1280", "screen.height=1024", "gp.count=19", "renderer.count=13",
        "ring.channels=4", "renderer.queue_words=2048", "renderer.balancing=dynamic",
        "renderer.overlap_shipping=1", "ring.hop_latency_cycles=2", "evaluator.double_buffered=0",
        "gp.code=assembly"}}};
  const AnalyticValidation v = validate_analytic("looked at", machines, load);
  for (const AnalyticPoint& p : v.points) {
    WARN(fmt::format("{}: event {:.3f} ms, analytic {:.3f} ms ({:+.1f}%)", p.machine.label(),
                     1e3 * p.event_seconds, 1e3 * p.analytic_seconds, 100 * p.error()));
    CHECK(std::abs(p.error()) <= 0.05);
  }
}

// The former worst machine of the grid of seed 0x3439 (held out when it was measured: 52.3%,
// 16.725 ms against 10.980 ms): its frame is each Renderer's ring interface shipping its
// regions in series, so it ends with the Renderer that holds the most regions. An empty
// stage that opened the next one after its clear rather than at its start, and GPs that
// could send at one instant going lowest first rather than nearest first (gp.send_order),
// let one Renderer claim a run of empty regions and book every channel ahead of the others'
// messages. Now 10.980 ms against 10.980 ms; with GPs lowest first, 12.629 ms (+15.0%).
TEST_CASE("analytic former worst machine: dynamic balancing spreads the empty regions",
          "[analytic]") {
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return test::load_program(name, c);
  };
  const std::vector<GridMachine> machines = {
      {"spheres-and-triangles",
       "threshold",
       {"screen.width=1280", "screen.height=1024", "gp.count=24", "renderer.count=10",
        "ring.channels=16", "renderer.queue_words=1024", "renderer.balancing=dynamic",
        "renderer.overlap_shipping=1", "ring.hop_latency_cycles=0", "evaluator.double_buffered=1",
        "gp.code=compiled"}}};
  const AnalyticValidation v = validate_analytic("looked at", machines, load);
  for (const AnalyticPoint& p : v.points) {
    WARN(fmt::format("{}: event {:.3f} ms, analytic {:.3f} ms ({:+.1f}%)", p.machine.label(),
                     1e3 * p.event_seconds, 1e3 * p.analytic_seconds, 100 * p.error()));
    CHECK(std::abs(p.error()) <= 0.05);
  }
}

// The worst machine of the grid of seed 0x3440 (held out when it was measured: 19.797 ms
// against 25.570 ms, -22.6%): shipping not overlapped, so each Renderer's array waits for its
// finished region's trip. The recurrence booked that trip on channel calendars as soon as the
// region was closed, ahead of messages asked for before it, which then waited a whole trip;
// the event ring books it when the array finishes, in request order, and the Renderer's next
// stages open and fill meanwhile. With that rule 22.002 ms (-14.0%; the rest is the order in
// which Renderers booking at one instant go, the SystemC kernel's).
TEST_CASE("analytic shipping without overlap: a region's trip booked in request order",
          "[analytic]") {
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return test::load_program(name, c);
  };
  const std::vector<GridMachine> machines = {
      {"spheres-and-triangles",
       "phong",
       {"screen.width=1280", "screen.height=1024", "gp.count=5", "renderer.count=9",
        "ring.channels=8", "renderer.queue_words=16384", "renderer.balancing=dynamic",
        "renderer.overlap_shipping=0", "ring.hop_latency_cycles=0", "evaluator.double_buffered=0",
        "gp.code=compiled"}}};
  const AnalyticValidation v = validate_analytic("looked at", machines, load);
  for (const AnalyticPoint& p : v.points) {
    WARN(fmt::format("{}: event {:.3f} ms, analytic {:.3f} ms ({:+.1f}%)", p.machine.label(),
                     1e3 * p.event_seconds, 1e3 * p.analytic_seconds, 100 * p.error()));
    CHECK(std::abs(p.error()) <= 0.15);
  }
}

// What the closed form could not see: the ring's channels with few Renderers (a plateau:
// 2 to 8 channels changed nothing there) and the Renderers' queue. Each now moves the
// analytic frame time the way it moves the event model's.
TEST_CASE("analytic frame time follows ring.channels and renderer.queue_words", "[analytic]") {
  const Scene scene = make_builtin_scene("torus");
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=640", "screen.height=512", "gp.count=32", "renderer.count=2"});
  const Program program = test::load_program("phong", config);
  auto frame = [&](const std::vector<std::string>& sets, const char* timing) {
    MachineConfig c = config;
    c.set(sets);
    return run(c, timing, "none", scene, program).frame_seconds;
  };
  for (const char* timing : {"event", "analytic"}) {
    INFO(timing);
    CHECK(frame({"ring.channels=1"}, timing) > 1.05 * frame({"ring.channels=8"}, timing));
    CHECK(frame({"ring.channels=2"}, timing) > frame({"ring.channels=8"}, timing));
    // A queue of one message makes the Renderer and the ring take turns.
    CHECK(frame({"renderer.queue_words=1024"}, timing) >
          1.02 * frame({"renderer.queue_words=16384"}, timing));
  }
  // The analytic level's gains track the event level's within a few per cent.
  const double e = frame({"ring.channels=2"}, "event") / frame({"ring.channels=8"}, "event");
  const double a = frame({"ring.channels=2"}, "analytic") / frame({"ring.channels=8"}, "analytic");
  CHECK(a == Approx(e).epsilon(0.05));
}

TEST_CASE("Kendall's tau-b: orders, reversals and ties", "[analytic]") {
  CHECK(kendall_tau({1, 2, 3, 4}, {10, 20, 30, 40}) == Approx(1.0));
  CHECK(kendall_tau({1, 2, 3, 4}, {4, 3, 2, 1}) == Approx(-1.0));
  // One discordant pair of six: (5 - 1) / 6.
  CHECK(kendall_tau({1, 2, 3, 4}, {1, 2, 4, 3}) == Approx(4.0 / 6.0));
  // A tie in y (x = 1, 2, 3; y = 1, 1, 2): one pair tied in y, two concordant, so
  // tau-b = (C - D) / sqrt((C + D + Tx)(C + D + Ty)) = 2 / sqrt(2 x 3).
  CHECK(kendall_tau({1, 2, 3}, {1, 1, 2}) == Approx(2.0 / std::sqrt(3.0 * 2.0)));
}
