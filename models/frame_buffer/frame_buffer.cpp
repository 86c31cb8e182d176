#include "models/frame_buffer/frame_buffer.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace pp5 {

FrameBuffer::FrameBuffer(sc_core::sc_module_name name, int width, int height, int region_width,
                         int region_height, int regions, bool image)
    : sc_module(name),
      width_(width),
      height_(height),
      region_width_(region_width),
      region_height_(region_height),
      has_image_(image),
      image_(width, height, region_width, region_height, image),
      arrival_(regions, sc_core::SC_ZERO_TIME) {}

void FrameBuffer::begin_frame(sc_core::sc_time start, FrameImage storage) {
  start_ = start;
  last_ = start;
  received_ = 0;
  std::fill(arrival_.begin(), arrival_.end(), start);
  image_ =
      FrameImage(width_, height_, region_width_, region_height_, has_image_, std::move(storage));
}

void FrameBuffer::receive_region(const RegionArrival& region) {
  arrival_[region.region] = region.arrival;
  last_ = std::max(last_, region.arrival);
  ++received_;
}

void FrameBuffer::store_region(int x0, int y0, RegionPixels pixels) {
  if (!image_.has_pixels()) {
    throw std::logic_error("frame buffer: a region's pixels arrived at a frame that holds none");
  }
  image_.set_region(x0, y0, std::move(pixels));
}

std::uint8_t* FrameBuffer::region_bytes(int x0, int y0) {
  if (!image_.has_pixels()) {
    throw std::logic_error("frame buffer: a region's pixels arrived at a frame that holds none");
  }
  return image_.own_bytes(x0, y0);
}

void FrameBuffer::store_region(int x0, int y0) { store_region(x0, y0, image_.own(x0, y0)); }

}  // namespace pp5
