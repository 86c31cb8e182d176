#pragma once
// Bit-sliced storage shared by the pixel array and the expression evaluator.
//
// Contract: a bit-plane holds one bit per pixel processor of a region. Pixel (x, y) of a
// region `width` pixels wide is pixel index p = y * width + x; it lives in word p / 64 at
// bit p % 64. `width` is a multiple of 64, so a row is width / 64 whole words and a row
// range [y0, y1) is the word range [y0 * width / 64, y1 * width / 64).
#include <cstdint>

namespace pp5 {

using Word = std::uint64_t;
constexpr int kWordBits = 64;

inline constexpr Word kAllOnes = ~Word{0};

inline int words_per_row(int width) { return width / kWordBits; }

// A half-open range of words of a bit-plane: the part of the region an operation touches.
struct WordRange {
  int begin = 0;
  int end = 0;
  bool empty() const { return begin >= end; }
  int size() const { return end > begin ? end - begin : 0; }
};

}  // namespace pp5
