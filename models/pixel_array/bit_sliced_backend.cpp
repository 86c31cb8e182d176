#include "models/pixel_array/bit_sliced_backend.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#if defined(__GFNI__) && defined(__AVX512VBMI__) && defined(__AVX512BW__)
#include <immintrin.h>
#endif

namespace pp5 {

BitSlicedBackend::BitSlicedBackend(const PixelBackendParams& params)
    : array_(params.array),
      evaluator_(params.evaluator, params.array.width, params.array.height),
      fraction_bits_(params.fraction_bits),
      scratch_(static_cast<std::size_t>(Bits::kMaxBits) * array_.words(), 0) {}

Bits BitSlicedBackend::source_bits(const Source& src) const {
  return src.is_field ? array_.bits_of(src.field) : array_.bits_of_constant(src.constant);
}

Bits BitSlicedBackend::expression_bits(const QuadraticCoefficients& expr, const Field& as) {
  settle();
  // Disabled pixels' values are never used (assign keeps them, compare clears their E
  // anyway), so words whose E is zero are not evaluated.
  if (!(held_.valid && held_.width == as.width && held_.expr == expr)) {
    evaluator_.planes(expr, fraction_bits_, as.width, array_.active_words(), scratch_.data(),
                      array_.enable());
    held_.valid = true;  // (member by member: a temporary copied whole stalls on its stores)
    held_.expr = expr;
    held_.width = as.width;
  }
  return array_.bits_of_planes(scratch_.data(), as.width, as.is_signed);
}

void BitSlicedBackend::qtest(const QuadraticCoefficients& expr, Compare cond) {
  // Held back when linear_row_band can take it: a one-interval condition on a linear value
  // formed exactly in 64 bits, which wraps nowhere in the region (so that the wrapped value
  // the hardware compares is the half-plane's).
  const PixelArrayGeometry& g = geometry();
  if (expr.is_linear() && one_interval(cond) && pending_count_ < pending_.size() &&
      fits_64(expr, evaluator_.origin_y(), evaluator_.origin_x(), g.width, g.height) &&
      evaluator_.linear_fast_path(expr, WordRange{0, array_.words()})) {
    pending_[pending_count_++] = LinearTest{expr, cond};
    return;
  }
  settle();
  and_test(expr, cond);
}

void BitSlicedBackend::and_test(const QuadraticCoefficients& expr, Compare cond) {
  const WordRange r = array_.active_words();
  if (r.empty()) return;
  held_.valid = false;
  evaluator_.test_plane(expr, cond, r, scratch_.data(), array_.enable());
  array_.and_enable(scratch_.data());
}

void BitSlicedBackend::apply_pending() {
  const std::size_t n = pending_count_;
  pending_count_ = 0;
  const PixelArrayGeometry& g = geometry();
  int lo = 0, hi = g.height - 1;
  linear_row_band(pending_.data(), n, evaluator_.origin_x(), evaluator_.origin_y(), g.width,
                  g.height, lo, hi);
  // No pixel outside the band passes every test: E is 0 there. Inside it, each test is
  // applied exactly, as qtest applies one, over what the tests before it left.
  const int words_per_row = g.width / kWordBits;
  const int first = std::min(lo, hi + 1) * words_per_row;
  array_.clear_enable_outside(WordRange{first, std::max(first, (hi + 1) * words_per_row)});
  for (std::size_t k = 0; k < n; ++k) and_test(pending_[k].c, pending_[k].cond);
}

void BitSlicedBackend::qload(const Field& dst, const QuadraticCoefficients& expr) {
  const Bits v = expression_bits(expr, dst);
  array_.assign(dst, v);
}

void BitSlicedBackend::qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) {
  const Bits v = expression_bits(expr, field);
  array_.compare(v, array_.bits_of(field), cond);
}

void BitSlicedBackend::mov(const Field& dst, const Source& src) {
  settle();
  array_.assign(dst, source_bits(src));
}

void BitSlicedBackend::add(const Field& dst, const Source& src) {
  settle();
  array_.add(dst, array_.bits_of(dst), source_bits(src));
}

void BitSlicedBackend::sub(const Field& dst, const Source& src) {
  settle();
  array_.sub(dst, array_.bits_of(dst), source_bits(src));
}

void BitSlicedBackend::logic(const Field& dst, const Source& src, Logic op) {
  settle();
  array_.logic(dst, array_.bits_of(dst), source_bits(src), op);
}

void BitSlicedBackend::compare(const Field& a, const Source& b, Compare cond) {
  settle();
  array_.compare(array_.bits_of(a), source_bits(b), cond);
}

void BitSlicedBackend::multiply(const Field& dst, const Field& a, const Field& b, bool window) {
  settle();
  array_.multiply(dst, array_.bits_of(a), array_.bits_of(b), multiply_window_bits(a, window));
}

void BitSlicedBackend::multiply_accumulate(const Field& dst, const Field& a, std::int64_t k) {
  settle();
  array_.multiply_accumulate(dst, array_.bits_of(a), k);
}

#if !(defined(__GFNI__) && defined(__AVX512VBMI__) && defined(__AVX512BW__))
namespace {

// spread[b] has bit k of b at bit 8k: one plane's byte becomes one bit in each of 8 byte lanes.
const std::array<std::uint64_t, 256>& spread_table() {
  static const std::array<std::uint64_t, 256> table = [] {
    std::array<std::uint64_t, 256> t{};
    for (int b = 0; b < 256; ++b) {
      for (int k = 0; k < 8; ++k) t[b] |= static_cast<std::uint64_t>((b >> k) & 1) << (8 * k);
    }
    return t;
  }();
  return table;
}

}  // namespace
#endif

