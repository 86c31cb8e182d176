#include "sim/image/region_map.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace pp5 {

namespace {

// The scale's stops, evenly spaced: dark blue, purple, red, orange, pale yellow. Brightness
// rises monotonically along it, so it also reads in grey.
constexpr std::array<std::array<int, 3>, 5> kStops = {
    {{20, 20, 90}, {120, 30, 140}, {210, 50, 60}, {245, 150, 30}, {255, 245, 170}}};

// Digits 0-9 as 3 x 5 bitmaps, one row a byte, bit 2 the leftmost column.
constexpr std::array<std::array<std::uint8_t, 5>, 10> kDigits = {{
    {7, 5, 5, 5, 7},
    {2, 6, 2, 2, 7},
    {7, 1, 7, 4, 7},
    {7, 1, 7, 1, 7},
    {5, 5, 7, 1, 1},
    {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7},
    {7, 1, 1, 1, 1},
    {7, 5, 7, 5, 7},
    {7, 5, 7, 1, 7},
}};

// Capital letters A-Z, then ':' and '-', in the same form (the legend's words).
constexpr std::array<std::array<std::uint8_t, 5>, 28> kLetters = {{
    {2, 5, 7, 5, 5}, {6, 5, 6, 5, 6}, {3, 4, 4, 4, 3}, {6, 5, 5, 5, 6}, {7, 4, 6, 4, 7},
    {7, 4, 6, 4, 4}, {3, 4, 5, 5, 3}, {5, 5, 7, 5, 5}, {7, 2, 2, 2, 7}, {1, 1, 1, 5, 2},
    {5, 5, 6, 5, 5}, {4, 4, 4, 4, 7}, {5, 7, 7, 5, 5}, {6, 5, 5, 5, 5}, {2, 5, 5, 5, 2},
    {6, 5, 6, 4, 4}, {2, 5, 5, 6, 3}, {6, 5, 6, 5, 5}, {3, 4, 2, 1, 6}, {7, 2, 2, 2, 2},
    {5, 5, 5, 5, 7}, {5, 5, 5, 5, 2}, {5, 5, 7, 7, 5}, {5, 5, 2, 5, 5}, {5, 5, 2, 2, 2},
    {7, 1, 2, 4, 7}, {0, 2, 0, 2, 0}, {0, 0, 7, 0, 0},
}};

constexpr int kDigitScale = 2;  // each font pixel is 2 x 2 image pixels

// The glyph of `ch` (a digit, a capital, ':', '-'), or none (a space).
const std::array<std::uint8_t, 5>* legend_glyph(char ch) {
  if (ch >= '0' && ch <= '9') return &kDigits[static_cast<std::size_t>(ch - '0')];
  if (ch >= 'A' && ch <= 'Z') return &kLetters[static_cast<std::size_t>(ch - 'A')];
  if (ch == ':') return &kLetters[26];
  if (ch == '-') return &kLetters[27];
  return nullptr;
}

void put(RgbImage& image, int x, int y, const std::uint8_t c[3]) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  std::uint8_t* p = &image.rgb[(static_cast<std::size_t>(y) * image.width + x) * 3];
  p[0] = c[0];
  p[1] = c[1];
  p[2] = c[2];
}

// Draws `text` (digits, capitals, ':', '-' and spaces) with its top-left corner at (x, y);
// returns its width.
int draw_number(RgbImage& image, int x, int y, const std::string& text, const std::uint8_t c[3]) {
  int cx = x;
  for (char ch : text) {
    const auto* found = legend_glyph(ch);
    if (!found) {
      cx += 4 * kDigitScale;
      continue;
    }
    const auto& glyph = *found;
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 3; ++col) {
        if (((glyph[row] >> (2 - col)) & 1) == 0) continue;
        for (int dy = 0; dy < kDigitScale; ++dy)
          for (int dx = 0; dx < kDigitScale; ++dx)
            put(image, cx + col * kDigitScale + dx, y + row * kDigitScale + dy, c);
      }
    }
    cx += 4 * kDigitScale;
  }
  return cx - x - kDigitScale;
}

constexpr std::uint8_t kCriticalOutline[3] = {0, 220, 255};

int number_width(const std::string& text) {
  return static_cast<int>(text.size()) * 4 * kDigitScale - kDigitScale;
}

}  // namespace

void heat_colour(double t, std::uint8_t rgb[3]) {
  t = std::clamp(t, 0.0, 1.0);
  const double s = t * static_cast<double>(kStops.size() - 1);
  const auto i = std::min(static_cast<std::size_t>(s), kStops.size() - 2);
  const double f = s - static_cast<double>(i);
  for (int k = 0; k < 3; ++k) {
    const double v = kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k]);
    rgb[k] = static_cast<std::uint8_t>(v + 0.5);
  }
}

