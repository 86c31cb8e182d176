#include "models/pixel_array/pixel_array.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace pp5 {

namespace {

Word majority(Word a, Word b, Word c) { return (a & b) | (c & (a ^ b)); }

void check_field(const Field& f, int memory_bits, const char* what) {
  if (f.width < 1 || f.width > Bits::kMaxBits || f.lo < 0 || f.lo + f.width > memory_bits) {
    throw std::out_of_range(std::string(what) + ": field [" + std::to_string(f.lo) + ", " +
                            std::to_string(f.lo + f.width) + ") outside pixel memory of " +
                            std::to_string(memory_bits) + " bits");
  }
}

}  // namespace

PixelArray::PixelArray(const PixelArrayGeometry& geometry) : geometry_(geometry) {
  if (geometry.width <= 0 || geometry.width % kWordBits != 0 || geometry.height <= 0) {
    throw std::invalid_argument("pixel array: width must be a positive multiple of 64, height > 0");
  }
  if (geometry.memory_bits < 1 || geometry.enable_stack_depth < 0 ||
      geometry.backing_store_bits < 0 || geometry.block_bits < 1) {
    throw std::invalid_argument("pixel array: bad memory geometry");
  }
  words_ = geometry.width * geometry.height / kWordBits;
  memory_.assign(static_cast<std::size_t>(geometry.memory_bits) * words_, 0);
  enable_.assign(words_, kAllOnes);
  bound_ = {0, words_};
  stack_bound_.assign(static_cast<std::size_t>(geometry.enable_stack_depth), WordRange{});
  carry_.assign(words_, 0);
  stack_.assign(static_cast<std::size_t>(geometry.enable_stack_depth) * words_, 0);
  zeros_.assign(words_, 0);
  sign_copy_.assign(static_cast<std::size_t>(words_) * 2, 0);
  ones_.assign(words_, kAllOnes);
}

Bits PixelArray::bits_of(const Field& field) const {
  check_field(field, geometry_.memory_bits, "operand");
  Bits b;
  b.width = field.width;
  for (int i = 0; i < field.width; ++i) b.plane[i] = plane(field.lo + i);
  b.extension = field.is_signed ? b.plane[field.width - 1] : zeros();
  return b;
}

Bits PixelArray::bits_of_constant(std::int64_t value) const {
  Bits b;
  const auto u = static_cast<std::uint64_t>(value);
  // The fewest bits that, extended by the sign, give the value back: a compare or an add
  // with a small constant walks no more planes than its field needs.
  const std::uint64_t magnitude = value < 0 ? ~u : u;
  b.width = magnitude == 0 ? 1 : std::min(Bits::kMaxBits, 65 - __builtin_clzll(magnitude));
  for (int i = 0; i < b.width; ++i) b.plane[i] = ((u >> i) & 1) ? ones() : zeros();
  b.extension = value < 0 ? ones() : zeros();
  return b;
}

Bits PixelArray::bits_of_planes(const Word* planes, int count, bool is_signed) const {
  if (count < 1 || count > Bits::kMaxBits) throw std::out_of_range("operand: bad plane count");
  Bits b;
  b.width = count;
  for (int i = 0; i < count; ++i) b.plane[i] = planes + static_cast<std::size_t>(i) * words_;
  b.extension = is_signed ? b.plane[count - 1] : zeros();
  return b;
}

void PixelArray::enable_all() {
  std::fill(enable_.begin(), enable_.end(), kAllOnes);
  active_ = bound_ = {0, words_};
  active_valid_ = true;
}

void PixelArray::clear_enable_outside(WordRange keep) {
  const WordRange r = active_words();
  for (int w = r.begin; w < std::min(keep.begin, r.end); ++w) enable_[w] = 0;
  for (int w = std::max(keep.end, r.begin); w < r.end; ++w) enable_[w] = 0;
  bound_ = {std::max(r.begin, keep.begin), std::min(r.end, keep.end)};
  mark_enable_shrunk();
}

void PixelArray::and_enable(const Word* mask) {
  const WordRange r = active_words();
  for (int w = r.begin; w < r.end; ++w) enable_[w] &= mask[w];
  mark_enable_shrunk();
}

