#pragma once
// regions.png: where a frame's Renderer time went, drawn over the frame itself.
//
// Contract:
//  - region_heat_map() returns an image as wide as the frame and kLegendHeight rows taller:
//    the frame, greyed, with every region tinted by its Renderer busy cycles on one linear
//    colour scale from 0 (dark blue) through purple, red and orange to the busiest region's
//    cycles (pale yellow) (heat_colour()), and every region of the busiest Renderer (the one
//    with the most busy cycles summed over its regions, the lowest index on a tie) outlined in
//    white lined with black, and (when `critical_renderer` is given) every region of the
//    Renderer on the critical path (timing.critical_renderer: the one whose last region
//    reached the frame buffer last) outlined in cyan lined with black, 3 to 5 pixels inside
//    the region, so that a Renderer that is both shows both; below it a legend of two rows:
//    the colour bar, "0" at its left end and the busiest region's cycles at its right with
//    the unit ("ARRAY CYCLES": busy cycles of the Renderer's array on that region), then a
//    key to the two outlines naming each Renderer ("BUSIEST RENDERER 3", "CRITICAL PATH
//    RENDERER 5", or "BUSIEST 3", "CRITICAL 5" where those do not fit the frame's width).
//  - It reads only its arguments: the same frame and loads give the same bytes.
//  - Throws std::invalid_argument when a region lies outside the frame or the frame's pixel
//    buffer does not match its size.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "models/frame_buffer/image.hpp"

namespace pp5 {

// One region of the frame and the Renderer work it took.
struct RegionLoad {
  int region = 0;
  int x0 = 0, y0 = 0, width = 0, height = 0;  // in frame pixels
  int renderer = 0;
  std::uint64_t busy_cycles = 0;
};

constexpr int kLegendHeight = 44;
constexpr int kLegendBarRows = 24;  // the legend's first row: the colour bar

// The colour of `t` in [0, 1] on the heat scale (t is clamped).
void heat_colour(double t, std::uint8_t rgb[3]);

RgbImage region_heat_map(const RgbImage& frame, const std::vector<RegionLoad>& regions,
                         int critical_renderer = -1);

// The same image a row at a time, for encode_png's row form: nothing holds the whole image
// (a 1280 x 1024 frame's map is 4 MB). Keeps a reference to `frame`, which must outlive it;
// throws as region_heat_map() does. A FrameImage that holds no pixels (timing only) gives the
// map on a black frame.
class RegionHeatMap {
 public:
  RegionHeatMap(const RgbImage& frame, const std::vector<RegionLoad>& regions,
                int critical_renderer = -1);
  RegionHeatMap(const FrameImage& frame, const std::vector<RegionLoad>& regions,
                int critical_renderer = -1);
  int busiest_renderer() const { return busiest_; }
  int width() const { return width_; }
  int height() const { return frame_height_ + kLegendHeight; }
  // Row y's width() * 3 bytes (RGB) into out. Not for two threads at once on one map.
  void row(int y, std::uint8_t* out) const;

 private:
  RegionHeatMap(int width, int height, std::function<void(int y, std::uint8_t* out)> frame_row,
                const std::vector<RegionLoad>& regions, int critical_renderer);
  struct Tint {
    RegionLoad load;
    std::array<std::array<std::uint8_t, 3>, 256> table;  // grey to tinted colour
  };
  int width_ = 0, frame_height_ = 0;
  std::function<void(int y, std::uint8_t* out)> frame_row_;  // the frame's row y
  std::vector<Tint> tints_;                                  // in the order of the loads
  int critical_ = -1;                                        // the critical-path Renderer
  int busiest_ = -1;                                         // the busiest Renderer
  RgbImage legend_;  // the kLegendHeight rows below the frame
  // row()'s frame row and its grey: row() is called from one thread at a time.
  mutable std::vector<std::uint8_t> src_, grey_;
};

}  // namespace pp5
