#include <algorithm>
#include <cstdint>
#include <cstring>
#include <set>
#include <stdexcept>

#include "common/huge_pages.hpp"
#include "models/frame_buffer/image.hpp"

namespace pp5 {
namespace {

const std::uint8_t kBlackPixel[3] = {0, 0, 0};

}  // namespace

FrameImage::FrameImage(int width, int height, int region_width, int region_height, bool pixels)
    : width_(width),
      height_(height),
      region_width_(region_width),
      region_height_(region_height),
      pixels_(pixels) {
  if (width < 0 || height < 0 || region_width <= 0 || region_height <= 0) {
    throw std::invalid_argument("frame image: invalid size");
  }
  columns_ = (width + region_width - 1) / region_width;
  const int rows = (height + region_height - 1) / region_height;
  if (pixels) {
    regions_.resize(static_cast<std::size_t>(columns_) * rows);
    own_ = new_own_bytes(own_size());
  }
}

std::size_t FrameImage::own_size() const {
  return regions_.size() * static_cast<std::size_t>(region_width_) * region_height_ * 3;
}

// Not initialised: a region's bytes are written before they are given, and the pages of
// regions that share pixels instead are never touched.
std::shared_ptr<std::uint8_t> FrameImage::new_own_bytes(std::size_t bytes) {
  std::shared_ptr<std::uint8_t> own(new std::uint8_t[bytes], std::default_delete<std::uint8_t[]>());
  advise_huge_pages(own.get(), bytes);
  return own;
}

FrameImage::FrameImage(int width, int height, int region_width, int region_height, bool pixels,
                       FrameImage&& storage)
    : FrameImage(width, height, region_width, region_height, false) {
  if (!pixels) return;
  pixels_ = true;
  regions_.resize(static_cast<std::size_t>(columns_) *
                  ((height + region_height - 1) / region_height));
  std::shared_ptr<std::uint8_t> old = std::move(storage.own_);
  const std::size_t old_bytes = storage.own_size();
  storage = FrameImage();  // its regions hold references to its bytes: gone now
  own_ = old && old.use_count() == 1 && old_bytes == own_size() ? std::move(old)
                                                                : new_own_bytes(own_size());
}

RegionPixels region_pixels(std::vector<std::uint8_t> rgb) {
  auto owner = std::make_shared<std::vector<std::uint8_t>>(std::move(rgb));
  return RegionPixels(owner, owner->data());
}

std::size_t FrameImage::index(int x0, int y0) const {
  if (x0 < 0 || y0 < 0 || x0 >= width_ || y0 >= height_ || x0 % region_width_ != 0 ||
      y0 % region_height_ != 0) {
    throw std::logic_error("frame image: a region's origin is not on the region grid");
  }
  return static_cast<std::size_t>(y0 / region_height_) * columns_ + x0 / region_width_;
}

std::uint8_t* FrameImage::own_bytes(int x0, int y0) {
  if (!pixels_) {
    throw std::logic_error("frame image: a region's pixels given to a timing-only frame");
  }
  return own_.get() + index(x0, y0) * region_width_ * region_height_ * 3;
}

RegionPixels FrameImage::own(int x0, int y0) const {
  if (!pixels_) {
    throw std::logic_error("frame image: a region's pixels given to a timing-only frame");
  }
  return RegionPixels(own_, own_.get() + index(x0, y0) * region_width_ * region_height_ * 3);
}

void FrameImage::set_region(int x0, int y0, RegionPixels pixels) {
  if (!pixels_) {
    throw std::logic_error("frame image: a region's pixels given to a timing-only frame");
  }
  if (flat_) throw std::logic_error("frame image: a region's pixels given after flat()");
  if (!pixels) throw std::logic_error("frame image: a region without pixels");
  regions_[index(x0, y0)] = std::move(pixels);
}

void FrameImage::row(int y, std::uint8_t* out) const {
  const int ry = y / region_height_;
  const std::size_t within = static_cast<std::size_t>(y % region_height_) * region_width_ * 3;
  for (int c = 0; c < columns_; ++c) {
    const int x0 = c * region_width_;
    const std::size_t bytes = static_cast<std::size_t>(std::min(region_width_, width_ - x0)) * 3;
    const RegionPixels* r =
        pixels_ ? &regions_[static_cast<std::size_t>(ry) * columns_ + c] : nullptr;
    if (r != nullptr && *r) {
      std::memcpy(out + static_cast<std::size_t>(x0) * 3, r->get() + within, bytes);
    } else {
      std::memset(out + static_cast<std::size_t>(x0) * 3, 0, bytes);
    }
  }
}

const std::uint8_t* FrameImage::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) {
    throw std::out_of_range("frame image: pixel outside the frame");
  }
  if (!pixels_) return kBlackPixel;
  const RegionPixels& r =
      regions_[static_cast<std::size_t>(y / region_height_) * columns_ + x / region_width_];
  if (!r) return kBlackPixel;
  return r.get() +
         (static_cast<std::size_t>(y % region_height_) * region_width_ + x % region_width_) * 3;
}

const RgbImage& FrameImage::flat() const {
  if (!flat_) {
    auto image = std::make_shared<RgbImage>();
    image->width = width_;
    image->height = height_;
    if (pixels_) {
      const std::size_t stride = static_cast<std::size_t>(width_) * 3;
      image->rgb.resize(stride * static_cast<std::size_t>(height_));
      for (int y = 0; y < height_; ++y) row(y, image->rgb.data() + stride * y);
    }
    flat_ = std::move(image);
  }
  return *flat_;
}

std::size_t FrameImage::distinct_regions() const {
  std::set<const std::uint8_t*> distinct;
  for (const RegionPixels& r : regions_) {
    if (r) distinct.insert(r.get());
  }
  return distinct.size();
}

}  // namespace pp5
