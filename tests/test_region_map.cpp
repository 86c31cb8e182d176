// regions.png: every region's Renderer busy cycles, as a heat map over the frame.
#include <catch2/catch.hpp>
#include <set>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/image/region_map.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

using namespace pp5;

namespace {

const std::uint8_t* pixel(const RgbImage& image, int x, int y) {
  return &image.rgb[(static_cast<std::size_t>(y) * image.width + x) * 3];
}

int brightness(const std::uint8_t* p) { return p[0] + p[1] + p[2]; }

}  // namespace

TEST_CASE("every region's busy cycles, summed per Renderer, are its busy cycles", "[region_map]") {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=512", "screen.height=384", "renderer.count=3",
                                      "gp.count=2"});
  const Program program = assemble_file(
      std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5", assembler_options(config));
  const FrameResult r = simulate_frame(config, make_builtin_scene("torus"), program, 2);
  REQUIRE(r.regions.size() == static_cast<std::size_t>(config.regions()));
  std::set<int> seen;
  std::vector<std::int64_t> per_renderer(3, 0);
  for (const RegionLoad& load : r.regions) {
    CHECK(seen.insert(load.region).second);
    CHECK(load.x0 == (load.region % config.regions_x()) * 128);
    CHECK(load.y0 == (load.region / config.regions_x()) * 128);
    REQUIRE(load.renderer >= 0);
    REQUIRE(load.renderer < 3);
    CHECK(load.busy_cycles > 0);  // clear and shade at least
    per_renderer[load.renderer] += static_cast<std::int64_t>(load.busy_cycles);
  }
  for (int k = 0; k < 3; ++k) {
    INFO("renderer " << k);
    CHECK(per_renderer[k] == r.stats.integer("renderer." + std::to_string(k) + ".busy_cycles"));
  }
}

TEST_CASE("the heat map tints each region by its cycles and outlines the busiest Renderer's",
          "[region_map]") {
  RgbImage frame;
  frame.width = 256;
  frame.height = 128;
  frame.rgb.assign(static_cast<std::size_t>(256) * 128 * 3, 100);
  // Renderer 0 has the one busy region (900 cycles), renderer 1 two regions of 300 and 0:
  // renderer 0 (900) is the busiest, though renderer 1 has more regions.
  const std::vector<RegionLoad> loads = {
      {0, 0, 0, 64, 128, 0, 900}, {1, 64, 0, 64, 128, 1, 300}, {2, 128, 0, 128, 128, 1, 0}};
  const RgbImage map = region_heat_map(frame, loads);
  REQUIRE(map.width == 256);
  REQUIRE(map.height == 128 + kLegendHeight);
  // Inside each region (away from outlines): 60% its heat colour over 40% the grey frame.
  const int grey = (77 * 100 + 150 * 100 + 29 * 100) >> 8;
  const std::pair<int, double> inside[] = {{32, 1.0}, {96, 300.0 / 900}, {192, 0.0}};
  for (const auto& [x, t] : inside) {
    std::uint8_t heat[3];
    heat_colour(t, heat);
    const std::uint8_t* p = pixel(map, x, 64);
    for (int k = 0; k < 3; ++k) CHECK(p[k] == (3 * heat[k] + 2 * grey) / 5);
  }
  // Busier is brighter.
  CHECK(brightness(pixel(map, 32, 64)) > brightness(pixel(map, 96, 64)));
  CHECK(brightness(pixel(map, 96, 64)) > brightness(pixel(map, 192, 64)));
  // The busiest Renderer's region is outlined (white, then black inside); the others are not.
  for (int d : {0, 1}) {
    CHECK(brightness(pixel(map, d, 64)) == 3 * 255);
    CHECK(brightness(pixel(map, 32, d)) == 3 * 255);
    CHECK(brightness(pixel(map, 63 - d, 64)) == 3 * 255);
  }
  CHECK(brightness(pixel(map, 2, 64)) == 0);
  CHECK(brightness(pixel(map, 64, 64)) != 3 * 255);
  CHECK(brightness(pixel(map, 128, 64)) != 3 * 255);
  // The legend's bar runs from the scale's bottom to its top, left to right.
  const int y = 128 + kLegendBarRows / 2;
  int first = -1, last = -1;
  for (int x = 0; x < map.width; ++x) {
    std::uint8_t lo[3];
    heat_colour(0, lo);
    if (first < 0 && std::equal(lo, lo + 3, pixel(map, x, y))) first = x;
    std::uint8_t hi[3];
    heat_colour(1, hi);
    if (std::equal(hi, hi + 3, pixel(map, x, y))) last = x;
  }
  REQUIRE(first >= 0);
  REQUIRE(last > first);
  for (int x = first + 1; x <= last; ++x) {
    CHECK(brightness(pixel(map, x, y)) >= brightness(pixel(map, x - 1, y)) - 3);
  }
}

