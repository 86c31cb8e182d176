// The expression evaluator against exact 128-bit evaluation at every pixel of the region.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/evaluator/evaluator.hpp"
#include "models/evaluator/linear_band.hpp"

using namespace pp5;

namespace {

using i128 = __int128;

constexpr int kScreen = 8192;
constexpr int kRegion = 128;
constexpr Word kPattern = 0xA5C3F00F5A3C0FF0ull;

const Condition kConditions[] = {Condition::lt, Condition::le, Condition::eq,
                                 Condition::ne, Condition::ge, Condition::gt};

std::int64_t max_coef(int bits) { return (std::int64_t{1} << (bits - 1)) - 1; }
std::int64_t min_coef(int bits) { return -max_coef(bits) - 1; }

// Reduction modulo 2^bits into [-2^(bits-1), 2^(bits-1)), by plain 128-bit arithmetic.
std::int64_t wrap_ref(i128 v, int bits) {
  const i128 mod = i128{1} << bits;
  i128 r = v % mod;
  if (r < 0) r += mod;
  if (r >= mod / 2) r -= mod;
  return static_cast<std::int64_t>(r);
}

i128 exact(const QuadraticCoefficients& c, i128 x, i128 y) {
  return c.A * x * x + c.B * x * y + c.C * y * y + c.D * x + c.E * y + c.F;
}

bool holds(Condition cond, std::int64_t v) {
  switch (cond) {
    case Condition::lt:
      return v < 0;
    case Condition::le:
      return v <= 0;
    case Condition::eq:
      return v == 0;
    case Condition::ne:
      return v != 0;
    case Condition::ge:
      return v >= 0;
    case Condition::gt:
      return v > 0;
  }
  return false;
}

std::string describe(const QuadraticCoefficients& c) {
  return "A=" + std::to_string(c.A) + " B=" + std::to_string(c.B) + " C=" + std::to_string(c.C) +
         " D=" + std::to_string(c.D) + " E=" + std::to_string(c.E) + " F=" + std::to_string(c.F);
}

// Wrapped value of every region pixel, indexed by pixel number.
std::vector<std::int64_t> reference(const ExpressionEvaluator& ev, const QuadraticCoefficients& c) {
  std::vector<std::int64_t> ref(static_cast<std::size_t>(ev.width()) * ev.height());
  for (int y = 0; y < ev.height(); ++y)
    for (int x = 0; x < ev.width(); ++x)
      ref[static_cast<std::size_t>(y) * ev.width() + x] =
          wrap_ref(exact(c, ev.origin_x() + x, ev.origin_y() + y), ev.params().result_bits);
  return ref;
}

bool bit_of(const Word* plane, int p) { return (plane[p / 64] >> (p % 64)) & 1; }

bool in_range(int w, WordRange r) { return w >= r.begin && w < r.end; }

// Words of planes() output for `range` that disagree with the reference; words outside `range`
// must still hold kPattern.
int planes_mismatches(const ExpressionEvaluator& ev, const QuadraticCoefficients& c,
                      const std::vector<std::int64_t>& ref, int first_bit, int count,
                      WordRange range) {
  const int words = ev.words();
  std::vector<Word> out(static_cast<std::size_t>(count) * words, kPattern);
  ev.planes(c, first_bit, count, range, out.data());
  int bad = 0;
  for (int k = 0; k < count; ++k) {
    const Word* plane = out.data() + static_cast<std::size_t>(k) * words;
    const int shift = std::min(first_bit + k, 63);
    for (int w = 0; w < words; ++w) {
      if (!in_range(w, range)) {
        bad += plane[w] != kPattern;
        continue;
      }
      Word expect = 0;
      for (int b = 0; b < 64; ++b)
        expect |= static_cast<Word>((ref[static_cast<std::size_t>(w) * 64 + b] >> shift) & 1) << b;
      bad += plane[w] != expect;
    }
  }
  return bad;
}

int test_plane_mismatches(const ExpressionEvaluator& ev, const QuadraticCoefficients& c,
                          const std::vector<std::int64_t>& ref, Condition cond, WordRange range) {
  std::vector<Word> out(ev.words(), kPattern);
  ev.test_plane(c, cond, range, out.data());
  int bad = 0;
  for (int w = 0; w < ev.words(); ++w) {
    if (!in_range(w, range)) {
      bad += out[w] != kPattern;
      continue;
    }
    Word expect = 0;
    for (int b = 0; b < 64; ++b)
      expect |= static_cast<Word>(holds(cond, ref[static_cast<std::size_t>(w) * 64 + b])) << b;
    bad += out[w] != expect;
  }
  return bad;
}

// value_at, every bit below 64 via planes(), windows reaching above result_bits, and every
// condition of test_plane(), all over the whole region.
void check_everything(const ExpressionEvaluator& ev, const QuadraticCoefficients& c) {
  INFO(describe(c) << " origin " << ev.origin_x() << "," << ev.origin_y() << " cb "
                   << ev.params().coefficient_bits << " rb " << ev.params().result_bits);
  const auto ref = reference(ev, c);
  int bad_values = 0;
  for (int y = 0; y < ev.height(); ++y)
    for (int x = 0; x < ev.width(); ++x)
      bad_values += ev.value_at(c, x, y) != ref[static_cast<std::size_t>(y) * ev.width() + x];
  CHECK(bad_values == 0);

  const WordRange all{0, ev.words()};
  {
    std::vector<Word> out(static_cast<std::size_t>(64) * ev.words());
    ev.planes(c, 0, 64, all, out.data());
    int bad = 0;
    for (int p = 0; p < ev.width() * ev.height(); ++p) {
      Word v = 0;
      for (int k = 0; k < 64; ++k)
        v |= static_cast<Word>(bit_of(out.data() + static_cast<std::size_t>(k) * ev.words(), p))
             << k;
      bad += v != static_cast<Word>(ref[p]);
    }
    CHECK(bad == 0);
  }
  const int rb = ev.params().result_bits;
  const int windows[][2] = {{rb - 1, 1}, {rb - 2, 6}, {rb, 3}, {70, 2}, {5, 17}};
  for (const auto& win : windows) {
    INFO("planes first_bit " << win[0] << " count " << win[1]);
    CHECK(planes_mismatches(ev, c, ref, win[0], win[1], all) == 0);
  }
  for (Condition cond : kConditions) {
    INFO("condition " << static_cast<int>(cond));
    CHECK(test_plane_mismatches(ev, c, ref, cond, all) == 0);
  }
}

std::int64_t uniform(std::mt19937_64& rng, std::int64_t lo, std::int64_t hi) {
  return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
}

QuadraticCoefficients random_coefficients(std::mt19937_64& rng, int bits, bool quadratic) {
  const std::int64_t lo = min_coef(bits), hi = max_coef(bits);
  QuadraticCoefficients c;
  if (quadratic) {
    c.A = uniform(rng, lo, hi);
    c.B = uniform(rng, lo, hi);
    c.C = uniform(rng, lo, hi);
  }
  c.D = uniform(rng, lo, hi);
  c.E = uniform(rng, lo, hi);
  c.F = uniform(rng, lo, hi);
  return c;
}

// A linear expression that cannot wrap anywhere on the screen, so test_plane takes its fast path.
QuadraticCoefficients small_linear(std::mt19937_64& rng, int cb, int rb) {
  const std::int64_t slope =
      rb >= 17 ? std::min(max_coef(cb), (std::int64_t{1} << (rb - 16)) - 1) : 0;
  const std::int64_t offset = std::min(max_coef(cb), (std::int64_t{1} << (rb - 3)) - 1);
  return QuadraticCoefficients::linear(uniform(rng, -slope, slope), uniform(rng, -slope, slope),
                                       uniform(rng, -offset, offset));
}

const EvaluatorParams kParams[] = {{32, 32}, {40, 40}, {24, 48}, {62, 64}, {40, 64}, {8, 8}};

}  // namespace

