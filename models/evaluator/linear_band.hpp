#pragma once
// A run of linear half-plane tests seen together: the rows of a region where all of them can
// hold. A triangle's three edge tests (qtest on E) each walk what the one before left; the
// first walks the whole region, although the triangle covers a band of its rows. Both pixel
// backends defer such a run and apply it over only the band (bit: BitSlicedBackend, word:
// WordBackend), with the same E as applying the tests one by one.
//
// Contract:
//  - one_interval(cond): the conditions whose pixels form one interval of each row (lt, le,
//    gt, ge); only those are gathered into a run.
//  - fits_64(c, ...): every term of c's value over the region (E (y0 + y), D x0, D (width -
//    1), their sums with F) is below 2^61 in magnitude, so it is formed exactly in 64 bits.
//    linear_row_band requires it of every test it is given.
//  - linear_row_band(tests, n, ...): narrows [lo, hi] to rows outside which the n tests hold
//    together at no pixel of the region. It may leave rows where they hold nowhere (the rows
//    inside are still tested exactly), never drop one where some pixel passes them all.
//    lo > hi on return means no pixel can pass. At most kMaxBandTests tests.
#include <cstddef>

#include "firmware/isa/types.hpp"

namespace pp5 {

struct LinearTest {
  QuadraticCoefficients c;
  Compare cond = Compare::ge;
};

constexpr std::size_t kMaxBandTests = 4;

bool one_interval(Compare cond);
bool fits_64(const QuadraticCoefficients& c, int y0, int x0, int width, int height);
void linear_row_band(const LinearTest* tests, std::size_t n, int x0, int y0, int width, int height,
                     int& lo, int& hi);

}  // namespace pp5
