#include "models/evaluator/evaluator.hpp"

#include <algorithm>
#include <cassert>
#include <climits>
#include <stdexcept>
#include <string>

#if defined(__AVX2__) || defined(__AVX512F__) || defined(__GFNI__)
#include <immintrin.h>
#endif

namespace pp5 {

namespace {

using i128 = __int128;
using u64 = std::uint64_t;

// The value at the first pixel (x, y) of a word and its forward differences along the row, all
// modulo 2^64. Unsigned arithmetic is exact modulo 2^64, hence modulo 2^result_bits, whatever
// overflows on the way: f(x + i) = f + i d + i (i - 1) A, so the first difference starts at d
// and the second is the constant 2A.
struct RowSeed {
  u64 f, d, A;
};

RowSeed seed(const QuadraticCoefficients& c, std::int64_t x, std::int64_t y) {
  const u64 X = static_cast<u64>(x), Y = static_cast<u64>(y);
  const u64 A = u64(c.A), B = u64(c.B), C = u64(c.C), D = u64(c.D), E = u64(c.E), F = u64(c.F);
  return {A * X * X + B * X * Y + C * Y * Y + D * X + E * Y + F, A * (2 * X + 1) + B * Y + D, A};
}

// Bits [a, b) set, 0 <= a <= b <= 64.
Word bit_span(int a, int b) {
  const Word below_b = b >= 64 ? kAllOnes : (Word{1} << b) - 1;
  const Word below_a = a >= 64 ? kAllOnes : (Word{1} << a) - 1;
  return below_b & ~below_a;
}

// The test_plane answer from the planes "value < 0" and "value == 0".
Word select_condition(Condition cond, Word lt, Word eq) {
  switch (cond) {
    case Condition::lt:
      return lt;
    case Condition::le:
      return lt | eq;
    case Condition::eq:
      return eq;
    case Condition::ne:
      return ~eq;
    case Condition::ge:
      return ~lt;
    case Condition::gt:
      return ~(lt | eq);
  }
  return 0;
}

// (-v) <cond> 0  <=>  v <mirror(cond)> 0
Condition mirror(Condition cond) {
  switch (cond) {
    case Condition::lt:
      return Condition::gt;
    case Condition::le:
      return Condition::ge;
    case Condition::ge:
      return Condition::le;
    case Condition::gt:
      return Condition::lt;
    default:
      return cond;
  }
}

template <class T>
T floor_div(T n, T d) {  // d > 0
  T q = n / d;
  if (n % d != 0 && n < 0) --q;
  return q;
}

template <class T>
T ceil_div(T n, T d) {  // d > 0
  T q = n / d;
  if (n % d != 0 && n > 0) ++q;
  return q;
}

#if defined(__AVX2__)

// Vector forward differences with stride 4: lane l holds f(x + 4q + l) at step q. Stepping by
// four pixels, the first difference is f(x+l+4) - f(x+l) = 4d + (8l + 12) A and grows by 32A.
struct Lanes {
  __m256i f, g, h;
  explicit Lanes(const RowSeed& s) {
    alignas(32) u64 f0[4], g0[4];
    for (int l = 0; l < 4; ++l) {
      const u64 L = static_cast<u64>(l);
      f0[l] = s.f + L * s.d + L * (L - 1) * s.A;
      g0[l] = 4 * s.d + (8 * L + 12) * s.A;
    }
    f = _mm256_load_si256(reinterpret_cast<const __m256i*>(f0));
    g = _mm256_load_si256(reinterpret_cast<const __m256i*>(g0));
    h = _mm256_set1_epi64x(static_cast<long long>(32 * s.A));
  }
  __m256i next() {
    const __m256i v = f;
    f = _mm256_add_epi64(f, g);
    g = _mm256_add_epi64(g, h);
    return v;
  }
};

// A transpose stage between registers: rows k and k + J live in registers J / 4 apart. Only
// registers below `regs` are transformed (a stage with J < 32 keeps rows within their half).
template <int J>
inline void stage_across(__m256i* r, __m256i mask, int regs = 16) {
  constexpr int kApart = J / 4;
  for (int g = 0; g < regs; ++g) {
    if (g & kApart) continue;
    const __m256i t =
        _mm256_and_si256(_mm256_xor_si256(_mm256_srli_epi64(r[g], J), r[g + kApart]), mask);
    r[g] = _mm256_xor_si256(r[g], _mm256_slli_epi64(t, J));
    r[g + kApart] = _mm256_xor_si256(r[g + kApart], t);
  }
}

template <int J>
inline void stage_pair(__m256i& lo, __m256i& hi, __m256i mask) {
  const __m256i t = _mm256_and_si256(_mm256_xor_si256(_mm256_srli_epi64(lo, J), hi), mask);
  lo = _mm256_xor_si256(lo, _mm256_slli_epi64(t, J));
  hi = _mm256_xor_si256(hi, t);
}

// In-place 64x64 bit transpose of r[16], row 4q + l being lane l of r[q]. The stages for
// J = 2 and J = 1 pair lanes of one register, so they regroup two registers so that partners
// share a lane, apply the stage, and regroup back. With low_half, only rows 0..31 of the
// result (r[0..7]) are formed: after the first stage the two halves no longer mix.
void transpose64(__m256i* r, bool low_half = false) {
  const int regs = low_half ? 8 : 16;
  stage_across<32>(r, _mm256_set1_epi64x(0x00000000FFFFFFFFll));
  stage_across<16>(r, _mm256_set1_epi64x(0x0000FFFF0000FFFFll), regs);
  stage_across<8>(r, _mm256_set1_epi64x(0x00FF00FF00FF00FFll), regs);
  stage_across<4>(r, _mm256_set1_epi64x(0x0F0F0F0F0F0F0F0Fll), regs);
  const __m256i m2 = _mm256_set1_epi64x(0x3333333333333333ll);
  const __m256i m1 = _mm256_set1_epi64x(0x5555555555555555ll);
  for (int g = 0; g < regs; g += 2) {
    __m256i lo = _mm256_permute2x128_si256(r[g], r[g + 1], 0x20);  // rows 0 1 4 5 of the pair
    __m256i hi = _mm256_permute2x128_si256(r[g], r[g + 1], 0x31);  // rows 2 3 6 7
    stage_pair<2>(lo, hi, m2);
    __m256i even = _mm256_unpacklo_epi64(lo, hi);  // rows 0 2 4 6
    __m256i odd = _mm256_unpackhi_epi64(lo, hi);   // rows 1 3 5 7
    stage_pair<1>(even, odd, m1);
    lo = _mm256_unpacklo_epi64(even, odd);
    hi = _mm256_unpackhi_epi64(even, odd);
    r[g] = _mm256_permute2x128_si256(lo, hi, 0x20);
    r[g + 1] = _mm256_permute2x128_si256(lo, hi, 0x31);
  }
}

// Sign-extended values of the 64 pixels of a word, as the rows of a bit matrix, transposed so
// that t[b] is the plane of bit b: for b < planes_needed at least (all 64 by default).
void word_planes(const RowSeed& s, int result_bits, Word* t, int planes_needed = 64) {
  const u64 field = result_bits == 64 ? kAllOnes : (u64{1} << result_bits) - 1;
  const __m256i mask = _mm256_set1_epi64x(static_cast<long long>(field));
  const __m256i sign = _mm256_set1_epi64x(static_cast<long long>(u64{1} << (result_bits - 1)));
  Lanes lanes(s);
  __m256i r[16];
  for (auto& v : r)
    v = _mm256_sub_epi64(_mm256_xor_si256(_mm256_and_si256(lanes.next(), mask), sign), sign);
  const bool low_half = planes_needed <= 32;
  transpose64(r, low_half);
  for (int q = 0; q < (low_half ? 8 : 16); ++q)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(t + 4 * q), r[q]);
}

// Planes "wrapped value < 0" and "wrapped value == 0" of one word. Shifting the result field to
// the top puts its sign in bit 63, and it is zero exactly when the shifted word is.
void word_sign_zero(const RowSeed& s, int result_bits, Word* lt, Word* eq) {
  const __m128i shift = _mm_cvtsi32_si128(64 - result_bits);
  const __m256i zero = _mm256_setzero_si256();
  Lanes lanes(s);
  Word neg = 0, nil = 0;
  for (int q = 0; q < 16; ++q) {
    const __m256i v = _mm256_sll_epi64(lanes.next(), shift);
    neg |= static_cast<Word>(_mm256_movemask_pd(_mm256_castsi256_pd(v))) << (4 * q);
    nil |= static_cast<Word>(_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(v, zero))))
           << (4 * q);
  }
  *lt = neg;
  *eq = nil;
}