namespace {

const RgbImage& checked_frame(const RgbImage& frame) {
  if (frame.width <= 0 || frame.height <= 0 ||
      frame.rgb.size() != static_cast<std::size_t>(frame.width) * frame.height * 3) {
    throw std::invalid_argument("regions.png: the frame's pixel buffer does not match its size");
  }
  return frame;
}

}  // namespace

RegionHeatMap::RegionHeatMap(const RgbImage& frame, const std::vector<RegionLoad>& regions,
                             int critical_renderer)
    : RegionHeatMap(
          checked_frame(frame).width, frame.height,
          [&frame](int y, std::uint8_t* out) {
            const std::size_t stride = static_cast<std::size_t>(frame.width) * 3;
            std::memcpy(out, frame.rgb.data() + stride * static_cast<std::size_t>(y), stride);
          },
          regions, critical_renderer) {}

RegionHeatMap::RegionHeatMap(const FrameImage& frame, const std::vector<RegionLoad>& regions,
                             int critical_renderer)
    : RegionHeatMap(
          frame.width(), frame.height(), [&frame](int y, std::uint8_t* out) { frame.row(y, out); },
          regions, critical_renderer) {}

RegionHeatMap::RegionHeatMap(int width, int height,
                             std::function<void(int y, std::uint8_t* out)> frame_row,
                             const std::vector<RegionLoad>& regions, int critical_renderer)
    : width_(width),
      frame_height_(height),
      frame_row_(std::move(frame_row)),
      critical_(critical_renderer),
      src_(static_cast<std::size_t>(std::max(width, 0)) * 3),
      grey_(static_cast<std::size_t>(std::max(width, 0))) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("regions.png: the frame is empty");
  }
  std::uint64_t peak = 0;
  std::map<int, std::uint64_t> per_renderer;
  for (const RegionLoad& r : regions) {
    if (r.x0 < 0 || r.y0 < 0 || r.width <= 0 || r.height <= 0 || r.x0 + r.width > width ||
        r.y0 + r.height > height) {
      throw std::invalid_argument("regions.png: region " + std::to_string(r.region) +
                                  " lies outside the frame");
    }
    peak = std::max(peak, r.busy_cycles);
    per_renderer[r.renderer] += r.busy_cycles;
  }
  std::uint64_t busiest_cycles = 0;
  for (const auto& [renderer, cycles] : per_renderer) {
    if (busiest_ < 0 || cycles > busiest_cycles) busiest_ = renderer, busiest_cycles = cycles;
  }
  // Each region 60% its heat colour over 40% the frame's grey, so that the scene stays
  // recognisable under the tint: per region a table from grey to tinted colour.
  for (const RegionLoad& r : regions) {
    Tint t{r, {}};
    std::uint8_t heat[3];
    heat_colour(peak ? static_cast<double>(r.busy_cycles) / static_cast<double>(peak) : 0, heat);
    for (int g = 0; g < 256; ++g) {
      for (int k = 0; k < 3; ++k)
        t.table[g][k] = static_cast<std::uint8_t>((3 * heat[k] + 2 * g) / 5);
    }
    tints_.push_back(t);
  }
  // The legend. Its first row: "0", the colour bar, the peak's cycles and their unit; its
  // second: which outline is which Renderer's.
  legend_.width = width;
  legend_.height = kLegendHeight;
  legend_.rgb.assign(static_cast<std::size_t>(legend_.width) * legend_.height * 3, 0);
  const std::uint8_t white[3] = {255, 255, 255};
  const std::uint8_t cyan[3] = {kCriticalOutline[0], kCriticalOutline[1], kCriticalOutline[2]};
  const int top = (kLegendBarRows - 5 * kDigitScale) / 2;
  const std::string peak_text = std::to_string(peak) + " ARRAY CYCLES";
  const int x = 4 + draw_number(legend_, 4, top, "0", white) + 6;
  const int bar_end = legend_.width - 4 - number_width(peak_text) - 6;
  for (int bx = x; bx < bar_end; ++bx) {
    std::uint8_t c[3];
    heat_colour(static_cast<double>(bx - x) / std::max(1, bar_end - 1 - x), c);
    for (int y = 4; y < kLegendBarRows - 4; ++y) put(legend_, bx, y, c);
  }
  if (bar_end > x) draw_number(legend_, bar_end + 6, top, peak_text, white);
  // "[white] BUSIEST RENDERER 3  [cyan] CRITICAL PATH RENDERER 5"
  const int key_top = kLegendBarRows + (kLegendHeight - kLegendBarRows - 5 * kDigitScale) / 2;
  int kx = 4;
  auto key = [&](const std::uint8_t* colour, const std::string& label) {
    for (int yy = key_top; yy < key_top + 5 * kDigitScale; ++yy)
      for (int xx = kx; xx < kx + 10; ++xx) put(legend_, xx, yy, colour);
    kx += 16;
    kx += draw_number(legend_, kx, key_top, label, white) + 16;
  };
  // The long labels where they fit the frame's width, else short ones ("BUSIEST 3",
  // "CRITICAL 5"), so that a small frame still shows both keys whole.
  auto labels = [&](bool long_form) {
    std::vector<std::pair<const std::uint8_t*, std::string>> out;
    if (busiest_ >= 0) {
      out.emplace_back(white,
                       (long_form ? "BUSIEST RENDERER " : "BUSIEST ") + std::to_string(busiest_));
    }
    if (critical_ >= 0) {
      out.emplace_back(
          cyan, (long_form ? "CRITICAL PATH RENDERER " : "CRITICAL ") + std::to_string(critical_));
    }
    return out;
  };
  auto fits = [&](const std::vector<std::pair<const std::uint8_t*, std::string>>& keys) {
    int end = 4;
    for (const auto& k : keys) end += 16 + number_width(k.second) + 16;
    return end - 16 <= legend_.width - 4;
  };
  const auto long_keys = labels(true);
  for (const auto& [colour, label] : fits(long_keys) ? long_keys : labels(false))
    key(colour, label);
}

