#include "models/frame_buffer/frame_buffer.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace pp5 {

FrameBuffer::FrameBuffer(sc_core::sc_module_name name, int width, int height, int regions,
                         bool image)
    : sc_module(name), arrival_(regions, sc_core::SC_ZERO_TIME) {
  image_.width = width;
  image_.height = height;
  if (!image) return;
  const std::size_t bytes = static_cast<std::size_t>(width) * height * 3;
  image_.rgb.reserve(bytes);
#if defined(__linux__)
  // Host speed only: a large frame (48 MB at 4096 x 4096) is first touched here, and with
  // 2 MB pages that takes 1/512 of the page faults. The advice may be ignored; nothing
  // depends on it.
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(image_.rgb.data());
  const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHugePage - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#endif
  image_.rgb.assign(bytes, 0);
}

void FrameBuffer::receive_region(const RegionArrival& region) {
  arrival_[region.region] = region.arrival;
  last_ = std::max(last_, region.arrival);
  ++received_;
}

void FrameBuffer::store_region(int x0, int y0, int region_width, int region_height,
                               const std::vector<std::uint8_t>& rgb) {
  if (image_.rgb.empty()) {
    throw std::logic_error("frame buffer: a region's pixels arrived at a frame that holds none");
  }
  const int w = std::min(region_width, image_.width - x0);
  const int h = std::min(region_height, image_.height - y0);
  for (int y = 0; y < h; ++y) {
    std::memcpy(&image_.rgb[(static_cast<std::size_t>(y0 + y) * image_.width + x0) * 3],
                &rgb[static_cast<std::size_t>(y) * region_width * 3],
                static_cast<std::size_t>(w) * 3);
  }
}

}  // namespace pp5
