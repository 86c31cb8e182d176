#include "models/frame_buffer/frame_buffer.hpp"

#include <algorithm>
#include <cstring>

namespace pp5 {

FrameBuffer::FrameBuffer(sc_core::sc_module_name name, int width, int height, int regions)
    : sc_module(name), arrival_(regions, sc_core::SC_ZERO_TIME) {
  image_.width = width;
  image_.height = height;
  image_.rgb.assign(static_cast<std::size_t>(width) * height * 3, 0);
}

void FrameBuffer::region_arrived(int region, sc_core::sc_time when) {
  arrival_[region] = when;
  last_ = std::max(last_, arrival_[region]);
  ++received_;
}

void FrameBuffer::store_region(int x0, int y0, int region_width, int region_height,
                               const std::vector<std::uint8_t>& rgb) {
  const int w = std::min(region_width, image_.width - x0);
  const int h = std::min(region_height, image_.height - y0);
  for (int y = 0; y < h; ++y) {
    std::memcpy(&image_.rgb[(static_cast<std::size_t>(y0 + y) * image_.width + x0) * 3],
                &rgb[static_cast<std::size_t>(y) * region_width * 3],
                static_cast<std::size_t>(w) * 3);
  }
}

}  // namespace pp5