#else

// Portable versions of the two kernels above: serial forward differences and a six-stage
// transpose in which stage J swaps, within every (2J x 2J) diagonal block, the upper-right and
// lower-left J x J blocks.
template <int J>
inline void transpose_stage(Word* a, Word mask) {
  for (int base = 0; base < 64; base += 2 * J) {
    for (int k = base; k < base + J; ++k) {
      const Word t = ((a[k] >> J) ^ a[k + J]) & mask;
      a[k] ^= t << J;
      a[k + J] ^= t;
    }
  }
}

void word_planes(const RowSeed& s, int result_bits, Word* t, int /*planes_needed*/ = 64) {
  const int shift = 64 - result_bits;
  u64 f = s.f, d = s.d;
  const u64 d2 = 2 * s.A;
  for (int i = 0; i < kWordBits; ++i) {
    t[i] = static_cast<Word>(static_cast<std::int64_t>(f << shift) >> shift);
    f += d;
    d += d2;
  }
  transpose_stage<32>(t, 0x00000000FFFFFFFFull);
  transpose_stage<16>(t, 0x0000FFFF0000FFFFull);
  transpose_stage<8>(t, 0x00FF00FF00FF00FFull);
  transpose_stage<4>(t, 0x0F0F0F0F0F0F0F0Full);
  transpose_stage<2>(t, 0x3333333333333333ull);
  transpose_stage<1>(t, 0x5555555555555555ull);
}

