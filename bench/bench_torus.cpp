// Host time against simulated time, on the built-in torus at 1280 x 1024 (8,192 triangles):
// a frame as `pp5sim render` makes it (scene set-up, the SystemC timing pass, the pixel pass on
// the bit backend, frame.png and regions.png encoded), 2 host threads. Each benchmark reports
// host_over_simulated: host seconds per simulated second (below 1 the simulator is faster than
// the machine). Two configurations: the machine at full speed (phong, gp.code=assembly, a
// 24.7 ms frame) and the Banks configuration (threshold, gp.code=compiled, a 103 ms frame).
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/image/region_map.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace {

void torus_frame(benchmark::State& state, const std::string& firmware, const char* gp_code) {
  pp5::MachineConfig config = pp5::MachineConfig::defaults();
  config.set(std::vector<std::string>{std::string("gp.code=") + gp_code});
  double host = 0;
  double simulated = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const pp5::Scene scene = pp5::make_builtin_scene("torus");
    const pp5::Program program =
        pp5::assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + firmware + ".pp5",
                           pp5::assembler_options(config));
    const pp5::FrameResult r = pp5::simulate_frame(config, scene, program, 2);
    const std::string frame = pp5::encode_png(r.image);
    const pp5::RegionHeatMap map(r.image, r.regions);
    const std::string regions = pp5::encode_png(
        map.width(), map.height(), [&map](int y, std::uint8_t* row) { map.row(y, row); });
    benchmark::DoNotOptimize(frame.data());
    benchmark::DoNotOptimize(regions.data());
    host += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    simulated = r.frame_seconds;
  }
  const double per_frame = host / static_cast<double>(state.iterations());
  state.counters["sim_ms"] = simulated * 1e3;
  state.counters["host_over_simulated"] = per_frame / simulated;
}

void BM_TorusFullSpeed(benchmark::State& state) { torus_frame(state, "phong", "assembly"); }
void BM_TorusBanks(benchmark::State& state) { torus_frame(state, "threshold", "compiled"); }
BENCHMARK(BM_TorusFullSpeed)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TorusBanks)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
