// Host cost of the tracing hook. One iteration runs one region's worth of the Phong firmware
// on a 128 x 128 board: its region stream over 64 small triangles and one light.
//   RegionBaseline        the board's instruction loop as it was before the hook existed
//                         (execute and cost each instruction from the table), here verbatim;
//   RegionTracingOff      RendererBoard::run with no observer: what every frame pays;
//   RegionTracingOnePixel the same with a recorder tracing one pixel's fields;
//   TracingOffVsBaseline  both of the first two, interleaved in one run, reporting
//                         off_over_baseline = time(off) / time(baseline): the claim "costs
//                         nothing measurable when off" is that this ratio is 1 within noise.
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/trace/recorder.hpp"

namespace {

using namespace pp5;

struct Workload {
  MachineConfig config = MachineConfig::defaults();
  Program program;
  FrameValues frame;  // one light, with the frame's parameters
  std::vector<Packet> triangles;

  Workload()
      : program(assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5",
                              assembler_options(config))) {
    const std::int64_t one = std::int64_t{1} << config.evaluator.fraction_bits;
    ParameterValues& p = frame.frame.parameters;
    p[static_cast<int>(Parameter::light_z)] = 127;
    p[static_cast<int>(Parameter::half_z)] = 127;
    p[static_cast<int>(Parameter::ambient)] = 40;
    p[static_cast<int>(Parameter::diffuse)] = 200;
    p[static_cast<int>(Parameter::specular)] = 100;
    frame.lights.push_back(frame.frame);
    // 64 right triangles of 12-pixel legs spread over the region, at decreasing depth.
    for (int k = 0; k < 64; ++k) {
      const int x0 = (k % 8) * 15 + 2, y0 = (k / 8) * 15 + 2;
      Packet v;
      v.primitive = k;
      auto e = [&](Expression x) -> QuadraticCoefficients& {
        return v.values.expressions[static_cast<int>(x)];
      };
      e(Expression::edge0) = QuadraticCoefficients::linear(one, 0, -x0 * one);
      e(Expression::edge1) = QuadraticCoefficients::linear(0, one, -y0 * one);
      e(Expression::edge2) = QuadraticCoefficients::linear(-one, -one, (x0 + y0 + 12) * one);
      e(Expression::depth) = QuadraticCoefficients::constant((1000000 - 1000 * k) * one);
      e(Expression::base_red) = QuadraticCoefficients::linear(one, 0, 60 * one);
      e(Expression::base_green) = QuadraticCoefficients::constant(120 * one);
      e(Expression::base_blue) = QuadraticCoefficients::linear(0, one, 30 * one);
      e(Expression::nz) = QuadraticCoefficients::constant(120 * one);
      triangles.push_back(v);
    }
  }
};

const Workload& workload() {
  static const Workload w;
  return w;
}

// The loop of RendererBoard::run before the observer hook, kept here as the yardstick.
ArrayCycles baseline_run(RendererBoard& board, const ProcedureCode& procedure,
                         const PacketValues& values, const TimingParams& timing) {
  ExecutionContext ctx{board.array(), values, timing.fraction_bits, timing.multiply_window};
  ArrayCycles cycles{};
  for (const Instruction& ins : procedure.code) {
    const InstructionInfo& info = instruction_info(ins.op);
    info.execute(ins, ctx);
    cycles += info.cost(ins, timing, values);
  }
  return cycles;
}

void region_baseline(RendererBoard& board) {
  const Workload& w = workload();
  const TimingParams t = timing_params(w.config);
  ArrayCycles c{};
  RegionStream(w.program, w.frame).for_each(w.triangles, [&](const RegionStep& step) {
    c += baseline_run(board, step.code, step.values, t);
  });
  benchmark::DoNotOptimize(c);
}

void region_run(RendererBoard& board) {
  const Workload& w = workload();
  ArrayCycles c{};
  RegionStream(w.program, w.frame).for_each(w.triangles, [&](const RegionStep& step) {
    c += board.run_step(step);
  });
  board.end_region(0);
  benchmark::DoNotOptimize(c);
}

void BM_RegionBaseline(benchmark::State& state) {
  RendererBoard board(board_params(workload().config));
  board.begin_region(0, 0);
  for (auto _ : state) region_baseline(board);
}
BENCHMARK(BM_RegionBaseline)->Unit(benchmark::kMicrosecond);

void BM_RegionTracingOff(benchmark::State& state) {
  RendererBoard board(board_params(workload().config));
  board.begin_region(0, 0);
  for (auto _ : state) region_run(board);
}
BENCHMARK(BM_RegionTracingOff)->Unit(benchmark::kMicrosecond);

void BM_RegionTracingOnePixel(benchmark::State& state) {
  const Workload& w = workload();
  const Scene scene = make_builtin_scene("two-triangles", {});
  trace::Selection sel;
  sel.rects.push_back({8, 8, 1, 1});
  trace::Recorder recorder(w.config, scene, w.program, sel);
  RendererBoard board(board_params(w.config));
  board.set_observer(recorder.observer(0));
  board.begin_region(0, 0);
  for (auto _ : state) region_run(board);
  std::uint64_t records = 0;
  state.counters["records_per_region"] =
      static_cast<double>(recorder.records(records).size() > 0 ? records : 0) /
      static_cast<double>(state.iterations());
}
BENCHMARK(BM_RegionTracingOnePixel)->Unit(benchmark::kMicrosecond);

void BM_TracingOffVsBaseline(benchmark::State& state) {
  RendererBoard a(board_params(workload().config)), b(board_params(workload().config));
  a.begin_region(0, 0);
  b.begin_region(0, 0);
  using clock = std::chrono::steady_clock;
  double base = 0, off = 0;
  for (auto _ : state) {
    const auto t0 = clock::now();
    region_baseline(a);
    const auto t1 = clock::now();
    region_run(b);
    const auto t2 = clock::now();
    base += std::chrono::duration<double>(t1 - t0).count();
    off += std::chrono::duration<double>(t2 - t1).count();
  }
  state.counters["off_over_baseline"] = off / base;
}
BENCHMARK(BM_TracingOffVsBaseline)->Unit(benchmark::kMicrosecond)->Repetitions(3);

}  // namespace
