#pragma once
// The quadratic expression evaluator of a Pixel-Planes 5 Renderer.
//
// The hardware broadcasts the coefficients of Ax^2 + Bxy + Cy^2 + Dx + Ey + F to a tree of
// adders that hands every pixel processor its own value, bit-serially, least significant bit
// first. This model is pure integer arithmetic: the coefficients are signed integers (any
// fixed-point scaling belongs to the Graphics Processor) and x, y are the integer screen
// coordinates of the pixel. Results are delivered in the bit-sliced layout of
// models/common/bitplane.hpp: "bit k of the result" is one bit-plane.
//
// Values are exact modulo 2^result_bits and read as two's complement of that width. Arithmetic is
// carried out on the int64 coefficients as given: the model does not truncate coefficients that do
// not fit() in coefficient_bits; callers that care about hardware fidelity must check fits().
// QuadraticCoefficients, EvaluatorParams and Condition (value <cond> 0, on the wrapped
// value) are the instruction set's types (firmware/isa/types.hpp).
#include <cstdint>

#include "firmware/isa/types.hpp"
#include "models/common/bitplane.hpp"

namespace pp5 {

class ExpressionEvaluator {
 public:
  // Throws std::invalid_argument unless 2 <= coefficient_bits <= 62, 2 <= result_bits <= 64,
  // region_width is a positive multiple of 64 and region_height is positive (and the region has
  // at most INT_MAX pixels).
  ExpressionEvaluator(EvaluatorParams params, int region_width, int region_height);

  // Screen coordinates of region pixel (0, 0). Any int is accepted; screens go up to 8192.
  void set_origin(int x0, int y0);
  int origin_x() const { return static_cast<int>(x0_); }
  int origin_y() const { return static_cast<int>(y0_); }

  const EvaluatorParams& params() const { return params_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Words in one bit-plane of the region: width * height / 64.
  int words() const { return words_; }

  // Every coefficient lies in [-2^(coefficient_bits-1), 2^(coefficient_bits-1) - 1].
  bool fits(const QuadraticCoefficients& c) const;

  // The exact value at region pixel (x, y), reduced modulo 2^result_bits and sign-extended.
  std::int64_t value_at(const QuadraticCoefficients& c, int x, int y) const;

  // Bit-planes of result bits [first_bit, first_bit + count): out[k * words() + w] is word w of
  // the plane of bit first_bit + k. Bits at or above result_bits are copies of the sign bit.
  // Requires first_bit >= 0, 1 <= count <= 64 and range within [0, words()). Only words in
  // `range` of each plane are written. With `live` (a plane of words() words, e.g. the Enable
  // register), a word w with live[w] == 0 need not be evaluated: its planes hold zero or its
  // values (the same for the same arguments). The caller promises not to use those pixels'
  // values (they are disabled); skipping them makes the cost follow the pixels a primitive
  // covers.
  void planes(const QuadraticCoefficients& c, int first_bit, int count, WordRange range, Word* out,
              const Word* live = nullptr) const;

  // One plane: bit set where (wrapped value) <cond> 0. Only words in `range` are written; with
  // `live`, words with live[w] == 0 are written as zero (as for planes()).
  void test_plane(const QuadraticCoefficients& c, Condition cond, WordRange range, Word* out,
                  const Word* live = nullptr) const;

  // True when test_plane() answers (c, range) with the exact per-row interval method rather
  // than per-pixel evaluation: c is linear and no pixel in the rows `range` touches can wrap.
  // Both methods give identical bits; this is exposed so tests can show both are exercised.
  bool linear_fast_path(const QuadraticCoefficients& c, WordRange range) const;

 private:
  // Screen coordinates of the first pixel of word w.
  std::int64_t word_x(int w) const { return x0_ + (w % words_per_row_) * kWordBits; }
  std::int64_t word_y(int w) const { return y0_ + w / words_per_row_; }
  std::int64_t wrap(std::uint64_t v) const;
  template <class T>
  void interval_rows(T slope, T offset, T row_step, Condition k, WordRange range, int row_first,
                     int row_last, Word* out, const Word* live) const;
  // planes() for a linear expression (A = B = C = 0).
  void linear_planes(const QuadraticCoefficients& c, int first_bit, int count, WordRange range,
                     Word* out, const Word* live) const;

  EvaluatorParams params_;
  int width_;
  int height_;
  int words_;
  int words_per_row_;
  std::int64_t x0_ = 0;
  std::int64_t y0_ = 0;
};

}  // namespace pp5