void PixelArray::push_enable() {
  if (stack_top_ >= geometry_.enable_stack_depth) {
    throw std::overflow_error("enable stack overflow: depth " +
                              std::to_string(geometry_.enable_stack_depth));
  }
  std::copy(enable_.begin(), enable_.end(),
            stack_.begin() + static_cast<std::ptrdiff_t>(stack_top_) * words_);
  stack_bound_[static_cast<std::size_t>(stack_top_)] = active_valid_ ? active_ : bound_;
  ++stack_top_;
}

void PixelArray::pop_enable() {
  if (stack_top_ == 0) throw std::underflow_error("enable stack underflow");
  --stack_top_;
  auto saved = stack_.begin() + static_cast<std::ptrdiff_t>(stack_top_) * words_;
  std::copy(saved, saved + words_, enable_.begin());
  bound_ = stack_bound_[static_cast<std::size_t>(stack_top_)];
  mark_enable_shrunk();
}

void PixelArray::else_enable() {
  if (stack_top_ == 0) throw std::underflow_error("else without a saved enable");
  const Word* saved = &stack_[static_cast<std::size_t>(stack_top_ - 1) * words_];
  for (int w = 0; w < words_; ++w) enable_[w] = saved[w] & ~enable_[w];
  bound_ = stack_bound_[static_cast<std::size_t>(stack_top_ - 1)];  // E is within the saved E
  mark_enable_shrunk();
}

int PixelArray::count_enabled() const {
  int n = 0;
  for (Word w : enable_) n += __builtin_popcountll(w);
  return n;
}

WordRange PixelArray::active_words() const {
  if (!active_valid_) {
    int b = bound_.begin;
    while (b < bound_.end && enable_[b] == 0) ++b;
    int e = bound_.end;
    while (e > b && enable_[e - 1] == 0) --e;
    active_ = b < e ? WordRange{b, e} : WordRange{words_, words_};
    bound_ = active_;
    active_valid_ = true;
  }
  return active_;
}

Bits PixelArray::stable(const Bits& src, const Field& dst, int slot) {
  // A signed source narrower than a destination at its own alignment extends with its top
  // plane, which the walk overwrites before it reads the extension: keep the old sign.
  const Word* first = plane(dst.lo);
  const Word* last = plane(dst.lo + dst.width - 1);
  if (src.extension < first || src.extension > last) return src;
  Word* copy = &sign_copy_[static_cast<std::size_t>(slot) * words_];
  const WordRange r = active_words();
  std::copy(src.extension + r.begin, src.extension + r.end, copy + r.begin);
  Bits b = src;
  b.extension = copy;
  return b;
}

// The ALU walks plane by plane (the bit-serial order) over the active words, keeping one
// carry per pixel in the carry register: every inner loop is a straight pass over a few
// contiguous rows of words.
void PixelArray::assign(const Field& dst, const Bits& src_in) {
  check_field(dst, geometry_.memory_bits, "assign");
  const Bits src = stable(src_in, dst, 0);
  const WordRange r = active_words();
  const Word* e = enable_.data();
  for (int i = 0; i < dst.width; ++i) {
    const Word* x = src.bit(i);
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) d[w] = (x[w] & e[w]) | (d[w] & ~e[w]);
  }
}

void PixelArray::add_walk(const Field& dst, const Bits& a, const Bits& b, bool subtract) {
  const WordRange r = active_words();
  const Word* e = enable_.data();
  Word* c = carry_.data();
  const Word invert = subtract ? kAllOnes : 0;  // a - b = a + ~b + 1
  for (int w = r.begin; w < r.end; ++w) c[w] = invert;
  for (int i = 0; i < dst.width; ++i) {
    const Word* x = a.bit(i);
    const Word* y = b.bit(i);
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) {
      const Word yw = y[w] ^ invert;
      const Word s = x[w] ^ yw ^ c[w];
      c[w] = majority(x[w], yw, c[w]);
      d[w] = (s & e[w]) | (d[w] & ~e[w]);
    }
  }
}

void PixelArray::add(const Field& dst, const Bits& a, const Bits& b) {
  check_field(dst, geometry_.memory_bits, "add");
  add_walk(dst, stable(a, dst, 0), stable(b, dst, 1), false);
}

