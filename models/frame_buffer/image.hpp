#pragma once
// The frame as the frame buffer holds it.
#include <cstdint>
#include <memory>
#include <vector>

namespace pp5 {

// An 8-bit-per-channel RGB image: row-major, top row first, 3 bytes per pixel, no padding, so
// rgb.size() == width * height * 3 for any image that write_png accepts.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

// One region's pixels as a Renderer board read them out: region width x region height RGB,
// row-major (RgbImage's layout), from the first byte pointed to. Shared, never copied, by
// every region of a frame that came out the same (a board's empty regions give one).
using RegionPixels = std::shared_ptr<const std::uint8_t>;

// Pixels held in a vector, as RegionPixels (the vector is kept alive by the pointer).
RegionPixels region_pixels(std::vector<std::uint8_t> rgb);

// A frame as the frame buffer assembled it: a grid of regions, each holding its Renderer's
// pixels by reference, so a frame is as large as its distinct regions, whatever the screen
// (a 4096 x 4096 screen with one drawn region holds two regions' pixels, not 48 MB).
// Regions that received no pixels (outside fidelity.regions, or every region of a timing-only
// frame) are black. Regions at the right and bottom edges may reach past the screen; only
// the part inside it is part of the frame.
//
// Readers take rows (row(): what the PNG writer and regions.png stream) or single pixels, or
// the whole frame as one RgbImage (flat(): made on first use and kept; not for two threads at
// once before that).
class FrameImage {
 public:
  FrameImage() = default;
  // A black frame of `width` x `height` pixels in regions of region_width x region_height.
  // `pixels` false: a timing-only frame, to which no region's pixels may be given.
  FrameImage(int width, int height, int region_width, int region_height, bool pixels = true);
  // The same, its bytes taken from `storage` (an image done with) when they are the size
  // needed and nothing else holds them (no region of it given away): a run of frames then
  // allocates, and the host's kernel zeroes, an image's pages once rather than per frame.
  FrameImage(int width, int height, int region_width, int region_height, bool pixels,
             FrameImage&& storage);

  int width() const { return width_; }
  int height() const { return height_; }
  // Whether the frame holds pixels at all (false: timing only; flat() is then width x height
  // with no bytes).
  bool has_pixels() const { return pixels_; }

  // The pixels of the region whose top-left pixel is (x0, y0), a multiple of the region size:
  // region width x region height x 3 bytes. Distinct regions may be given from different
  // threads at once, never after flat().
  void set_region(int x0, int y0, RegionPixels pixels);
  // The frame's own bytes for that region, to be written (by one thread) and then given
  // with set_region(x0, y0, own(x0, y0)). Allocated with the frame, untouched until written,
  // and made on the thread that made the frame: a worker thread that writes them pays no
  // page faults in a malloc arena of its own.
  std::uint8_t* own_bytes(int x0, int y0);
  RegionPixels own(int x0, int y0) const;

  // Row y's width() * 3 bytes (RGB) into out.
  void row(int y, std::uint8_t* out) const;
  // Row y's part in region column `column` where it is held, without a copy: the bytes of
  // pixels column * region_width() .. min(width(), (column + 1) * region_width()) - 1; null
  // where that region is black (no pixels given, or a timing-only frame).
  const std::uint8_t* region_row(int column, int y) const {
    if (!pixels_) return nullptr;
    const RegionPixels& r =
        regions_[static_cast<std::size_t>(y / region_height_) * columns_ + column];
    return r ? r.get() + static_cast<std::size_t>(y % region_height_) * region_width_ * 3 : nullptr;
  }
  int region_width() const { return region_width_; }
  int columns() const { return columns_; }
  // The RGB of pixel (x, y), inside the frame.
  const std::uint8_t* pixel(int x, int y) const;
  // The whole frame as one image (no bytes for a timing-only frame).
  const RgbImage& flat() const;
  // The distinct region pixel blocks held (shared ones once).
  std::size_t distinct_regions() const;

 private:
  int width_ = 0, height_ = 0;
  int region_width_ = 1, region_height_ = 1;
  int columns_ = 0;
  bool pixels_ = false;
  std::size_t index(int x0, int y0) const;  // checked
  std::size_t own_size() const;             // own_'s bytes: every region's
  static std::shared_ptr<std::uint8_t> new_own_bytes(std::size_t bytes);
  std::vector<RegionPixels> regions_;  // row-major, null: black
  std::shared_ptr<std::uint8_t> own_;  // a region's bytes for each region, row-major
  mutable std::shared_ptr<const RgbImage> flat_;
};

}  // namespace pp5
