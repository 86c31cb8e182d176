// Model only what a scene requires: empty regions executed once and reused must give exactly
// what executing each one gives, for every program, whatever ran on the board before.
#include <catch2/catch.hpp>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/scene/scene.hpp"

using namespace pp5;

TEST_CASE("reused empty regions equal executed ones, on any board history", "[regions]") {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  Scene scene = make_builtin_scene("two-triangles");
  // Two lights: the empty regions run the `light` procedure of each.
  scene.lights.push_back(scene.lights[0]);
  scene.lights[1].direction = glm::vec3(0.0f, 0.0f, 1.0f);
  const GeometryEngine geometry(geometry_params(config), scene);
  const FrameValues values = geometry.frame_values();
  for (const char* name : {"flat", "gouraud", "phong"}) {
    INFO(name);
    const Program program =
        assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + name + ".pp5",
                      assembler_options(config));
    std::bitset<static_cast<int>(Expression::count)> needed;
    for (const auto& p : program.procedures) needed |= p.expressions;
    std::vector<ScreenTriangle> tris;
    SetupCounts counts;
    for (int i = 0; i < 2; ++i) geometry.transform(i, tris, counts);
    std::vector<Packet> packets;
    for (const auto& t : tris) {
      SetupResult r;
      if (!geometry.setup(t, needed, r, counts)) continue;
      packets.emplace_back();
      packets.back().values = r.values;
    }
    const RegionStream stream(program, values);
    const std::vector<Packet> none;
    REQUIRE_FALSE(packets.empty());
    // Regions: empty ones before and after one with triangles, and at other origins; then
    // drawn and empty ones alternating, as on a board that draws every other region (its
    // empty regions after a drawn one are executed unchecked after two misses, and checked
    // again at every eighth).
    std::vector<std::pair<int, bool>> regions = {{0, false},   {128, false}, {0, true},
                                                 {128, false}, {0, false},   {128, true},
                                                 {0, false},   {128, false}};
    for (int k = 0; k < 24; ++k) regions.emplace_back(k % 3 == 0 ? 128 : 0, k % 2 == 0);
    RendererBoard reusing(board_params(config)), executing(board_params(config));
    RendererBoard donor(board_params(config));
    donor.run_empty_region(0, 0, program, values);
    reusing.share_empty_region(donor);
    std::vector<std::uint8_t> a, b;
    for (const auto& [x0, busy] : regions) {
      executing.begin_region(x0, 0);
      stream.for_each(busy ? packets : none,
                      [&](const RegionStep& step) { executing.run_step(step); });
      executing.read_outputs(program, b);
      if (busy) {
        reusing.begin_region(x0, 0);
        stream.for_each(packets, [&](const RegionStep& step) { reusing.run_step(step); });
        reusing.end_region(x0 / 128);
        reusing.read_outputs(program, a);
      } else {
        const RegionPixels pixels = reusing.run_empty_region(x0, 0, program, values);
        a.assign(pixels.get(), pixels.get() + b.size());
      }
      CHECK(a == b);
      CHECK(reusing.array().same_state(executing.array()));
    }
    CHECK(reusing.empty_regions_reused() >= 2);
  }
}

// A board that has executed nothing holds the state every new board holds: once a donor has
// run an empty region on a new board (and probed that clear after shade gives the same
// state), a board sharing the donor's empty region runs a new board's empty regions without
// executing one instruction, before and after a restart, and ends where executing them
// leaves a board. A program whose clear does not initialise (so that clear gives another
// state on every region) executes all but its first, and a restarted board starts anew.
TEST_CASE("a new board's empty regions are reused from a donor without executing", "[regions]") {
  MachineConfig config = MachineConfig::defaults();
  const Scene scene = make_builtin_scene("two-triangles");
  const GeometryEngine geometry(geometry_params(config), scene);
  const FrameValues values = geometry.frame_values();
  // Its clear counts the regions the board has run (a history the colour shows).
  const std::string counting = R"(field runs 8
output runs runs runs
proc clear
  eall
  add runs, 40
end
proc triangle
  eall
end
)";
  // 0: phong; 1: the counting program; 2: the same, with a donor whose kept state is not
  // what clear gives a new board (it ran two empty regions, and kept the second's).
  for (const int variant : {0, 1, 2}) {
    INFO("variant " << variant);
    const bool clears_all = variant == 0;
    const Program program =
        clears_all ? assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5",
                                   assembler_options(config))
                   : assemble(counting, "counting", assembler_options(config));
    RendererBoard donor(board_params(config)), fresh(board_params(config));
    donor.run_empty_region(0, 0, program, values);
    if (variant == 2) {
      donor.run_empty_region(0, 0, program, values);
    } else {
      donor.probe_clear_after_shade(program, values);
    }
    RendererBoard reusing(board_params(config)), executing(board_params(config));
    const RegionStream stream(program, values);
    for (int round = 0; round < 2; ++round) {
      if (round == 1) {
        reusing.restart(fresh);
        executing.restart(fresh);
      }
      reusing.share_empty_region(donor);
      const std::uint64_t before = reusing.instructions_executed();
      for (int x0 : {0, 128, 256}) {
        const RegionPixels a = reusing.run_empty_region(x0, 0, program, values);
        std::vector<std::uint8_t> b;
        executing.begin_region(x0, 0);
        stream.for_each(std::vector<Packet>{},
                        [&](const RegionStep& step) { executing.run_step(step); });
        executing.read_outputs(program, b);
        CHECK(std::equal(b.begin(), b.end(), a.get()));
      }
      if (clears_all) {
        CHECK(reusing.instructions_executed() == before);
      } else {
        CHECK(reusing.instructions_executed() > before);
      }
      // Read through the const view: nothing here may change the board.
      const RendererBoard& reused = reusing;
      CHECK(reused.array().same_state(executing.array()));
    }
  }
}
