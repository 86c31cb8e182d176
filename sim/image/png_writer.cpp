#include "sim/image/png_writer.hpp"

#include <fmt/format.h>
#include <png.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>

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

}  // namespace

std::string encode_png(const RgbImage& image, const std::string& what) {
  constexpr const char* kWhat = "cannot write PNG";
  if (image.width <= 0 || image.height <= 0) {
    fail(kWhat, what, fmt::format("invalid size {}x{}", image.width, image.height));
  }
  // Computed in size_t, where the product of two positive ints cannot overflow.
  const auto expected =
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3u;
  if (image.rgb.size() != expected) {
    fail(kWhat, what,
         fmt::format("pixel buffer holds {} bytes, a {}x{} RGB image needs {}", image.rgb.size(),
                     image.width, image.height, expected));
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  PngImageGuard guard(png);
  // One compression, into a buffer of the largest size libpng can need (asking for the size
  // first would compress the image twice).
  png_alloc_size_t size = PNG_IMAGE_PNG_SIZE_MAX(png);
  std::string bytes(size, '\0');
  if (png_image_write_to_memory(&png, bytes.data(), &size, /*convert_to_8bit=*/0, image.rgb.data(),
                                /*row_stride=*/0, /*colormap=*/nullptr) == 0) {
    fail(kWhat, what, png.message[0] != '\0' ? png.message : "libpng reported an error");
  }
  bytes.resize(size);
  return bytes;
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