TEST_CASE("the heat map refuses regions outside the frame", "[region_map]") {
  RgbImage frame;
  frame.width = 128;
  frame.height = 128;
  frame.rgb.assign(static_cast<std::size_t>(128) * 128 * 3, 0);
  CHECK_THROWS_WITH(region_heat_map(frame, {{7, 64, 0, 128, 128, 0, 1}}),
                    Catch::Contains("region 7 lies outside the frame"));
  frame.rgb.pop_back();
  CHECK_THROWS_WITH(region_heat_map(frame, {}), Catch::Contains("does not match its size"));
}

TEST_CASE("the heat map outlines the critical-path Renderer apart from the busiest",
          "[region_map]") {
  RgbImage frame;
  frame.width = 256;
  frame.height = 128;
  frame.rgb.assign(static_cast<std::size_t>(256) * 128 * 3, 100);
  // Renderer 0 is the busiest (900 cycles); renderer 1 (300) is named the critical path.
  const std::vector<RegionLoad> loads = {{0, 0, 0, 128, 128, 0, 900},
                                         {1, 128, 0, 128, 128, 1, 300}};
  const RgbImage map = region_heat_map(frame, loads, 1);
  const std::uint8_t cyan[3] = {0, 220, 255};
  // Renderer 1's region: cyan 3 and 4 pixels in, black at 5, no white frame at its edge.
  for (int d : {3, 4}) {
    CHECK(std::equal(cyan, cyan + 3, pixel(map, 128 + d, 64)));
    CHECK(std::equal(cyan, cyan + 3, pixel(map, 192, d)));
  }
  CHECK(brightness(pixel(map, 128 + 5, 64)) == 0);
  CHECK(brightness(pixel(map, 128, 64)) != 3 * 255);
  // Renderer 0's region: the white frame, and no cyan one.
  CHECK(brightness(pixel(map, 0, 64)) == 3 * 255);
  CHECK(!std::equal(cyan, cyan + 3, pixel(map, 3, 64)));
  // Both on one Renderer: both frames.
  const RgbImage both = region_heat_map(frame, loads, 0);
  CHECK(brightness(pixel(both, 0, 64)) == 3 * 255);
  CHECK(std::equal(cyan, cyan + 3, pixel(both, 3, 64)));
  // The legend's second row names them: white text pixels below the bar rows.
  int lit = 0;
  for (int y = 128 + kLegendBarRows; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) lit += brightness(pixel(map, x, y)) == 3 * 255;
  CHECK(lit > 100);
  // ... whole, on a frame too narrow for the long labels: the text stops short of the edge
  // (short labels) rather than running off it, and both keys' swatches are drawn.
  int edge = 0, swatches = 0;
  for (int y = 128 + kLegendBarRows; y < map.height; ++y) {
    for (int x = map.width - 4; x < map.width; ++x) edge += brightness(pixel(map, x, y)) > 0;
    for (int x = 0; x < map.width; ++x) swatches += std::equal(cyan, cyan + 3, pixel(map, x, y));
  }
  CHECK(edge == 0);
  CHECK(swatches > 0);
}