void PixelArray::sub(const Field& dst, const Bits& a, const Bits& b) {
  check_field(dst, geometry_.memory_bits, "sub");
  add_walk(dst, stable(a, dst, 0), stable(b, dst, 1), true);
}

void PixelArray::logic(const Field& dst, const Bits& a_in, const Bits& b_in, Logic op) {
  check_field(dst, geometry_.memory_bits, "logic");
  const Bits a = stable(a_in, dst, 0);
  const Bits b = stable(b_in, dst, 1);
  const WordRange r = active_words();
  const Word* e = enable_.data();
  for (int i = 0; i < dst.width; ++i) {
    const Word* x = a.bit(i);
    const Word* y = b.bit(i);
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) {
      const Word s = op == Logic::and_  ? (x[w] & y[w])
                     : op == Logic::or_ ? (x[w] | y[w])
                                        : (x[w] ^ y[w]);
      d[w] = (s & e[w]) | (d[w] & ~e[w]);
    }
  }
}

void PixelArray::invert(const Field& dst) {
  check_field(dst, geometry_.memory_bits, "not");
  const WordRange r = active_words();
  for (int i = 0; i < dst.width; ++i) {
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) d[w] ^= enable_[w];
  }
}

void PixelArray::check_no_overlap(const Field& dst, const Bits& src, const char* what) const {
  const Word* first = plane(dst.lo);
  const Word* last = plane(dst.lo + dst.width - 1);
  for (int k = 0; k < src.width; ++k) {
    if (src.plane[k] >= first && src.plane[k] <= last) {
      throw std::invalid_argument(std::string(what) + ": destination overlaps a source");
    }
  }
}

// dst[j..] += (a << j) masked by `gate` (per pixel), under E; the carry register holds the
// chain. `negate` adds the two's complement instead.
void PixelArray::shifted_add(const Field& dst, const Bits& a, int j, const Word* gate, bool negate,
                             int end) {
  const int top = end > 0 ? std::min(end, dst.width) : dst.width;
  const WordRange r = active_words();
  const Word* e = enable_.data();
  Word* c = carry_.data();
  const Word flip = negate ? kAllOnes : 0;
  for (int w = r.begin; w < r.end; ++w) c[w] = gate ? (flip & gate[w]) : flip;
  for (int i = j; i < top; ++i) {
    const Word* x = a.bit(i - j);
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) {
      const Word g = gate ? gate[w] : kAllOnes;
      const Word xw = (x[w] ^ flip) & g;
      const Word s = d[w] ^ xw ^ c[w];
      c[w] = majority(d[w], xw, c[w]);
      d[w] = (s & e[w]) | (d[w] & ~e[w]);
    }
  }
}

void PixelArray::multiply(const Field& dst, const Bits& a, const Bits& b, int window) {
  check_field(dst, geometry_.memory_bits, "mul");
  check_no_overlap(dst, a, "mul");
  check_no_overlap(dst, b, "mul");
  const WordRange r = active_words();
  for (int i = 0; i < dst.width; ++i) {
    Word* d = plane(dst.lo + i);
    for (int w = r.begin; w < r.end; ++w) d[w] &= ~enable_[w];
  }
  for (int j = 0; j < dst.width; ++j) {
    const Word* bj = b.bit(j);
    if (bj == zeros()) continue;  // a bit beyond an unsigned multiplier adds nothing
    shifted_add(dst, a, j, bj, false, window > 0 ? j + window : 0);
  }
}

void PixelArray::multiply_accumulate(const Field& dst, const Bits& a, std::int64_t k) {
  check_field(dst, geometry_.memory_bits, "mac");
  check_no_overlap(dst, a, "mac");
  const bool negative = k < 0;
  const std::uint64_t magnitude =
      negative ? std::uint64_t{0} - static_cast<std::uint64_t>(k) : static_cast<std::uint64_t>(k);
  for (int j = 0; j < dst.width && j < 64; ++j) {
    if (((magnitude >> j) & 1) != 0) shifted_add(dst, a, j, nullptr, negative);
  }
}