TEST_CASE("evaluator rejects invalid parameters and sizes", "[evaluator]") {
  CHECK_THROWS_AS(ExpressionEvaluator({1, 40}, 128, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({63, 40}, 128, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({-4, 40}, 128, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 1}, 128, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 65}, 128, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, 0, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, 100, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, -64, 128), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, 128, 0), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, 128, -1), std::invalid_argument);
  CHECK_THROWS_AS(ExpressionEvaluator({40, 40}, 1 << 16, 1 << 16), std::invalid_argument);
  CHECK_NOTHROW(ExpressionEvaluator({2, 2}, 64, 1));
  CHECK_NOTHROW(ExpressionEvaluator({62, 64}, 128, 128));
  ExpressionEvaluator ev(EvaluatorParams{}, 128, 128);
  CHECK(ev.params().coefficient_bits == 40);
  CHECK(ev.params().result_bits == 40);
  CHECK(ev.words() == 256);
}

TEST_CASE("coefficient helpers", "[evaluator]") {
  const auto lin = QuadraticCoefficients::linear(3, -4, 5);
  CHECK(lin.is_linear());
  CHECK((lin.A == 0 && lin.B == 0 && lin.C == 0 && lin.D == 3 && lin.E == -4 && lin.F == 5));
  const auto k = QuadraticCoefficients::constant(-9);
  CHECK(k.is_linear());
  CHECK((k.D == 0 && k.E == 0 && k.F == -9));
  for (int i = 0; i < 3; ++i) {
    QuadraticCoefficients q;
    (i == 0 ? q.A : i == 1 ? q.B : q.C) = 1;
    CHECK_FALSE(q.is_linear());
  }
}

