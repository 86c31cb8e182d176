// Assembler time on programs of many fields, most of them spilled: the layout must stay
// linear in the program's size (it was fields x instructions). Google Benchmark fits the
// complexity over the sizes and prints it (BigO), from one run.
#include <benchmark/benchmark.h>

#include <string>

#include "firmware/assembler/assembler.hpp"

namespace {

std::string wide_program(int fields) {
  std::string source = "option spill\nfield red 8\nfield green 8\nfield blue 8\n";
  for (int k = 0; k < fields; ++k) source += "field f" + std::to_string(k) + " 1\n";
  source += "output red green blue\nproc triangle\n";
  for (int k = 0; k + 1 < fields; k += 2)
    source += "  and f" + std::to_string(k) + ", f" + std::to_string(k + 1) + "\n";
  return source + "end\n";
}

void AssembleWide(benchmark::State& state) {
  const std::string source = wide_program(static_cast<int>(state.range(0)));
  pp5::AssemblerOptions o;
  o.backing_store_bits = 1 << 16;
  o.block_bits = 1;
  for (auto _ : state) benchmark::DoNotOptimize(pp5::assemble(source, "wide", o));
  state.SetComplexityN(state.range(0));
}
BENCHMARK(AssembleWide)->RangeMultiplier(2)->Range(5000, 40000)->Complexity();

}  // namespace