void word_sign_zero(const RowSeed& s, int result_bits, Word* lt, Word* eq) {
  const int shift = 64 - result_bits;
  u64 f = s.f, d = s.d;
  const u64 d2 = 2 * s.A;
  Word neg = 0, nil = 0;
  for (int i = 0; i < kWordBits; ++i) {
    const u64 v = f << shift;
    neg |= (v >> 63) << i;
    nil |= static_cast<Word>(v == 0) << i;
    f += d;
    d += d2;
  }
  *lt = neg;
  *eq = nil;
}

#endif

// The planes of j D (j = 0..63): plane k's bit j is bit k of j D, for k < planes_needed at
// least.
#if defined(__GFNI__) && defined(__AVX512VBMI__)

// The 64 x 64 bit transpose as an 8 x 8 grid of 8 x 8 blocks. Register R holds rows 8R..8R+7;
// a byte permutation puts byte C of its eight rows in qword C (row 8R + i in byte 7 - i) and a
// GF(2) affine transform with the identity as data transposes each block, so that qword C's byte
// c is byte R of plane 8C + c. A transpose of the 8 x 8 qwords across the registers and a byte
// transpose within each then leave planes 8C..8C+7 in register C.
void lane_planes(u64 D, Word* t, int /*planes_needed*/) {
  alignas(64) std::uint8_t to_blocks[64], to_planes[64];
  for (int a = 0; a < 8; ++a) {
    for (int b = 0; b < 8; ++b) {
      to_blocks[8 * a + 7 - b] = static_cast<std::uint8_t>(8 * b + a);
      to_planes[8 * a + b] = static_cast<std::uint8_t>(8 * b + a);
    }
  }
  const __m512i blocks = _mm512_load_si512(to_blocks);
  const __m512i planes = _mm512_load_si512(to_planes);
  const __m512i identity = _mm512_set1_epi64(static_cast<long long>(0x8040201008040201ull));
  const __mmask64 all = ~__mmask64{0};
  alignas(64) u64 first[8];
  for (int i = 0; i < 8; ++i) first[i] = static_cast<u64>(i) * D;
  __m512i v = _mm512_load_si512(first);
  const __m512i step = _mm512_set1_epi64(static_cast<long long>(8 * D));
  __m512i z[8];
  for (int R = 0; R < 8; ++R) {
    z[R] =
        _mm512_gf2p8affine_epi64_epi8(identity, _mm512_maskz_permutexvar_epi8(all, blocks, v), 0);
    v = _mm512_add_epi64(v, step);
  }
  // z[R] qword C -> z[C] qword R, in three stages of pairs 1, 2 and 4 registers apart.
  __m512i y[8];
  for (int k = 0; k < 8; k += 2) {
    y[k] = _mm512_maskz_unpacklo_epi64(0xFF, z[k], z[k + 1]);
    y[k + 1] = _mm512_maskz_unpackhi_epi64(0xFF, z[k], z[k + 1]);
  }
  const __m512i lo2 = _mm512_set_epi64(13, 12, 5, 4, 9, 8, 1, 0);
  const __m512i hi2 = _mm512_set_epi64(15, 14, 7, 6, 11, 10, 3, 2);
  for (int k : {0, 1, 4, 5}) {
    z[k] = _mm512_permutex2var_epi64(y[k], lo2, y[k + 2]);
    z[k + 2] = _mm512_permutex2var_epi64(y[k], hi2, y[k + 2]);
  }
  const __m512i lo4 = _mm512_set_epi64(11, 10, 9, 8, 3, 2, 1, 0);
  const __m512i hi4 = _mm512_set_epi64(15, 14, 13, 12, 7, 6, 5, 4);
  for (int k = 0; k < 4; ++k) {
    y[k] = _mm512_permutex2var_epi64(z[k], lo4, z[k + 4]);
    y[k + 4] = _mm512_permutex2var_epi64(z[k], hi4, z[k + 4]);
  }
  for (int C = 0; C < 8; ++C)
    _mm512_storeu_si512(t + 8 * C, _mm512_maskz_permutexvar_epi8(all, planes, y[C]));
}