TEST_CASE("fits() accepts exactly the signed coefficient range", "[evaluator]") {
  for (int cb : {2, 24, 32, 40, 62}) {
    ExpressionEvaluator ev({cb, 64}, 64, 1);
    INFO("coefficient_bits " << cb);
    CHECK(ev.fits(QuadraticCoefficients{}));
    for (int slot = 0; slot < 6; ++slot) {
      INFO("slot " << slot);
      auto with = [&](std::int64_t v) {
        QuadraticCoefficients c;
        std::int64_t* fields[] = {&c.A, &c.B, &c.C, &c.D, &c.E, &c.F};
        *fields[slot] = v;
        return c;
      };
      CHECK(ev.fits(with(max_coef(cb))));
      CHECK(ev.fits(with(min_coef(cb))));
      CHECK_FALSE(ev.fits(with(max_coef(cb) + 1)));
      CHECK_FALSE(ev.fits(with(min_coef(cb) - 1)));
    }
  }
}

TEST_CASE("random coefficients match exact evaluation at every pixel", "[evaluator]") {
  std::mt19937_64 rng(0x5eed0001);
  for (const EvaluatorParams& params : kParams) {
    ExpressionEvaluator ev(params, kRegion, kRegion);
    const int origins[][2] = {{0, 0},
                              {kScreen - kRegion, kScreen - kRegion},
                              {static_cast<int>(uniform(rng, 0, kScreen - kRegion)),
                               static_cast<int>(uniform(rng, 0, kScreen - kRegion))}};
    for (const auto& o : origins) {
      ev.set_origin(o[0], o[1]);
      check_everything(ev, random_coefficients(rng, params.coefficient_bits, false));
      check_everything(ev, random_coefficients(rng, params.coefficient_bits, true));
      const auto small = small_linear(rng, params.coefficient_bits, params.result_bits);
      CHECK(ev.linear_fast_path(small, {0, ev.words()}));
      check_everything(ev, small);
    }
  }
}

TEST_CASE("extreme coefficients at the far corner of the largest screen", "[evaluator]") {
  for (const EvaluatorParams& params : kParams) {
    const std::int64_t hi = max_coef(params.coefficient_bits);
    const std::int64_t lo = min_coef(params.coefficient_bits);
    ExpressionEvaluator ev(params, kRegion, kRegion);
    for (int origin : {0, kScreen - kRegion}) {
      ev.set_origin(origin, origin);
      check_everything(ev, {hi, hi, hi, hi, hi, hi});
      check_everything(ev, {lo, lo, lo, lo, lo, lo});
      check_everything(ev, {hi, lo, hi, lo, hi, lo});
      check_everything(ev, {lo, hi, lo, hi, lo, hi});
      check_everything(ev, QuadraticCoefficients::linear(hi, hi, hi));
      check_everything(ev, QuadraticCoefficients::linear(lo, lo, lo));
      check_everything(ev, QuadraticCoefficients::linear(hi, lo, 0));
      check_everything(ev, QuadraticCoefficients::constant(lo));
    }
  }
}

