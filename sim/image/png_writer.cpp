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

// zlib's level 1 (Z_BEST_SPEED).
constexpr int kCompressionLevel = 1;

// Where the encoder's bytes and its error go; libpng's callbacks reach it through their
// user pointers.
struct PngWriteState {
  std::string what;
  std::string bytes;
  std::string message = "libpng reported an error";
};

void on_png_write(png_structp png, png_bytep data, png_size_t length) {
  auto* state = static_cast<PngWriteState*>(png_get_io_ptr(png));
  state->bytes.append(reinterpret_cast<const char*>(data), length);
}

[[noreturn]] void on_png_error(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngWriteState*>(png_get_error_ptr(png));
  state->message = message;
  png_longjmp(png, 1);
}

// Releases the write structures on every exit path.
class PngWriteGuard {
 public:
  PngWriteGuard(png_structp& png, png_infop& info) : png_(png), info_(info) {}
  ~PngWriteGuard() { png_destroy_write_struct(&png_, &info_); }
  PngWriteGuard(const PngWriteGuard&) = delete;
  PngWriteGuard& operator=(const PngWriteGuard&) = delete;

 private:
  png_structp& png_;
  png_infop& info_;
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

std::string encode_png(int width, int height,
                       const std::function<void(int y, std::uint8_t* row)>& rows,
                       const std::string& what) {
  constexpr const char* kWhat = "cannot write PNG";
  if (width <= 0 || height <= 0) {
    fail(kWhat, what, fmt::format("invalid size {}x{}", width, height));
  }
  // The full libpng API rather than png_image_write_to_memory, for its compression settings:
  // run-length matches only (Z_RLE) at zlib's fastest level after the Up filter: a rendered
  // frame's flat areas and repeated rows compress almost as well as with the default search,
  // in a fraction of the time (the image bits are the same).
  PngWriteState state;
  state.what = what;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, on_png_error, nullptr);
  if (png == nullptr) fail(kWhat, what, "libpng could not start");
  png_infop info = png_create_info_struct(png);
  PngWriteGuard guard(png, info);
  if (info == nullptr) fail(kWhat, what, "libpng could not start");
  // One row's buffer, outside the setjmp scope (no object with a destructor is created
  // between setjmp and a longjmp back to it).
  std::vector<std::uint8_t> row(static_cast<std::size_t>(width) * 3u);
  if (setjmp(png_jmpbuf(png)) != 0) fail(kWhat, what, state.message);
  png_set_write_fn(png, &state, on_png_write, nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, kCompressionLevel);
  png_set_compression_strategy(png, Z_RLE);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y) {
    rows(y, row.data());
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  return std::move(state.bytes);
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
