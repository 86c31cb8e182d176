// A simulation that persists across frames (sim/simulation.hpp, Session): one SystemC context
// and one machine run frame after frame; each frame reports what a run of that frame alone
// reports, and a long run keeps its memory flat.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "models/machine.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {

MachineConfig small_machine(const std::vector<std::string>& sets) {
  MachineConfig c = MachineConfig::defaults();
  c.set({"screen.width=128", "screen.height=128", "gp.count=3", "renderer.count=2"});
  c.set(sets);
  return c;
}

// Resident memory of this process, in bytes (/proc/self/statm's second field).
double resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  double pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<double>(sysconf(_SC_PAGESIZE));
}

}  // namespace

TEST_CASE("session: every frame of a run reports what a single frame reports", "[session]") {
  // Dynamic balancing and round-robin arbitration keep state across a frame in the scheduler;
  // a multipass program keeps it in the Renderers' stages: each must start every frame anew.
  const std::vector<std::vector<std::string>> machines = {
      {},
      {"renderer.balancing=dynamic", "gp.send_order=round_robin"},
      {"renderer.overlap_shipping=0", "gp.count=1"},
  };
  const Scene scene = make_builtin_scene("torus", {24, 12});
  for (const auto& sets : machines) {
    const MachineConfig c = small_machine(sets);
    const auto program = std::make_shared<const Program>(load_program("phong", c));
    INFO(c.to_json().dump());
    const FrameResult alone = simulate_frame(c, scene, *program, 2);
    Session session(c, std::make_shared<const Scene>(scene), program, 2);
    for (int f = 0; f < 3; ++f) {
      INFO("frame " << f);
      const FrameResult r = session.frame();
      const nlohmann::json diff =
          nlohmann::json::diff(without_host(alone.stats_json), without_host(r.stats_json));
      INFO(diff.dump().substr(0, 2000));
      CHECK(diff.empty());
      CHECK(r.image.flat().rgb == alone.image.flat().rgb);
    }
    CHECK(session.frames() == 3);
    // The run's summary is over its frames: three of the single frame's time.
    const RunSummary& run = session.summary();
    CHECK(run.frames == 3);
    CHECK(run.simulated_seconds == Approx(3 * alone.frame_seconds));
    CHECK(run.shortest_frame_seconds == alone.frame_seconds);
    CHECK(run.longest_frame_seconds == alone.frame_seconds);
    CHECK(run.host_seconds > 0);
    CHECK(run.text().find("run: 3 frames") == 0);
  }
}

TEST_CASE("session: frames follow one another in simulated time", "[session]") {
  const MachineConfig c = small_machine({});
  const auto program = std::make_shared<const Program>(load_program("phong", c));
  Session session(c, std::make_shared<const Scene>(make_builtin_scene("torus", {16, 8})), program,
                  1);
  nlohmann::json timeline;
  const FrameResult first = session.frame({}, &timeline);
  session.frame({}, &timeline);
  // The second frame's slices come after the first frame's end, on one clock.
  const sc_core::sc_time end(first.frame_seconds, sc_core::SC_SEC);
  std::size_t later = 0;
  for (const TimelineSlice& sl : session.machine()->slices()) {
    if (sl.frame != 1) continue;
    CHECK(sl.start >= end);
    ++later;
  }
  CHECK(later > 0);
  CHECK(timeline["traceEvents"].size() > 0);
  CHECK(session.machine()->clock().frame() == 1);
}

TEST_CASE("session: resident memory stays flat over many frames", "[session]") {
  // Frames 20..220 of a small scene: a frame that kept anything (a SystemC context, a
  // Renderer's regions, a ring log) would grow the process by far more than the bound.
  // Measured: 64 KiB over 1,000 frames (15.6 MB peak). Under AddressSanitizer, whose
  // quarantine keeps freed memory, LeakSanitizer checks instead (ctest session_leaks).
  const MachineConfig c = small_machine({});
  const auto program = std::make_shared<const Program>(load_program("phong", c));
  Session session(c, std::make_shared<const Scene>(make_builtin_scene("torus", {16, 8})), program,
                  1);
  for (int f = 0; f < 20; ++f) session.frame();
  const double before = resident_bytes();
  for (int f = 0; f < 200; ++f) session.frame();
  const double grown = resident_bytes() - before;
  INFO("resident memory grew by " << grown << " bytes over 200 frames");
#if !defined(__SANITIZE_ADDRESS__)
  CHECK(grown < 256 * 1024);
#endif
}