TEST_CASE("test_plane on expressions that are exactly zero on many pixels", "[evaluator]") {
  for (const EvaluatorParams& params : {EvaluatorParams{40, 40}, EvaluatorParams{32, 32}}) {
    ExpressionEvaluator ev(params, kRegion, kRegion);
    for (int origin : {0, 3000, kScreen - kRegion}) {
      ev.set_origin(origin, origin);
      const std::int64_t x0 = origin, y0 = origin;
      const QuadraticCoefficients linear_cases[] = {
          QuadraticCoefficients::linear(1, 0, -(x0 + 17)),
          QuadraticCoefficients::linear(-1, 0, x0 + 17),
          QuadraticCoefficients::linear(0, 1, -(y0 + 5)),
          QuadraticCoefficients::linear(0, -3, 3 * (y0 + 5)),
          QuadraticCoefficients::linear(3, -2, -(3 * x0 - 2 * y0) + 7),
          QuadraticCoefficients::linear(-5, 7, 5 * x0 - 7 * y0 - 40),
          QuadraticCoefficients::linear(1 << 20, -(1 << 20), -(std::int64_t{1} << 20) * (x0 - y0)),
          QuadraticCoefficients::linear(64, 1, -(64 * (x0 + 64) + y0)),
          QuadraticCoefficients::constant(0),
          QuadraticCoefficients::constant(1),
          QuadraticCoefficients::constant(-1),
      };
      for (const auto& c : linear_cases) {
        INFO(describe(c));
        CHECK(ev.linear_fast_path(c, {0, ev.words()}));
        check_everything(ev, c);
      }
      // Circle of radius 25 about a pixel inside the region; it passes through the pixels of
      // every Pythagorean pair (0, 25), (7, 24), (15, 20). The rectangular hyperbola
      // (x - xc)(y - yc) = 36 exercises B alone.
      const std::int64_t xc = x0 + 60, yc = y0 + 70;
      const QuadraticCoefficients quadratic_cases[] = {
          {1, 0, 1, -2 * xc, -2 * yc, xc * xc + yc * yc - 625},
          {-1, 0, -1, 2 * xc, 2 * yc, -(xc * xc + yc * yc - 625)},
          {0, 1, 0, -yc, -xc, xc * yc - 36},
      };
      for (const auto& c : quadratic_cases) {
        CHECK_FALSE(ev.linear_fast_path(c, {0, ev.words()}));
        check_everything(ev, c);
      }
    }
  }
}

TEST_CASE("linear fast path on random lines through a pixel", "[evaluator]") {
  std::mt19937_64 rng(0x5eed0002);
  ExpressionEvaluator ev({40, 40}, kRegion, kRegion);
  const WordRange all{0, ev.words()};
  for (int trial = 0; trial < 60; ++trial) {
    const int x0 = static_cast<int>(uniform(rng, 0, kScreen - kRegion));
    const int y0 = static_cast<int>(uniform(rng, 0, kScreen - kRegion));
    ev.set_origin(x0, y0);
    const std::int64_t slope = trial < 30 ? 40 : (std::int64_t{1} << 24);
    const std::int64_t d = uniform(rng, -slope, slope), e = uniform(rng, -slope, slope);
    const std::int64_t px = x0 + uniform(rng, 0, kRegion - 1),
                       py = y0 + uniform(rng, 0, kRegion - 1);
    const auto c = QuadraticCoefficients::linear(d, e, -(d * px + e * py));
    INFO(describe(c));
    REQUIRE(ev.linear_fast_path(c, all));
    const auto ref = reference(ev, c);
    for (Condition cond : kConditions) {
      INFO("condition " << static_cast<int>(cond));
      CHECK(test_plane_mismatches(ev, c, ref, cond, all) == 0);
    }
  }
}