#else

void lane_planes(u64 D, Word* t, int planes_needed) {
  word_planes(RowSeed{0, D, 0}, 64, t, planes_needed);
}

#endif

// The bit-serial additions of linear_planes for a run of kLinearBatch words: base[l] is the
// value at the first pixel of word l, lane[k] the plane k of j D (j = 0..63). Planes first_bit
// .. last of words 0..n-1 go to out[(plane - first_bit) * stride + l]; planes are computed up
// to top (the sign bit, or last if lower) and repeated above it. Below first_bit only the carry
// is kept (a majority per plane: the sum is not needed).
constexpr int kLinearBatch = 8;

#if defined(__AVX512F__)

// One 512-bit vector holds the batch: per plane, the broadcast value's bit k as a lane mask
// (shifted to bit 63 and spread by an arithmetic shift), a majority and a three-way XOR.
// The masked forms with every lane kept: the unmasked shifts' headers (GCC 12) warn of an
// undefined source they never read.
constexpr __mmask8 kAll8 = 0xFF;

// All ones in the 64-bit lanes whose bit 0 is set, zero in the others.
inline __m512i lane_mask_of_bit0(__m512i v) {
  const __m512i top = _mm512_mask_slli_epi64(v, kAll8, v, 63);
  return _mm512_mask_srai_epi64(top, kAll8, top, 63);
}

