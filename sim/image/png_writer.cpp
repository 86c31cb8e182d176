#include "sim/image/png_writer.hpp"

#include <fmt/format.h>
#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/output/output_set.hpp"

namespace pp5 {
namespace {

// Releases libpng's state on every exit path; png_image_free is a no-op once libpng has already
// freed it (after png_image_finish_read or a failed call).
class PngImageGuard {
 public:
  explicit PngImageGuard(png_image& image) : image_(image) {}
  ~PngImageGuard() { png_image_free(&image_); }
  PngImageGuard(const PngImageGuard&) = delete;
  PngImageGuard& operator=(const PngImageGuard&) = delete;

 private:
  png_image& image_;
};

[[noreturn]] void fail(const char* what, const std::string& path, const std::string& reason) {
  throw std::runtime_error(fmt::format("{} '{}': {}", what, path, reason));
}

// zlib's level 1 (Z_BEST_SPEED), run-length matches only (Z_RLE), after the Up filter: a
// rendered frame's flat areas and repeated rows compress almost as well as with the default
// search, in a fraction of the time (the image bits are the same).
constexpr int kCompressionLevel = 1;
// Rows are filtered and compressed this many bytes at a time: nothing holds the whole
// filtered image.
constexpr std::size_t kStripBytes = std::size_t{1} << 18;
// The longest IDAT chunk written (PNG allows 2^31 - 1 bytes).
constexpr std::size_t kMaxChunk = std::size_t{1} << 30;

void put_u32(std::string& out, std::uint32_t v) {
  const char bytes[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                         static_cast<char>(v >> 8), static_cast<char>(v)};
  out.append(bytes, 4);
}

// A PNG chunk: length, type, data, and the CRC of type and data.
void put_chunk(std::string& out, const char type[4], const char* data, std::size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t at = out.size();
  out.append(type, 4);
  out.append(data, size);
  const auto* crc_from = reinterpret_cast<const Bytef*>(out.data() + at);
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t done = 0; done < size + 4;) {  // crc32 takes a uInt length
    const auto n = static_cast<uInt>(std::min<std::size_t>(size + 4 - done, 1u << 30));
    crc = crc32(crc, crc_from + done, n);
    done += n;
  }
  put_u32(out, static_cast<std::uint32_t>(crc));
}

// Releases zlib's state on every exit path.
class DeflateGuard {
 public:
  explicit DeflateGuard(z_stream& z) : z_(z) {}
  ~DeflateGuard() { deflateEnd(&z_); }
  DeflateGuard(const DeflateGuard&) = delete;
  DeflateGuard& operator=(const DeflateGuard&) = delete;

 private:
  z_stream& z_;
};

}  // namespace

std::string encode_png(const RgbImage& image, const std::string& what) {
  // Computed in size_t, where the product of two positive ints cannot overflow.
  const auto expected = static_cast<std::size_t>(std::max(image.width, 0)) *
                        static_cast<std::size_t>(std::max(image.height, 0)) * 3u;
  if (image.width > 0 && image.height > 0 && image.rgb.size() != expected) {
    fail("cannot write PNG", what,
         fmt::format("pixel buffer holds {} bytes, a {}x{} RGB image needs {}", image.rgb.size(),
                     image.width, image.height, expected));
  }
  const std::size_t stride = static_cast<std::size_t>(std::max(image.width, 0)) * 3u;
  return encode_png(
      image.width, image.height,
      [&](int y, std::uint8_t* row) {
        std::memcpy(row, image.rgb.data() + stride * static_cast<std::size_t>(y), stride);
      },
      what);
}

std::string encode_png(const FrameImage& frame, const std::string& what) {
  if (!frame.has_pixels()) fail("cannot write PNG", what, "the frame holds no pixels");
  return encode_png(
      frame.width(), frame.height(), [&frame](int y, std::uint8_t* row) { frame.row(y, row); },
      what);
}