TEST_CASE("linear fast path stops exactly where the result could wrap", "[evaluator]") {
  ExpressionEvaluator ev({40, 32}, kRegion, kRegion);
  ev.set_origin(kScreen - kRegion, 0);
  const std::int64_t top = (std::int64_t{1} << 31) - 1;
  const std::int64_t x_last = kScreen - 1;
  const WordRange all{0, ev.words()};
  // Largest value exactly 2^31 - 1 at the right edge, then one past it.
  const auto at_limit = QuadraticCoefficients::linear(1, 0, top - x_last);
  const auto past_limit = QuadraticCoefficients::linear(1, 0, top - x_last + 1);
  // Smallest value exactly -2^31 at the right edge, then one below it.
  const auto at_floor = QuadraticCoefficients::linear(-1, 0, -top - 1 + x_last);
  const auto below_floor = QuadraticCoefficients::linear(-1, 0, -top - 2 + x_last);
  CHECK(ev.linear_fast_path(at_limit, all));
  CHECK_FALSE(ev.linear_fast_path(past_limit, all));
  CHECK(ev.linear_fast_path(at_floor, all));
  CHECK_FALSE(ev.linear_fast_path(below_floor, all));
  CHECK(ev.value_at(past_limit, kRegion - 1, 0) == -top - 1);
  CHECK(ev.value_at(below_floor, kRegion - 1, 0) == top);
  for (const auto& c : {at_limit, past_limit, at_floor, below_floor}) check_everything(ev, c);
}

TEST_CASE("partial word ranges write only their words", "[evaluator]") {
  std::mt19937_64 rng(0x5eed0003);
  struct Shape {
    int width, height;
    WordRange range;
  };
  const Shape shapes[] = {{128, 128, {37, 101}}, {128, 128, {0, 1}}, {128, 128, {255, 256}},
                          {512, 16, {13, 45}},   {512, 16, {8, 16}}, {64, 32, {5, 6}},
                          {128, 128, {40, 40}}};
  for (const Shape& s : shapes) {
    INFO("region " << s.width << "x" << s.height << " words [" << s.range.begin << ", "
                   << s.range.end << ")");
    ExpressionEvaluator ev({40, 40}, s.width, s.height);
    ev.set_origin(kScreen - s.width, 4000);
    const std::int64_t y_mid = 4000 + s.range.begin / words_per_row(s.width);
    const QuadraticCoefficients cases[] = {
        QuadraticCoefficients::linear(1, 0, -(kScreen - s.width + 17)),
        QuadraticCoefficients::linear(-7, 3, 7 * (kScreen - s.width + 100) - 3 * y_mid),
        small_linear(rng, 40, 40),
        random_coefficients(rng, 40, false),
        random_coefficients(rng, 40, true),
        {1, -1, 2, -3, 5, -8},
    };
    for (const auto& c : cases) {
      INFO(describe(c));
      const auto ref = reference(ev, c);
      CHECK(planes_mismatches(ev, c, ref, 0, 64, s.range) == 0);
      CHECK(planes_mismatches(ev, c, ref, 30, 20, s.range) == 0);
      for (Condition cond : kConditions) {
        INFO("condition " << static_cast<int>(cond));
        CHECK(test_plane_mismatches(ev, c, ref, cond, s.range) == 0);
      }
    }
  }
}