void linear_batch(const Word* lane, const u64* base, int n, int first_bit, int top, int last,
                  Word* out, std::size_t stride) {
  // Shifted right by one per plane: bit k in bit 0. Built lane by lane from the scalars (a
  // vector load of eight just-stored words would wait for the stores to retire).
  __m512i b = _mm512_setzero_si512();
  for (int l = 0; l < kLinearBatch; ++l)
    b = _mm512_mask_set1_epi64(b, static_cast<__mmask8>(1u << l), static_cast<long long>(base[l]));
  const __mmask8 keep = static_cast<__mmask8>((1u << n) - 1);
  __m512i carry = _mm512_setzero_si512();
  __m512i sum = _mm512_setzero_si512();
  const int full = std::min(first_bit, top);
  for (int k = 0; k < full; ++k) {
    const __m512i p = _mm512_set1_epi64(static_cast<long long>(lane[k]));
    const __m512i kb = lane_mask_of_bit0(b);
    b = _mm512_mask_srli_epi64(b, kAll8, b, 1);
    carry = _mm512_ternarylogic_epi64(p, kb, carry, 0xE8);  // majority
  }
  for (int k = full; k <= top; ++k) {
    const __m512i p = _mm512_set1_epi64(static_cast<long long>(lane[k]));
    const __m512i kb = lane_mask_of_bit0(b);
    b = _mm512_mask_srli_epi64(b, kAll8, b, 1);
    sum = _mm512_ternarylogic_epi64(p, kb, carry, 0x96);    // p ^ kb ^ carry
    carry = _mm512_ternarylogic_epi64(p, kb, carry, 0xE8);  // majority
    if (k >= first_bit)
      _mm512_mask_storeu_epi64(out + static_cast<std::size_t>(k - first_bit) * stride, keep, sum);
  }
  for (int k = std::max(first_bit, top + 1); k <= last; ++k)
    _mm512_mask_storeu_epi64(out + static_cast<std::size_t>(k - first_bit) * stride, keep, sum);
}

#else

// Eight independent carry chains, which the compiler turns into vector operations.
void linear_batch(const Word* lane, const u64* base, int n, int first_bit, int top, int last,
                  Word* out, std::size_t stride) {
  Word carry[kLinearBatch] = {};
  Word sum[kLinearBatch] = {};
  auto store = [&](int plane) {
    Word* o = out + static_cast<std::size_t>(plane - first_bit) * stride;
    if (n == kLinearBatch) {
      for (int l = 0; l < kLinearBatch; ++l) o[l] = sum[l];
    } else {
      for (int l = 0; l < n; ++l) o[l] = sum[l];
    }
  };
  const int full = std::min(first_bit, top);
  for (int k = 0; k < full; ++k) {
    const Word p = lane[k];
    for (int l = 0; l < kLinearBatch; ++l) {
      const Word kb = Word{0} - ((base[l] >> k) & 1);
      carry[l] = (p & kb) | (carry[l] & (p | kb));
    }
  }
  for (int k = full; k <= top; ++k) {
    const Word p = lane[k];
    for (int l = 0; l < kLinearBatch; ++l) {
      const Word kb = Word{0} - ((base[l] >> k) & 1);
      sum[l] = p ^ kb ^ carry[l];
      carry[l] = (p & kb) | (carry[l] & (p | kb));
    }
    if (k >= first_bit) store(k);
  }
  for (int b = std::max(first_bit, top + 1); b <= last; ++b) store(b);
}

#endif

}  // namespace

