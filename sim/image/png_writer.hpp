#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "models/frame_buffer/image.hpp"

namespace pp5 {

// `image` as the bytes of an 8-bit RGB PNG file; std::runtime_error naming `what` on a bad
// image or a zlib error.
std::string encode_png(const RgbImage& image, const std::string& what = "image");

// A frame, streamed region row by region row (no whole-frame copy); a frame that holds no
// pixels (timing only) is refused.
std::string encode_png(const FrameImage& frame, const std::string& what = "image");

// The same for an image made a row at a time: rows(y, out) writes row y's width * 3 bytes
// (RGB) to out, for y = 0 .. height - 1 in order. Nothing holds the whole image.
std::string encode_png(int width, int height,
                       const std::function<void(int y, std::uint8_t* row)>& rows,
                       const std::string& what = "image");

// Writes `image` as an 8-bit RGB PNG. The data go to `path + ".tmp"` first, which is then renamed
// onto `path`, so a reader never sees a half-written file. On any failure (bad image dimensions,
// unwritable directory, zlib error, failed rename) the temporary file is removed, `path` is left
// as it was, and std::runtime_error is thrown with the path and the reason in its message.
void write_png(const std::string& path, const RgbImage& image);

// Reads any PNG libpng understands and converts it to 8-bit RGB (alpha is composed onto black).
// Throws std::runtime_error naming the path and the reason on error.
RgbImage read_png(const std::string& path);

}  // namespace pp5