TEST_CASE("fast path judges wrap only over the rows a range touches", "[evaluator]") {
  // The value depends on y alone: rows 0..69 stay below 2^39, rows from 70 on wrap. A range that
  // ends in row 69 may take the fast path; one that reaches even the first word of row 70, or the
  // whole region, may not. All must be exact.
  ExpressionEvaluator ev({40, 40}, kRegion, kRegion);
  ev.set_origin(0, 0);
  const std::int64_t limit = std::int64_t{1} << 39;
  const auto c = QuadraticCoefficients::linear(0, limit / 64, -5 * (limit / 64) - 3);
  REQUIRE(ev.value_at(c, 0, 69) == limit - 3);
  REQUIRE(ev.value_at(c, 0, 70) < 0);
  const WordRange safe{0, 70 * 2}, one_word_more{0, 70 * 2 + 1}, tail{139, 141};
  const WordRange all{0, ev.words()};
  CHECK(ev.linear_fast_path(c, safe));
  CHECK_FALSE(ev.linear_fast_path(c, one_word_more));
  CHECK_FALSE(ev.linear_fast_path(c, tail));
  CHECK_FALSE(ev.linear_fast_path(c, all));
  const auto ref = reference(ev, c);
  for (Condition cond : kConditions) {
    INFO("condition " << static_cast<int>(cond));
    for (WordRange r : {safe, one_word_more, tail, all})
      CHECK(test_plane_mismatches(ev, c, ref, cond, r) == 0);
  }
}

TEST_CASE("fast path with a 64-bit result reaching its most negative value", "[evaluator]") {
  // Row 0 of the region (screen row 3) starts at exactly -2^63, which the interval arithmetic has
  // to negate without overflow; later rows wrap, so only a range within row 0 is fast. Slopes
  // near 2^57 cross zero in the middle of the row, at column 64 exactly or just after it.
  ExpressionEvaluator ev({62, 64}, kRegion, kRegion);
  ev.set_origin(0, 3);
  const std::int64_t big = std::int64_t{1} << 61;
  for (std::int64_t slope : {std::int64_t{1}, std::int64_t{1} << 57, (std::int64_t{1} << 57) - 3}) {
    const QuadraticCoefficients c{0, 0, 0, slope, -big, -big};
    INFO(describe(c));
    REQUIRE(ev.fits(c));
    REQUIRE(ev.value_at(c, 0, 0) == INT64_MIN);
    const WordRange row0{0, 2};
    CHECK(ev.linear_fast_path(c, row0));
    CHECK_FALSE(ev.linear_fast_path(c, {0, 3}));
    const auto ref = reference(ev, c);
    for (Condition cond : kConditions) {
      INFO("condition " << static_cast<int>(cond));
      CHECK(test_plane_mismatches(ev, c, ref, cond, row0) == 0);
    }
    check_everything(ev, c);
  }
}

// test_plane's interval walk keeps floor(n / slope) and its remainder in 64-bit integers when
// every value of the walk fits, and in 128-bit ones otherwise: near the 64-bit result's limits
// (lines through a pixel with constants around 2^61 and 2^62) both must give every pixel's bit,
// and so must a disabled word skipped through `live`.
TEST_CASE("linear fast path near 64-bit limits, and live words", "[evaluator]") {
  std::mt19937_64 rng(0x5eed0007);
  ExpressionEvaluator ev({62, 64}, kRegion, kRegion);
  const WordRange all{0, ev.words()};
  int wide = 0;
  for (int trial = 0; trial < 40; ++trial) {
    ev.set_origin(0, 0);
    const std::int64_t d = uniform(rng, -(std::int64_t{1} << 40), std::int64_t{1} << 40);
    const std::int64_t e = uniform(rng, -(std::int64_t{1} << 40), std::int64_t{1} << 40);
    // A constant far from zero: the line crosses the region only for small F, so half the
    // trials shift it, which leaves whole rows on one side.
    const std::int64_t f = (trial % 2 ? 1 : -1) * (std::int64_t{1} << (trial < 20 ? 61 : 62)) +
                           uniform(rng, -(std::int64_t{1} << 40), std::int64_t{1} << 40);
    const auto c = QuadraticCoefficients::linear(d, e, f);
    INFO(describe(c));
    if (!ev.linear_fast_path(c, all)) continue;
    ++wide;
    const auto ref = reference(ev, c);
    for (Condition cond : kConditions) {
      INFO("condition " << static_cast<int>(cond));
      CHECK(test_plane_mismatches(ev, c, ref, cond, all) == 0);
    }
  }
  CHECK(wide >= 20);
  // A word whose live bits are zero is written as zero; the others as without `live`.
  const auto c = QuadraticCoefficients::linear(3, -5, 100);
  std::vector<Word> live(ev.words(), kAllOnes), with(ev.words()), without(ev.words());
  for (int w = 0; w < ev.words(); w += 3) live[w] = 0;
  ev.test_plane(c, Condition::ge, all, with.data(), live.data());
  ev.test_plane(c, Condition::ge, all, without.data());
  for (int w = 0; w < ev.words(); ++w) CHECK(with[w] == (live[w] ? without[w] : 0));
}

