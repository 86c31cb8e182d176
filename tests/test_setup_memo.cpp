// The GPs' set-up kept from frame to frame (models/gp/setup_memo.hpp): a run of configurations
// that replays it gives the same statistics and images as one that sets every frame up afresh.
#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "models/gp/setup_memo.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {

MachineConfig configured(const std::vector<std::string>& sets) {
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 256;
  c.screen.height = 256;
  c.set(sets);
  return c;
}

// A run of configurations: some keep the set-up's key (GP and Renderer counts, clocks, the
// ring), some change it (culling, subpixel bits, coefficient width, screen), one comes back
// to an earlier key after others, and the culling pair replays a record whose counts are
// not zero.
const std::vector<std::vector<std::string>> kRun = {
    {"gp.count=1", "renderer.count=1"},
    {"gp.count=3", "renderer.count=2"},
    {"gp.count=7", "renderer.count=5", "ring.clock_hz=40e6"},
    {"gp.count=2", "gp.cull_back_faces=1"},
    {"gp.count=4", "renderer.count=3", "gp.cull_back_faces=1"},
    {"gp.count=2", "gp.subpixel_bits=3"},
    {"gp.count=4", "renderer.count=3"},
    {"gp.count=5", "evaluator.coefficient_bits=38"},
    {"gp.count=6", "screen.width=384"},
    {"gp.count=1", "renderer.count=4", "screen.width=384"},
};
// The configurations above that replay the set-up of the one before them.
constexpr int kReplayed = 4;

// Projects `c` afresh and with `memo`: the statistics must be the same, and the frame must
// have made packets. Returns the replayed frame's statistics.
Statistics check_replay(const MachineConfig& c, const Scene& scene, const std::string& program_name,
                        SetupMemo& memo) {
  const Program program = load_program(program_name, c);
  INFO(scene.name << " " << program_name << " " << c.to_json().dump());
  const FrameResult fresh = project_frame(c, scene, program);
  FrameResult replayed = project_frame(c, scene, program, &memo);
  CHECK(without_host(replayed.stats_json) == without_host(fresh.stats_json));
  CHECK(count(replayed.stats, "setup.packets") > 0);
  return std::move(replayed.stats);
}

}  // namespace

TEST_CASE("setup memo: statistics are the same as without it, at both timing levels",
          "[setup_memo]") {
  const Scene scene = make_builtin_scene("torus", {24, 12});
  for (const std::string timing : {"event", "analytic"}) {
    for (const std::string program_name : {"phong", "threshold"}) {
      SetupMemo memo(scene);
      for (const auto& sets : kRun) {
        std::vector<std::string> s = sets;
        s.push_back("fidelity.timing=" + timing);
        const MachineConfig c = configured(s);
        const Statistics replayed = check_replay(c, scene, program_name, memo);
        if (c.gp.cull_back_faces) CHECK(count(replayed, "setup.culled") > 0);
      }
      CHECK(memo.reuses() == kReplayed);
    }
  }
}

TEST_CASE("setup memo: the images and pixel statistics are the same as without it",
          "[setup_memo]") {
  const Scene scene = make_builtin_scene("torus", {24, 12});
  SetupMemo memo(scene);
  for (const auto& sets : {std::vector<std::string>{"gp.count=2", "fidelity.pixels=word"},
                           std::vector<std::string>{"gp.count=5", "fidelity.pixels=word"},
                           std::vector<std::string>{"gp.count=3", "fidelity.pixels=bit"}}) {
    const MachineConfig c = configured(sets);
    const Program program = load_program("phong", c);
    const FrameResult fresh = simulate_frame(c, scene, program, 2);
    const FrameResult replayed = simulate_frame(c, scene, program, 2, {}, nullptr, &memo);
    CHECK(replayed.image.rgb == fresh.image.rgb);
    CHECK(without_host(replayed.stats_json) == without_host(fresh.stats_json));
  }
  CHECK(memo.reuses() == 2);
}

TEST_CASE("setup memo: a machine of another scene is refused", "[setup_memo]") {
  const Scene torus = make_builtin_scene("torus", {8, 4});
  const Scene other = make_builtin_scene("two-triangles");
  SetupMemo memo(torus);
  const MachineConfig c = configured({});
  const Program program = load_program("phong", c);
  CHECK_THROWS_WITH(
      project_frame(c, other, program, &memo),
      Catch::Contains("set-up memo of scene 'torus'") && Catch::Contains("scene 'two-triangles'"));
}

TEST_CASE("setup memo: spheres, adjacency-reading expressions and multipass programs",
          "[setup_memo]") {
  // Each kind and each way set-up reads the scene: sphere primitives beside triangles, the
  // accurate program's side expressions (mesh adjacency), a pass plan that sends the same
  // packets once per pass.
  const std::vector<std::pair<std::string, std::string>> runs = {{"spheres-and-triangles", "phong"},
                                                                 {"folded-slab", "accurate"},
                                                                 {"crossing-quads", "transparent"}};
  for (const auto& [scene_name, program_name] : runs) {
    const Scene scene = make_builtin_scene(scene_name);
    SetupMemo memo(scene);
    for (const auto& sets : {std::vector<std::string>{"gp.count=1", "renderer.count=2"},
                             std::vector<std::string>{"gp.count=4", "renderer.count=3"},
                             std::vector<std::string>{"gp.count=3", "fidelity.timing=analytic"}}) {
      check_replay(configured(sets), scene, program_name, memo);
    }
    CHECK(memo.reuses() == 2);
  }
}
