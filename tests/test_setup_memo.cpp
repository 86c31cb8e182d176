// The GPs' set-up kept from frame to frame (models/gp/setup_memo.hpp): a run of configurations
// that replays it gives the same statistics and images as one that sets every frame up afresh.
#include <catch2/catch.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "models/gp/graphics_processor.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/protocol/packet.hpp"
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
    CHECK(replayed.image.flat().rgb == fresh.image.flat().rgb);
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

TEST_CASE("setup memo: its summary counts what the GPs' geometry passes make", "[setup_memo]") {
  // A torus cut by the screen's edge (clipped and culled primitives count something) over an
  // uneven number of GPs, so that blocks end between the summary's checkpoints.
  MachineConfig c = configured({"screen.width=200", "gp.cull_back_faces=1"});
  const Scene scene = make_builtin_scene("torus");
  const Program program = load_program("threshold", c);
  SetupMemo memo(scene);
  MachinePlan plan(c, scene, program);
  plan.use_setup_memo(memo);
  const int n = static_cast<int>(plan.geometry().display_list().size());
  const int gps = 7;
  std::vector<std::vector<std::shared_ptr<const Packet>>> all(
      static_cast<std::size_t>(c.regions()));
  std::vector<GpStats> stats(gps);
  std::vector<std::pair<int, int>> blocks;
  for (int k = 0; k < gps; ++k) {
    const int first = n * k / gps, last = n * (k + 1) / gps;
    blocks.emplace_back(first, last);
    RegionBins bins;
    geometry_pass(plan, first, last, stats[static_cast<std::size_t>(k)], &bins);
    REQUIRE(std::is_sorted(bins.regions().begin(), bins.regions().end()));
    for (int r = 0; r < c.regions(); ++r) {
      const RegionBins::Bin& bin = bins.bin(r);
      CHECK((bins.slot(r) >= 0) == !bin.empty());
      all[static_cast<std::size_t>(r)].insert(all[static_cast<std::size_t>(r)].end(), bin.begin(),
                                              bin.end());
    }
  }
  REQUIRE(memo.complete());
  const SetupMemo::Summary& s = memo.summary(c.regions());
  // Each region's packets, in display-list order, are the bins' (the same packets).
  std::uint64_t packets = 0;
  for (int r = 0; r < c.regions(); ++r) {
    const auto i = static_cast<std::size_t>(r);
    REQUIRE(s.region_first[i + 1] - s.region_first[i] == all[i].size());
    for (std::size_t k = 0; k < all[i].size(); ++k) {
      CHECK(s.region_packets[s.region_first[i] + k]->get() == all[i][k].get());
      CHECK(s.region_primitive[s.region_first[i] + k] == all[i][k]->primitive);
    }
    std::uint32_t by_signature = 0;
    for (std::uint32_t g = s.signature_first[i]; g < s.signature_first[i + 1]; ++g)
      by_signature += s.signatures[g].count;
    CHECK(by_signature == all[i].size());
    packets += all[i].size();
  }
  CHECK(packets > 0);
  // Each GP's classes add up to its pieces and packets; its counted primitives to its counts.
  bool counted = false;
  std::vector<std::uint32_t> in_class;
  for (int k = 0; k < gps; ++k) {
    const auto [first, last] = blocks[static_cast<std::size_t>(k)];
    const GpStats& st = stats[static_cast<std::size_t>(k)];
    s.count_classes(first, last, in_class);
    std::uint64_t primitives = 0, pieces = 0, placed = 0;
    for (std::size_t cl = 0; cl < in_class.size(); ++cl) {
      primitives += in_class[cl];
      pieces += static_cast<std::uint64_t>(s.classes[cl].tally.pieces) * in_class[cl];
      placed += static_cast<std::uint64_t>(s.classes[cl].tally.regions) * in_class[cl];
    }
    CHECK(primitives == static_cast<std::uint64_t>(last - first));
    CHECK(pieces == st.screen_triangles);
    CHECK(placed == st.packets);
    SetupCounts sum;
    for (const auto& [i, counts] : s.counted) {
      if (i >= first && i < last) sum += counts;
    }
    CHECK(sum.clipped_away == st.setup.clipped_away);
    CHECK(sum.culled == st.setup.culled);
    CHECK(sum.no_pixels == st.setup.no_pixels);
    counted = counted || st.setup.culled > 0 || st.setup.clipped_away > 0;
  }
  CHECK(counted);
  // Any block, against a count one primitive at a time.
  for (const auto& [first, last] : std::vector<std::pair<int, int>>{
           {0, 0}, {0, 1}, {63, 64}, {64, 128}, {1, n - 1}, {100, 1000}, {n - 65, n}, {0, n}}) {
    s.count_classes(first, last, in_class);
    std::vector<std::uint32_t> brute(s.classes.size(), 0);
    for (int i = first; i < last; ++i) ++brute[s.class_of[static_cast<std::size_t>(i)]];
    CHECK(in_class == brute);
  }
}

TEST_CASE("setup memo: a summary of many tally classes counts a block one by one", "[setup_memo]") {
  // More classes than the summary keeps checkpoints for (kMaxCheckpointed): no checkpoints,
  // and every block is counted from class_of.
  SetupMemo::Summary s;
  const std::size_t classes = SetupMemo::Summary::kMaxCheckpointed + 44;
  s.classes.resize(classes);
  std::uint32_t state = 12345;
  for (int i = 0; i < 5000; ++i) {
    state = state * 1664525u + 1013904223u;
    s.class_of.push_back((state >> 8) % static_cast<std::uint32_t>(classes));
  }
  std::vector<std::uint32_t> in_class;
  for (const auto& [first, last] :
       std::vector<std::pair<int, int>>{{0, 0}, {0, 5000}, {17, 4093}, {4999, 5000}}) {
    s.count_classes(first, last, in_class);
    std::vector<std::uint32_t> brute(classes, 0);
    for (int i = first; i < last; ++i) ++brute[s.class_of[static_cast<std::size_t>(i)]];
    CHECK(in_class == brute);
  }
}

TEST_CASE("setup memo: filled in parts on several threads, it replays the frame set up alone",
          "[setup_memo]") {
  const MachineConfig c = configured({"gp.count=3", "renderer.count=2"});
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"torus", "phong"},
      {"spheres-and-triangles", "phong"},
      {"molecule", "threshold"},
      {"figure-eight", "parity_accurate"}};
  for (const auto& [scene_name, program_name] : cases) {
    const Scene scene = make_builtin_scene(scene_name);
    const Program program = load_program(program_name, c);
    INFO(scene_name << " " << program_name);
    SetupMemo memo(scene);
    {
      MachinePlan plan(c, scene, program);
      plan.use_setup_memo(memo);
      // Parts of 64 primitives at least, on 3 threads: several parts even for small scenes.
      fill_setup_memo(plan, 3, 64);
    }
    REQUIRE(memo.complete());
    const FrameResult fresh = project_frame(c, scene, program);
    const FrameResult replayed = project_frame(c, scene, program, &memo);
    CHECK(memo.reuses() == 1);
    CHECK(without_host(replayed.stats_json) == without_host(fresh.stats_json));
    MachineConfig word = c;
    word.set(std::vector<std::string>{"fidelity.pixels=word"});
    CHECK(simulate_frame(word, scene, program, 2, {}, nullptr, &memo).image.flat().rgb ==
          simulate_frame(word, scene, program, 1).image.flat().rgb);
  }
}