void RegionHeatMap::row(int y, std::uint8_t* out) const {
  const int width = width_;
  if (y >= frame_height_) {
    const std::size_t stride = static_cast<std::size_t>(width) * 3;
    std::memcpy(out, legend_.rgb.data() + static_cast<std::size_t>(y - frame_height_) * stride,
                stride);
    return;
  }
  // The frame in grey, then the tint of each region on this row (in order), then the
  // busiest Renderer's outlines.
  frame_row_(y, src_.data());
  const std::uint8_t* src = src_.data();
  std::uint8_t* grey = grey_.data();  // the row's grey, computed once
  for (int x = 0; x < width; ++x) {
    grey[x] = static_cast<std::uint8_t>(
        (77 * src[3 * x] + 150 * src[3 * x + 1] + 29 * src[3 * x + 2]) >> 8);
  }
  for (int x = 0; x < width; ++x) out[3 * x] = out[3 * x + 1] = out[3 * x + 2] = grey[x];
  for (const Tint& t : tints_) {
    const RegionLoad& r = t.load;
    if (y < r.y0 || y >= r.y0 + r.height) continue;
    for (int x = r.x0; x < r.x0 + r.width; ++x) {
      const auto& c = t.table[grey[x]];
      out[3 * x] = c[0];
      out[3 * x + 1] = c[1];
      out[3 * x + 2] = c[2];
    }
  }
  // A white frame 2 pixels wide just inside each of the busiest Renderer's regions, lined
  // with black, so that it shows on the palest colours too; inside it (3 to 5 pixels in) a
  // cyan one, lined with black, on each of the critical-path Renderer's regions. A Renderer
  // that is both has both.
  for (const Tint& t : tints_) {
    const RegionLoad& r = t.load;
    const bool busiest = r.renderer == busiest_, critical = r.renderer == critical_;
    if ((!busiest && !critical) || y < r.y0 || y >= r.y0 + r.height) continue;
    const int dy = std::min(y - r.y0, r.y0 + r.height - 1 - y);
    for (int x = r.x0; x < r.x0 + r.width; ++x) {
      const int d = std::min({dy, x - r.x0, r.x0 + r.width - 1 - x});
      if (busiest && d <= 2) {
        const std::uint8_t v = d < 2 ? 255 : 0;
        out[3 * x] = out[3 * x + 1] = out[3 * x + 2] = v;
      } else if (critical && d >= 3 && d <= 5) {
        for (int k = 0; k < 3; ++k) out[3 * x + k] = d < 5 ? kCriticalOutline[k] : 0;
      }
    }
  }
}

RgbImage region_heat_map(const RgbImage& frame, const std::vector<RegionLoad>& regions,
                         int critical_renderer) {
  const RegionHeatMap map(frame, regions, critical_renderer);
  RgbImage out;
  out.width = map.width();
  out.height = map.height();
  out.rgb.resize(static_cast<std::size_t>(out.width) * out.height * 3);
  for (int y = 0; y < out.height; ++y)
    map.row(y, out.rgb.data() + static_cast<std::size_t>(y) * out.width * 3);
  return out;
}

}  // namespace pp5