void BitSlicedBackend::read_field(const Field& field, std::uint64_t* out) const {
  // The same bits PixelArray::read gives pixel by pixel (pixel p is bit p % 64 of word
  // p / 64), eight planes at a time.
  const int words = array_.words();
  std::fill(out, out + array_.pixels(), std::uint64_t{0});
#if defined(__GFNI__) && defined(__AVX512VBMI__) && defined(__AVX512BW__)
  // One word of eight planes is an 8 x 64 bit matrix. A byte permutation gathers, for each
  // group of 8 pixels b, byte b of every plane into one qword (plane i in byte 7 - i); an
  // affine transform with the identity as the data and that qword as the matrix transposes
  // each 8 x 8 block, leaving pixel 8b + j's bits of the eight planes in byte 8b + j.
  alignas(64) std::uint8_t gather[64];
  for (int b = 0; b < 8; ++b)
    for (int i = 0; i < 8; ++i) gather[8 * b + 7 - i] = static_cast<std::uint8_t>(8 * i + b);
  const __m512i index = _mm512_load_si512(gather);
  const __m512i identity = _mm512_set1_epi64(static_cast<long long>(0x8040201008040201ull));
  alignas(64) std::uint8_t pixel_bytes[64];
  for (int g = 0; g < field.width; g += 8) {
    const int n = std::min(8, field.width - g);
    const __m128i shift = _mm_cvtsi32_si128(g);
    const __mmask8 planes_in = static_cast<__mmask8>((1u << n) - 1);
    const std::uint64_t* first = array_.plane(field.lo + g);
    const std::size_t stride = static_cast<std::size_t>(words);
    const __m512i strides =
        _mm512_set_epi64(7 * static_cast<long long>(stride), 6 * static_cast<long long>(stride),
                         5 * static_cast<long long>(stride), 4 * static_cast<long long>(stride),
                         3 * static_cast<long long>(stride), 2 * static_cast<long long>(stride),
                         static_cast<long long>(stride), 0);
    for (int w = 0; w < words; ++w) {
      const __m512i planes =
          _mm512_mask_i64gather_epi64(_mm512_setzero_si512(), planes_in, strides, first + w, 8);
      // (The zero-masking forms with every lane kept: GCC 12's plain forms warn of an
      // undefined source they never read.)
      const __m512i blocks = _mm512_maskz_permutexvar_epi8(~__mmask64{0}, index, planes);
      _mm512_store_si512(pixel_bytes, _mm512_gf2p8affine_epi64_epi8(identity, blocks, 0));
      std::uint64_t* o = out + static_cast<std::size_t>(w) * 64;
      for (int q = 0; q < 8; ++q) {
        const __m512i wide = _mm512_maskz_cvtepu8_epi64(
            0xFF, _mm_loadl_epi64(reinterpret_cast<const __m128i*>(pixel_bytes + 8 * q)));
        __m512i* dst = reinterpret_cast<__m512i*>(o + 8 * q);
        _mm512_storeu_si512(dst, _mm512_or_si512(_mm512_loadu_si512(dst),
                                                 _mm512_maskz_sll_epi64(0xFF, wide, shift)));
      }
    }
  }
#else
  // A table lookup per byte of a plane puts that plane's bit of 8 pixels into 8 byte lanes, so
  // 8 pixels' bytes are assembled in one register.
  const auto& spread = spread_table();
  for (int g = 0; g < field.width; g += 8) {
    const int n = std::min(8, field.width - g);
    for (int w = 0; w < words; ++w) {
      std::uint64_t lanes[8] = {};
      for (int i = 0; i < n; ++i) {
        const Word bits = array_.plane(field.lo + g + i)[w];
        for (int b = 0; b < 8; ++b) lanes[b] |= spread[(bits >> (8 * b)) & 0xFF] << i;
      }
      std::uint64_t* o = out + static_cast<std::size_t>(w) * 64;
      for (int b = 0; b < 8; ++b) {
        for (int k = 0; k < 8; ++k) o[8 * b + k] |= ((lanes[b] >> (8 * k)) & 0xFF) << g;
      }
    }
  }
#endif
}

void BitSlicedBackend::read_memory_planes(std::vector<std::uint64_t>& planes) const {
  const std::size_t n = static_cast<std::size_t>(geometry().memory_bits) * array_.words();
  planes.assign(array_.plane(0), array_.plane(0) + n);
}

std::unique_ptr<PixelBackend> BitSlicedBackend::clone() const {
  settle();
  return std::make_unique<BitSlicedBackend>(*this);
}

bool BitSlicedBackend::same_state(const PixelBackend& other) const {
  const auto* o = dynamic_cast<const BitSlicedBackend*>(&other);
  if (o == nullptr) return false;
  settle();
  o->settle();
  return array_.same_state(o->array_);
}

void BitSlicedBackend::copy_state_from(const PixelBackend& other) {
  const auto* o = dynamic_cast<const BitSlicedBackend*>(&other);
  if (o == nullptr || o->geometry() != geometry()) {
    throw std::invalid_argument(std::string("bit backend: cannot take the state of a '") +
                                other.name() + "' backend of another kind or geometry");
  }
  o->settle();
  array_ = o->array_;
  pending_count_ = 0;
  held_.valid = false;
}

}  // namespace pp5
