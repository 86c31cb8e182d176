// Whole-machine behaviour: determinism across runs and host threads, and the timing of
// each unit at its earliest legal cycle.
#include <fmt/format.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <stdexcept>
#include <vector>

#include "common/parallel_for.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

TEST_CASE("frames and statistics are identical across runs and host thread counts", "[machine]") {
  MachineConfig config = MachineConfig::defaults();
  config.screen.width = 384;
  config.screen.height = 256;
  config.gp.count = 5;
  config.renderer.count = 3;
  const Scene scene = make_builtin_scene("torus", {64, 16});
  const Program program = load_program("phong", config);
  const FrameResult one = simulate_frame(config, scene, program, 1);
  const FrameResult four = simulate_frame(config, scene, program, 4);
  const FrameResult again = simulate_frame(config, scene, program, 1);
  CHECK(one.image.flat().rgb == four.image.flat().rgb);
  CHECK(one.image.flat().rgb == again.image.flat().rgb);
  CHECK(without_host(one.stats_json) == without_host(four.stats_json));
  CHECK(without_host(one.stats_json) == without_host(again.stats_json));
  CHECK(one.stats.integer("frame.array_cycles") > 0);
}

TEST_CASE("each Renderer's board starts as a new one, whatever the host thread count",
          "[machine]") {
  // A program whose clear leaves a field alone: each region's colour counts the regions its
  // board ran before, so the frame shows each board's history. The host reuses one board
  // per thread (execute_pixels): a board carried over from another Renderer unrestarted
  // would make the frame depend on the thread count.
  const std::string source = R"(field runs 8
field zero 8
output runs zero zero
proc clear
  eall
  add runs, 40
  mov zero, 0
end
proc triangle
  eall
end
)";
  const Scene scene = make_builtin_scene("torus", {16, 8});
  for (const char* pixels : {"word", "bit"}) {
    MachineConfig config = MachineConfig::defaults();
    config.set({"screen.width=768", "screen.height=256", "gp.count=2", "renderer.count=5",
                std::string("fidelity.pixels=") + pixels});
    const Program program = assemble(source, "runs", assembler_options(config));
    const FrameResult one = simulate_frame(config, scene, program, 1);
    const FrameResult three = simulate_frame(config, scene, program, 3);
    CHECK(one.image.flat().rgb == three.image.flat().rgb);
    // Renderer k's first region (region k) shows one run from a new board's zeros.
    for (int k = 0; k < config.renderer.count; ++k) {
      const std::size_t pixel = static_cast<std::size_t>(k) * 128;  // row 0, region k
      CHECK(static_cast<int>(one.image.flat().rgb[pixel * 3]) == 40);
    }
  }
}

TEST_CASE("each Renderer is busy for exactly the instruction table's cycles", "[machine]") {
  MachineConfig config = MachineConfig::defaults();
  config.screen.width = 512;
  config.screen.height = 256;
  config.gp.count = 4;
  config.renderer.count = 3;
  const Scene scene = make_builtin_scene("sphere");
  const Program program = load_program("flat", config);  // no data-dependent costs
  const FrameResult r = simulate_frame(config, scene, program, 2);
  const TimingParams timing = timing_params(config);
  const OwnedValues none{};
  const std::uint64_t overhead = config.renderer.packet_overhead_cycles;
  const std::uint64_t clear =
      procedure_cost(program.procedure(Procedure::clear), timing, none).count;
  const std::uint64_t tri =
      procedure_cost(program.procedure(Procedure::triangle), timing, none).count;
  std::vector<std::uint64_t> per_region;
  for (std::size_t k = 0; k < r.stats.elements("primitives_per_region"); ++k)
    per_region.push_back(test::count(r.stats, "primitives_per_region." + std::to_string(k)));
  std::vector<std::uint64_t> expected(config.renderer.count, 0);
  std::uint64_t packets = 0;
  for (std::size_t region = 0; region < per_region.size(); ++region) {
    // Each finished region's colours are copied to the backing store (one 32-bit block).
    expected[region % config.renderer.count] += overhead + clear +
                                                per_region[region] * (overhead + tri) +
                                                config.renderer.backing_store_cycles_per_block;
    packets += per_region[region];
  }
  CHECK(packets == test::count(r.stats, "setup.packets"));
  for (int k = 0; k < config.renderer.count; ++k) {
    CHECK(test::count(r.stats, fmt::format("renderer.{}.busy_cycles", k)) == expected[k]);
    // A Renderer cannot finish before it has spent its cycles.
    CHECK(r.frame_seconds >= static_cast<double>(expected[k]) / config.renderer.clock_hz);
  }
}

