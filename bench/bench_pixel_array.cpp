// Host cost of the bit-sliced pixel array on one 128 x 128 board (208 bit-planes of 256 words).
// The Add32, Compare32, Multiply8x8 and AssignPlanes benchmarks run one ALU operation per
// iteration and report time_per_array_cycle: host time divided by the array cycles the
// instruction table charges for it (width(dst) for add and assign, max width + 1 for cmp,
// 16 + 16 + 15 + ... + 9 = 116 for an 8 x 8 -> 16-bit mul; the evaluator's own cycles are
// not part of AssignPlanes). Add32/half runs under a mask enabling every other pixel, so every
// word is active; Add32/triangle runs the same add with only a triangle inside 8 rows enabled,
// showing that the cost follows the rows a primitive covers, not the board. StreamXor32 is the
// bandwidth yardstick: a plain word loop reading two 32-plane operands and writing a third in
// the same memory; its bytes_per_second, and the same figure counted for Add32 (two operands
// read, one written, over the words the add touches), give the add's speed as a fraction of
// what the memory system can deliver for that working set.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include "models/pixel_array/pixel_array.hpp"
#include "sim/host_memory.hpp"

namespace {

using pp5::Bits;
using pp5::Field;
using pp5::PixelArray;
using pp5::PixelArrayGeometry;
using pp5::Word;

constexpr int kPlaneBytes = 128 * 128 / 8;

void fill_random(PixelArray& a) {
  std::mt19937_64 rng(7);
  for (int b = 0; b < a.geometry().memory_bits; ++b) {
    for (int w = 0; w < a.words(); ++w) a.plane(b)[w] = rng();
  }
}

// Every other pixel enabled: every word of the board is active.
void enable_half(PixelArray& a) {
  const std::vector<Word> mask(a.words(), 0x5555555555555555ull);
  a.enable_all();
  a.and_enable(mask.data());
}

// A triangle with its apex at row 60, 8 rows tall: 16 of the 256 words are active.
void enable_triangle(PixelArray& a) {
  std::vector<Word> mask(a.words(), 0);
  for (int y = 60; y < 68; ++y) {
    const int half_width = 8 * (y - 60) + 1;
    for (int x = 64 - half_width; x < 64 + half_width; ++x) {
      const int p = y * a.width() + x;
      mask[p / 64] |= Word{1} << (p % 64);
    }
  }
  a.enable_all();
  a.and_enable(mask.data());
}

void report_cycles(benchmark::State& state, double cycles) {
  state.counters["time_per_array_cycle"] = benchmark::Counter(
      cycles, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_Add32(benchmark::State& state) {
  PixelArray a{PixelArrayGeometry{}};
  fill_random(a);
  if (state.range(0) == 0) {
    state.SetLabel("half");
    enable_half(a);
  } else {
    state.SetLabel("triangle");
    enable_triangle(a);
  }
  const Field d{64, 32, false};
  const Bits x = a.bits_of(Field{0, 32, false});
  const Bits y = a.bits_of(Field{32, 32, false});
  for (auto _ : state) {
    a.add(d, x, y);
    benchmark::ClobberMemory();
  }
  report_cycles(state, 32);
  state.SetBytesProcessed(state.iterations() * 3 * 32 * a.active_words().size() *
                          static_cast<std::int64_t>(sizeof(Word)));
}
BENCHMARK(BM_Add32)->Arg(0)->Arg(1);

void BM_Compare32(benchmark::State& state) {
  PixelArray a{PixelArrayGeometry{}};
  fill_random(a);
  enable_half(a);
  // b = 0 and a unsigned, so a >= b everywhere and E stays the same from one iteration to
  // the next; the bit-serial walk does the same work for any data.
  const Field zero{32, 32, false};
  for (int i = 0; i < zero.width; ++i) {
    for (int w = 0; w < a.words(); ++w) a.plane(zero.lo + i)[w] = 0;
  }
  const Bits x = a.bits_of(Field{0, 32, false});
  const Bits y = a.bits_of(zero);
  for (auto _ : state) {
    a.compare(x, y, pp5::Compare::ge);
    benchmark::ClobberMemory();
  }
  report_cycles(state, 33);
}
BENCHMARK(BM_Compare32);

void BM_Multiply8x8(benchmark::State& state) {
  PixelArray a{PixelArrayGeometry{}};
  fill_random(a);
  enable_half(a);
  const Field d{16, 16, false};
  const Bits x = a.bits_of(Field{0, 8, false});
  const Bits y = a.bits_of(Field{8, 8, false});
  for (auto _ : state) {
    a.multiply(d, x, y);
    benchmark::ClobberMemory();
  }
  report_cycles(state, 116);
}
BENCHMARK(BM_Multiply8x8);

// The evaluator hands the array `count` consecutive planes of words() words each.
void BM_AssignPlanes(benchmark::State& state) {
  PixelArray a{PixelArrayGeometry{}};
  fill_random(a);
  enable_half(a);
  constexpr int kBits = 20;
  std::vector<Word> planes(static_cast<std::size_t>(kBits) * a.words());
  std::mt19937_64 rng(9);
  for (auto& w : planes) w = rng();
  const Field d{100, kBits, true};
  const Bits v = a.bits_of_planes(planes.data(), kBits, true);
  for (auto _ : state) {
    a.assign(d, v);
    benchmark::ClobberMemory();
  }
  report_cycles(state, kBits);
}
BENCHMARK(BM_AssignPlanes);

void BM_StreamXor32(benchmark::State& state) {
  PixelArray a{PixelArrayGeometry{}};
  fill_random(a);
  const int words = a.words();
  for (auto _ : state) {
    for (int i = 0; i < 32; ++i) {
      const Word* x = a.plane(i);
      const Word* y = a.plane(32 + i);
      Word* d = a.plane(64 + i);
      for (int w = 0; w < words; ++w) d[w] = x[w] ^ y[w];
    }
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * 3 * 32 * kPlaneBytes);
}
BENCHMARK(BM_StreamXor32);

}  // namespace

// The benchmarks measure frames as pp5sim runs them: with its allocator settings
// (sim/host_memory.hpp), set before anything allocates.
int main(int argc, char** argv) {
  pp5::tune_host_memory();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
