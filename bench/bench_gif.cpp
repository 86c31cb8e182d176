// GIF encoding of a rendered frame (the default torus at `word`, 1280 x 1024), as `pp5sim
// animate` adds each frame (sim/output/gif.cpp: GifWriter::add of the frame buffer's frame,
// region row by region row: the fixed 252-colour palette, then LZW), against a reference
// kept here that shares no code with it: each channel's nearest level by division, and
// textbook greedy LZW over a std::unordered_map dictionary, with the same code-size and
// clear rules. Timed alternately in one run. BM_GifEncode reports
//   new_ms, ref_ms   mean milliseconds of processor time per frame (a one-frame GIF file)
//   ref_over_new     how many times quicker the encoder is than the reference
//   bytes            the file's size
// and stops with an error if the two files differ in any byte.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <ctime>
#include <string>
#include <vector>

#include "bench/bench_frames.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/gp/machine_plan.hpp"
#include "sim/output/gif.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "tests/gif_reference.hpp"

namespace {

void BM_GifEncode(benchmark::State& state) {
  const pp5::FrameImage frame = pp5::bench::torus_word_frame();
  const pp5::RgbImage& flat = frame.flat();
  auto encode = [&frame] {
    pp5::GifWriter gif(4);
    gif.add(frame);
    return gif.finish();
  };
  if (encode() != pp5::gif_textbook({&flat}, 4)) {
    state.SkipWithError("the GIF differs from the reference encoder's");
    return;
  }
  const pp5::bench::EncoderTimes t =
      pp5::bench::time_encoders(state, encode, [&flat] { return pp5::gif_textbook({&flat}, 4); });
  state.counters["new_ms"] = t.new_ms;
  state.counters["ref_ms"] = t.ref_ms;
  state.counters["ref_over_new"] = t.ref_ms / t.new_ms;
  state.counters["bytes"] = static_cast<double>(t.new_bytes);
}

BENCHMARK(BM_GifEncode)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

// The encoder alone, many times (for perf record): `pp5_bench --benchmark_filter=GifOnly`.
void BM_GifOnly(benchmark::State& state) {
  const pp5::FrameImage frame = pp5::bench::torus_word_frame();
  pp5::GifWriter gif(4);
  for (auto _ : state) {
    gif.add(frame);
    benchmark::DoNotOptimize(gif.take().data());
  }
}

BENCHMARK(BM_GifOnly)->Unit(benchmark::kMillisecond)->Iterations(200);

}  // namespace