TEST_CASE("a one-GP, one-Renderer frame ends at the earliest legal time", "[machine]") {
  MachineConfig config = MachineConfig::defaults();
  config.screen.width = 128;
  config.screen.height = 128;
  config.gp.count = 1;
  config.renderer.count = 1;
  const Scene scene = make_builtin_scene("two-triangles");
  const Program program = load_program("flat", config);
  const FrameResult r = simulate_frame(config, scene, program, 1);
  REQUIRE(r.stats.integer("setup.packets") == 2);

  // The critical path, unit by unit: the GP transforms and sets up both triangles (the i860
  // cost model's clocks), sends its bin map (a header word and one bit for the one region),
  // then starts its one bin message; the ring carries the bin one hop; the
  // Renderer, which ran clear while it waited, loads the first packet's coefficients, runs two
  // triangle packets, copies the colours
  // to the backing store, and the ring carries the region one hop to the frame buffer.
  // A header word, then flat's three edges and depth (3 coefficients each) and three
  // face-lit colours (constants, 1 each), of two 32-bit words per 40-bit coefficient.
  REQUIRE(program.procedure(Procedure::triangle).expressions.count() == 7);
  const double packet_words = 1 + (4 * 3 + 3 * 1) * 2;
  GpWorkload workload;
  workload.expressions = program.procedure(Procedure::triangle).expressions;
  workload.packet_words = static_cast<std::uint64_t>(packet_words);
  const I860Model i860(i860_params(config));
  const double gp_clocks =
      static_cast<double>(i860.clocks(I860Work::triangle(workload, 1, 1, 1), 1).count) * 2 +
      2.0 * static_cast<double>(i860.clocks(I860Work::send_bin(), 0).count);
  CHECK(static_cast<double>(r.stats.integer("gp.0.busy_clocks")) == gp_clocks);
  const double map_words = 2;
  const double bin_words = 1 + 2 * packet_words;
  const TimingParams timing = timing_params(config);
  const OwnedValues none{};
  const double clear_cycles =
      config.renderer.packet_overhead_cycles +
      procedure_cost(program.procedure(Procedure::clear), timing, none).count;
  // The first packet's coefficients load after the bin arrives (one word per cycle); the
  // second's load while the first executes.
  const double renderer_cycles =
      (packet_words - 1) / config.evaluator.coefficient_words_per_cycle +
      2.0 * (config.renderer.packet_overhead_cycles +
             procedure_cost(program.procedure(Procedure::triangle), timing, none).count) +
      config.renderer.backing_store_cycles_per_block;
  const double region_words =
      128.0 * 128 * config.frame_buffer.bits_per_pixel / config.ring.word_bits;
  const double hop = config.ring.hop_latency_cycles;
  // The GP's ring interface is busy with the map before the bin starts.
  const double bin_arrival =
      gp_clocks / config.gp.clock_hz + (map_words + bin_words + hop) / config.ring.clock_hz;
  REQUIRE(clear_cycles / config.renderer.clock_hz < bin_arrival);
  const double expected = bin_arrival + renderer_cycles / config.renderer.clock_hz +
                          (region_words + hop) / config.ring.clock_hz;
  // Not one array cycle early, and on time (to SystemC's picosecond resolution).
  CHECK(r.frame_seconds == Approx(expected).margin(1e-11));
  CHECK(r.frame_seconds > expected - 1.0 / config.renderer.clock_hz);
}

TEST_CASE("a multipass program sees every triangle once per pass, with 'pass' between",
          "[machine]") {
  MachineConfig config = MachineConfig::defaults();
  config.screen.width = 256;
  config.screen.height = 128;
  config.gp.count = 2;
  config.renderer.count = 2;
  const Scene scene = make_builtin_scene("two-triangles");
  // Red counts the triangles covering a pixel over all passes; green counts the passes that
  // have ended (the 'pass' procedure runs between passes, so 2 for 3 passes).
  const std::string source = R"(
option passes 3
field r 8
field g 8
field b 8
output r g b
proc clear
  eall
  mov r, 0
  mov g, 0
  mov b, 0
end
proc triangle
  eall
  qtest.ge edge0
  qtest.ge edge1
  qtest.ge edge2
  add r, 1
end
proc pass
  eall
  add g, 1
end
)";
  const Program program = assemble(source, "passes", assembler_options(config));
  REQUIRE(program.passes == 3);
  const Program single =
      assemble(source.substr(source.find('\n', 1)), "one", assembler_options(config));
  const FrameResult three = simulate_frame(config, scene, program, 2);
  const FrameResult one = simulate_frame(config, scene, single, 2);
  std::size_t covered = 0;
  for (std::size_t p = 0; p < one.image.flat().rgb.size(); p += 3) {
    CHECK(int(three.image.flat().rgb[p]) == 3 * int(one.image.flat().rgb[p]));
    CHECK(int(three.image.flat().rgb[p + 1]) == 2);
    CHECK(int(one.image.flat().rgb[p + 1]) == 0);
    covered += one.image.flat().rgb[p] > 0;
  }
  CHECK(covered > 1000);
  // Each pass's bins cross the ring again, so the multipass frame carries more words.
  CHECK(three.stats.integer("ring.words") > one.stats.integer("ring.words"));
}