std::string encode_png(int width, int height,
                       const std::function<void(int y, std::uint8_t* row)>& rows,
                       const std::string& what) {
  constexpr const char* kWhat = "cannot write PNG";
  if (width <= 0 || height <= 0) {
    fail(kWhat, what, fmt::format("invalid size {}x{}", width, height));
  }
  // The PNG container written here, its zlib stream made by zlib directly (libpng reads):
  // the rows are filtered a strip at a time, without libpng's per-row calls.
  const std::size_t stride = static_cast<std::size_t>(width) * 3u;
  if (stride + 1 > std::numeric_limits<uInt>::max()) {  // a row goes to zlib whole
    fail(kWhat, what, fmt::format("a row of {} pixels is too wide to compress", width));
  }
  std::vector<std::uint8_t> row(stride), above(stride, 0);  // row 0's Up is its bytes
  const std::size_t strip_rows = std::max<std::size_t>(1, kStripBytes / (stride + 1));
  std::vector<std::uint8_t> strip(strip_rows * (stride + 1));
  z_stream z{};
  if (deflateInit2(&z, kCompressionLevel, Z_DEFLATED, 15, 8, Z_RLE) != Z_OK) {
    fail(kWhat, what, "zlib could not start");
  }
  DeflateGuard guard(z);
  std::string stream;
  stream.resize(std::max<std::size_t>(stride * 2, 1u << 16));
  std::size_t written = 0;
  // Compresses `n` bytes of filtered rows, growing the stream's buffer as it fills.
  auto compress = [&](const std::uint8_t* in, std::size_t n, bool last) {
    z.next_in = const_cast<Bytef*>(in);
    z.avail_in = static_cast<uInt>(n);
    for (;;) {
      if (written == stream.size()) stream.resize(stream.size() * 2);
      const std::size_t room = std::min<std::size_t>(stream.size() - written, 1u << 30);
      z.next_out = reinterpret_cast<Bytef*>(&stream[written]);
      z.avail_out = static_cast<uInt>(room);
      const int rc = deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
      written += room - z.avail_out;
      if (rc == Z_STREAM_END) return;
      if (rc != Z_OK && rc != Z_BUF_ERROR) fail(kWhat, what, "zlib reported an error");
      if (!last && z.avail_in == 0) return;
    }
  };
  std::size_t filled = 0;  // bytes of `strip` in use
  for (int y = 0; y < height; ++y) {
    rows(y, row.data());
    std::uint8_t* out = strip.data() + filled;
    out[0] = 2;  // the Up filter: each byte less the byte above it
    for (std::size_t i = 0; i < stride; ++i)
      out[1 + i] = static_cast<std::uint8_t>(row[i] - above[i]);
    row.swap(above);
    filled += stride + 1;
    const bool last = y + 1 == height;
    if (last || filled == strip.size()) {
      compress(strip.data(), filled, last);
      filled = 0;
    }
  }
  std::string png;
  png.reserve(written + 64 + written / kMaxChunk * 12);
  png.append("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  put_u32(header, static_cast<std::uint32_t>(width));
  put_u32(header, static_cast<std::uint32_t>(height));
  header.append("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, filters 0, no interlace
  put_chunk(png, "IHDR", header.data(), header.size());
  for (std::size_t at = 0; at < written; at += kMaxChunk) {
    put_chunk(png, "IDAT", stream.data() + at, std::min(kMaxChunk, written - at));
  }
  put_chunk(png, "IEND", "", 0);
  return png;
}

void write_png(const std::string& path, const RgbImage& image) {
  const std::string bytes = encode_png(image, path);
  try {
    write_file_atomically(path, bytes);
  } catch (const OutputError& e) {
    throw std::runtime_error(std::string("cannot write PNG: ") + e.what());
  }
}

RgbImage read_png(const std::string& path) {
  constexpr const char* kWhat = "cannot read PNG";
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  PngImageGuard guard(png);
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    fail(kWhat, path, png.message);
  }
  png.format = PNG_FORMAT_RGB;
  if (png.width > static_cast<png_uint_32>(std::numeric_limits<int>::max()) ||
      png.height > static_cast<png_uint_32>(std::numeric_limits<int>::max())) {
    fail(kWhat, path, "image too large");
  }
  RgbImage out;
  out.width = static_cast<int>(png.width);
  out.height = static_cast<int>(png.height);
  // Sized in size_t rather than with PNG_IMAGE_SIZE, whose 32-bit arithmetic can wrap; libpng
  // itself rejects images whose rows do not fit its own limits.
  out.rgb.resize(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 3u);
  const png_color black{0, 0, 0};
  if (png_image_finish_read(&png, &black, out.rgb.data(), /*row_stride=*/0,
                            /*colormap=*/nullptr) == 0) {
    fail(kWhat, path, png.message);
  }
  return out;
}

}  // namespace pp5
