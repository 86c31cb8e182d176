#include "models/pixel_array/word_backend.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

namespace pp5 {

namespace {

using u64 = std::uint64_t;
using i64 = std::int64_t;

u64 low_mask(int width) { return width >= 64 ? ~u64{0} : (u64{1} << width) - 1; }

// Eight pixels at a time: GCC vector types (AVX-512 registers where the host has them, two or
// four narrower ones where not; each operation is the scalar one lane by lane, so the result
// is the same on any host). A row's part is short after a triangle's edge tests (six pixels
// on average on the default torus), too short for a compiler's vector loop, which runs its
// scalar remainder instead.
using V8 = u64 __attribute__((vector_size(64)));
using V8s = i64 __attribute__((vector_size(64)));
using B8 = std::uint8_t __attribute__((vector_size(8)));

// for_chunks(begin, end, limit, f): pixels [begin, end) of an array of `limit` >= 8 as chunks
// of eight, f(base, live): the chunk is pixels [base, base + 8), live (-1 or 0 per lane) the
// ones of them to process. Chunk k covers [begin + 8k, begin + 8k + 8) cut to end, moved back
// to end by `limit` if it would pass it (its lanes before begin + 8k then not live): every
// pixel is processed once, and nothing outside the array is read or written. The lanes not
// live are read and written back unchanged.
template <class F>
inline void for_chunks(int begin, int end, int limit, F f) {
  const V8s iota = {0, 1, 2, 3, 4, 5, 6, 7};
  for (int c = begin; c < end; c += 8) {
    const int base = std::min(c, limit - 8);
    const V8s x = iota + base;
    f(base, reinterpret_cast<V8>((x >= c) & (x < end)));
  }
}

inline V8 load8(const u64* p) {
  V8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline void store8(u64* p, const V8& v) { std::memcpy(p, &v, sizeof v); }

// Eight E bytes, one per lane (zero-extended), and back: the lanes' low bytes. One
// instruction each with AVX-512 (GCC's generic conversion goes byte by byte).
inline V8 load_enable8(const std::uint8_t* p) {
#ifdef __AVX512F__
  return reinterpret_cast<V8>(
      _mm512_maskz_cvtepu8_epi64(0xFF, _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
#else
  B8 b;
  std::memcpy(&b, p, sizeof b);
  return __builtin_convertvector(b, V8);
#endif
}

inline void store_enable8(std::uint8_t* p, const V8& v) {
#ifdef __AVX512F__
  _mm_storel_epi64(reinterpret_cast<__m128i*>(p),
                   _mm512_maskz_cvtepi64_epi8(0xFF, reinterpret_cast<__m512i>(v)));
#else
  const B8 b = __builtin_convertvector(v, B8);
  std::memcpy(p, &b, sizeof b);
#endif
}

template <class T>
inline bool holds(Compare cond, T a, T b) {
  switch (cond) {
    case Compare::lt:
      return a < b;
    case Compare::le:
      return a <= b;
    case Compare::eq:
      return a == b;
    case Compare::ne:
      return a != b;
    case Compare::ge:
      return a >= b;
    case Compare::gt:
      return a > b;
  }
  return false;
}

// E &= (a[p] cond b[p]) over [begin, end); returns the OR of the new E bytes (whether any
// pixel is still enabled), formed in the same pass.
template <class GetA, class GetB, class Cmp>
std::uint8_t and_compare_loop(std::uint8_t* e, GetA a, GetB b, Cmp cmp, int begin, int end) {
  std::uint8_t any = 0;
  for (int p = begin; p < end; ++p) {
    const std::uint8_t v = e[p] & static_cast<std::uint8_t>(cmp(a(p), b(p)));
    e[p] = v;
    any |= v;
  }
  return any;
}

// E &= (a[p] cond b[p]) as signed 64-bit values; one loop per condition so that each
// vectorises. Whether any pixel of [begin, end) is still enabled.
template <class GetA, class GetB>
bool and_compare_with(std::uint8_t* e, GetA a, GetB b, Compare cond, int begin, int end) {
  switch (cond) {
    case Compare::lt:
      return and_compare_loop(e, a, b, std::less<>(), begin, end) != 0;
    case Compare::le:
      return and_compare_loop(e, a, b, std::less_equal<>(), begin, end) != 0;
    case Compare::eq:
      return and_compare_loop(e, a, b, std::equal_to<>(), begin, end) != 0;
    case Compare::ne:
      return and_compare_loop(e, a, b, std::not_equal_to<>(), begin, end) != 0;
    case Compare::ge:
      return and_compare_loop(e, a, b, std::greater_equal<>(), begin, end) != 0;
    case Compare::gt:
      return and_compare_loop(e, a, b, std::greater<>(), begin, end) != 0;
  }
  return false;
}

template <class GetB>
void and_compare(std::uint8_t* e, const u64* a, GetB b, Compare cond, int begin, int end) {
  and_compare_with(
      e, [a](int p) { return static_cast<i64>(a[p]); }, b, cond, begin, end);
}
}  // namespace

// Named (not anonymous): the compare passes' lambdas, members of WordBackend's functions,
// capture it.
namespace word_rows {

// Span [a, b) joined to the spans kept: a row enabled to its end and the next from its start
// stay one span.
template <class Spans>
void keep_span(Spans& kept, int a, int b) {
  if (!kept.empty() && kept.back().end == a) {
    kept.back().end = b;
  } else {
    kept.push_back({a, b});
  }
}

// The first and last pixels of a row's part that a compare left enabled, gathered chunk by
// chunk as it compares (its chunks come in increasing order, and a chunk's lanes that are not
// live are 0 in `left`): the span keep_enabled would find by reading E back, without the read.
struct RowEnabled {
  int first = -1, last = -1;  // -1: none yet
  // left: 1 or 0 per lane, the chunk's new E bytes where live, else 0.
  void add(int base, const V8& left) {
#ifdef __AVX512F__
    const unsigned m =
        _mm512_test_epi64_mask(reinterpret_cast<__m512i>(left), reinterpret_cast<__m512i>(left));
    if (m == 0) return;
    if (first < 0) first = base + __builtin_ctz(m);
    last = base + 31 - __builtin_clz(m);
#else
    const B8 b = __builtin_convertvector(left, B8);
    std::uint64_t w;
    std::memcpy(&w, &b, sizeof w);
    if (w == 0) return;
    if (first < 0) first = base + __builtin_ctzll(w) / 8;  // little-endian: lane 0 lowest
    last = base + 7 - __builtin_clzll(w) / 8;
#endif
  }
  // Its span joined to the spans kept (keep_span), as keep_enabled does. `start`: the row's
  // first pixel.
  template <class Spans>
  void keep(Spans& kept, int start) const {
    if (first >= 0) keep_span(kept, start + first, start + last + 1);
  }
};

// A condition on eight signed 64-bit pairs, as three flags: (less and lt) or (equal and eq),
// inverted when inv; and E &= it on a chunk, its span noted (qcmp's and cmp's passes).
class ChunkCompare {
 public:
  explicit ChunkCompare(Compare cond) {
    const bool lt =
        cond == Compare::lt || cond == Compare::le || cond == Compare::ge || cond == Compare::gt;
    const bool eq =
        cond == Compare::le || cond == Compare::eq || cond == Compare::ne || cond == Compare::gt;
    const bool inv = cond == Compare::ne || cond == Compare::ge || cond == Compare::gt;
    lt_mask_ = V8s{} - static_cast<std::int64_t>(lt);
    eq_mask_ = V8s{} - static_cast<std::int64_t>(eq);
    inv_mask_ = V8{} - static_cast<std::uint64_t>(inv);
  }
  // E's chunk at en + base ANDed with (a cond b) in the live lanes, the lanes left noted.
  void apply(std::uint8_t* en, int base, const V8& live, const V8s& a, const V8s& b,
             RowEnabled& row) const {
    apply(en, en, base, live, a, b, row);
  }
  // The same from E's bytes at from + base into to + base (another buffer).
  void apply(const std::uint8_t* from, std::uint8_t* to, int base, const V8& live, const V8s& a,
             const V8s& b, RowEnabled& row) const {
    const V8 holds = reinterpret_cast<V8>(((a < b) & lt_mask_) | ((a == b) & eq_mask_)) ^ inv_mask_;
    const V8 left = load_enable8(from + base) & holds & live;
    row.add(base, left);
    store_enable8(to + base, left | (load_enable8(to + base) & ~live));
  }

 private:
  V8s lt_mask_, eq_mask_;
  V8 inv_mask_;
};

}  // namespace word_rows
using word_rows::ChunkCompare;
using word_rows::RowEnabled;

WordBackend::WordBackend(const PixelBackendParams& params)
    : geometry_(params.array),
      evaluator_(params.evaluator),
      fraction_bits_(params.fraction_bits),
      pixels_(params.array.width * params.array.height),
      lanes_((params.array.memory_bits + 63) / 64) {
  if (geometry_.width <= 0 || geometry_.width % 64 != 0 || geometry_.height <= 0) {
    throw std::invalid_argument("pixel array: width must be a positive multiple of 64, height > 0");
  }
  if (geometry_.memory_bits < 1 || geometry_.enable_stack_depth < 0 ||
      geometry_.backing_store_bits < 0 || geometry_.block_bits < 1) {
    throw std::invalid_argument("pixel array: bad memory geometry");
  }
  if (evaluator_.result_bits < 2 || evaluator_.result_bits > 64 || fraction_bits_ < 0) {
    throw std::invalid_argument("word backend: result_bits must be 2..64, fraction_bits >= 0");
  }
  const auto n = static_cast<std::size_t>(pixels_);
  memory_.assign(static_cast<std::size_t>(lanes_) * n, 0);
  enable_.assign(n, 1);
  spans_ = {Range{0, pixels_}};
  stack_spans_.assign(static_cast<std::size_t>(geometry_.enable_stack_depth), {});
  stack_.assign(static_cast<std::size_t>(geometry_.enable_stack_depth), {});
  allocate_scratch();  // here, on the thread that makes the backend (see Scratch)
}

void WordBackend::allocate_scratch() const {
  const auto n = static_cast<std::size_t>(pixels_);
  scratch_.s0.assign(n, 0);
  scratch_.s1.assign(n, 0);
  scratch_.s2.assign(n, 0);
  scratch_.row_a.assign(static_cast<std::size_t>(geometry_.width), 0);
  scratch_.row_b.assign(static_cast<std::size_t>(geometry_.width), 0);
}

void WordBackend::check_field(const Field& f, const char* what) const {
  if (f.width < 1 || f.width > kMaxFieldBits || f.lo < 0 ||
      f.lo + f.width > geometry_.memory_bits) {
    throw std::out_of_range(std::string(what) + ": field [" + std::to_string(f.lo) + ", " +
                            std::to_string(f.lo + f.width) + ") outside pixel memory of " +
                            std::to_string(geometry_.memory_bits) + " bits");
  }
}

void WordBackend::load(const u64* lanes, const Field& f, Range r, u64* out, bool extend) const {
  const int lane = f.lo / 64;
  const int off = f.lo % 64;
  const int w = f.width;
  const u64 mask = low_mask(w);
  const u64* lo = lanes + static_cast<std::size_t>(lane) * pixels_;
  if (off + w <= 64) {
    for (int p = r.begin; p < r.end; ++p) out[p] = (lo[p] >> off) & mask;
  } else {
    const u64* hi = lo + pixels_;
    const int up = 64 - off;
    for (int p = r.begin; p < r.end; ++p) out[p] = ((lo[p] >> off) | (hi[p] << up)) & mask;
  }
  if (extend && f.is_signed && w < 64) {
    const int s = 64 - w;
    for (int p = r.begin; p < r.end; ++p)
      out[p] = static_cast<u64>(static_cast<i64>(out[p] << s) >> s);
  }
}

void WordBackend::store(u64* lanes, const Field& f, Range r, const u64* in, bool masked) {
  const int lane = f.lo / 64;
  const int off = f.lo % 64;
  const int w = f.width;
  const u64 mask = low_mask(w);
  u64* lo = lanes + static_cast<std::size_t>(lane) * pixels_;
  const std::uint8_t* e = enable_.data();
  const u64 lo_bits = mask << off;
  if (masked) {
    for (int p = r.begin; p < r.end; ++p) {
      const u64 m = lo_bits & (u64{0} - e[p]);
      lo[p] = (lo[p] & ~m) | ((in[p] << off) & m);
    }
  } else {
    for (int p = r.begin; p < r.end; ++p) lo[p] = (lo[p] & ~lo_bits) | ((in[p] << off) & lo_bits);
  }
  if (off + w > 64) {
    u64* hi = lo + pixels_;
    const int down = 64 - off;
    const u64 hi_bits = mask >> down;
    if (masked) {
      for (int p = r.begin; p < r.end; ++p) {
        const u64 m = hi_bits & (u64{0} - e[p]);
        hi[p] = (hi[p] & ~m) | ((in[p] >> down) & m);
      }
    } else {
      for (int p = r.begin; p < r.end; ++p)
        hi[p] = (hi[p] & ~hi_bits) | ((in[p] >> down) & hi_bits);
    }
  }
}

// Exact modulo 2^64 (hence modulo 2^result_bits): per call, the column terms A X^2 + D X and
// B X of the region's columns; per row, the row term C Y^2 + E Y + F; per pixel two adds and,
// only for a cross term, one multiply.
void WordBackend::prepare_columns(const QuadraticCoefficients& c) const {
  const u64 A = static_cast<u64>(c.A), B = static_cast<u64>(c.B), D = static_cast<u64>(c.D);
  u64* ta = scratch().row_a.data();
  u64* tb = scratch().row_b.data();
  for (int x = 0; x < geometry_.width; ++x) {
    const u64 X = static_cast<u64>(static_cast<i64>(x0_) + x);
    ta[x] = A * X * X + D * X;
    tb[x] = B * X;
  }
}

namespace {

// One row of for_each_value: the evaluator's value (column terms, the cross term when
// kCross, the row term), wrapped to result_bits (s = 64 - result_bits), shifted down by
// `shift` and cut to the field (sign-extended from its width when kSigned, sw = 64 -
// width, else masked): one pass over the pixels.
template <bool kSigned, bool kCross, class Sink>
void field_row(Sink sink, const u64* ta, const u64* tb, u64 Y, u64 row, int from, int to, int s,
               int shift, int sw, u64 mask) {
  for (int x = from; x < to; ++x) {
    u64 v = ta[x] + row;
    if constexpr (kCross) v += Y * tb[x];
    v = static_cast<u64>(static_cast<i64>(v << s) >> s);
    v = static_cast<u64>(static_cast<i64>(v) >> shift);
    if constexpr (kSigned) {
      v = static_cast<u64>(static_cast<i64>(v << sw) >> sw);
    } else {
      v &= mask;
    }
    sink(x, v);
  }
}

}  // namespace

template <class RowSink>
void WordBackend::for_each_value(const QuadraticCoefficients& c, Range r, int shift,
                                 const Field& as, RowSink row_sink) const {
  if (r.begin >= r.end) return;
  // Per row, the row term C Y^2 + E Y + F; per pixel the column terms, and only for a cross
  // term one multiply (exact modulo 2^64, hence modulo 2^result_bits); the value wrapped to
  // result_bits and sign-extended, shifted down by `shift` (bits at and above 64 copy the
  // sign, as the evaluator's planes above result_bits do) and cut to the field: one pass.
  const int width = geometry_.width;
  const u64 C = static_cast<u64>(c.C), E = static_cast<u64>(c.E), F = static_cast<u64>(c.F);
  const u64* ta = scratch().row_a.data();
  const u64* tb = scratch().row_b.data();
  const int s = 64 - evaluator_.result_bits;
  const int w = as.width;
  const bool sign = as.is_signed && w < 64;
  const int sw = sign ? 64 - w : 0;
  const u64 mask = low_mask(w);
  const bool cross = c.B != 0;
  for (int y = r.begin / width; y * width < r.end; ++y) {
    const u64 Y = static_cast<u64>(static_cast<i64>(y0_) + y);
    const u64 row = C * Y * Y + E * Y + F;
    const int from = std::max(r.begin - y * width, 0);
    const int to = std::min(r.end - y * width, width);
    const auto sink = row_sink(static_cast<std::size_t>(y) * width);
    if (sign) {
      if (cross) {
        field_row<true, true>(sink, ta, tb, Y, row, from, to, s, shift, sw, mask);
      } else {
        field_row<true, false>(sink, ta, tb, Y, row, from, to, s, shift, sw, mask);
      }
    } else if (cross) {
      field_row<false, true>(sink, ta, tb, Y, row, from, to, s, shift, sw, mask);
    } else {
      field_row<false, false>(sink, ta, tb, Y, row, from, to, s, shift, sw, mask);
    }
  }
}

void WordBackend::evaluate(const QuadraticCoefficients& c, Range r, u64* out) const {
  for_each_value(c, r, 0, Field{0, 64, false}, [out](std::size_t row_start) {
    return [o = out + row_start](int x, u64 v) { o[x] = v; };
  });
}

void WordBackend::expression_field(const QuadraticCoefficients& c, const Field& as, Range r,
                                   u64* out) const {
  for_each_value(c, r, std::min(fraction_bits_, 63), as, [out](std::size_t row_start) {
    return [o = out + row_start](int x, u64 v) { o[x] = v; };
  });
}

void WordBackend::enable_all() {
  write_loads();
  pending_.clear();  // E becomes all 1: no earlier test matters
  ones_ = true;      // filled by materialize(), over the spans the next tests leave
  spans_.assign(1, Range{0, pixels_});
}

void WordBackend::push_enable() {
  materialize();
  if (stack_top_ >= geometry_.enable_stack_depth) {
    throw std::overflow_error("enable stack overflow: depth " +
                              std::to_string(geometry_.enable_stack_depth));
  }
  own_enable();  // a level below that still shares E's bytes gets its copy now
  // The spans are saved now, the bytes when E's are first written (own_enable, or a compare
  // that writes the new E into the level's buffer and swaps): until then they are E's own.
  stack_spans_[static_cast<std::size_t>(stack_top_)] = spans_;
  shared_level_ = stack_top_;
  ++stack_top_;
}

std::uint8_t* WordBackend::level_bytes(int level) const {
  // Levels are allocated as the stack first reaches them (most programs use one or two of
  // the eight), so that a clone or kept state copies only those.
  std::vector<std::uint8_t>& saved = stack_[static_cast<std::size_t>(level)];
  if (saved.empty()) saved.resize(static_cast<std::size_t>(pixels_));
  return saved.data();
}

void WordBackend::own_enable() const {
  if (shared_level_ < 0) return;
  // E outside the saved spans is 0 whatever its bytes hold: only the spans are copied, as
  // whole 8-byte words, the spans rounded out to them (the array's size is a multiple of
  // 64): a short row is a word or two, not a library call; the bytes outside the spans are
  // copied too, and mean nothing there either.
  std::uint8_t* level = level_bytes(shared_level_);
  const std::uint8_t* e = enable_.data();
  for (const Range& r : stack_spans_[static_cast<std::size_t>(shared_level_)]) {
    for (int p = r.begin & ~7; p < r.end; p += 8) std::memcpy(level + p, e + p, 8);
  }
  shared_level_ = -1;
}

void WordBackend::pop_enable() {
  materialize();
  if (stack_top_ == 0) throw std::underflow_error("enable stack underflow");
  --stack_top_;
  if (shared_level_ == stack_top_) {
    // No E byte was written since the push: E's bytes are the level's, and only the spans
    // come back.
    shared_level_ = -1;
    spans_.swap(stack_spans_[static_cast<std::size_t>(stack_top_)]);
    return;
  }
  // The saved level becomes E, bytes and spans, by a swap rather than a copy: what E held
  // goes to the level, above the top now, which nothing reads before a push overwrites its
  // spans.
  enable_.swap(stack_[static_cast<std::size_t>(stack_top_)]);
  spans_.swap(stack_spans_[static_cast<std::size_t>(stack_top_)]);
}

void WordBackend::else_enable() {
  materialize();
  if (stack_top_ == 0) throw std::underflow_error("else without a saved enable");
  own_enable();
  const std::uint8_t* saved = stack_[static_cast<std::size_t>(stack_top_ - 1)].data();
  std::uint8_t* e = enable_.data();
  const std::vector<Range>& keep = stack_spans_[static_cast<std::size_t>(stack_top_ - 1)];
  // E <- saved & ~E over the saved level's spans (outside them the result is 0): where E's
  // own spans cover a pixel, saved & ~E; elsewhere E is 0 and the result is saved.
  auto cur = spans_.begin();
  for (const Range& r : keep) {
    int p = r.begin;
    while (p < r.end) {
      while (cur != spans_.end() && cur->end <= p) ++cur;
      if (cur == spans_.end() || cur->begin >= r.end) {
        std::copy(saved + p, saved + r.end, e + p);
        break;
      }
      if (cur->begin > p) {
        std::copy(saved + p, saved + cur->begin, e + p);
        p = cur->begin;
      }
      const int q = std::min(r.end, cur->end);
      for (; p < q; ++p) e[p] = saved[p] & (e[p] ^ 1);
    }
  }
  spans_ = keep;
}

bool WordBackend::enabled(int pixel) const {
  materialize();
  // The span holding the pixel, if any: the first that ends after it.
  const auto it = std::upper_bound(spans_.begin(), spans_.end(), pixel,
                                   [](int p, const Range& r) { return p < r.end; });
  return it != spans_.end() && it->begin <= pixel && enable_[static_cast<std::size_t>(pixel)] != 0;
}

int WordBackend::count_enabled() const {
  materialize();
  int n = 0;
  for (const Range& r : spans_) {
    for (int p = r.begin; p < r.end; ++p) n += enable_[static_cast<std::size_t>(p)];
  }
  return n;
}

namespace {

// quo = floor(n / d), rem = n - d quo (0 <= rem < d), for d > 0.
void floor_div_rem(std::int64_t n, std::int64_t d, std::int64_t& quo, std::int64_t& rem) {
  quo = n / d;
  rem = n % d;
  if (rem < 0) rem += d, --quo;
}

// A linear test's columns row by row: row y's columns where the condition holds are up to
// two intervals [a0, a1), [b0, b1). In an increasing coordinate u (u = x when D >= 0,
// u = width - 1 - x otherwise) the value is g(u) = g0 + s u with s >= 0: "< 0" holds for
// u < lt, "<= 0" for u < le. With n = -g0 = s q + m (floor division, 0 <= m < s), lt = q +
// (m != 0) and le = q + 1. From row y to y + 1, n falls by E = s qe + me: q and m follow by a
// subtraction and a borrow, with no division per row (one per jump to a row not following
// the last). In 64-bit integers: the caller checks fits_64 and that the values do not wrap.
class LinearRows {
 public:
  using T = std::int64_t;
  LinearRows() = default;
  LinearRows(const QuadraticCoefficients& c, Compare cond, int x0, int y0, int width)
      : c_(c), cond_(cond), x0_(x0), y0_(y0), width_(width), sl_(c.D >= 0 ? T(c.D) : -T(c.D)) {
    if (sl_ != 0) floor_div_rem(T(c.E), sl_, qe_, me_);
  }
  int a0 = 0, a1 = 0, b0 = 0, b1 = 0;
  void at(int y) {
    if (y == row_y_) return;
    int lt, le;
    if (sl_ == 0) {
      const T g0 = T(c_.E) * (y0_ + y) + T(c_.F);
      lt = g0 < 0 ? width_ : 0;
      le = g0 <= 0 ? width_ : 0;
    } else {
      if (y == row_y_ + 1 && row_y_ >= 0) {
        q_ -= qe_;
        m_ -= me_;
        if (m_ < 0) m_ += sl_, --q_;
      } else {
        const T f0 = T(c_.E) * (y0_ + y) + T(c_.F) + T(c_.D) * x0_;  // column 0
        const T g0 = c_.D >= 0 ? f0 : f0 + T(c_.D) * (width_ - 1);
        floor_div_rem(-g0, sl_, q_, m_);
      }
      lt = clamp_width(m_ != 0 ? q_ + 1 : q_);
      le = clamp_width(q_ + 1);
    }
    int u[4] = {0, 0, 0, 0};  // [u0, u1) and [u2, u3) in u
    switch (cond_) {
      case Compare::lt:
        u[1] = lt;
        break;
      case Compare::le:
        u[1] = le;
        break;
      case Compare::eq:
        u[0] = lt, u[1] = le;
        break;
      case Compare::ne:
        u[1] = lt, u[2] = le, u[3] = width_;
        break;
      case Compare::ge:
        u[0] = lt, u[1] = width_;
        break;
      case Compare::gt:
        u[0] = le, u[1] = width_;
        break;
    }
    if (c_.D >= 0) {
      a0 = u[0], a1 = u[1], b0 = u[2], b1 = u[3];
    } else {  // x = width - u: the intervals mirror, and swap order
      a0 = width_ - u[3], a1 = width_ - u[2], b0 = width_ - u[1], b1 = width_ - u[0];
      if (u[3] <= u[2]) a0 = a1 = 0;  // the second was empty
    }
    row_y_ = y;
  }

 private:
  int clamp_width(T v) const {
    return static_cast<int>(v < 0 ? T(0) : (v > T(width_) ? T(width_) : v));
  }
  QuadraticCoefficients c_{};
  Compare cond_ = Compare::ge;
  int x0_ = 0, y0_ = 0, width_ = 0;
  T sl_ = 0;
  T q_ = 0, m_ = 0, qe_ = 0, me_ = 0;
  int row_y_ = -1;
};

// A pending half-plane test (lt, le, gt, ge) with D != 0 as a bound on each row's columns:
// on row y the test holds exactly for x >= L (a lower bound) or for x < U (an upper one),
// with the bound floor(n(y) / d) + 1 clamped to [0, width], d = |D| and n(y) = s h(y) + c0,
// h(y) = D x0 + E (y0 + y) + F the value at the row's column 0:
//   D > 0:  g < 0: U, n = -h - 1    g <= 0: U, n = -h    g >= 0: L, n = -h - 1    g > 0: L, n = -h
//   D < 0:  g < 0: L, n = h         g <= 0: L, n = h - 1  g > 0: U, n = h - 1     g >= 0: U, n = h
// (with g(x) = D x + h: for D > 0, g < 0 iff x < ceil(-h / d) = floor((-h - 1) / d) + 1, and
// so on). From row y to y + 1, n changes by s E: the quotient and remainder follow by an add
// and a carry, with no division (one per jump to a row that does not follow the last). In
// 64-bit integers: fits_64 keeps |h| below 2^61.
class RowBound {
 public:
  using T = std::int64_t;
  RowBound() = default;
  RowBound(const QuadraticCoefficients& c, Compare cond, int x0, int y0, int width)
      : d_(c.D > 0 ? T(c.D) : -T(c.D)), width_(width), y0_(y0) {
    const bool up = c.D > 0;
    const bool below = cond == Compare::lt || cond == Compare::le;
    upper = up == below;
    s_ = up ? -1 : 1;
    // The -1: D > 0 with lt or ge, D < 0 with le or gt.
    c0_ = (up ? (cond == Compare::lt || cond == Compare::ge)
              : (cond == Compare::le || cond == Compare::gt))
              ? -1
              : 0;
    e_ = T(c.E);
    f_ = T(c.F) + T(c.D) * x0;
    floor_div_rem(s_ * e_, d_, qe_, re_);
  }
  bool upper = false;
  int at(int y) {
    if (y == y_ + 1 && y_ >= 0) {
      q_ += qe_;
      r_ += re_;
      const bool carry = r_ >= d_;
      r_ -= carry ? d_ : 0;
      q_ += carry;
    } else if (y != y_) {
      floor_div_rem(s_ * (e_ * (y0_ + y) + f_) + c0_, d_, q_, r_);
    }
    y_ = y;
    const T b = q_ + 1;
    return static_cast<int>(b < 0 ? T(0) : (b > T(width_) ? T(width_) : b));
  }

 private:
  T d_ = 1, s_ = 1, c0_ = 0, e_ = 0, f_ = 0;
  T q_ = 0, r_ = 0, qe_ = 0, re_ = 0;
  int width_ = 0, y0_ = 0;
  int y_ = -1;
};

}  // namespace

void WordBackend::settle_enable() const {
  if (!pending_.empty()) apply_pending();
  if (ones_) {  // after the tests: only the spans they left are filled
    own_enable();
    for (const Range& r : spans_) std::fill(enable_.begin() + r.begin, enable_.begin() + r.end, 1);
    ones_ = false;
  }
}

void WordBackend::apply_pending() const {
  const int width = geometry_.width;
  int lo = 0, hi = geometry_.height - 1;
  const std::size_t n = pending_.size();
  linear_row_band(pending_.data(), n, x0_, y0_, width, geometry_.height, lo, hi);
  bool sloped = true;  // every test has D != 0 (a row bound)
  for (std::size_t k = 0; k < n; ++k) sloped = sloped && pending_[k].c.D != 0;
  std::vector<Range>& kept = spare_spans_;
  kept.clear();
  if (sloped) {
    // The bounds, lower ones first: each row's part is [max of L, min of U) within the span.
    std::array<RowBound, kMaxPending> bounds;
    std::size_t lower = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const RowBound b(pending_[k].c, pending_[k].cond, x0_, y0_, width);
      if (!b.upper) bounds[lower++] = b;
    }
    std::size_t m = lower;
    for (std::size_t k = 0; k < n; ++k) {
      const RowBound b(pending_[k].c, pending_[k].cond, x0_, y0_, width);
      if (b.upper) bounds[m++] = b;
    }
    pending_.clear();
    // At most one part per row of each span within the band: written through a pointer (no
    // push_back per row), the vector cut to what was written.
    std::size_t most = 0;
    for (const Range& sp : spans_) {
      const int first = std::max(sp.begin / width, lo);
      const int last = std::min((sp.end - 1) / width, hi);
      if (last >= first) most += static_cast<std::size_t>(last - first + 1);
    }
    kept.resize(most);
    Range* out = kept.data();
    for (const Range& sp : spans_) {
      const int first = std::max(sp.begin / width, lo);
      for (int y = first; y * width < sp.end && y <= hi; ++y) {
        const int start = y * width;
        int from = std::max(sp.begin - start, 0), to = std::min(sp.end - start, width);
        for (std::size_t k = 0; k < lower; ++k) from = std::max(from, bounds[k].at(y));
        for (std::size_t k = lower; k < n; ++k) to = std::min(to, bounds[k].at(y));
        if (to > from) *out++ = Range{start + from, start + to};
      }
    }
    kept.resize(static_cast<std::size_t>(out - kept.data()));
    spans_.swap(kept);
    return;
  }
  std::array<LinearRows, kMaxPending> tests;
  for (std::size_t k = 0; k < n; ++k) {
    const LinearTest& t = pending_[k];
    tests[k] = LinearRows(t.c, t.cond, x0_, y0_, width);
  }
  pending_.clear();
  for (const Range& sp : spans_) {
    const int first = std::max(sp.begin / width, lo);
    for (int y = first; y * width < sp.end && y <= hi; ++y) {
      const int start = y * width;
      int from = std::max(sp.begin, start), to = std::min(sp.end, start + width);
      for (std::size_t k = 0; k < n; ++k) {
        LinearRows& t = tests[k];
        t.at(y);
        // One interval: [a0, a1), or [b0, b1) when D < 0 mirrors it there.
        const bool a = t.a1 > t.a0;
        from = std::max(from, start + (a ? t.a0 : t.b0));
        to = std::min(to, start + (a ? t.a1 : t.b1));
        if (to <= from) break;
      }
      if (to > from) kept.push_back({from, to});
    }
  }
  spans_.swap(kept);
}

bool WordBackend::qtest_linear(const QuadraticCoefficients& c, Compare cond) {
  using i128 = __int128;
  if (!c.is_linear()) return false;
  if (spans_.empty()) return true;
  const int width = geometry_.width;
  const int R = evaluator_.result_bits;
  const i128 lo = -(i128(1) << (R - 1)), hi = (i128(1) << (R - 1)) - 1;
  // Rows of the spans before any pending test: a superset of the rows after them.
  const int first = spans_.front().begin / width, last = (spans_.back().end - 1) / width;
  // The value is linear: exact (no wrap) over the band of rows when it is at its corners.
  for (const int y : {first, last}) {
    const i128 row = i128(c.E) * (y0_ + y) + c.F;
    for (const int x : {0, width - 1}) {
      const i128 v = row + i128(c.D) * (x0_ + x);
      if (v < lo || v > hi) return false;
    }
  }
  // The row walk is in 64-bit integers: every term it forms (and so every value, quotient
  // and remainder) must stay below 2^61 in magnitude. Coefficients that large go the general
  // way (qtest's per-pixel evaluation), which is exact for any.
  if (!fits_64(c, y0_, x0_, width, geometry_.height)) return false;
  if (one_interval(cond) && pending_.size() < kMaxPending) {
    pending_.push_back({c, cond});
    return true;
  }
  materialize();
  std::vector<Range>& kept = spare_spans_;  // becomes spans_; the old spans become the spare
  kept.clear();
  LinearRows rows(c, cond, x0_, y0_, width);
  // Within a segment [from, to) of row y: what lies inside the row's intervals stays a
  // span, the rest leaves the spans (and so is 0, whatever E's bytes there hold).
  for (const Range& sp : spans_) {
    for (int y = sp.begin / width; y * width < sp.end; ++y) {
      rows.at(y);
      const int start = y * width;
      const int from = std::max(sp.begin, start), to = std::min(sp.end, start + width);
      const int k0 = std::max(from, start + rows.a0), k1 = std::min(to, start + rows.a1);
      if (k1 > k0) kept.push_back({k0, k1});
      const int l0 = std::max(from, start + rows.b0), l1 = std::min(to, start + rows.b1);
      if (l1 > l0) kept.push_back({l0, l1});
    }
  }
  spans_.swap(kept);
  return true;
}

void WordBackend::qtest(const QuadraticCoefficients& expr, Compare cond) {
  write_loads();  // before a test joins the pending ones
  if (qtest_linear(expr, cond)) return;
  // The pending tests narrow the spans first. E's bytes after eall (ones_) wait on: a
  // quadratic test that narrows the spans exactly reads none of them (every pixel of the
  // spans is enabled), and they are then filled over only what it leaves (a sphere's disc,
  // not the region).
  if (!pending_.empty()) apply_pending();
  if (qtest_quadratic(expr, cond)) return;
  materialize();
  own_enable();
  prepare_columns(expr);
  u64* v = scratch().s0.data();
  // As for a linear test, the spans narrow to what the test leaves: on each row of a span,
  // from its first pixel with E = 1 to its last (a sphere's disc, not the region, for every
  // instruction after it).
  for (const Range& r : spans_) {
    evaluate(expr, r, v);
    and_compare(
        enable_.data(), v, [](int) { return i64{0}; }, cond, r.begin, r.end);
  }
  narrow_spans();
}

namespace {

// The first pixel in [from, to) whose E byte is set, else `to`; the last one plus one, else
// `from`. Eight bytes at a time.
int first_enabled(const std::uint8_t* e, int from, int to) {
  while (from < to && (from & 7) != 0) {
    if (e[from] != 0) return from;
    ++from;
  }
  for (; from + 8 <= to; from += 8) {
    std::uint64_t w;
    std::memcpy(&w, e + from, 8);
    if (w != 0) return from + __builtin_ctzll(w) / 8;  // little-endian: the lowest byte first
  }
  for (; from < to; ++from) {
    if (e[from] != 0) return from;
  }
  return to;
}

int end_of_enabled(const std::uint8_t* e, int from, int to) {
  while (to > from && (to & 7) != 0) {
    if (e[to - 1] != 0) return to;
    --to;
  }
  for (; to - 8 >= from; to -= 8) {
    std::uint64_t w;
    std::memcpy(&w, e + to - 8, 8);
    if (w != 0) return to - __builtin_clzll(w) / 8;
  }
  for (; to > from; --to) {
    if (e[to - 1] != 0) return to;
  }
  return from;
}

}  // namespace

void WordBackend::keep_enabled(std::vector<Range>& kept, int from, int to) const {
  const std::uint8_t* e = enable_.data();
  const int a = first_enabled(e, from, to);
  if (a == to) return;
  word_rows::keep_span(kept, a, end_of_enabled(e, a, to));
}

void WordBackend::narrow_spans() {
  std::vector<Range>& kept = spare_spans_;
  kept.clear();
  for_each_span_row([&](int, std::size_t row_start, int from, int to) {
    const int start = static_cast<int>(row_start);
    keep_enabled(kept, start + from, start + to);
  });
  spans_.swap(kept);
}

namespace {

// Where a condition that holds as at `same` and not at `other` switches between them, the
// condition switching once on the way (monotone): the point nearest `same` where it no longer
// holds as there. is_same(x) tells whether it holds at x as at `same`. With a hint strictly
// between the two (the switch point of the row before, which a disc's edge leaves near),
// the search starts there and steps away from it by 1, 2, 4, ... until the switch is
// bracketed, then halves the bracket: a point that moves by a few columns from row to row
// is found in a few evaluations instead of log2 of the row's length. The point found is the
// same with or without the hint (there is one switch).
template <class IsSame>
int switch_point(int same, int other, int hint, IsSame is_same) {
  const int dir = other > same ? 1 : -1;
  if ((hint - same) * dir > 0 && (other - hint) * dir > 0) {
    if (is_same(hint)) {
      same = hint;
      for (int step = 1;; step *= 2) {
        const int probe = same + dir * step;
        if ((other - probe) * dir <= 0) break;
        if (!is_same(probe)) {
          other = probe;
          break;
        }
        same = probe;
      }
    } else {
      other = hint;
      for (int step = 1;; step *= 2) {
        const int probe = other - dir * step;
        if ((probe - same) * dir <= 0) break;
        if (is_same(probe)) {
          same = probe;
          break;
        }
        other = probe;
      }
    }
  }
  while ((other - same) * dir > 1) {
    const int mid = same + (other - same) / 2;
    (is_same(mid) ? same : other) = mid;
  }
  return other;
}

// One row part [first, last] of a quadratic qtest (qtest_quadratic): g(x) = (a x + b) x + k
// in integers of type T (wide enough for every value formed), the condition `below` (g < 0,
// or g <= 0 when not strict) or above (g > 0, g >= 0). The integer arg-extremum m (the
// minimum when a > 0, the maximum when a < 0) is the floor or the ceiling of the vertex
// -b / 2a, clamped; g is monotone on [first, m] and on [m, last] over the integers (linear,
// a = 0: monotone throughout, m = first), and so is the condition on each side. Sets
// `at_m`, whether it holds at m, `left`, the last column left of m where it does not hold as
// at m (first - 1 if none), and `right`, the first right of m (last + 1 if none), each found
// by switch_point from the hints (the row before's left and right; any value without one).
// False when g leaves [lo, hi] (the value wraps): g's extremes over the integers of the part
// are at its ends and at m.
template <class T>
bool quadratic_row(T a, T b, T k, int first, int last, T lo, T hi, bool below, bool strict,
                   bool& at_m, int& left, int& right, int hint_left = -1, int hint_right = -1) {
  auto g = [a, b, k](int x) { return (a * x + b) * x + k; };
  auto holds_at = [below, strict](T v) {
    return below ? (strict ? v < 0 : v <= 0) : (strict ? v > 0 : v >= 0);
  };
  int m = first;
  T gm = 0;
  if (a != 0) {
    T num = -b, den = 2 * a;
    if (den < 0) num = -num, den = -den;
    T vertex = num / den;
    if (num % den != 0 && num < 0) --vertex;  // floor
    auto clamp = [first, last](T v) {
      return static_cast<int>(v < first ? T(first) : v > last ? T(last) : v);
    };
    const int m0 = clamp(vertex), m1 = clamp(vertex + 1);
    const T g0 = g(m0), g1 = g(m1);
    const bool second = a > 0 ? g1 < g0 : g1 > g0;
    m = second ? m1 : m0;
    gm = second ? g1 : g0;
  } else {
    gm = g(first);
  }
  const T gl = g(first), gr = g(last);
  if (gl < lo || gl > hi || gr < lo || gr > hi || gm < lo || gm > hi) return false;
  at_m = holds_at(gm);
  // Right of m: [m, right) where the condition is as at m, [right, last] where it is not.
  auto as_at_m = [&](int x) { return holds_at(g(x)) == at_m; };
  right = last + 1;
  if (holds_at(gr) != at_m) right = switch_point(m, last, hint_right, as_at_m);
  // Left of m: [first, left] where it is not as at m, (left, m] where it is.
  left = first - 1;
  if (holds_at(gl) != at_m) left = switch_point(m, first, hint_left, as_at_m);
  return true;
}

}  // namespace

bool WordBackend::qtest_quadratic(const QuadraticCoefficients& c, Compare cond) {
  using i128 = __int128;
  if (!one_interval(cond)) return false;
  if (spans_.empty()) return true;
  const int width = geometry_.width;
  if (width > (1 << 28)) return false;  // below: |a x^2| < 2^63 2^56, exact in 128 bits
  const int R = evaluator_.result_bits;
  const int s = 64 - R;
  // v modulo 2^R, as the value in [-2^(R-1), 2^(R-1)) it is congruent to.
  auto wrap = [s](u64 v) { return static_cast<i64>(v << s) >> s; };
  const bool below = cond == Compare::lt || cond == Compare::le;
  const bool strict = cond == Compare::lt || cond == Compare::gt;
  // On row y, with X = x0 + x: A X^2 + (B Y + D) X + (C Y^2 + E Y + F) = a x^2 + b x + k with
  // a = A, b = 2 A x0 + B Y + D, k = A x0^2 + (B Y + D) x0 + C Y^2 + E Y + F. Modulo 2^R (all
  // the evaluator keeps) each of a, b, k may be replaced by its residue in [-2^(R-1),
  // 2^(R-1)) (x^2, x and 1 are integers), formed modulo 2^64 as the evaluator forms the
  // value. Where the exact value of g(x) = a x^2 + b x + k, so reduced, lies within
  // result_bits at every column of a row part, it is the value the evaluator delivers there.
  // In 64-bit integers when every value formed (|a| (w^2 + w) + |b| w + |k| < 2^(R-1) 4 w^2,
  // the vertex's 2a) stays below 2^62, else in 128.
  const u64 A = static_cast<u64>(c.A), B = static_cast<u64>(c.B), C = static_cast<u64>(c.C),
            D = static_cast<u64>(c.D), E = static_cast<u64>(c.E), F = static_cast<u64>(c.F);
  const u64 X0 = static_cast<u64>(static_cast<i64>(x0_));
  const i64 a = wrap(A);
  int width_bits = 0;
  while ((1 << width_bits) < width) ++width_bits;
  const bool narrow = R - 1 + 2 + 2 * width_bits <= 62;
  const i64 lo = R == 64 ? std::numeric_limits<i64>::min() : -(i64{1} << (R - 1)), hi = -(lo + 1);
  // The band of rows that can hold the test at all (a sphere's outline: its disc's rows).
  // Over the region, with local x, y, the value is, modulo 2^R, the polynomial
  // a x^2 + B' x y + c y^2 + d x + e y + f whose coefficients are the residues of
  // A, B, C, 2 A x0 + B y0 + D, 2 C y0 + B x0 + E and the value at (x0, y0). Where it stays
  // within result_bits over the whole region (bounded term by term), it is the value the
  // evaluator delivers at every pixel. If the form is definite (B'^2 < 4ac) and the test
  // keeps the side of the rows' extremum (a < 0 with gt or ge, a > 0 with lt or le), a row
  // can hold the test only where its real extremum is on that side: where the discriminant
  // (B' y + d)^2 - 4a (c y^2 + e y + f) >= 0, a concave quadratic in y, so an interval of
  // rows, found by quadratic_row. The other rows leave the spans without a look.
  int band_lo = 0, band_hi = geometry_.height - 1;
  {
    const u64 Y0 = static_cast<u64>(static_cast<i64>(y0_));
    const i128 ca = a, cb = wrap(B), cc = wrap(C), cd = wrap(2 * A * X0 + B * Y0 + D),
               ce = wrap(2 * C * Y0 + B * X0 + E),
               cf = wrap((A * X0 + B * Y0 + D) * X0 + (C * Y0 + E) * Y0 + F);
    auto mag = [](i128 v) { return v < 0 ? -v : v; };
    const i128 W = width - 1, H = geometry_.height - 1;
    // Coefficients below 2^48 and at most 4096 rows keep every product below in 128 bits.
    const i128 limit = i128{1} << 48;
    const bool small = H < 4096 && mag(ca) < limit && mag(cb) < limit && mag(cc) < limit &&
                       mag(cd) < limit && mag(ce) < limit && mag(cf) < limit;
    const i128 bound = small ? mag(ca) * W * W + mag(cb) * W * H + mag(cc) * H * H + mag(cd) * W +
                                   mag(ce) * H + mag(cf)
                             : i128{hi} + 1;
    const i128 disc = small ? cb * cb - 4 * ca * cc : 0;
    if (bound <= i128{hi} && disc < 0 && (ca < 0) != below) {
      // D(y) = disc y^2 + (2 B' d - 4 a e) y + (d^2 - 4 a f): coefficients below 2^99, values
      // at y < 4096 below 2^124.
      bool holds = false;
      int left = 0, right = 0;
      const i128 huge = i128{1} << 120;
      quadratic_row<i128>(disc, 2 * cb * cd - 4 * ca * ce, cd * cd - 4 * ca * cf, 0,
                          geometry_.height - 1, -huge, huge, false, false, holds, left, right);
      if (!holds) {  // no row can hold it
        spans_.clear();
        return true;
      }
      band_lo = left + 1;
      band_hi = right - 1;
    }
  }
  std::vector<Range>& kept = spare_spans_;  // becomes spans_ (the old ones the spare)
  kept.clear();
  bool exact = true;
  int row_y = -1;
  i64 b = 0, k = 0;
  int left_before = -1, right_before = -1;
  for_each_span_row([&](int y, std::size_t row_start, int from, int to) {
    if (!exact || y < band_lo || y > band_hi) return;
    if (y != row_y) {
      const u64 Y = static_cast<u64>(static_cast<i64>(y0_) + y);
      const u64 linear = B * Y + D;
      b = wrap(2 * A * X0 + linear);
      k = wrap((A * X0 + linear) * X0 + (C * Y + E) * Y + F);
      row_y = y;
    }
    bool at_m = false;
    int left = 0, right = 0;
    const int first = from, last = to - 1;
    // The row before's switch points as hints (same results, found sooner).
    const int hint_left = left_before, hint_right = right_before;
    exact = narrow ? quadratic_row<i64>(a, b, k, first, last, lo, hi, below, strict, at_m, left,
                                        right, hint_left, hint_right)
                   : quadratic_row<i128>(a, b, k, first, last, lo, hi, below, strict, at_m, left,
                                         right, hint_left, hint_right);
    if (!exact) return;
    left_before = left;
    right_before = right;
    const int start = static_cast<int>(row_start);
    // Pixels [a, b) where the test holds, trimmed to E's first to last enabled pixel, or as
    // they are while E is 1 throughout the spans (ones_).
    auto keep = [&](int a, int b) {
      if (!ones_) {
        keep_enabled(kept, a, b);
      } else if (a < b) {
        word_rows::keep_span(kept, a, b);
      }
    };
    if (at_m) {
      keep(start + left + 1, start + right);
    } else {  // the row's ends, each when not empty (most rows outside a sphere's disc: both)
      if (left >= first) keep(start + first, start + left + 1);
      if (right <= last) keep(start + right, start + last + 1);
    }
  });
  if (!exact) return false;
  spans_.swap(kept);
  return true;
}

void WordBackend::qload(const Field& dst, const QuadraticCoefficients& expr) {
  check_field(dst, "assign");
  const int off = dst.lo % 64;
  if (off + dst.width > 64) {  // the field straddles two lanes
    materialize();
    prepare_columns(expr);
    for (const Range& r : spans_) {
      expression_field(expr, dst, r, scratch().s0.data());
      store(memory_.data(), dst, r, scratch().s0.data(), true);
    }
    return;
  }
  queue_load({dst, expr, false});
}

void WordBackend::queue_load(const PendingLoad& load) {
  // Waits with the ones before it (loads_): E settled now stays as it is until they are
  // written.
  settle_enable();
  if (loads_.size() == kMaxLoads) apply_loads();
  loads_.push_back(load);
}

template <class F>
void WordBackend::for_each_span_row(F f) const {
  const int width = geometry_.width;
  int y = 0;
  int row_start = 0;
  for (const Range& r : spans_) {
    if (r.begin >= r.end) continue;
    if (r.begin < row_start || r.begin - row_start >= 2 * width) {
      y = r.begin / width;
      row_start = y * width;
    } else if (r.begin - row_start >= width) {
      ++y;
      row_start += width;
    }
    int from = r.begin - row_start;
    for (;;) {
      f(y, static_cast<std::size_t>(row_start), from, std::min(r.end - row_start, width));
      if (r.end <= row_start + width) break;
      ++y;
      row_start += width;
      from = 0;
    }
  }
}

// qload_lane's and qcmp_lane's value at a pixel, as for_each_value gives it (modulo 2^64
// the same sum: ((A X + (D + B Y)) X + (C Y^2 + E Y + F)), wrapped to result_bits, shifted
// down by the fraction): the row's terms once per row, two adds and a multiply per pixel
// (two multiplies with a square term).
struct WordBackend::PixelValues {
  PixelValues() = default;
  PixelValues(const QuadraticCoefficients& c, int x0, int y0, int result_bits, int fraction_bits)
      : A(static_cast<u64>(c.A)),
        B(static_cast<u64>(c.B)),
        C(static_cast<u64>(c.C)),
        D(static_cast<u64>(c.D)),
        E(static_cast<u64>(c.E)),
        F(static_cast<u64>(c.F)),
        X0(static_cast<u64>(static_cast<i64>(x0))),
        y0(y0),
        s(64 - result_bits),
        shift(std::min(fraction_bits, 63)) {}
  struct Row {
    u64 row, linear;
  };
  Row row(int y) const {
    const u64 Y = static_cast<u64>(static_cast<i64>(y0) + y);
    return {C * Y * Y + E * Y + F, D + B * Y};
  }
  // The screen columns of the eight pixels base + [0, 8) of a row.
  V8 columns8(int base) const {
    const V8s iota = {0, 1, 2, 3, 4, 5, 6, 7};
    return X0 + static_cast<u64>(base) + reinterpret_cast<V8>(iota);
  }
  // The value at the eight pixels of a row whose columns are X, lane by lane.
  template <bool kSquare>
  V8 value8(const Row& r, const V8& X) const {
    return finish(kSquare ? (A * X + r.linear) * X + r.row : r.linear * X + r.row, s, shift);
  }
  // A sum modulo 2^64 as the evaluator delivers it: wrapped to result_bits (sign_shift =
  // 64 - result_bits) and sign-extended, then shifted down by the fraction.
  static V8 finish(V8 v, int sign_shift, int shift) {
    v = reinterpret_cast<V8>(reinterpret_cast<V8s>(v << sign_shift) >> sign_shift);
    return reinterpret_cast<V8>(reinterpret_cast<V8s>(v) >> shift);
  }
  // The value at the eight pixels base + [0, 8) of the row.
  template <bool kSquare>
  V8 at8(const Row& r, int base) const {
    return value8<kSquare>(r, columns8(base));
  }
  u64 A = 0, B = 0, C = 0, D = 0, E = 0, F = 0, X0 = 0;
  int y0 = 0, s = 0, shift = 0;
};

// The waiting writes (loads_) in one walk over the spans: per eight pixels E is read once,
// and each lane they write is read and stored once, the writes to it merged in their order
// between (only a field's own bits, so its signedness does not matter here), then the lane
// merged under E. A qload's value is as for_each_value computes it (modulo 2^64 the same
// sum); a mov's constant is the same at every pixel, so consecutive constants into a lane
// merge into one mask and value before the walk, and a run of constants alone walks the
// spans as they are rather than row by row.
void WordBackend::apply_loads() const {
  const std::size_t n = loads_.size();
  // Each lane's writes in their order (a later one wins where two overlap); a run of
  // constants within a lane is one term.
  // plane: A = B = 0, so that the value steps by D from pixel to pixel on every row.
  enum class Kind { constant, plane, linear, square };
  struct Term {
    Kind kind;
    PixelValues values;
    u64 bits;   // the field's bits in the lane
    u64 value;  // a constant's bits in the lane (within `bits`)
    int off;
    PixelValues::Row row;
  };
  struct LaneGroup {
    u64* lane;
    std::size_t begin, end;  // terms[begin, end)
  };
  std::array<std::size_t, kMaxLoads> order;
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  std::stable_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
                   [this](std::size_t a, std::size_t b) {
                     return loads_[a].dst.lo / 64 < loads_[b].dst.lo / 64;
                   });
  std::array<Term, kMaxLoads> terms;
  std::array<LaneGroup, kMaxLoads> groups;
  std::size_t term_count = 0, group_count = 0;
  bool all_constant = true;
  for (std::size_t k = 0; k < n; ++k) {
    const PendingLoad& l = loads_[order[k]];
    const int off = l.dst.lo % 64;
    const u64 bits = low_mask(l.dst.width) << off;
    u64* lane = memory_.data() + static_cast<std::size_t>(l.dst.lo / 64) * pixels_;
    if (group_count == 0 || groups[group_count - 1].lane != lane) {
      groups[group_count++] = {lane, term_count, term_count};
    }
    LaneGroup& g = groups[group_count - 1];
    if (l.constant) {
      const u64 value = (static_cast<u64>(l.c.F) << off) & bits;
      if (g.end > g.begin && terms[g.end - 1].kind == Kind::constant) {
        Term& t = terms[g.end - 1];  // the constant before it in this lane: one mask and value
        t.value = (t.value & ~bits) | value;
        t.bits |= bits;
        continue;
      }
      terms[term_count++] = {Kind::constant, PixelValues(), bits, value, off, {}};
    } else {
      all_constant = false;
      terms[term_count++] = {l.c.A != 0   ? Kind::square
                             : l.c.B != 0 ? Kind::linear
                                          : Kind::plane,
                             PixelValues(l.c, x0_, y0_, evaluator_.result_bits, fraction_bits_),
                             bits,
                             0,
                             off,
                             {}};
    }
    ++g.end;
  }
  loads_.clear();
  const std::uint8_t* e = enable_.data();
  // One lane's writes at the eight pixels from base, merged under E (k).
  auto merge = [&](const LaneGroup& g, std::size_t base, const V8& k, auto value) {
    u64* m = g.lane + base;
    const V8 old = load8(m);
    V8 word = old;
    for (std::size_t t = g.begin; t < g.end; ++t) {
      const Term& l = terms[t];
      word = (word & ~l.bits) | value(l);
    }
    store8(m, (old & ~k) | (word & k));
  };
  if (all_constant) {
    for (const Range& r : spans_) {
      for_chunks(r.begin, r.end, pixels_, [&](int base, const V8& live) {
        const V8 k = (V8{} - load_enable8(e + base)) & live;
        for (std::size_t g = 0; g < group_count; ++g) {
          merge(groups[g], static_cast<std::size_t>(base), k,
                [](const Term& l) { return V8{} + l.value; });
        }
      });
    }
    return;
  }
  const int width = geometry_.width;
  PixelValues columns;  // any expression's: the columns are the region's
  for (std::size_t t = 0; t < term_count; ++t) {
    if (terms[t].kind != Kind::constant) columns = terms[t].values;
  }
  if (term_count == 1) {
    // A single qload (a sphere's, between other instructions): its square term compiled in
    // or out, no loop over terms.
    auto walk_one = [&](auto square) {
      constexpr bool kSquare = decltype(square)::value;
      const Term& l = terms[0];
      u64* lane = groups[0].lane;
      for_each_span_row([&](int y, std::size_t row_start, int from, int to) {
        const PixelValues::Row r = l.values.row(y);
        u64* m = lane + row_start;
        const std::uint8_t* en = e + row_start;
        for_chunks(from, to, width, [&](int base, const V8& live) {
          const V8 v = l.values.at8<kSquare>(r, base);
          const V8 k = l.bits & (V8{} - load_enable8(en + base)) & live;
          const V8 old = load8(m + base);
          store8(m + base, (old & ~k) | ((v << l.off) & k));
        });
      });
    };
    terms[0].kind == Kind::square ? walk_one(std::true_type{}) : walk_one(std::false_type{});
    return;
  }
  // A run (a triangle's attributes, planes): a plane's value along a chunk is its value at the
  // chunk's first pixel (one scalar multiply) plus D times [0, 8) (made once), not a vector
  // multiply per chunk. Every expression shares the evaluator's width and fraction.
  const int sign_shift = 64 - evaluator_.result_bits, shift = std::min(fraction_bits_, 63);
  const V8s iota = {0, 1, 2, 3, 4, 5, 6, 7};
  std::array<V8, kMaxLoads> steps;
  for (std::size_t t = 0; t < term_count; ++t) {
    if (terms[t].kind == Kind::plane) steps[t] = terms[t].values.D * reinterpret_cast<V8>(iota);
  }
  std::array<u64, kMaxLoads> at_x0;  // a plane's value at the region's column 0 on the row
  for_each_span_row([&](int y, std::size_t row_start, int from, int to) {
    for (std::size_t t = 0; t < term_count; ++t) {
      Term& l = terms[t];
      if (l.kind == Kind::constant) continue;
      l.row = l.values.row(y);
      at_x0[t] = l.row.row + l.row.linear * l.values.X0;
    }
    const std::uint8_t* en = e + row_start;
    for_chunks(from, to, width, [&](int base, const V8& live) {
      const V8 k = (V8{} - load_enable8(en + base)) & live;
      const V8 X = columns.columns8(base);
      for (std::size_t g = 0; g < group_count; ++g) {
        merge(groups[g], row_start + static_cast<std::size_t>(base), k, [&](const Term& l) {
          const auto t = static_cast<std::size_t>(&l - terms.data());
          V8 v;
          switch (l.kind) {
            case Kind::constant:
              return V8{} + l.value;
            case Kind::plane:
              v = (at_x0[t] + l.row.linear * static_cast<u64>(base)) + steps[t];
              break;
            case Kind::linear:
              v = l.row.linear * X + l.row.row;
              break;
            default:
              v = (l.values.A * X + l.row.linear) * X + l.row.row;
              break;
          }
          return (PixelValues::finish(v, sign_shift, shift) << l.off) & l.bits;
        });
      }
    });
  });
}

// E &= (value cond field), both cut to the field's width and extended by its signedness
// (as expression_field and load give them to compare_values), in one pass. The condition
// as three flags: (less and lt) or (equal and eq), inverted when inv.
template <bool kSquare, bool kSigned>
void WordBackend::qcmp_lane(const Field& field, const QuadraticCoefficients& c, Compare cond) {
  const PixelValues values(c, x0_, y0_, evaluator_.result_bits, fraction_bits_);
  const int off = field.lo % 64;
  const int sw = 64 - field.width;
  const u64 mask = low_mask(field.width);
  const u64* lane = memory_.data() + static_cast<std::size_t>(field.lo / 64) * pixels_;
  std::uint8_t* e = enable_.data();
  const ChunkCompare test(cond);
  const int width = geometry_.width;
  // Each row's part narrowed (as narrow_spans does) as soon as it is compared, skipped when
  // the pass found no pixel left.
  std::vector<Range>& kept = spare_spans_;
  kept.clear();
  for_each_span_row([&](int y, std::size_t row_start, int from, int to) {
    const PixelValues::Row r = values.row(y);
    const u64* m = lane + row_start;
    std::uint8_t* en = e + row_start;
    RowEnabled row;
    for_chunks(from, to, width, [&](int base, const V8& live) {
      V8 v = values.at8<kSquare>(r, base);
      V8 f = (load8(m + base) >> off) & mask;
      if constexpr (kSigned) {
        v = reinterpret_cast<V8>(reinterpret_cast<V8s>(v << sw) >> sw);
        f = reinterpret_cast<V8>(reinterpret_cast<V8s>(f << sw) >> sw);
      } else {
        v &= mask;
      }
      test.apply(en, base, live, reinterpret_cast<V8s>(v), reinterpret_cast<V8s>(f), row);
    });
    row.keep(kept, static_cast<int>(row_start));
  });
  spans_.swap(kept);
}

void WordBackend::qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) {
  materialize();
  own_enable();
  check_field(field, "operand");
  const bool wide = !field.is_signed && field.width == 64;
  if (!wide && field.lo % 64 + field.width <= 64) {
    const bool square = expr.A != 0;
    if (field.is_signed) {
      square ? qcmp_lane<true, true>(field, expr, cond) : qcmp_lane<false, true>(field, expr, cond);
    } else {
      square ? qcmp_lane<true, false>(field, expr, cond)
             : qcmp_lane<false, false>(field, expr, cond);
    }
    return;
  }
  prepare_columns(expr);
  for (const Range& r : spans_) {
    expression_field(expr, field, r, scratch().s0.data());
    load(memory_.data(), field, r, scratch().s1.data(), true);
    compare_values(scratch().s0.data(), wide, scratch().s1.data(), wide, cond, r);
  }
  narrow_spans();
}

void WordBackend::compare_values(const u64* a, bool a_unsigned64, const u64* b, bool b_unsigned64,
                                 Compare cond, Range r) {
  std::uint8_t* e = enable_.data();
  if (!a_unsigned64 && !b_unsigned64) {
    and_compare(
        e, a, [b](int p) { return static_cast<i64>(b[p]); }, cond, r.begin, r.end);
  } else {
    // A 64-bit unsigned field does not fit int64: compare as 65-bit values.
    using i128 = __int128;
    for (int p = r.begin; p < r.end; ++p) {
      const i128 x = a_unsigned64 ? i128(a[p]) : i128(static_cast<i64>(a[p]));
      const i128 y = b_unsigned64 ? i128(b[p]) : i128(static_cast<i64>(b[p]));
      e[p] &= holds(cond, x, y) ? 1 : 0;
    }
  }
  enable_changed();
}

// E &= (a cond b) for a field a within one lane and b a constant or a field within one lane,
// each read as load gives it (sign-extended when signed; neither is a 64-bit unsigned field,
// so a signed 64-bit comparison is exact), eight pixels at a time; each row's part narrowed
// as soon as it is compared (RowEnabled). read_b(base) gives b at the eight pixels.
template <class ReadB>
void WordBackend::compare_lane(const Field& a, Compare cond, ReadB read_b) {
  const int off = a.lo % 64;
  const int sw = 64 - a.width;
  const u64 mask = low_mask(a.width);
  const bool is_signed = a.is_signed;
  const u64* lane = memory_.data() + static_cast<std::size_t>(a.lo / 64) * pixels_;
  // Right after an epush whose level still shares E's bytes (a clamp: epush, cmp, mov,
  // epop), the new E is written into the level's buffer, read from E's, and the two
  // swapped: the level keeps the old bytes without a copy of them.
  const bool into_level = shared_level_ >= 0;
  const std::uint8_t* e_from = enable_.data();
  std::uint8_t* e_to = into_level ? level_bytes(shared_level_) : enable_.data();
  const ChunkCompare test(cond);
  const int width = geometry_.width;
  std::vector<Range>& kept = spare_spans_;
  kept.clear();
  for_each_span_row([&](int, std::size_t row_start, int from, int to) {
    const std::uint8_t* en_from = e_from + row_start;
    std::uint8_t* en_to = e_to + row_start;
    const int start = static_cast<int>(row_start);
    RowEnabled row;
    for_chunks(from, to, width, [&](int base, const V8& live) {
      const int p = start + base;
      V8 f = (load8(lane + p) >> off) & mask;
      if (is_signed) f = reinterpret_cast<V8>(reinterpret_cast<V8s>(f << sw) >> sw);
      test.apply(en_from, en_to, base, live, reinterpret_cast<V8s>(f),
                 reinterpret_cast<V8s>(read_b(p)), row);
    });
    row.keep(kept, start);
  });
  spans_.swap(kept);
  if (into_level) {
    enable_.swap(stack_[static_cast<std::size_t>(shared_level_)]);
    shared_level_ = -1;
  }
}

void WordBackend::compare(const Field& a, const Source& b, Compare cond) {
  materialize();
  check_field(a, "operand");
  if (b.is_field) check_field(b.field, "operand");
  auto in_lane = [](const Field& f) {
    return f.lo % 64 + f.width <= 64 && (f.is_signed || f.width < 64);
  };
  if (in_lane(a) && (!b.is_field || in_lane(b.field))) {
    if (!b.is_field) {
      const V8 k = V8{} + static_cast<u64>(b.constant);
      compare_lane(a, cond, [k](int) { return k; });
      return;
    }
    const Field& f = b.field;
    const u64* s = memory_.data() + static_cast<std::size_t>(f.lo / 64) * pixels_;
    const int soff = f.lo % 64;
    const u64 smask = low_mask(f.width);
    const int ssw = 64 - f.width;
    if (f.is_signed) {
      compare_lane(a, cond, [s, soff, smask, ssw](int p) {
        return reinterpret_cast<V8>(
            reinterpret_cast<V8s>(((load8(s + p) >> soff) & smask) << ssw) >> ssw);
      });
    } else {
      compare_lane(a, cond, [s, soff, smask](int p) { return (load8(s + p) >> soff) & smask; });
    }
    return;
  }
  // Row by row, each row's part narrowed (as narrow_spans does) as soon as it is compared,
  // and skipped when the comparison's own pass found no pixel left.
  own_enable();
  std::vector<Range>& kept = spare_spans_;
  kept.clear();
  for_each_span_row([&](int, std::size_t row_start, int from, int to) {
    const int start = static_cast<int>(row_start);
    if (compare_range(a, b, cond, Range{start + from, start + to})) {
      keep_enabled(kept, start + from, start + to);
    }
  });
  spans_.swap(kept);
}

bool WordBackend::compare_range(const Field& a, const Source& b, Compare cond, Range r) {
  const bool a_wide = !a.is_signed && a.width == 64;
  if (!b.is_field && !a_wide && a.lo % 64 + a.width <= 64) {
    // A field within one lane against a constant: read and compared in one pass.
    const u64* lane = memory_.data() + static_cast<std::size_t>(a.lo / 64) * pixels_;
    const int off = a.lo % 64;
    const u64 mask = low_mask(a.width);
    const i64 k = b.constant;
    auto constant = [k](int) { return k; };
    if (a.is_signed && a.width < 64) {
      const int sh = 64 - a.width;
      return and_compare_with(
          enable_.data(),
          [lane, off, mask, sh](int p) {
            return static_cast<i64>(((lane[p] >> off) & mask) << sh) >> sh;
          },
          constant, cond, r.begin, r.end);
    }
    return and_compare_with(
        enable_.data(),
        [lane, off, mask](int p) { return static_cast<i64>((lane[p] >> off) & mask); }, constant,
        cond, r.begin, r.end);
  }
  load(memory_.data(), a, r, scratch().s0.data(), true);
  if (b.is_field) {
    load(memory_.data(), b.field, r, scratch().s1.data(), true);
    compare_values(scratch().s0.data(), a_wide, scratch().s1.data(),
                   !b.field.is_signed && b.field.width == 64, cond, r);
  } else if (!a_wide) {
    const i64 k = b.constant;
    and_compare(
        enable_.data(), scratch().s0.data(), [k](int) { return k; }, cond, r.begin, r.end);
    enable_changed();
  } else {
    std::fill(scratch().s1.begin() + r.begin, scratch().s1.begin() + r.end,
              static_cast<u64>(b.constant));
    compare_values(scratch().s0.data(), true, scratch().s1.data(), false, cond, r);
  }
  return true;
}

void WordBackend::alu(const Field& dst, const Source& src, Alu op) {
  if (op == Alu::mov && !src.is_field && dst.lo % 64 + dst.width <= 64) {
    // A constant into a field within one lane reads no pixel memory: it waits with the
    // qloads (a sphere's colour after its depth, a triangle's `covered` after its attributes).
    check_field(dst, "assign");
    queue_load({dst, QuadraticCoefficients::constant(src.constant), true});
    return;
  }
  materialize();
  if (src.is_field) check_field(src.field, "operand");
  check_field(dst, op == Alu::mov   ? "assign"
                   : op == Alu::add ? "add"
                   : op == Alu::sub ? "sub"
                                    : "logic");
  const bool serial =
      src.is_field && src.field.lo < dst.lo && src.field.lo + src.field.width > dst.lo;
  if (!serial) {
    alu_merged(dst, src, op);
    return;
  }
  for (const Range& r : spans_) alu_serial(dst, src.field, op, r);
}

namespace {

// A field read at pixel p, extended to 64 bits by its signedness: within one 64-bit lane
// (hi == lo, up == 0: the second read adds nothing), or straddling two.
struct WordFieldReader {
  const u64* lo;
  const u64* hi;
  int off, up, sign_shift;
  u64 mask;
  bool is_signed;
  // The field at the eight pixels p .. p + 7, sign-extended when signed.
  V8 at8(int p) const {
    V8 v = load8(lo + p) >> off;
    if (up != 0) v |= load8(hi + p) << up;
    v &= mask;
    if (is_signed) v = reinterpret_cast<V8>(reinterpret_cast<V8s>(v << sign_shift) >> sign_shift);
    return v;
  }
};

// The reader of field f in pixel memory `memory` (lane-major, `pixels` per lane).
WordFieldReader word_field_reader(const u64* memory, int pixels, const Field& f) {
  const u64* lo = memory + static_cast<std::size_t>(f.lo / 64) * pixels;
  const int off = f.lo % 64;
  const bool split = off + f.width > 64;
  return WordFieldReader{lo,
                         split ? lo + pixels : lo,
                         off,
                         split ? 64 - off : 0,
                         64 - f.width,
                         low_mask(f.width),
                         f.is_signed && f.width < 64};
}

}  // namespace

// One ALU operation merged into dst under E (merge_lane: eight pixels at a time, in one
// pass, a destination across two lanes too), with the same result as the bit-serial walk:
// the destination read unsigned, a field source sign-extended when signed, the result cut to
// the destination. source(base) reads the source at pixels base .. base + 7.
template <WordBackend::Alu kOp, class Read>
void WordBackend::alu_merge(const Field& dst, Read source) {
  merge_lane(dst, [source](const V8& a, int base) {
    const V8 b = source(base);
    if constexpr (kOp == Alu::mov) return b;
    if constexpr (kOp == Alu::add) return a + b;
    if constexpr (kOp == Alu::sub) return a - b;
    if constexpr (kOp == Alu::and_) return a & b;
    if constexpr (kOp == Alu::or_) return a | b;
    if constexpr (kOp == Alu::xor_) return a ^ b;
  });
}

// The operation chosen once per instruction, not per chunk.
template <class Read>
void WordBackend::alu_merge_op(Alu op, const Field& dst, Read source) {
  switch (op) {
    case Alu::mov:
      return alu_merge<Alu::mov>(dst, source);
    case Alu::add:
      return alu_merge<Alu::add>(dst, source);
    case Alu::sub:
      return alu_merge<Alu::sub>(dst, source);
    case Alu::and_:
      return alu_merge<Alu::and_>(dst, source);
    case Alu::or_:
      return alu_merge<Alu::or_>(dst, source);
    case Alu::xor_:
      return alu_merge<Alu::xor_>(dst, source);
  }
}

void WordBackend::alu_merged(const Field& dst, const Source& src, Alu op) {
  if (!src.is_field) {
    const V8 k = V8{} + static_cast<u64>(src.constant);
    alu_merge_op(op, dst, [k](int) { return k; });
    return;
  }
  const Field& f = src.field;
  if (f.lo % 64 + f.width > 64) {  // a source across two lanes
    const WordFieldReader r = word_field_reader(memory_.data(), pixels_, f);
    alu_merge_op(op, dst, [r](int base) { return r.at8(base); });
    return;
  }
  const u64* s = memory_.data() + static_cast<std::size_t>(f.lo / 64) * pixels_;
  const int soff = f.lo % 64;
  const u64 smask = low_mask(f.width);
  if (f.is_signed && f.width < 64) {
    const int sh = 64 - f.width;
    alu_merge_op(op, dst, [s, soff, smask, sh](int base) {
      return reinterpret_cast<V8>(
          reinterpret_cast<V8s>(((load8(s + base) >> soff) & smask) << sh) >> sh);
    });
    return;
  }
  alu_merge_op(op, dst, [s, soff, smask](int base) { return (load8(s + base) >> soff) & smask; });
}

// The bit-serial walk itself, for a source that overlaps its destination from below: at bit
// i it reads source bit i from memory as the walk has left it (bits the walk wrote already
// are the result's), and above the source's width its original sign (the bit backend keeps
// a copy of that plane before the walk).
void WordBackend::alu_serial(const Field& dst, const Field& src, Alu op, Range r) {
  u64* mem = memory_.data();
  const std::size_t n = static_cast<std::size_t>(pixels_);
  auto bit = [&](int b, int p) -> u64 { return (mem[(b / 64) * n + p] >> (b % 64)) & 1; };
  auto set = [&](int b, int p, u64 v) {
    u64& word = mem[(b / 64) * n + p];
    word = (word & ~(u64{1} << (b % 64))) | (v << (b % 64));
  };
  for (int p = r.begin; p < r.end; ++p) {
    if (!enable_[static_cast<std::size_t>(p)]) continue;
    const u64 sign = src.is_signed ? bit(src.lo + src.width - 1, p) : 0;
    u64 carry = op == Alu::sub ? 1 : 0;
    for (int i = 0; i < dst.width; ++i) {
      const u64 x = bit(dst.lo + i, p);
      u64 y = i < src.width ? bit(src.lo + i, p) : sign;
      u64 s = 0;
      switch (op) {
        case Alu::mov:
          s = y;
          break;
        case Alu::sub:
          y ^= 1;
          [[fallthrough]];
        case Alu::add:
          s = x ^ y ^ carry;
          carry = (x & y) | (carry & (x ^ y));
          break;
        case Alu::and_:
          s = x & y;
          break;
        case Alu::or_:
          s = x | y;
          break;
        case Alu::xor_:
          s = x ^ y;
          break;
      }
      set(dst.lo + i, p, s);
    }
  }
}

void WordBackend::mov(const Field& dst, const Source& src) { alu(dst, src, Alu::mov); }
void WordBackend::add(const Field& dst, const Source& src) { alu(dst, src, Alu::add); }
void WordBackend::sub(const Field& dst, const Source& src) { alu(dst, src, Alu::sub); }

void WordBackend::logic(const Field& dst, const Source& src, Logic op) {
  alu(dst, src, op == Logic::and_ ? Alu::and_ : op == Logic::or_ ? Alu::or_ : Alu::xor_);
}

void WordBackend::invert(const Field& dst) {
  materialize();
  check_field(dst, "not");
  u64* a = scratch().s0.data();
  for (const Range& r : spans_) {
    load(memory_.data(), dst, r, a, false);
    for (int p = r.begin; p < r.end; ++p) a[p] = ~a[p];
    store(memory_.data(), dst, r, a, true);
  }
}

namespace {
bool overlaps(const Field& a, const Field& b) {
  return a.lo < b.lo + b.width && b.lo < a.lo + a.width;
}
}  // namespace

// value(old, base) merged into dst under E, modulo 2^width, over every span, in one pass,
// eight pixels at a time: `old` is dst's value at pixels base .. base + 7, and value gives the
// eight new ones (only their low width bits are kept). A destination across two lanes is
// read from and written to both.
template <class Value>
void WordBackend::merge_lane(const Field& dst, Value value) {
  u64* lo = memory_.data() + static_cast<std::size_t>(dst.lo / 64) * pixels_;
  const int off = dst.lo % 64;
  const bool split = off + dst.width > 64;
  u64* hi = split ? lo + pixels_ : lo;
  const int up = split ? 64 - off : 0;  // dst's bits in the low lane
  const u64 mask = low_mask(dst.width);
  const u64 bits_lo = mask << off, bits_hi = split ? mask >> up : 0;
  const std::uint8_t* e = enable_.data();
  for (const Range& r : spans_) {
    for_chunks(r.begin, r.end, pixels_, [&](int base, const V8& live) {
      const V8 en = (V8{} - load_enable8(e + base)) & live;
      const V8 old_lo = load8(lo + base);
      V8 old = old_lo >> off;
      V8 old_hi{};
      if (split) {
        old_hi = load8(hi + base);
        old |= old_hi << up;
      }
      const V8 v = value(old & mask, base);
      const V8 m_lo = bits_lo & en;
      store8(lo + base, (old_lo & ~m_lo) | ((v << off) & m_lo));
      if (split) {
        const V8 m_hi = bits_hi & en;
        store8(hi + base, (old_hi & ~m_hi) | ((v >> up) & m_hi));
      }
    });
  }
}

void WordBackend::multiply(const Field& dst, const Field& a, const Field& b, bool window) {
  materialize();
  check_field(a, "operand");
  check_field(b, "operand");
  check_field(dst, "mul");
  if (overlaps(dst, a) || overlaps(dst, b)) {
    throw std::invalid_argument("mul: destination overlaps a source");
  }
  // The windowed passes (PixelBackend::multiply) drop each window's carry out, but
  // multiply_window_bits gives a window only for an unsigned `a` of width w, w + 1 bits wide:
  // before the pass for bit j of b the sum is a (b mod 2^j) < a 2^j, so after adding a 2^j it
  // is below 2^(j + w + 1), inside the window, and no carry is ever dropped. The result is
  // the plain product modulo 2^width either way.
  (void)window;
  const WordFieldReader x = word_field_reader(memory_.data(), pixels_, a),
                        y = word_field_reader(memory_.data(), pixels_, b);
  merge_lane(dst, [x, y](const V8&, int base) { return x.at8(base) * y.at8(base); });
}

void WordBackend::multiply_accumulate(const Field& dst, const Field& a, i64 k) {
  materialize();
  check_field(a, "operand");
  check_field(dst, "mac");
  if (overlaps(dst, a)) throw std::invalid_argument("mac: destination overlaps a source");
  const u64 m = static_cast<u64>(k);
  const WordFieldReader x = word_field_reader(memory_.data(), pixels_, a);
  merge_lane(dst, [x, m](const V8& old, int base) { return old + x.at8(base) * m; });
}

u64* WordBackend::backing() {
  if (backing_.empty()) {
    backing_.assign(static_cast<std::size_t>((geometry_.backing_store_bits + 63) / 64) * pixels_,
                    0);
  }
  return backing_.data();
}

void WordBackend::store_to_backing(const Field& field, int block) {
  materialize();
  check_field(field, "backing-store transfer");
  const int first = block * geometry_.block_bits;
  if (block < 0 || first + field.width > geometry_.backing_store_bits) {
    throw std::out_of_range("backing store: block " + std::to_string(block) + " out of range");
  }
  const Range all{0, pixels_};
  load(memory_.data(), field, all, scratch().s0.data(), false);
  store(backing(), Field{first, field.width, false}, all, scratch().s0.data(), false);
}

void WordBackend::load_from_backing(const Field& field, int block) {
  materialize();
  check_field(field, "backing-store transfer");
  const int first = block * geometry_.block_bits;
  if (block < 0 || first + field.width > geometry_.backing_store_bits) {
    throw std::out_of_range("backing store: block " + std::to_string(block) + " out of range");
  }
  const Range all{0, pixels_};
  load(backing(), Field{first, field.width, false}, all, scratch().s0.data(), false);
  store(memory_.data(), field, all, scratch().s0.data(), false);
}

u64 WordBackend::read(int pixel, const Field& field) const {
  write_loads();
  const int lane = field.lo / 64;
  const int off = field.lo % 64;
  const std::size_t n = static_cast<std::size_t>(pixels_);
  u64 v = memory_[lane * n + pixel] >> off;
  if (off + field.width > 64) v |= memory_[(lane + 1) * n + pixel] << (64 - off);
  return v & low_mask(field.width);
}

void WordBackend::read_field(const Field& field, u64* out) const {
  check_field(field, "read");
  write_loads();
  load(memory_.data(), field, Range{0, pixels_}, out, false);
}

namespace {
using U32x8 = std::uint32_t __attribute__((vector_size(32)));
using B32 = std::uint8_t __attribute__((vector_size(32)));

// Picks bytes i / N * 4 + i % N of a 32-byte vector for i < 8 * N: the low N bytes of each
// of eight 32-bit words, packed. __builtin_shufflevector takes constant indices only, and
// both GCC (12 on) and clang have it.
template <int N, std::size_t... I>
B32 pack_low_bytes(B32 b, std::index_sequence<I...> /*unused*/) {
  return __builtin_shufflevector(b, b, (I < 8 * N ? I / N * 4 + I % N : 0)...);
}

// out[p * N + k] = the byte of lane[p] at bit shift[k], for N fields; pixels is a multiple
// of 8. Eight pixels at a time: each lane word's N bytes are shifted into one 32-bit word,
// and one byte shuffle packs the eight words' 8 N bytes, in order.
template <int N>
void gather_bytes(const u64* lane, std::size_t pixels, const int* shift, std::uint8_t* out) {
  for (std::size_t p = 0; p < pixels; p += 8) {
    V8 word;
    std::memcpy(&word, lane + p, sizeof word);
    V8 packed = (word >> shift[0]) & 0xff;
    for (int k = 1; k < N; ++k) packed |= ((word >> shift[k]) & 0xff) << (8 * k);
    const U32x8 words = __builtin_convertvector(packed, U32x8);
    B32 bytes;
    std::memcpy(&bytes, &words, sizeof bytes);
    const B32 picked = pack_low_bytes<N>(bytes, std::make_index_sequence<32>{});
    std::memcpy(out + p * N, &picked, 8 * N);
  }
}
}  // namespace

// Fields whose low 8 bits lie in one lane (phong's red, green and blue are three bytes of
// lane 0): each pixel's lane word is read once and its bytes shifted out, in one pass over
// the pixels, eight pixels at a time (gather_bytes). Otherwise the generic reads.
void WordBackend::read_bytes(const Field* fields, int count, std::uint8_t* out) const {
  write_loads();
  constexpr int kMost = 4;
  bool one_lane = count > 0 && count <= kMost;
  int shift[kMost] = {};
  for (int k = 0; one_lane && k < count; ++k) {
    check_field(fields[k], "read");
    one_lane = fields[k].lo / 64 == fields[0].lo / 64 && fields[k].width >= 8 &&
               fields[k].lo % 64 + 8 <= 64;
    shift[k] = fields[k].lo % 64;
  }
  if (!one_lane) {
    PixelBackend::read_bytes(fields, count, out);
    return;
  }
  const u64* lane = memory_.data() + static_cast<std::size_t>(fields[0].lo / 64) * pixels_;
  // pixels_ is a multiple of 64 (the width is), so of gather_bytes' eight.
  const auto n = static_cast<std::size_t>(pixels_);
  switch (count) {
    case 1:
      gather_bytes<1>(lane, n, shift, out);
      break;
    case 2:
      gather_bytes<2>(lane, n, shift, out);
      break;
    case 3:
      gather_bytes<3>(lane, n, shift, out);
      break;
    default:
      gather_bytes<4>(lane, n, shift, out);
      break;
  }
}

void WordBackend::read_memory_planes(std::vector<u64>& planes) const {
  write_loads();
  const int words = pixels_ / 64;
  const int bits = geometry_.memory_bits;
  planes.assign(static_cast<std::size_t>(bits) * words, 0);
  for (int b = 0; b < bits; ++b) {
    const u64* lane = &memory_[static_cast<std::size_t>(b / 64) * pixels_];
    const int off = b % 64;
    u64* plane = &planes[static_cast<std::size_t>(b) * words];
    for (int w = 0; w < words; ++w) {
      u64 bitsw = 0;
      for (int j = 0; j < 64; ++j) bitsw |= ((lane[w * 64 + j] >> off) & 1) << j;
      plane[w] = bitsw;
    }
  }
}

void WordBackend::write(int pixel, const Field& field, u64 value) {
  check_field(field, "write");
  write_loads();
  const int lane = field.lo / 64;
  const int off = field.lo % 64;
  const std::size_t n = static_cast<std::size_t>(pixels_);
  const u64 mask = low_mask(field.width);
  u64& lo = memory_[lane * n + pixel];
  lo = (lo & ~(mask << off)) | ((value & mask) << off);
  if (off + field.width > 64) {
    u64& hi = memory_[(lane + 1) * n + pixel];
    const u64 hi_bits = mask >> (64 - off);
    hi = (hi & ~hi_bits) | ((value & mask) >> (64 - off));
  }
}

std::unique_ptr<PixelBackend> WordBackend::clone() const {
  materialize();
  own_enable();
  return std::make_unique<WordBackend>(*this);
}

bool WordBackend::same_state(const PixelBackend& other) const {
  const auto* o = dynamic_cast<const WordBackend*>(&other);
  if (o == nullptr || o->geometry_ != geometry_) return false;
  materialize();
  o->materialize();
  own_enable();
  o->own_enable();
  if (stack_top_ != o->stack_top_ || memory_ != o->memory_) return false;
  // E and each saved level compared as values: 0 outside their spans, whatever the bytes
  // there hold. Stack levels above the top are never read before a push overwrites them.
  std::vector<std::uint8_t> a, b;
  auto value = [this](const std::uint8_t* bytes, const std::vector<Range>& spans,
                      std::vector<std::uint8_t>& out) {
    out.assign(static_cast<std::size_t>(pixels_), 0);
    for (const Range& r : spans) std::copy(bytes + r.begin, bytes + r.end, out.begin() + r.begin);
  };
  for (int level = -1; level < stack_top_; ++level) {
    const auto k = static_cast<std::size_t>(std::max(level, 0));
    value(level < 0 ? enable_.data() : stack_[k].data(), level < 0 ? spans_ : stack_spans_[k], a);
    value(level < 0 ? o->enable_.data() : o->stack_[k].data(),
          level < 0 ? o->spans_ : o->stack_spans_[k], b);
    if (a != b) return false;
  }
  // A backing store never allocated is all 0.
  auto zero = [](const std::vector<u64>& v) {
    return std::all_of(v.begin(), v.end(), [](u64 x) { return x == 0; });
  };
  if (backing_.empty() || o->backing_.empty()) return zero(backing_) && zero(o->backing_);
  return backing_ == o->backing_;
}

void WordBackend::copy_state_from(const PixelBackend& other) {
  const auto* o = dynamic_cast<const WordBackend*>(&other);
  if (o == nullptr || o->geometry() != geometry()) {
    throw std::invalid_argument(std::string("word backend: cannot take the state of a '") +
                                other.name() + "' backend of another kind or geometry");
  }
  o->materialize();
  o->own_enable();
  shared_level_ = -1;
  loads_.clear();
  pending_.clear();
  ones_ = false;
  memory_ = o->memory_;
  enable_ = o->enable_;
  stack_ = o->stack_;
  stack_top_ = o->stack_top_;
  spans_ = o->spans_;
  stack_spans_ = o->stack_spans_;
  backing_ = o->backing_;
}

}  // namespace pp5