ExpressionEvaluator::ExpressionEvaluator(EvaluatorParams params, int region_width,
                                         int region_height)
    : params_(params), width_(region_width), height_(region_height) {
  if (params.coefficient_bits < 2 || params.coefficient_bits > 62)
    throw std::invalid_argument("evaluator: coefficient_bits must be in 2..62, got " +
                                std::to_string(params.coefficient_bits));
  if (params.result_bits < 2 || params.result_bits > 64)
    throw std::invalid_argument("evaluator: result_bits must be in 2..64, got " +
                                std::to_string(params.result_bits));
  if (region_width <= 0 || region_width % kWordBits != 0)
    throw std::invalid_argument("evaluator: region width must be a positive multiple of 64, got " +
                                std::to_string(region_width));
  if (region_height <= 0)
    throw std::invalid_argument("evaluator: region height must be positive, got " +
                                std::to_string(region_height));
  if (static_cast<std::int64_t>(region_width) * region_height > INT_MAX)
    throw std::invalid_argument("evaluator: region too large");
  words_per_row_ = words_per_row(region_width);
  words_ = words_per_row_ * region_height;
}

void ExpressionEvaluator::set_origin(int x0, int y0) {
  x0_ = x0;
  y0_ = y0;
}

bool ExpressionEvaluator::fits(const QuadraticCoefficients& c) const {
  const std::int64_t hi = (std::int64_t{1} << (params_.coefficient_bits - 1)) - 1;
  const std::int64_t lo = -hi - 1;
  for (std::int64_t v : {c.A, c.B, c.C, c.D, c.E, c.F})
    if (v < lo || v > hi) return false;
  return true;
}

std::int64_t ExpressionEvaluator::wrap(u64 v) const {
  const int shift = 64 - params_.result_bits;
  return static_cast<std::int64_t>(v << shift) >> shift;
}

std::int64_t ExpressionEvaluator::value_at(const QuadraticCoefficients& c, int x, int y) const {
  return wrap(seed(c, x0_ + x, y0_ + y).f);
}

void ExpressionEvaluator::planes(const QuadraticCoefficients& c, int first_bit, int count,
                                 WordRange range, Word* out, const Word* live) const {
  assert(first_bit >= 0 && count >= 1 && count <= 64);
  assert(range.begin >= 0 && range.end <= words_);
  if (c.is_linear()) {
    linear_planes(c, first_bit, count, range, out, live);
    return;
  }
  alignas(32) Word t[kWordBits];
  for (int w = range.begin; w < range.end; ++w) {
    if (live != nullptr && live[w] == 0) {
      for (int k = 0; k < count; ++k) out[static_cast<std::size_t>(k) * words_ + w] = 0;
      continue;
    }
    word_planes(seed(c, word_x(w), word_y(w)), params_.result_bits, t);
    // Values are sign-extended to 64 bits, so plane 63 stands for every bit above.
    for (int k = 0; k < count; ++k)
      out[static_cast<std::size_t>(k) * words_ + w] = t[std::min(first_bit + k, 63)];
  }
}

