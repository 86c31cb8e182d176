// The frame as the frame buffer holds it: regions by reference, black where none arrived,
// cut at the screen's edge; its rows, pixels and flat image agree, and what cannot be a
// region's pixels is refused.
#include <catch2/catch.hpp>
#include <memory>
#include <stdexcept>
#include <vector>

#include "models/frame_buffer/image.hpp"
#include "sim/image/png_writer.hpp"

using namespace pp5;

namespace {

// A 4 x 2 region whose pixel (x, y) is (tag, x, y).
std::vector<std::uint8_t> tagged_bytes(std::uint8_t tag) {
  std::vector<std::uint8_t> p;
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 4; ++x) {
      p.insert(p.end(), {tag, static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(y)});
    }
  }
  return p;
}

RegionPixels tagged_region(std::uint8_t tag) { return region_pixels(tagged_bytes(tag)); }

}  // namespace

TEST_CASE("a frame image holds regions by reference and reads as one image", "[frame]") {
  // 10 x 3 pixels in 4 x 2 regions: 3 columns (the last cut to 2 pixels), 2 rows (the last
  // cut to 1).
  FrameImage frame(10, 3, 4, 2);
  REQUIRE(frame.has_pixels());
  const RegionPixels shared = tagged_region(7);
  frame.set_region(0, 0, shared);
  // Region (2, 0) in the frame's own bytes.
  const std::vector<std::uint8_t> nine = tagged_bytes(9);
  std::copy(nine.begin(), nine.end(), frame.own_bytes(8, 0));
  frame.set_region(8, 0, frame.own(8, 0));
  frame.set_region(4, 2, shared);  // the same pixels twice: held once
  CHECK(frame.distinct_regions() == 2);
  CHECK(shared.use_count() == 3);
  CHECK(frame.pixel(9, 1) == frame.own_bytes(8, 0) + 3 * (1 * 4 + 1));
  // Region (1, 0) never arrived: black.
  CHECK(frame.pixel(5, 1)[0] == 0);
  CHECK(frame.pixel(9, 1)[0] == 9);
  CHECK(frame.pixel(9, 1)[1] == 1);  // x within its region
  CHECK(frame.pixel(6, 2)[1] == 2);
  std::vector<std::uint8_t> row(30);
  frame.row(2, row.data());
  const std::vector<std::uint8_t> expected_row = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,  //
                                                  7, 0, 0, 7, 1, 0, 7, 2, 0, 7, 3, 0,  //
                                                  0, 0, 0, 0, 0, 0};
  CHECK(row == expected_row);
  const RgbImage& flat = frame.flat();
  REQUIRE(flat.width == 10);
  REQUIRE(flat.height == 3);
  REQUIRE(flat.rgb.size() == 90u);
  for (int y = 0; y < 3; ++y) {
    frame.row(y, row.data());
    CHECK(std::equal(row.begin(), row.end(), flat.rgb.begin() + y * 30));
    for (int x = 0; x < 10; ++x) {
      CHECK(
          std::equal(frame.pixel(x, y), frame.pixel(x, y) + 3, flat.rgb.begin() + y * 30 + 3 * x));
    }
  }
  // The PNG of the frame is the PNG of its flat image.
  CHECK(encode_png(frame) == encode_png(flat));
}

TEST_CASE("a frame image refuses what cannot be a region's pixels", "[frame]") {
  FrameImage frame(10, 3, 4, 2);
  CHECK_THROWS_AS(frame.set_region(2, 0, tagged_region(1)), std::logic_error);   // off the grid
  CHECK_THROWS_AS(frame.set_region(12, 0, tagged_region(1)), std::logic_error);  // off the screen
  CHECK_THROWS_AS(frame.own_bytes(4, 1), std::logic_error);
  CHECK_THROWS_AS(frame.set_region(0, 0, nullptr), std::logic_error);
  CHECK_THROWS_AS(frame.pixel(10, 0), std::out_of_range);
  (void)frame.flat();
  CHECK_THROWS_AS(frame.set_region(0, 0, tagged_region(1)), std::logic_error);  // after flat()

  // Timing only: no pixels, black rows, a flat image with no bytes, no PNG.
  FrameImage timing(10, 3, 4, 2, false);
  CHECK_FALSE(timing.has_pixels());
  CHECK_THROWS_AS(timing.set_region(0, 0, tagged_region(1)), std::logic_error);
  CHECK_THROWS_AS(timing.own_bytes(0, 0), std::logic_error);
  std::vector<std::uint8_t> row(30, 1);
  timing.row(0, row.data());
  CHECK(row == std::vector<std::uint8_t>(30, 0));
  CHECK(timing.flat().width == 10);
  CHECK(timing.flat().rgb.empty());
  CHECK_THROWS_WITH(encode_png(timing, "frame.png"), Catch::Contains("holds no pixels"));
}

TEST_CASE("a frame image reuses the bytes of one done with, only when nothing else holds them",
          "[frame]") {
  FrameImage first(10, 3, 4, 2);
  const std::uint8_t* bytes = first.own_bytes(0, 0);
  first.set_region(0, 0, first.own(0, 0));
  FrameImage second(10, 3, 4, 2, true, std::move(first));
  CHECK(second.own_bytes(0, 0) == bytes);  // its regions were all the frame held
  // What the new frame shows starts black: no region of it arrived, whatever the bytes hold.
  CHECK(second.pixel(1, 1)[0] == 0);
  CHECK(second.distinct_regions() == 0);
  // A region of it given away (a caller keeping a frame's pixels) keeps the bytes its own.
  const RegionPixels kept = second.own(4, 0);
  FrameImage third(10, 3, 4, 2, true, std::move(second));
  CHECK(third.own_bytes(0, 0) != bytes);
  CHECK(kept.get() == bytes + 3 * 4 * 2);
  // Bytes of another size are not taken.
  FrameImage wider(12, 3, 4, 2, true, std::move(third));
  CHECK(wider.width() == 12);
  CHECK(wider.distinct_regions() == 0);
}