TEST_CASE("linear_row_band never drops a row where some pixel passes every test",
          "[evaluator][band]") {
  // Against every pixel, exactly: runs of one to four half-plane tests (a triangle's edges),
  // of every slope and size up to fits_64's limit, regions anywhere, and the hard cases for
  // a band computed in doubles: slivers one pixel thick (a line and its opposite test, both
  // holding only on pixel centres the line passes through), and lines grazing a single
  // pixel centre at the region's corner.
  std::mt19937_64 rng(20261126);
  const Condition one_interval_conds[] = {Condition::lt, Condition::le, Condition::gt,
                                          Condition::ge};
  const int sizes[][2] = {{128, 128}, {64, 3}, {192, 40}};
  int narrowed = 0, empty = 0, slivers_kept = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int width = sizes[trial % 3][0], height = sizes[trial % 3][1];
    const int x0 = static_cast<int>(uniform(rng, -40, 40)) * 128;
    const int y0 = static_cast<int>(uniform(rng, -40, 40)) * 128;
    const int kind = trial % 4;  // 0, 1: crossing edges; 2: a sliver; 3: huge gradients
    const int bits = kind == 3 ? 48 : 13;
    auto coef = [&] { return uniform(rng, -(std::int64_t{1} << bits), std::int64_t{1} << bits); };
    // A pixel near the region, through whose centre an edge passes (value 0 there).
    auto through = [&](std::int64_t d, std::int64_t e, int spread) {
      const std::int64_t px = x0 + uniform(rng, -spread, width + spread);
      const std::int64_t py = y0 + uniform(rng, -spread, height + spread);
      return -(d * px + e * py);
    };
    std::vector<LinearTest> tests;
    const int n = kind == 2 ? 2 : static_cast<int>(uniform(rng, 1, 4));
    for (int k = 0; k < n; ++k) {
      LinearTest t;
      if (kind == 2 && k == 1) {
        t.c = tests[0].c;  // the opposite side of the same line: only the line itself passes
        t.cond = tests[0].cond == Condition::ge ? Condition::le : Condition::ge;
      } else {
        const int zero = static_cast<int>(uniform(rng, 0, 9));
        t.c.D = zero == 0 ? 0 : coef();
        t.c.E = zero == 1 ? 0 : coef();
        t.c.F = through(t.c.D, t.c.E, 16) + (kind == 2 ? 0 : coef() / 4);
        t.cond = kind == 2 ? (uniform(rng, 0, 1) ? Condition::ge : Condition::le)
                           : one_interval_conds[uniform(rng, 0, 3)];
      }
      REQUIRE(one_interval(t.cond));
      if (!fits_64(t.c, y0, x0, width, height)) continue;
      tests.push_back(t);
    }
    int lo = 0, hi = height - 1;
    linear_row_band(tests.data(), tests.size(), x0, y0, width, height, lo, hi);
    INFO("trial " << trial << ", " << tests.size() << " tests, region at " << x0 << "," << y0
                  << ", band " << lo << ".." << hi);
    REQUIRE(lo >= 0);
    REQUIRE(hi <= height - 1);
    int rows_passing = 0;
    for (int y = 0; y < height; ++y) {
      bool any = false;
      for (int x = 0; x < width && !any; ++x) {
        bool all = true;
        for (const LinearTest& t : tests) {
          const i128 v = i128(t.c.D) * (x0 + x) + i128(t.c.E) * (y0 + y) + t.c.F;
          all = all && holds(t.cond, static_cast<std::int64_t>(v));  // below 2^63: fits_64
        }
        any = all;
      }
      if (!any) continue;
      ++rows_passing;
      INFO("row " << y << " has a pixel passing every test");
      REQUIRE(lo <= y);
      REQUIRE(y <= hi);
    }
    narrowed += hi - lo + 1 < height;
    empty += lo > hi;
    slivers_kept += kind == 2 && rows_passing > 0;
  }
  // The band is worth having (it leaves rows out), and the hard cases were reached.
  CHECK(narrowed > 150);
  CHECK(empty > 20);
  CHECK(slivers_kept > 20);
}