// A linear expression's 64 pixels of a word are v + j D (j = 0..63, v its first pixel's value),
// and the planes of j D are the same for every word: transposed once, each word's planes are
// then a bit-serial addition of the broadcast constant v to them, LSB first, as the hardware's
// adder tree would do it, over only the planes up to the highest one asked for (carries run
// upwards only). Below first_bit only the carry is kept (a majority per plane, the sum is not
// needed). Modulo 2^64 throughout, so the bits below result_bits are exact; the planes above
// the result's sign bit repeat it. Eight words at a time (linear_batch), whose carry chains are
// independent; v steps by 64 D along a row and by E from row to row, so no word's coordinates
// are divided out.
void ExpressionEvaluator::linear_planes(const QuadraticCoefficients& c, int first_bit, int count,
                                        WordRange range, Word* out, const Word* live) const {
  const int sign_bit = params_.result_bits - 1;
  const int last = first_bit + count - 1;    // the highest plane asked for
  const int top = std::min(last, sign_bit);  // the highest plane computed
  alignas(64) Word lane[kWordBits];
  lane_planes(static_cast<u64>(c.D), lane, top + 1);
  const u64 D = static_cast<u64>(c.D), E = static_cast<u64>(c.E), F = static_cast<u64>(c.F);
  const u64 word_step = D * static_cast<u64>(kWordBits);
  // The walk's position: column `col` of the row whose first word's v is row_v.
  int col = range.begin % words_per_row_;
  u64 row_v = D * static_cast<u64>(x0_) + E * static_cast<u64>(word_y(range.begin)) + F;
  auto advance = [&] {
    if (++col == words_per_row_) {
      col = 0;
      row_v += E;
    }
  };
  constexpr int kBatch = kLinearBatch;
  for (int w0 = range.begin; w0 < range.end; w0 += kBatch) {
    const int n = std::min(kBatch, range.end - w0);
    if (live != nullptr) {
      Word any = 0;
      for (int l = 0; l < n; ++l) any |= live[w0 + l];
      if (any == 0) {
        for (int k = 0; k < count; ++k)
          std::fill_n(out + static_cast<std::size_t>(k) * words_ + w0, n, Word{0});
        for (int l = 0; l < n; ++l) advance();
        continue;
      }
    }
    u64 base[kBatch];
    for (int l = 0; l < n; ++l) {
      base[l] = row_v + static_cast<u64>(col) * word_step;
      advance();
    }
    for (int l = n; l < kBatch; ++l) base[l] = base[n - 1];
    linear_batch(lane, base, n, first_bit, top, last, out + w0, static_cast<std::size_t>(words_));
  }
}

bool ExpressionEvaluator::linear_fast_path(const QuadraticCoefficients& c, WordRange range) const {
  if (!c.is_linear() || range.empty()) return false;
  const std::int64_t row_first = range.begin / words_per_row_;
  const std::int64_t row_last = (range.end - 1) / words_per_row_;
  // A linear function over a rectangle takes its extremes at the corners, so if every corner
  // lies within the result range no pixel between them wraps.
  const i128 limit = i128{1} << (params_.result_bits - 1);
  for (std::int64_t x : {x0_, x0_ + width_ - 1}) {
    for (std::int64_t y : {y0_ + row_first, y0_ + row_last}) {
      const i128 v = i128{c.D} * x + i128{c.E} * y + c.F;
      if (v < -limit || v >= limit) return false;
    }
  }
  return true;
}

void ExpressionEvaluator::test_plane(const QuadraticCoefficients& c, Condition cond,
                                     WordRange range, Word* out, const Word* live) const {
  assert(range.begin >= 0 && range.end <= words_);
  if (range.empty()) return;
  if (!linear_fast_path(c, range)) {
    for (int w = range.begin; w < range.end; ++w) {
      if (live != nullptr && live[w] == 0) {
        out[w] = 0;
        continue;
      }
      Word lt, eq;
      word_sign_zero(seed(c, word_x(w), word_y(w)), params_.result_bits, &lt, &eq);
      out[w] = select_condition(cond, lt, eq);
    }
    return;
  }
  // No wrap, so the wrapped value is the exact D x + E y + F. Within a row it is monotone in x,
  // so the pixels satisfying cond form an interval [lo, hi) of region columns or, for gt, ge and
  // ne, the complement of one.
  const int row_first = range.begin / words_per_row_;
  const int row_last = (range.end - 1) / words_per_row_;
  i128 slope = c.D;
  i128 offset = i128{c.D} * x0_ + i128{c.E} * (y0_ + row_first) + c.F;  // at column 0
  i128 row_step = c.E;
  Condition k = cond;
  if (slope < 0) {
    slope = -slope;
    offset = -offset;
    row_step = -row_step;
    k = mirror(cond);
  }
  // 64-bit arithmetic whenever every value of the walk fits it with room to spare (always, at
  // any configuration the checks allow, but exactness does not depend on it).
  const i128 limit = i128{1} << 61;
  const i128 rows = row_last - row_first + 1;
  const bool narrow =
      slope < limit && offset < limit && offset > -limit && row_step < limit && row_step > -limit &&
      (offset < 0 ? -offset : offset) + rows * (row_step < 0 ? -row_step : row_step) < limit;
  if (narrow) {
    interval_rows<std::int64_t>(static_cast<std::int64_t>(slope), static_cast<std::int64_t>(offset),
                                static_cast<std::int64_t>(row_step), k, range, row_first, row_last,
                                out, live);
  } else {
    interval_rows<i128>(slope, offset, row_step, k, range, row_first, row_last, out, live);
  }
}

