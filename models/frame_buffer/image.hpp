#pragma once
// The frame as the frame buffer holds it.
#include <cstdint>
#include <vector>

namespace pp5 {

// An 8-bit-per-channel RGB image: row-major, top row first, 3 bytes per pixel, no padding, so
// rgb.size() == width * height * 3 for any image that write_png accepts.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

}  // namespace pp5
