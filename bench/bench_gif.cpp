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
#include <unordered_map>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/machine_plan.hpp"
#include "sim/output/gif.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace {

void gif_ref_put16(std::string& out, int v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>((v >> 8) & 0xff));
}

// A one-frame GIF of `image` as the GIF specification and gif.hpp's contract describe it.
std::string gif_ref_encode(const pp5::RgbImage& image, int delay) {
  constexpr int kLevels[3] = {6, 7, 6};
  std::string out = "GIF89a";
  gif_ref_put16(out, image.width);
  gif_ref_put16(out, image.height);
  out += std::string("\xF7\x00\x00", 3);
  for (int i = 0; i < 256; ++i) {
    const int level[3] = {i / 42, i / 6 % 7, i % 6};
    for (int c = 0; c < 3; ++c) {
      const int l = kLevels[c] - 1;
      out.push_back(static_cast<char>(i < 252 ? (level[c] * 255 + l / 2) / l : 0));
    }
  }
  out += std::string("\x21\xFF\x0B", 3) + "NETSCAPE2.0" + std::string("\x03\x01\x00\x00\x00", 5);
  out += std::string("\x21\xF9\x04\x04", 4);
  gif_ref_put16(out, delay);
  out += std::string("\x00\x00\x2C", 3);
  gif_ref_put16(out, 0);
  gif_ref_put16(out, 0);
  gif_ref_put16(out, image.width);
  gif_ref_put16(out, image.height);
  out += std::string("\x00\x08", 2);  // no local table; minimum code size 8
  // Palette indices: red * 42 + green * 6 + blue, each the nearest level.
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  std::vector<std::uint8_t> px(n);
  for (std::size_t i = 0; i < n; ++i) {
    int index = 0;
    for (int c = 0; c < 3; ++c) {
      const int l = kLevels[c] - 1;
      index = index * kLevels[c] + (image.rgb[3 * i + c] * l + 127) / 255;
    }
    px[i] = static_cast<std::uint8_t>(index);
  }
  // LZW, codes LSB first, in sub-blocks of 255 bytes.
  std::string data;
  std::uint64_t acc = 0;
  int bits = 0;
  auto emit = [&](int code, int size) {
    acc |= static_cast<std::uint64_t>(code) << bits;
    bits += size;
    for (; bits >= 8; bits -= 8, acc >>= 8) data.push_back(static_cast<char>(acc & 0xff));
  };
  std::unordered_map<std::uint32_t, int> table;
  int size = 9, next = 258;
  emit(256, size);
  int current = px[0];
  for (std::size_t i = 1; i < n; ++i) {
    const std::uint32_t key = static_cast<std::uint32_t>(current) << 8 | px[i];
    const auto it = table.find(key);
    if (it != table.end()) {
      current = it->second;
      continue;
    }
    emit(current, size);
    table.emplace(key, next);
    if (next >= (1 << size)) ++size;
    if (next == 4095) {
      emit(256, size);
      table.clear();
      size = 9;
      next = 257;
    }
    ++next;
    current = px[i];
  }
  emit(current, size);
  emit(257, size);
  if (bits > 0) data.push_back(static_cast<char>(acc & 0xff));
  for (std::size_t at = 0; at < data.size(); at += 255) {
    const std::size_t k = std::min<std::size_t>(255, data.size() - at);
    out.push_back(static_cast<char>(k));
    out.append(data, at, k);
  }
  out += std::string("\x00\x3B", 2);
  return out;
}

void BM_GifEncode(benchmark::State& state) {
  pp5::MachineConfig config = pp5::MachineConfig::defaults();
  config.set(std::vector<std::string>{"fidelity.pixels=word"});
  const pp5::Scene scene = pp5::make_builtin_scene("torus");
  const pp5::Program program = pp5::assemble_file(
      std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5", pp5::assembler_options(config));
  const pp5::FrameImage frame = pp5::simulate_frame(config, scene, program, 2).image;
  const pp5::RgbImage& flat = frame.flat();
  auto encode = [&frame] {
    pp5::GifWriter gif(4);
    gif.add(frame);
    return gif.finish();
  };
  if (encode() != gif_ref_encode(flat, 4)) {
    state.SkipWithError("the GIF differs from the reference encoder's");
    return;
  }
  // This thread's processor time: the machine is shared, and the encoders are single-threaded.
  auto cpu_seconds = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
  };
  double t_new = 0, t_ref = 0;
  std::size_t bytes = 0;
  for (auto _ : state) {
    double t0 = cpu_seconds();
    const std::string a = encode();
    t_new += cpu_seconds() - t0;
    t0 = cpu_seconds();
    const std::string b = gif_ref_encode(flat, 4);
    t_ref += cpu_seconds() - t0;
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
    bytes = a.size();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["new_ms"] = t_new / n * 1e3;
  state.counters["ref_ms"] = t_ref / n * 1e3;
  state.counters["ref_over_new"] = t_ref / t_new;
  state.counters["bytes"] = static_cast<double>(bytes);
}

BENCHMARK(BM_GifEncode)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

// The encoder alone, many times (for perf record): `pp5_bench --benchmark_filter=GifOnly`.
void BM_GifOnly(benchmark::State& state) {
  pp5::MachineConfig config = pp5::MachineConfig::defaults();
  config.set(std::vector<std::string>{"fidelity.pixels=word"});
  const pp5::Scene scene = pp5::make_builtin_scene("torus");
  const pp5::Program program = pp5::assemble_file(
      std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5", pp5::assembler_options(config));
  const pp5::FrameImage frame = pp5::simulate_frame(config, scene, program, 2).image;
  pp5::GifWriter gif(4);
  for (auto _ : state) {
    gif.add(frame);
    benchmark::DoNotOptimize(gif.take().data());
  }
}

BENCHMARK(BM_GifOnly)->Unit(benchmark::kMillisecond)->Iterations(200);

}  // namespace