TEST_CASE("linear planes with live words: runs of dead words, ranges starting mid-row",
          "[evaluator]") {
  // planes() of a linear expression walks the words in runs of eight, stepping each word's
  // value by 64 D along a row and E to the next, and skips a run whose words are all dead.
  // Live words must match exact evaluation for every window, however the run of dead words
  // before them falls; dead words hold zero or their value.
  std::mt19937_64 rng(0x5eed000b);
  struct Shape {
    int width, height;
    WordRange range;
  };
  const Shape shapes[] = {{128, 128, {0, 256}},
                          {128, 128, {37, 219}},
                          {192, 64, {5, 190}},
                          {512, 16, {13, 125}},
                          {64, 128, {3, 120}}};
  for (const EvaluatorParams& params : kParams) {
    for (const Shape& s : shapes) {
      ExpressionEvaluator ev(params, s.width, s.height);
      ev.set_origin(static_cast<int>(uniform(rng, 0, kScreen - s.width)),
                    static_cast<int>(uniform(rng, 0, kScreen - s.height)));
      const std::int64_t hi = max_coef(params.coefficient_bits);
      const std::int64_t lo = min_coef(params.coefficient_bits);
      const QuadraticCoefficients cases[] = {
          random_coefficients(rng, params.coefficient_bits, false),
          small_linear(rng, params.coefficient_bits, params.result_bits),
          QuadraticCoefficients::linear(hi, lo, hi),
          QuadraticCoefficients::linear(lo, hi, lo),
          QuadraticCoefficients::linear(-1, 1, -(std::int64_t{1} << (params.result_bits - 2))),
          QuadraticCoefficients::linear(4095, -4097, 2047),
      };
      // Live words: runs of 0..20 dead words between runs of 1..5 live ones.
      std::vector<Word> live(ev.words(), 0);
      for (int w = 0; w < ev.words();) {
        w += static_cast<int>(uniform(rng, 0, 20));
        for (int n = static_cast<int>(uniform(rng, 1, 5)); n > 0 && w < ev.words(); --n, ++w)
          live[w] = Word{1} << uniform(rng, 0, 63);
      }
      const int rb = params.result_bits;
      const int windows[][2] = {{0, 24}, {12, 8}, {12, 24}, {rb - 3, 6}, {rb + 2, 3}, {5, 59}};
      for (const auto& c : cases) {
        const auto ref = reference(ev, c);
        for (const auto& win : windows) {
          INFO(describe(c) << " region " << s.width << "x" << s.height << " range ["
                           << s.range.begin << ", " << s.range.end << ") rb " << rb << " first_bit "
                           << win[0] << " count " << win[1]);
          const int words = ev.words();
          std::vector<Word> out(static_cast<std::size_t>(win[1]) * words, kPattern);
          ev.planes(c, win[0], win[1], s.range, out.data(), live.data());
          int bad = 0;
          for (int k = 0; k < win[1]; ++k) {
            const int shift = std::min(win[0] + k, 63);
            for (int w = 0; w < words; ++w) {
              const Word got = out[static_cast<std::size_t>(k) * words + w];
              if (!in_range(w, s.range)) {
                bad += got != kPattern;
                continue;
              }
              Word expect = 0;
              for (int b = 0; b < 64; ++b)
                expect |=
                    static_cast<Word>((ref[static_cast<std::size_t>(w) * 64 + b] >> shift) & 1)
                    << b;
              bad += live[w] != 0 ? got != expect : (got != 0 && got != expect);
            }
          }
          CHECK(bad == 0);
        }
      }
    }
  }
}