// The rows [row_first, row_last] of test_plane's interval method: the value at column i of a
// row is slope * i + offset (slope >= 0), offset grows by row_step per row, and cond is k.
template <class T>
void ExpressionEvaluator::interval_rows(T slope, T offset, T row_step, Condition k, WordRange range,
                                        int row_first, int row_last, Word* out,
                                        const Word* live) const {
  // Which interval each condition keeps: [lo, hi) from the ends below, or its complement.
  const bool use_lo = k == Condition::eq || k == Condition::ne;
  const bool hi_is_le = k == Condition::le || k == Condition::gt || use_lo;
  const bool invert = k == Condition::ge || k == Condition::gt || k == Condition::ne;
  // With n = -offset = q * slope + r (0 <= r < slope), the columns where the value is < 0 end
  // at ceil(n / slope) = q + (r != 0), those where it is <= 0 at floor(n / slope) + 1 = q + 1.
  // From row to row n drops by row_step: q and r follow with one addition and one
  // comparison, so the walk divides twice per call instead of once per row.
  T q = 0, r = 0, step_q = 0, step_r = 0;
  if (slope != 0) {
    q = floor_div<T>(-offset, slope);
    r = -offset - q * slope;
    step_q = floor_div<T>(-row_step, slope);
    step_r = -row_step - step_q * slope;
  }
  const T width = width_;
  for (int row = row_first; row <= row_last; ++row) {
    int lo = 0, hi = 0;
    if (slope == 0) {
      // The value is offset in every column.
      const Word lt = offset < 0 ? kAllOnes : 0, eq = offset == 0 ? kAllOnes : 0;
      hi = select_condition(k, lt, eq) != 0 ? width_ : 0;
      lo = 0;
      offset += row_step;
      const int row_base = row * words_per_row_;
      const int w_begin = std::max(range.begin, row_base);
      const int w_end = std::min(range.end, row_base + words_per_row_);
      for (int w = w_begin; w < w_end; ++w) {
        out[w] = live != nullptr && live[w] == 0 ? 0 : (hi != 0 ? kAllOnes : 0);
      }
      continue;
    }
    const T lt_end = q + (r != 0 ? 1 : 0);
    const T le_end = q + 1;
    const T h = hi_is_le ? le_end : lt_end;
    hi = static_cast<int>(h < 0 ? 0 : h > width ? width : h);
    lo = use_lo ? static_cast<int>(lt_end < 0 ? 0 : lt_end > width ? width : lt_end) : 0;
    q += step_q;
    r += step_r;
    if (r >= slope) {
      r -= slope;
      ++q;
    }
    const int row_base = row * words_per_row_;
    const int w_begin = std::max(range.begin, row_base);
    const int w_end = std::min(range.end, row_base + words_per_row_);
    for (int w = w_begin; w < w_end; ++w) {
      if (live != nullptr && live[w] == 0) {
        out[w] = 0;
        continue;
      }
      const int col = (w - row_base) * kWordBits;
      const Word m =
          bit_span(std::clamp(lo - col, 0, kWordBits), std::clamp(hi - col, 0, kWordBits));
      out[w] = invert ? ~m : m;
    }
  }
}

}  // namespace pp5
