// PNG encoding of a rendered frame (the default torus at `word`, 1280 x 1024): the encoder
// pp5sim uses (sim/image/png_writer.cpp, its own deflate) against a reference kept here, the zlib
// encoder it replaced (level 1, run-length matches only, the Up filter a 256 KB strip at a
// time), timed alternately in one run. BM_PngEncode reports
//   new_ms, zlib_ms      mean milliseconds of processor time per image
//   zlib_over_new        how many times quicker the new encoder is
//   new_bytes, zlib_bytes  the files' sizes
// and stops with an error if the new file does not decode (libpng) to the frame's pixels.
#include <benchmark/benchmark.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_frames.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/gp/machine_plan.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace {

void png_ref_put_u32(std::string& out, std::uint32_t v) {
  const char bytes[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                         static_cast<char>(v >> 8), static_cast<char>(v)};
  out.append(bytes, 4);
}

void png_ref_chunk(std::string& out, const char type[4], const char* data, std::size_t size) {
  png_ref_put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t at = out.size();
  out.append(type, 4);
  out.append(data, size);
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(out.data() + at),
                          static_cast<uInt>(size + 4));
  png_ref_put_u32(out, static_cast<std::uint32_t>(crc));
}

// The zlib encoder pp5sim used before libdeflate, as it was.
std::string png_ref_encode_zlib(const pp5::RgbImage& image) {
  const std::size_t stride = static_cast<std::size_t>(image.width) * 3u;
  constexpr std::size_t kStripBytes = std::size_t{1} << 18;
  std::vector<std::uint8_t> row(stride), above(stride, 0);
  const std::size_t strip_rows = std::max<std::size_t>(1, kStripBytes / (stride + 1));
  std::vector<std::uint8_t> strip(strip_rows * (stride + 1));
  z_stream z{};
  if (deflateInit2(&z, 1, Z_DEFLATED, 15, 8, Z_RLE) != Z_OK) std::abort();
  std::string stream(std::max<std::size_t>(stride * 2, 1u << 16), '\0');
  std::size_t written = 0;
  auto compress = [&](const std::uint8_t* in, std::size_t n, bool last) {
    z.next_in = const_cast<Bytef*>(in);
    z.avail_in = static_cast<uInt>(n);
    for (;;) {
      if (written == stream.size()) stream.resize(stream.size() * 2);
      const std::size_t room = stream.size() - written;
      z.next_out = reinterpret_cast<Bytef*>(&stream[written]);
      z.avail_out = static_cast<uInt>(room);
      const int rc = deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
      written += room - z.avail_out;
      if (rc == Z_STREAM_END) return;
      if (!last && z.avail_in == 0) return;
    }
  };
  std::size_t filled = 0;
  for (int y = 0; y < image.height; ++y) {
    std::copy_n(image.rgb.data() + stride * static_cast<std::size_t>(y), stride, row.data());
    std::uint8_t* out = strip.data() + filled;
    out[0] = 2;
    for (std::size_t i = 0; i < stride; ++i)
      out[1 + i] = static_cast<std::uint8_t>(row[i] - above[i]);
    row.swap(above);
    filled += stride + 1;
    const bool last = y + 1 == image.height;
    if (last || filled == strip.size()) {
      compress(strip.data(), filled, last);
      filled = 0;
    }
  }
  deflateEnd(&z);
  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  png_ref_put_u32(header, static_cast<std::uint32_t>(image.width));
  png_ref_put_u32(header, static_cast<std::uint32_t>(image.height));
  header.append("\x08\x02\x00\x00\x00", 5);
  png_ref_chunk(png, "IHDR", header.data(), header.size());
  png_ref_chunk(png, "IDAT", stream.data(), written);
  png_ref_chunk(png, "IEND", "", 0);
  return png;
}

void BM_PngEncode(benchmark::State& state) {
  const pp5::RgbImage image = pp5::bench::torus_word_frame().flat();
  // The new file decodes to the frame's pixels.
  const std::string check = pp5::encode_png(image);
  const auto path = std::filesystem::temp_directory_path() / "pp5_bench_png_check.png";
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(check.data(), 1, check.size(), f);
    std::fclose(f);
  }
  const pp5::RgbImage back = pp5::read_png(path.string());
  std::filesystem::remove(path);
  if (back.rgb != image.rgb) {
    state.SkipWithError("the new encoder's PNG does not decode to the frame");
    return;
  }
  const pp5::bench::EncoderTimes t = pp5::bench::time_encoders(
      state, [&image] { return pp5::encode_png(image); },
      [&image] { return png_ref_encode_zlib(image); });
  state.counters["new_ms"] = t.new_ms;
  state.counters["zlib_ms"] = t.ref_ms;
  state.counters["zlib_over_new"] = t.ref_ms / t.new_ms;
  state.counters["new_bytes"] = static_cast<double>(t.new_bytes);
  state.counters["zlib_bytes"] = static_cast<double>(t.ref_bytes);
}

BENCHMARK(BM_PngEncode)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

}  // namespace

namespace {

// The encoder alone on the frame buffer's frame, as `pp5sim animate` encodes each frame (for
// perf record): `pp5_bench --benchmark_filter=PngOnly`.
void BM_PngOnly(benchmark::State& state) {
  const pp5::FrameImage frame = pp5::bench::torus_word_frame();
  for (auto _ : state) benchmark::DoNotOptimize(pp5::encode_png(frame).data());
}

BENCHMARK(BM_PngOnly)->Unit(benchmark::kMillisecond)->Iterations(200);

}  // namespace