void PixelArray::compare(const Bits& a, const Bits& b, Compare cmp) {
  const int n = std::max(a.width, b.width) + 2;
  const WordRange r = active_words();
  Word* c = carry_.data();
  Word* nonzero = &sign_copy_[0];
  Word* sign = &sign_copy_[static_cast<std::size_t>(words_)];
  for (int w = r.begin; w < r.end; ++w) {
    c[w] = kAllOnes;  // a - b = a + ~b + 1
    nonzero[w] = 0;
  }
  for (int i = 0; i < n; ++i) {
    const Word* x = a.bit(i);
    const Word* y = b.bit(i);
    for (int w = r.begin; w < r.end; ++w) {
      const Word yw = ~y[w];
      const Word s = x[w] ^ yw ^ c[w];
      c[w] = majority(x[w], yw, c[w]);
      nonzero[w] |= s;
      sign[w] = s;
    }
  }
  for (int w = r.begin; w < r.end; ++w) {
    const Word lt = sign[w];  // sign of the exact difference
    Word result = 0;
    switch (cmp) {
      case Compare::lt:
        result = lt;
        break;
      case Compare::le:
        result = lt | ~nonzero[w];
        break;
      case Compare::eq:
        result = ~nonzero[w];
        break;
      case Compare::ne:
        result = nonzero[w];
        break;
      case Compare::ge:
        result = ~lt;
        break;
      case Compare::gt:
        result = ~lt & nonzero[w];
        break;
    }
    enable_[w] &= result;
  }
  mark_enable_shrunk();
}

Word* PixelArray::backing_plane(int bit) {
  if (backing_.empty()) {
    backing_.assign(static_cast<std::size_t>(geometry_.backing_store_bits) * words_, 0);
  }
  return &backing_[static_cast<std::size_t>(bit) * words_];
}

void PixelArray::store_to_backing(const Field& field, int block) {
  check_field(field, geometry_.memory_bits, "backing-store transfer");
  const int first = block * geometry_.block_bits;
  if (block < 0 || first + field.width > geometry_.backing_store_bits) {
    throw std::out_of_range("backing store: block " + std::to_string(block) + " out of range");
  }
  for (int i = 0; i < field.width; ++i) {
    std::copy_n(plane(field.lo + i), words_, backing_plane(first + i));
  }
}

void PixelArray::load_from_backing(const Field& field, int block) {
  check_field(field, geometry_.memory_bits, "backing-store transfer");
  const int first = block * geometry_.block_bits;
  if (block < 0 || first + field.width > geometry_.backing_store_bits) {
    throw std::out_of_range("backing store: block " + std::to_string(block) + " out of range");
  }
  for (int i = 0; i < field.width; ++i) {
    std::copy_n(backing_plane(first + i), words_, plane(field.lo + i));
  }
}

std::uint64_t PixelArray::read(int pixel, const Field& field) const {
  std::uint64_t v = 0;
  const int w = pixel / kWordBits;
  const int b = pixel % kWordBits;
  for (int i = 0; i < field.width; ++i) v |= ((plane(field.lo + i)[w] >> b) & 1) << i;
  return v;
}

std::int64_t PixelArray::read_signed(int pixel, const Field& field) const {
  const std::uint64_t v = read(pixel, field);
  if (!field.is_signed || field.width >= 64) return static_cast<std::int64_t>(v);
  const std::uint64_t sign = std::uint64_t{1} << (field.width - 1);
  return static_cast<std::int64_t>((v ^ sign) - sign);
}

void PixelArray::write(int pixel, const Field& field, std::uint64_t value) {
  check_field(field, geometry_.memory_bits, "write");
  const int w = pixel / kWordBits;
  const Word m = Word{1} << (pixel % kWordBits);
  for (int i = 0; i < field.width; ++i) {
    Word* d = plane(field.lo + i) + w;
    *d = ((value >> i) & 1) ? (*d | m) : (*d & ~m);
  }
}

bool PixelArray::enabled(int pixel) const {
  return (enable_[pixel / kWordBits] >> (pixel % kWordBits)) & 1;
}

std::uint64_t PixelArray::carry_bit(int pixel) const {
  return (carry_[pixel / kWordBits] >> (pixel % kWordBits)) & 1;
}

bool PixelArray::same_state(const PixelArray& other) const {
  return words_ == other.words_ && stack_top_ == other.stack_top_ && memory_ == other.memory_ &&
         enable_ == other.enable_ && carry_ == other.carry_ && stack_ == other.stack_ &&
         backing_ == other.backing_;
}

}  // namespace pp5