TEST_CASE("parallel_for rethrows a worker thread's exception on the caller", "[machine]") {
  // Every index but the last succeeds; the last is taken by whichever thread is free, which
  // with 4 threads and 64 indices is rarely the caller's.
  for (int threads : {1, 4}) {
    std::atomic<int> ran{0};
    CHECK_THROWS_AS(parallel_for(64, threads,
                                 [&](int i) {
                                   if (i == 63) throw std::out_of_range("index 63");
                                   ++ran;
                                 }),
                    std::out_of_range);
    CHECK(ran.load() <= 63);
  }
  // Per-worker state: no two calls with the same worker overlap.
  std::vector<int> busy(static_cast<std::size_t>(parallel_workers(100, 3)), 0);
  std::atomic<int> overlaps{0};
  parallel_for(100, 3, [&](int, int worker) {
    if (busy[static_cast<std::size_t>(worker)]++ != 0) ++overlaps;
    --busy[static_cast<std::size_t>(worker)];
  });
  CHECK(overlaps.load() == 0);
}

TEST_CASE("parallel_for keeps its threads from call to call, and nests", "[machine]") {
  // A run of frames calls it once a frame or more: its threads are kept, not made each time.
  // Calls one after another need at most two other threads at once (a thread that finished
  // its part may already serve the same call's next one), so no more than two are ever made.
  std::atomic<int> sum{0};
  for (int call = 0; call < 200; ++call) parallel_for(8, 3, [&sum](int i) { sum += i; });
  CHECK(sum.load() == 200 * 28);
  CHECK(host_threads_kept() >= 1);
  CHECK(host_threads_kept() <= 2);
  // A body that calls parallel_for itself (every kept thread busy) gets threads of its own
  // rather than waiting for one: it finishes, with every index run once.
  std::atomic<int> inner{0};
  parallel_for(4, 4, [&inner](int) { parallel_for(5, 3, [&inner](int) { ++inner; }); });
  CHECK(inner.load() == 20);
  // An exception still reaches the caller from a kept thread, and the threads stay usable.
  CHECK_THROWS_AS(parallel_for(16, 3,
                               [](int i) {
                                 if (i == 5) throw std::runtime_error("five");
                               }),
                  std::runtime_error);
  std::atomic<int> after{0};
  parallel_for(16, 3, [&after](int) { ++after; });
  CHECK(after.load() == 16);
}

TEST_CASE("a board's exception during execute_pixels reaches the caller (issue 18)", "[machine]") {
  // The triangle procedure stores to backing-store block 3; the machine has one block. Only
  // regions with triangles run it, and those execute on the host's worker threads.
  MachineConfig config = MachineConfig::defaults();
  config.screen.width = 512;
  config.screen.height = 256;
  config.gp.count = 2;
  config.renderer.count = 4;
  AssemblerOptions options = assembler_options(config);
  options.backing_store_bits = 4096;
  const Program program = assemble(
      "field z 24\n"
      "field red 8\n"
      "field green 8\n"
      "field blue 8\n"
      "output red green blue\n"
      "proc clear\n  eall\n  mov z, 0xFFFFFF\nend\n"
      "proc triangle\n  eall\n  qtest.ge edge0\n  bsst z, 3\nend\n",
      "out_of_store.pp5", options);
  config.renderer.backing_store_bits = 32;
  const Scene scene = make_builtin_scene("sphere");
  for (int threads : {1, 4}) {
    INFO("threads " << threads);
    CHECK_THROWS_AS(simulate_frame(config, scene, program, threads), std::out_of_range);
  }
}
