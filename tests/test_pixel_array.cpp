// PixelArray against a scalar model of the same machine: per pixel, local memory and backing
// store as little-endian 64-bit words, an Enable flag and a stack of saved flags, with every ALU
// operation evaluated in exact 128-bit arithmetic. After each operation the whole bit-sliced
// memory and the Enable register are compared with the model (the model is turned into planes
// by the layout bitplane.hpp specifies), so a write to a disabled pixel, to a bit outside the
// destination field or to a word outside the active range is caught wherever it lands.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/pixel_array/pixel_array.hpp"

using namespace pp5;

namespace {

using i128 = __int128;
using u128 = unsigned __int128;

constexpr std::int64_t kMin64 = std::numeric_limits<std::int64_t>::min();
constexpr std::int64_t kMax64 = std::numeric_limits<std::int64_t>::max();

const Compare kCompares[] = {Compare::lt, Compare::le, Compare::eq,
                             Compare::ne, Compare::ge, Compare::gt};

std::uint64_t low_mask(int w) { return w >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << w) - 1; }

// Bits [lo, lo + w) of an array of 64-bit words, bit 0 being bit 0 of word 0.
std::uint64_t get_bits(const std::uint64_t* m, int lo, int w) {
  const int q = lo / 64;
  const int r = lo % 64;
  std::uint64_t v = m[q] >> r;
  if (r != 0 && r + w > 64) v |= m[q + 1] << (64 - r);
  return v & low_mask(w);
}

void set_bits(std::uint64_t* m, int lo, int w, std::uint64_t v) {
  const int q = lo / 64;
  const int r = lo % 64;
  v &= low_mask(w);
  m[q] = (m[q] & ~(low_mask(w) << r)) | (v << r);
  if (r != 0 && r + w > 64) {
    const int hi = r + w - 64;
    m[q + 1] = (m[q + 1] & ~low_mask(hi)) | (v >> (64 - r));
  }
}

i128 extend(std::uint64_t raw, int w, bool is_signed) {
  if (!is_signed) return static_cast<i128>(raw);
  if (w == 64) return static_cast<std::int64_t>(raw);
  return static_cast<std::int64_t>(raw << (64 - w)) >> (64 - w);
}

// The low 64 bits of v's two's complement (the caller masks to the field width).
std::uint64_t low64(i128 v) { return static_cast<std::uint64_t>(static_cast<u128>(v)); }

bool holds(Compare c, i128 a, i128 b) {
  switch (c) {
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

const char* name_of(Compare c) {
  switch (c) {
    case Compare::lt:
      return "lt";
    case Compare::le:
      return "le";
    case Compare::eq:
      return "eq";
    case Compare::ne:
      return "ne";
    case Compare::ge:
      return "ge";
    case Compare::gt:
      return "gt";
  }
  return "?";
}

std::string describe(const Field& f) {
  return "[" + std::to_string(f.lo) + "," + std::to_string(f.lo + f.width) + ")" +
         (f.is_signed ? "s" : "u");
}

bool overlaps(const Field& a, const Field& b) {
  return a.lo < b.lo + b.width && b.lo < a.lo + a.width;
}

// In-place transpose of a 64 x 64 bit matrix: afterwards bit j of a[i] is bit i of the old a[j].
void transpose64(std::uint64_t* a) {
  std::uint64_t m = 0x00000000FFFFFFFFull;
  for (int j = 32; j != 0; j >>= 1, m ^= m << j) {
    for (int k = 0; k < 64; k = ((k | j) + 1) & ~j) {
      const std::uint64_t t = ((a[k] >> j) ^ a[k | j]) & m;
      a[k] ^= t << j;
      a[k | j] ^= t;
    }
  }
}

// The scalar reference: one record per pixel processor.
struct Model {
  explicit Model(const PixelArrayGeometry& geometry)
      : g(geometry),
        pixels(g.width * g.height),
        per_pixel((g.memory_bits + 63) / 64),
        backing_per_pixel((g.backing_store_bits + 63) / 64),
        mem(static_cast<std::size_t>(pixels) * per_pixel, 0),
        backing(static_cast<std::size_t>(pixels) * backing_per_pixel, 0),
        enable(pixels, 1) {}

  std::uint64_t get(int p, const Field& f) const {
    return get_bits(&mem[static_cast<std::size_t>(p) * per_pixel], f.lo, f.width);
  }
  void set(int p, const Field& f, std::uint64_t v) {
    set_bits(&mem[static_cast<std::size_t>(p) * per_pixel], f.lo, f.width, v);
  }
  i128 value(int p, const Field& f) const { return extend(get(p, f), f.width, f.is_signed); }

  void store(const Field& f, int block) {
    for (int p = 0; p < pixels; ++p) {
      set_bits(&backing[static_cast<std::size_t>(p) * backing_per_pixel], block * g.block_bits,
               f.width, get(p, f));
    }
  }
  void load(const Field& f, int block) {
    for (int p = 0; p < pixels; ++p) {
      set(p, f,
          get_bits(&backing[static_cast<std::size_t>(p) * backing_per_pixel], block * g.block_bits,
                   f.width));
    }
  }

  PixelArrayGeometry g;
  int pixels;
  int per_pixel;
  int backing_per_pixel;
  std::vector<std::uint64_t> mem;
  std::vector<std::uint64_t> backing;
  std::vector<std::uint8_t> enable;
  std::vector<std::vector<std::uint8_t>> stack;
};

// A source operand, both as the array sees it and as the model evaluates it.
struct OperandSource {
  enum class Kind { field, constant, planes };
  Kind kind = Kind::field;
  Field f{};
  std::int64_t k = 0;
  int count = 0;
  bool is_signed = false;
  std::vector<Word> buf;   // planes: count consecutive planes of words() words
  std::vector<i128> vals;  // planes: the value each pixel sees, already extended

  Bits bits(const PixelArray& a) const {
    switch (kind) {
      case Kind::field:
        return a.bits_of(f);
      case Kind::constant:
        return a.bits_of_constant(k);
      case Kind::planes:
        return a.bits_of_planes(buf.data(), count, is_signed);
    }
    return {};
  }
  i128 value(const Model& m, int p) const {
    switch (kind) {
      case Kind::field:
        return m.value(p, f);
      case Kind::constant:
        return k;
      case Kind::planes:
        return vals[p];
    }
    return 0;
  }
  std::string describe() const {
    switch (kind) {
      case Kind::field:
        return "field" + ::describe(f);
      case Kind::constant:
        return "const " + std::to_string(k);
      case Kind::planes:
        return "planes[" + std::to_string(count) + (is_signed ? "s]" : "u]");
    }
    return "?";
  }
};

enum class Op {
  assign,
  add,
  sub,
  logic,
  invert,
  multiply,
  mac,
  compare,
  push,
  pop,
  else_,
  store,
  load
};

// An array and its model kept in lock step, plus the random choices the tests draw from.
class Harness {
 public:
  Harness(const PixelArrayGeometry& g, std::uint64_t seed)
      : arr(g), model(g), rng(seed), written(g.backing_store_bits, 0) {
    randomize();
  }

  PixelArray arr;
  Model model;
  std::mt19937_64 rng;
  std::vector<std::uint8_t> written;  // backing-store bits stored at least once

  const PixelArrayGeometry& geo() const { return model.g; }
  int words() const { return arr.words(); }

  int uniform(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  bool one_in(int n) { return uniform(0, n - 1) == 0; }

  // The model's memory as bit-planes in the layout of bitplane.hpp.
  std::vector<Word> model_planes() const {
    std::vector<Word> planes(static_cast<std::size_t>(geo().memory_bits) * words());
    std::uint64_t block[64];
    for (int w = 0; w < words(); ++w) {
      for (int k = 0; k < model.per_pixel; ++k) {
        for (int j = 0; j < 64; ++j) {
          block[j] = model.mem[static_cast<std::size_t>(w * 64 + j) * model.per_pixel + k];
        }
        transpose64(block);
        for (int i = 0; i < 64 && k * 64 + i < geo().memory_bits; ++i) {
          planes[static_cast<std::size_t>(k * 64 + i) * words() + w] = block[i];
        }
      }
    }
    return planes;
  }

  std::vector<Word> model_enable() const {
    std::vector<Word> e(words(), 0);
    for (int p = 0; p < model.pixels; ++p) {
      if (model.enable[p]) e[p / 64] |= Word{1} << (p % 64);
    }
    return e;
  }

  // Model memory -> array memory, written straight into the planes (test set-up only).
  void sync() {
    const std::vector<Word> planes = model_planes();
    for (int b = 0; b < geo().memory_bits; ++b) {
      std::copy_n(&planes[static_cast<std::size_t>(b) * words()], words(), arr.plane(b));
    }
  }

  void randomize() {
    for (auto& w : model.mem) w = rng();
    if (geo().memory_bits % 64 != 0) {
      for (int p = 0; p < model.pixels; ++p) {
        model.mem[static_cast<std::size_t>(p) * model.per_pixel + model.per_pixel - 1] &=
            low_mask(geo().memory_bits % 64);
      }
    }
    sync();
  }

  // "" when the array's memory, Enable register and stack depth all match the model, else the
  // first difference.
  std::string mismatch() const {
    const std::vector<Word> planes = model_planes();
    for (int b = 0; b < geo().memory_bits; ++b) {
      for (int w = 0; w < words(); ++w) {
        const Word want = planes[static_cast<std::size_t>(b) * words() + w];
        const Word got = arr.plane(b)[w];
        if (want != got) {
          const int j = __builtin_ctzll(want ^ got);
          const int p = w * 64 + j;
          return "memory bit " + std::to_string(b) + " of pixel " + std::to_string(p) + " (" +
                 std::to_string(p % geo().width) + "," + std::to_string(p / geo().width) +
                 "): model " + std::to_string((want >> j) & 1) + ", array " +
                 std::to_string((got >> j) & 1) + ", pixel " +
                 (model.enable[p] ? "enabled" : "disabled");
        }
      }
    }
    const std::vector<Word> e = model_enable();
    int first = words();
    int last = 0;
    int count = 0;
    for (int w = 0; w < words(); ++w) {
      if (e[w] != arr.enable()[w]) {
        const int p = w * 64 + __builtin_ctzll(e[w] ^ arr.enable()[w]);
        return "enable of pixel " + std::to_string(p) + ": model " +
               std::to_string(model.enable[p]);
      }
      if (e[w] != 0) {
        first = std::min(first, w);
        last = w + 1;
      }
      count += __builtin_popcountll(e[w]);
    }
    if (arr.count_enabled() != count) return "count_enabled " + std::to_string(arr.count_enabled());
    const WordRange r = arr.active_words();
    if (count == 0 ? !r.empty() : (r.begin != first || r.end != last)) {
      return "active_words [" + std::to_string(r.begin) + "," + std::to_string(r.end) +
             ") but E spans [" + std::to_string(first) + "," + std::to_string(last) + ")";
    }
    if (arr.enable_depth() != static_cast<int>(model.stack.size())) {
      return "enable_depth " + std::to_string(arr.enable_depth());
    }
    return "";
  }

  std::vector<Word> words_of(const std::vector<std::uint8_t>& mask) const {
    std::vector<Word> m(words(), 0);
    for (int p = 0; p < model.pixels; ++p) {
      if (mask[p]) m[p / 64] |= Word{1} << (p % 64);
    }
    return m;
  }

  // E <- mask through the public interface (enable_all, then and_enable).
  void set_enable(const std::vector<std::uint8_t>& mask) {
    arr.enable_all();
    const std::vector<Word> m = words_of(mask);
    arr.and_enable(m.data());
    model.enable = mask;
  }

  std::vector<std::uint8_t> random_mask(std::string* name) {
    const int width = geo().width;
    const int height = geo().height;
    const int pixels = model.pixels;
    std::vector<std::uint8_t> m(pixels, 0);
    switch (uniform(0, 8)) {
      case 0:
        *name = "all off";
        break;
      case 1:
        *name = "all on";
        std::fill(m.begin(), m.end(), 1);
        break;
      case 2: {
        const int p = uniform(0, pixels - 1);
        *name = "single pixel " + std::to_string(p);
        m[p] = 1;
        break;
      }
      case 3:
      case 4:
        *name = "random half";
        for (auto& x : m) x = rng() & 1;
        break;
      case 5: {
        const int h = uniform(1, std::min(8, height));
        const int y0 = uniform(0, height - h);
        *name = "rows " + std::to_string(y0) + ".." + std::to_string(y0 + h);
        std::fill(m.begin() + y0 * width, m.begin() + (y0 + h) * width, 1);
        break;
      }
      case 6: {
        // Random bits with whole zero words at both ends and in the middle.
        *name = "random with zero words";
        for (auto& x : m) x = rng() & 1;
        const int quarter = std::max(1, words() / 4);
        const int head = uniform(1, quarter);
        const int tail = uniform(1, quarter);
        const int mid = uniform(head, std::max(head, words() - tail - 1));
        const int gap = uniform(1, quarter);
        auto clear = [&](int w0, int w1) {
          for (int p = w0 * 64; p < std::min(w1, words()) * 64; ++p) m[p] = 0;
        };
        clear(0, head);
        clear(words() - tail, words());
        clear(mid, mid + gap);
        break;
      }
      case 7:
        *name = "sparse";
        for (auto& x : m) x = one_in(97);
        break;
      case 8: {
        // A triangle-like primitive: a few rows, each covering a different span.
        const int h = uniform(1, std::min(8, height));
        const int y0 = uniform(0, height - h);
        const int x0 = uniform(0, width - 1);
        *name = "triangle at row " + std::to_string(y0);
        for (int y = y0; y < y0 + h; ++y) {
          const int a = std::max(0, x0 - 3 * (y - y0));
          const int b = std::min(width, x0 + 2 * (y - y0) + 1);
          for (int x = a; x < b; ++x) m[y * width + x] = 1;
        }
        break;
      }
    }
    return m;
  }

  std::string new_mask() {
    std::string name;
    set_enable(random_mask(&name));
    return "E = " + name + "; ";
  }

  int random_width(int max_width = 64) {
    int w = 0;
    switch (uniform(0, 3)) {
      case 0:
        w = uniform(1, 4);
        break;
      case 1:
        w = uniform(60, 64);
        break;
      default:
        w = uniform(1, 64);
        break;
    }
    return std::min({w, max_width, geo().memory_bits});
  }

  // Fields at bit 0 and fields ending at the last bit of memory are drawn often.
  Field random_field(int w) {
    Field f;
    f.width = w;
    const int top = geo().memory_bits - w;
    switch (uniform(0, 4)) {
      case 0:
        f.lo = 0;
        break;
      case 1:
        f.lo = top;
        break;
      default:
        f.lo = uniform(0, top);
        break;
    }
    f.is_signed = rng() & 1;
    return f;
  }

  Field random_field_avoiding(const std::vector<Field>& avoid) {
    for (;;) {
      const Field f = random_field(random_width());
      if (std::none_of(avoid.begin(), avoid.end(),
                       [&](const Field& a) { return overlaps(a, f); })) {
        return f;
      }
    }
  }

  std::int64_t random_constant() {
    static const std::int64_t kSpecial[] = {0,
                                            1,
                                            -1,
                                            2,
                                            -2,
                                            3,
                                            kMin64,
                                            kMax64,
                                            kMin64 + 1,
                                            kMax64 - 1,
                                            std::int64_t{1} << 31,
                                            -(std::int64_t{1} << 31),
                                            std::int64_t{1} << 32,
                                            (std::int64_t{1} << 62) + 12345};
    switch (uniform(0, 3)) {
      case 0:
        return kSpecial[uniform(0, static_cast<int>(std::size(kSpecial)) - 1)];
      case 1:
        return uniform(-300, 300);
      case 2:
        return static_cast<std::int64_t>(rng());
      default: {
        const auto v = static_cast<std::int64_t>(rng() >> uniform(1, 63));
        return (rng() & 1) ? -v : v;
      }
    }
  }

  // A raw w-bit pattern: random, or one of the values at which carries run the full width.
  std::uint64_t random_raw(int w) {
    switch (uniform(0, 7)) {
      case 0:
        return 0;
      case 1:
        return low_mask(w);
      case 2:
        return std::uint64_t{1} << (w - 1);
      case 3:
        return low_mask(w - 1);
      default:
        return rng() & low_mask(w);
    }
  }

  // Writes carry-chain values into about a third of the pixels of f, half of the time.
  void maybe_specials(const Field& f) {
    if (rng() & 1) return;
    for (int p = 0; p < model.pixels; ++p) {
      if (one_in(3)) model.set(p, f, random_raw(f.width));
    }
    sync();
  }

  // A field source never overlaps `avoid` (the contract allows aliasing only at the same
  // alignment, which alias_source() draws on purpose).
  OperandSource random_source(int max_width = 64, const Field* avoid = nullptr) {
    OperandSource s;
    switch (uniform(0, 3)) {
      case 0:
      case 1:
        s.kind = OperandSource::Kind::field;
        do {
          s.f = random_field(random_width(max_width));
        } while (avoid != nullptr && overlaps(s.f, *avoid));
        maybe_specials(s.f);
        break;
      case 2:
        s.kind = OperandSource::Kind::constant;
        s.k = random_constant();
        break;
      default:
        s.kind = OperandSource::Kind::planes;
        s.count = random_width();
        s.is_signed = rng() & 1;
        s.buf.assign(static_cast<std::size_t>(s.count) * words(), 0);
        s.vals.resize(model.pixels);
        for (int p = 0; p < model.pixels; ++p) {
          const std::uint64_t raw = random_raw(s.count);
          s.vals[p] = extend(raw, s.count, s.is_signed);
          for (int i = 0; i < s.count; ++i) {
            if ((raw >> i) & 1) {
              s.buf[static_cast<std::size_t>(i) * words() + p / 64] |= Word{1} << (p % 64);
            }
          }
        }
        break;
    }
    return s;
  }

  // A field source at dst's own alignment: the same width, wider (either signedness), or
  // narrower and unsigned (its extension is the zero plane, never a plane of dst).
  OperandSource alias_source(const Field& dst) {
    OperandSource s;
    s.f = dst;
    s.f.is_signed = rng() & 1;
    const int room = std::min(64, geo().memory_bits - dst.lo);
    if (one_in(3) && room > dst.width) {
      s.f.width = uniform(dst.width + 1, room);
    } else if (one_in(2) && dst.width > 1) {
      s.f.width = uniform(1, dst.width - 1);
      s.f.is_signed = false;
    }
    return s;
  }

  // Makes a field source equal (or off by one) to the other operand on many pixels.
  void equalize(OperandSource& s, const OperandSource& other) {
    if (s.kind != OperandSource::Kind::field) return;
    if (other.kind == OperandSource::Kind::field && overlaps(s.f, other.f)) return;
    const int w = s.f.width;
    const i128 lo = s.f.is_signed ? -(i128{1} << (w - 1)) : 0;
    const i128 hi = s.f.is_signed ? (i128{1} << (w - 1)) - 1 : (i128{1} << w) - 1;
    for (int p = 0; p < model.pixels; ++p) {
      const int pick = uniform(0, 3);
      if (pick == 3) continue;
      const i128 v = other.value(model, p) + (pick - 1) * (p & 1);
      if (v >= lo && v <= hi) model.set(p, s.f, low64(v));
    }
    sync();
  }

  // The carry register holds the carry out of the destination's top bit at enabled pixels.
  std::string carry_mismatch(const std::vector<std::uint8_t>& want) const {
    for (int p = 0; p < model.pixels; ++p) {
      if (model.enable[p] && arr.carry_bit(p) != want[p]) {
        return "carry of pixel " + std::to_string(p) + ": model " + std::to_string(want[p]);
      }
    }
    return "";
  }

  // Performs one random operation on both the array and the model and returns what it did;
  // a non-empty *carry names a carry-register mismatch.
  std::string step(Op op, std::string* carry) {
    std::string what;
    if (one_in(3)) what += new_mask();
    switch (op) {
      case Op::assign:
      case Op::add:
      case Op::sub:
      case Op::logic: {
        const Field dst = random_field(random_width());
        maybe_specials(dst);
        const OperandSource a = one_in(4) ? alias_source(dst) : random_source(64, &dst);
        const OperandSource b = one_in(4) ? alias_source(dst) : random_source(64, &dst);
        const Logic lop = static_cast<Logic>(uniform(0, 2));
        std::vector<std::uint8_t> carries(model.pixels, 0);
        const int w = dst.width;
        if (op == Op::assign) {
          arr.assign(dst, a.bits(arr));
          what += "assign " + describe(dst) + " <- " + a.describe();
        } else if (op == Op::add) {
          arr.add(dst, a.bits(arr), b.bits(arr));
          what += "add " + describe(dst) + " <- " + a.describe() + " + " + b.describe();
        } else if (op == Op::sub) {
          arr.sub(dst, a.bits(arr), b.bits(arr));
          what += "sub " + describe(dst) + " <- " + a.describe() + " - " + b.describe();
        } else {
          arr.logic(dst, a.bits(arr), b.bits(arr), lop);
          what += "logic " + std::to_string(static_cast<int>(lop)) + " " + describe(dst) + " <- " +
                  a.describe() + ", " + b.describe();
        }
        for (int p = 0; p < model.pixels; ++p) {
          if (!model.enable[p]) continue;
          const i128 x = a.value(model, p);
          const i128 y = b.value(model, p);
          const u128 xw = low64(x) & low_mask(w);
          const u128 yw = low64(y) & low_mask(w);
          std::uint64_t r = 0;
          switch (op) {
            case Op::assign:
              r = low64(x);
              break;
            case Op::add:
              r = low64(x + y);
              carries[p] = static_cast<std::uint8_t>((xw + yw) >> w);
              break;
            case Op::sub:
              r = low64(x - y);
              carries[p] = xw >= yw;
              break;
            default:
              r = lop == Logic::and_  ? low64(x & y)
                  : lop == Logic::or_ ? low64(x | y)
                                      : low64(x ^ y);
              break;
          }
          model.set(p, dst, r);
        }
        if (op == Op::add || op == Op::sub) *carry = carry_mismatch(carries);
        break;
      }
      case Op::invert: {
        const Field dst = random_field(random_width());
        arr.invert(dst);
        what += "invert " + describe(dst);
        for (int p = 0; p < model.pixels; ++p) {
          if (model.enable[p]) model.set(p, dst, ~model.get(p, dst));
        }
        break;
      }
      case Op::multiply: {
        // Narrow source fields leave room for a destination that overlaps neither.
        const OperandSource a = random_source(geo().memory_bits / 4);
        const OperandSource b = random_source(geo().memory_bits / 4);
        std::vector<Field> avoid;
        if (a.kind == OperandSource::Kind::field) avoid.push_back(a.f);
        if (b.kind == OperandSource::Kind::field) avoid.push_back(b.f);
        const Field dst = random_field_avoiding(avoid);
        arr.multiply(dst, a.bits(arr), b.bits(arr));
        what += "multiply " + describe(dst) + " <- " + a.describe() + " * " + b.describe();
        for (int p = 0; p < model.pixels; ++p) {
          if (!model.enable[p]) continue;
          const u128 x = static_cast<u128>(a.value(model, p));
          const u128 y = static_cast<u128>(b.value(model, p));
          model.set(p, dst, static_cast<std::uint64_t>(x * y));
        }
        break;
      }
      case Op::mac: {
        const OperandSource a = random_source(geo().memory_bits / 4);
        std::vector<Field> avoid;
        if (a.kind == OperandSource::Kind::field) avoid.push_back(a.f);
        const Field dst = random_field_avoiding(avoid);
        maybe_specials(dst);
        const std::int64_t k = random_constant();
        arr.multiply_accumulate(dst, a.bits(arr), k);
        what += "mac " + describe(dst) + " += " + a.describe() + " * " + std::to_string(k);
        for (int p = 0; p < model.pixels; ++p) {
          if (!model.enable[p]) continue;
          const u128 x = static_cast<u128>(a.value(model, p));
          const u128 d = model.get(p, dst);
          model.set(p, dst, static_cast<std::uint64_t>(d + x * static_cast<u128>(i128{k})));
        }
        break;
      }
      case Op::compare: {
        // Compare only narrows E, so start from a fresh mask more often.
        if (what.empty() && one_in(2)) what += new_mask();
        OperandSource a = random_source();
        OperandSource b = random_source();
        if (one_in(2)) equalize(a, b);
        const Compare c = kCompares[uniform(0, 5)];
        arr.compare(a.bits(arr), b.bits(arr), c);
        what += std::string("compare ") + name_of(c) + " " + a.describe() + ", " + b.describe();
        for (int p = 0; p < model.pixels; ++p) {
          model.enable[p] = model.enable[p] && holds(c, a.value(model, p), b.value(model, p));
        }
        break;
      }
      case Op::push:
        if (static_cast<int>(model.stack.size()) == geo().enable_stack_depth) {
          what += "push (overflow)";
          REQUIRE_THROWS_AS(arr.push_enable(), std::overflow_error);
        } else {
          what += "push";
          arr.push_enable();
          model.stack.push_back(model.enable);
        }
        break;
      case Op::pop:
        if (model.stack.empty()) {
          what += "pop (underflow)";
          REQUIRE_THROWS_AS(arr.pop_enable(), std::underflow_error);
        } else {
          what += "pop";
          arr.pop_enable();
          model.enable = model.stack.back();
          model.stack.pop_back();
        }
        break;
      case Op::else_:
        if (model.stack.empty()) {
          what += "else (underflow)";
          REQUIRE_THROWS_AS(arr.else_enable(), std::underflow_error);
        } else {
          what += "else";
          arr.else_enable();
          for (int p = 0; p < model.pixels; ++p) {
            model.enable[p] = model.stack.back()[p] && !model.enable[p];
          }
        }
        break;
      case Op::store: {
        const int bits = geo().backing_store_bits;
        if (bits == 0) break;
        const Field f = random_field(random_width(bits));
        const int block = uniform(0, (bits - f.width) / geo().block_bits);
        arr.store_to_backing(f, block);
        model.store(f, block);
        std::fill_n(written.begin() + block * geo().block_bits, f.width, 1);
        what += "store " + describe(f) + " to block " + std::to_string(block);
        break;
      }
      case Op::load: {
        const int bits = geo().backing_store_bits;
        if (bits == 0) break;
        for (int tries = 0; tries < 20; ++tries) {
          const Field f = random_field(random_width(bits));
          const int block = uniform(0, (bits - f.width) / geo().block_bits);
          const auto from = written.begin() + block * geo().block_bits;
          if (!std::all_of(from, from + f.width, [](std::uint8_t x) { return x != 0; })) continue;
          arr.load_from_backing(f, block);
          model.load(f, block);
          what += "load " + describe(f) + " from block " + std::to_string(block);
          break;
        }
        break;
      }
    }
    return what;
  }

  void run(const std::vector<Op>& ops, int iterations) {
    for (int i = 0; i < iterations; ++i) {
      std::string carry;
      const std::string what = step(ops[uniform(0, static_cast<int>(ops.size()) - 1)], &carry);
      INFO("step " << i << ": " << what);
      REQUIRE(mismatch() == "");
      REQUIRE(carry == "");
    }
  }
};

PixelArrayGeometry default_geometry() { return PixelArrayGeometry{}; }

}  // namespace

TEST_CASE("pixel array: the 64x64 transpose used by the model is a transpose", "[pixel_array]") {
  std::mt19937_64 rng(1);
  std::uint64_t a[64];
  std::uint64_t b[64];
  for (auto& x : a) x = rng();
  std::copy_n(a, 64, b);
  transpose64(b);
  for (int i = 0; i < 64; ++i) {
    for (int j = 0; j < 64; ++j) REQUIRE(((b[i] >> j) & 1) == ((a[j] >> i) & 1));
  }
}

TEST_CASE("pixel array: write, read and read_signed follow the bit-sliced layout",
          "[pixel_array]") {
  Harness h(default_geometry(), 11);
  // Scalar access is not an ALU path: it works with every pixel disabled.
  h.set_enable(std::vector<std::uint8_t>(h.model.pixels, 0));
  for (int i = 0; i < 400; ++i) {
    const Field f = h.random_field(h.random_width());
    const int p = h.uniform(0, h.model.pixels - 1);
    const std::uint64_t v = h.rng();
    h.arr.write(p, f, v);
    h.model.set(p, f, v);
    INFO("pixel " << p << " field " << describe(f));
    for (int b = 0; b < f.width; ++b) {
      REQUIRE(((h.arr.plane(f.lo + b)[p / 64] >> (p % 64)) & 1) == ((v >> b) & 1));
    }
    REQUIRE(h.arr.read(p, f) == (v & low_mask(f.width)));
    if (f.is_signed) {
      REQUIRE(h.arr.read_signed(p, f) ==
              static_cast<std::int64_t>(extend(v & low_mask(f.width), f.width, true)));
    } else if (f.width < 64) {
      REQUIRE(h.arr.read_signed(p, f) == static_cast<std::int64_t>(v & low_mask(f.width)));
    }
  }
  REQUIRE(h.mismatch() == "");
  // Reading random fields of random pixels of the random memory.
  for (int i = 0; i < 200; ++i) {
    const Field f = h.random_field(h.random_width());
    const int p = h.uniform(0, h.model.pixels - 1);
    REQUIRE(h.arr.read(p, f) == h.model.get(p, f));
    if (f.is_signed || f.width < 64) {
      REQUIRE(static_cast<i128>(h.arr.read_signed(p, f)) == h.model.value(p, f));
    }
  }
}

TEST_CASE("pixel array: assign from fields, constants and planes", "[pixel_array]") {
  Harness h(default_geometry(), 21);
  h.run({Op::assign}, 90);
}

TEST_CASE("pixel array: add and sub", "[pixel_array]") {
  Harness h(default_geometry(), 22);
  h.run({Op::add, Op::sub}, 140);
}

TEST_CASE("pixel array: logic and invert", "[pixel_array]") {
  Harness h(default_geometry(), 23);
  h.run({Op::logic, Op::invert}, 90);
}

TEST_CASE("pixel array: multiply", "[pixel_array]") {
  Harness h(default_geometry(), 24);
  h.run({Op::multiply}, 60);
}

TEST_CASE("pixel array: multiply_accumulate", "[pixel_array]") {
  Harness h(default_geometry(), 25);
  h.run({Op::mac}, 90);
}

TEST_CASE("pixel array: compare", "[pixel_array]") {
  Harness h(default_geometry(), 26);
  h.run({Op::compare}, 150);
}

TEST_CASE("pixel array: all operations interleaved with the enable stack and backing store",
          "[pixel_array]") {
  Harness h(default_geometry(), 27);
  h.run({Op::assign, Op::add, Op::sub, Op::logic, Op::invert, Op::multiply, Op::mac, Op::compare,
         Op::push, Op::push, Op::pop, Op::else_, Op::store, Op::load},
        200);
}

TEST_CASE("pixel array: non-default geometries", "[pixel_array]") {
  const std::vector<Op> all = {Op::assign,   Op::add,   Op::sub,     Op::logic, Op::invert,
                               Op::multiply, Op::mac,   Op::compare, Op::push,  Op::pop,
                               Op::else_,    Op::store, Op::load};
  SECTION("64 x 8, 256 bits, stack of 3, 16-bit blocks") {
    Harness h(PixelArrayGeometry{64, 8, 256, 3, 512, 16}, 31);
    h.run(all, 400);
  }
  SECTION("192 x 3, 70 bits, stack of 1, no backing store") {
    Harness h(PixelArrayGeometry{192, 3, 70, 1, 0, 32}, 32);
    h.run(all, 300);
    REQUIRE_THROWS_AS(h.arr.store_to_backing(Field{0, 1, false}, 0), std::out_of_range);
    REQUIRE_THROWS_AS(h.arr.load_from_backing(Field{0, 1, false}, 0), std::out_of_range);
  }
}

TEST_CASE("pixel array: compare mixes widths and signedness exactly", "[pixel_array]") {
  Harness h(default_geometry(), 41);
  const int pixels = h.model.pixels;
  struct Pair {
    Field a;
    Field b;
  };
  const Pair pairs[] = {
      {{3, 7, false}, {100, 12, true}},   // 7-bit unsigned vs 12-bit signed
      {{0, 64, false}, {144, 64, true}},  // 2^64 - 1 vs -1 needs 65 bits
      {{64, 1, true}, {65, 1, false}},    // -1 / 0 vs 0 / 1
      {{10, 33, true}, {200, 8, false}},  // ends at bit 207
  };
  for (const Pair& pr : pairs) {
    // Equal values on half of the pixels, neighbours on a quarter, random elsewhere.
    for (int p = 0; p < pixels; ++p) {
      h.model.set(p, pr.a, h.random_raw(pr.a.width));
      h.model.set(p, pr.b, h.random_raw(pr.b.width));
    }
    OperandSource sa;
    sa.f = pr.a;
    OperandSource sb;
    sb.f = pr.b;
    h.equalize(sb, sa);
    for (const Compare c : kCompares) {
      for (int order = 0; order < 2; ++order) {
        const Field& x = order == 0 ? pr.a : pr.b;
        const Field& y = order == 0 ? pr.b : pr.a;
        std::string name;
        h.set_enable(h.random_mask(&name));
        h.arr.compare(h.arr.bits_of(x), h.arr.bits_of(y), c);
        int hits = 0;
        for (int p = 0; p < pixels; ++p) {
          h.model.enable[p] =
              h.model.enable[p] && holds(c, h.model.value(p, x), h.model.value(p, y));
          hits += h.model.enable[p];
        }
        INFO(name_of(c) << " " << describe(x) << " vs " << describe(y) << " under " << name << ", "
                        << hits << " pixels pass");
        REQUIRE(h.mismatch() == "");
      }
    }
  }
  // Against the extreme constants, where a 64-bit difference would overflow.
  const Field u64{0, 64, false};
  const Field s64{144, 64, true};
  for (int p = 0; p < pixels; ++p) {
    h.model.set(p, u64, p % 3 == 0 ? ~std::uint64_t{0} : p % 3 == 1 ? std::uint64_t{1} << 63 : 0);
    h.model.set(p, s64, p % 3 == 0 ? 0 : p % 3 == 1 ? std::uint64_t{1} << 63 : low64(kMax64));
  }
  h.sync();
  for (const std::int64_t k : {kMin64, kMax64, std::int64_t{-1}, std::int64_t{0}}) {
    for (const Compare c : kCompares) {
      for (const Field& f : {u64, s64}) {
        h.set_enable(std::vector<std::uint8_t>(pixels, 1));
        h.arr.compare(h.arr.bits_of(f), h.arr.bits_of_constant(k), c);
        for (int p = 0; p < pixels; ++p) h.model.enable[p] = holds(c, h.model.value(p, f), k);
        INFO(name_of(c) << " " << describe(f) << " vs " << k);
        REQUIRE(h.mismatch() == "");
      }
    }
  }
}

TEST_CASE("pixel array: carries and borrows run the whole width of the field", "[pixel_array]") {
  Harness h(default_geometry(), 51);
  const int pixels = h.model.pixels;
  const int top = h.geo().memory_bits;
  std::vector<std::uint8_t> half(pixels);
  for (int p = 0; p < pixels; ++p) half[p] = p % 2;
  h.set_enable(half);
  const int enabled_pixel = 1;
  for (const int w : {1, 7, 32, 63, 64}) {
    for (const int lo : {0, top - w}) {
      const Field f{lo, w, false};
      const Field fs{lo, w, true};
      const std::uint64_t ones = low_mask(w);
      INFO("field " << describe(f));
      auto fill = [&](std::uint64_t v) {
        for (int p = 0; p < pixels; ++p) h.model.set(p, f, v);
        h.sync();
      };
      // carry < 0: multiply_accumulate, whose carry register the contract leaves open.
      auto expect = [&](std::uint64_t v, int carry) {
        for (int p = 0; p < pixels; ++p) {
          if (half[p]) h.model.set(p, f, v);
        }
        REQUIRE(h.arr.read(enabled_pixel, f) == v);
        if (carry >= 0)
          REQUIRE(h.arr.carry_bit(enabled_pixel) == static_cast<std::uint64_t>(carry));
        REQUIRE(h.mismatch() == "");
      };
      fill(ones);
      h.arr.add(f, h.arr.bits_of(f), h.arr.bits_of_constant(1));
      expect(0, 1);
      fill(0);
      h.arr.sub(f, h.arr.bits_of(f), h.arr.bits_of_constant(1));
      expect(ones, 0);
      fill(ones >> 1);
      h.arr.add(f, h.arr.bits_of(f), h.arr.bits_of_constant(1));
      expect(std::uint64_t{1} << (w - 1), 0);
      fill(std::uint64_t{1} << (w - 1));
      h.arr.sub(fs, h.arr.bits_of(fs), h.arr.bits_of_constant(1));
      expect(ones >> 1, 1);
      // A 1-bit signed field holding 1 is -1 and sign-extends across the whole destination.
      const Field minus_one{lo == 0 ? top - 1 : 0, 1, true};
      for (int p = 0; p < pixels; ++p) h.model.set(p, minus_one, 1);
      fill(0);
      h.arr.add(f, h.arr.bits_of(f), h.arr.bits_of(minus_one));
      expect(ones, 0);
      fill(ones);
      h.arr.multiply_accumulate(f, h.arr.bits_of(minus_one), -1);
      expect(0, -1);
      fill(0);
      h.arr.multiply_accumulate(f, h.arr.bits_of(minus_one), 1);
      expect(ones, -1);
    }
  }
  const Field s64{144, 64, true};
  for (int p = 0; p < pixels; ++p) h.model.set(p, s64, low64(kMin64));
  h.sync();
  h.arr.sub(s64, h.arr.bits_of(s64), h.arr.bits_of_constant(1));
  REQUIRE(h.arr.read_signed(enabled_pixel, s64) == kMax64);
  h.arr.add(s64, h.arr.bits_of(s64), h.arr.bits_of_constant(1));
  REQUIRE(h.arr.read_signed(enabled_pixel, s64) == kMin64);
  REQUIRE(h.arr.read_signed(0, s64) == kMin64);
}

TEST_CASE("pixel array: multiply_accumulate with extreme constants", "[pixel_array]") {
  Harness h(default_geometry(), 55);
  const Field dsts[] = {{144, 64, false}, {0, 64, true}, {1, 63, true}, {207, 1, false}};
  const Field srcs[] = {{70, 64, false}, {70, 64, true}, {70, 3, true}, {70, 1, false}};
  const std::int64_t ks[] = {
      kMin64, kMin64 + 1, kMax64, -1, 0, std::int64_t{1} << 62, -(std::int64_t{1} << 62) - 1};
  std::string name;
  for (const Field& dst : dsts) {
    for (const Field& src : srcs) {
      for (const std::int64_t k : ks) {
        h.set_enable(h.random_mask(&name));
        h.arr.multiply_accumulate(dst, h.arr.bits_of(src), k);
        for (int p = 0; p < h.model.pixels; ++p) {
          if (!h.model.enable[p]) continue;
          const u128 x = static_cast<u128>(h.model.value(p, src));
          h.model.set(
              p, dst,
              static_cast<std::uint64_t>(h.model.get(p, dst) + x * static_cast<u128>(i128{k})));
        }
        INFO(describe(dst) << " += " << describe(src) << " * " << k << " under " << name);
        REQUIRE(h.mismatch() == "");
      }
    }
  }
}

TEST_CASE("pixel array: a destination may alias a source at the same alignment", "[pixel_array]") {
  Harness h(default_geometry(), 61);
  std::string name;
  for (int i = 0; i < 40; ++i) {
    h.set_enable(h.random_mask(&name));
    const Field f = h.random_field(h.random_width());
    const OperandSource s = h.alias_source(f);
    const Bits x = h.arr.bits_of(f);
    const Bits y = s.bits(h.arr);
    const int op = h.uniform(0, 5);
    INFO("op " << op << " on " << describe(f) << " with " << s.describe() << " under " << name);
    switch (op) {
      case 0:
        h.arr.add(f, x, y);
        break;
      case 1:
        h.arr.sub(f, x, y);
        break;
      case 2:
        h.arr.sub(f, y, x);
        break;
      case 3:
        h.arr.logic(f, x, y, Logic::xor_);
        break;
      case 4:
        h.arr.logic(f, y, x, Logic::or_);
        break;
      default:
        h.arr.assign(f, y);
        break;
    }
    for (int p = 0; p < h.model.pixels; ++p) {
      if (!h.model.enable[p]) continue;
      const i128 a = h.model.value(p, f);
      const i128 b = s.value(h.model, p);
      const i128 r = op == 0   ? a + b
                     : op == 1 ? a - b
                     : op == 2 ? b - a
                     : op == 3 ? a ^ b
                     : op == 4 ? a | b
                               : b;
      h.model.set(p, f, low64(r));
    }
    REQUIRE(h.mismatch() == "");
  }
}

// The contract lets a destination alias a source at the same alignment; a signed source
// narrower than the destination extends by its own top plane, which the walk has already
// rewritten by the time it reads the extension.
TEST_CASE("pixel array: aliasing a narrower signed source extends the source's old sign",
          "[pixel_array]") {
  Harness h(default_geometry(), 62);
  const Field dst{0, 16, true};
  const Field src{0, 8, true};  // dst's low byte, at dst's alignment
  auto reset = [&] {
    for (int p = 0; p < h.model.pixels; ++p) h.model.set(p, dst, 0x0080);  // src = -128
    h.sync();
  };
  reset();
  h.arr.add(dst, h.arr.bits_of(src), h.arr.bits_of_constant(128));
  CHECK(h.arr.read_signed(0, dst) == -128 + 128);
  reset();
  h.arr.sub(dst, h.arr.bits_of(src), h.arr.bits_of_constant(-128));
  CHECK(h.arr.read_signed(0, dst) == -128 - -128);
  reset();
  h.arr.logic(dst, h.arr.bits_of(src), h.arr.bits_of_constant(0x80), Logic::xor_);
  CHECK(h.arr.read_signed(0, dst) == (-128 ^ 0x80));
}

TEST_CASE("pixel array: multiply and multiply_accumulate reject an overlapping destination",
          "[pixel_array]") {
  Harness h(default_geometry(), 71);
  const Field dst{10, 16, false};
  const Field inside{20, 8, false};  // planes 20..27, overlapping dst's top planes
  const Field top{25, 4, true};      // its first plane is dst's last
  const Field below{6, 4, false};    // planes 6..9, adjacent to dst
  const Field above{26, 8, false};   // planes 26..33, adjacent to dst
  const Bits k = h.arr.bits_of_constant(3);
  REQUIRE_THROWS_AS(h.arr.multiply(dst, h.arr.bits_of(inside), k), std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply(dst, k, h.arr.bits_of(inside)), std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply(dst, h.arr.bits_of(top), k), std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply(dst, h.arr.bits_of(dst), h.arr.bits_of(dst)),
                    std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply_accumulate(dst, h.arr.bits_of(inside), 5),
                    std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply_accumulate(dst, h.arr.bits_of(dst), -1), std::invalid_argument);
  REQUIRE_THROWS_AS(h.arr.multiply_accumulate(dst, h.arr.bits_of(Field{0, 64, true}), 0),
                    std::invalid_argument);
  REQUIRE(h.mismatch() == "");
  // Adjacent fields do not overlap.
  h.arr.multiply(dst, h.arr.bits_of(below), h.arr.bits_of(above));
  for (int p = 0; p < h.model.pixels; ++p) {
    h.model.set(p, dst, h.model.get(p, below) * h.model.get(p, above));
  }
  REQUIRE(h.mismatch() == "");
  h.arr.multiply_accumulate(dst, h.arr.bits_of(above), -7);
  for (int p = 0; p < h.model.pixels; ++p) {
    h.model.set(p, dst, h.model.get(p, dst) - 7 * h.model.get(p, above));
  }
  REQUIRE(h.mismatch() == "");
}

TEST_CASE("pixel array: nested conditionals to the full stack depth", "[pixel_array]") {
  Harness h(default_geometry(), 81);
  const int depth = h.geo().enable_stack_depth;
  const int pixels = h.model.pixels;
  REQUIRE_THROWS_AS(h.arr.pop_enable(), std::underflow_error);
  REQUIRE_THROWS_AS(h.arr.else_enable(), std::underflow_error);
  std::string name;
  h.set_enable(h.random_mask(&name));
  for (int round = 0; round < 3; ++round) {
    // if: each level keeps the pixels whose level-th field bit is set.
    for (int level = 0; level < depth; ++level) {
      h.arr.push_enable();
      h.model.stack.push_back(h.model.enable);
      const Field bit{level * 3, 1, false};
      h.arr.compare(h.arr.bits_of(bit), h.arr.bits_of_constant(1), Compare::eq);
      for (int p = 0; p < pixels; ++p) h.model.enable[p] = h.model.enable[p] && h.model.get(p, bit);
      INFO("round " << round << " level " << level);
      REQUIRE(h.mismatch() == "");
    }
    REQUIRE(h.arr.enable_depth() == depth);
    REQUIRE_THROWS_AS(h.arr.push_enable(), std::overflow_error);
    REQUIRE(h.mismatch() == "");
    // else, a write under the else branch, then endif, innermost first.
    for (int level = depth - 1; level >= 0; --level) {
      INFO("round " << round << " unwinding level " << level);
      h.arr.else_enable();
      for (int p = 0; p < pixels; ++p) {
        h.model.enable[p] = h.model.stack.back()[p] && !h.model.enable[p];
      }
      REQUIRE(h.mismatch() == "");
      const Field f{100 + level * 12, 12, false};
      h.arr.add(f, h.arr.bits_of(f), h.arr.bits_of_constant(level + 1));
      for (int p = 0; p < pixels; ++p) {
        if (h.model.enable[p]) h.model.set(p, f, h.model.get(p, f) + level + 1);
      }
      REQUIRE(h.mismatch() == "");
      h.arr.pop_enable();
      h.model.enable = h.model.stack.back();
      h.model.stack.pop_back();
      REQUIRE(h.mismatch() == "");
    }
    REQUIRE_THROWS_AS(h.arr.pop_enable(), std::underflow_error);
    REQUIRE_THROWS_AS(h.arr.else_enable(), std::underflow_error);
    REQUIRE(h.mismatch() == "");
    h.randomize();
  }
  PixelArrayGeometry g;
  g.enable_stack_depth = 0;
  PixelArray none(g);
  REQUIRE_THROWS_AS(none.push_enable(), std::overflow_error);
}

TEST_CASE("pixel array: backing store round trip ignores Enable", "[pixel_array]") {
  Harness h(default_geometry(), 91);
  const int blocks = h.geo().backing_store_bits / h.geo().block_bits;
  std::string name;
  h.set_enable(h.random_mask(&name));
  INFO("E = " << name);
  const Field a{5, 40, true};     // two blocks
  const Field b{144, 64, false};  // two blocks, ends at bit 207
  const Field c{0, 32, false};    // one block
  h.arr.store_to_backing(a, 3);
  h.model.store(a, 3);
  h.arr.store_to_backing(b, 5);
  h.model.store(b, 5);
  h.arr.store_to_backing(c, blocks - 1);
  h.model.store(c, blocks - 1);
  REQUIRE(h.mismatch() == "");
  h.randomize();
  h.set_enable(std::vector<std::uint8_t>(h.model.pixels, 0));
  const Field a2{100, 40, false};
  h.arr.load_from_backing(a2, 3);
  h.model.load(a2, 3);
  h.arr.load_from_backing(b, 5);
  h.model.load(b, 5);
  h.arr.load_from_backing(Field{60, 32, true}, blocks - 1);
  h.model.load(Field{60, 32, true}, blocks - 1);
  REQUIRE(h.mismatch() == "");
  // The loaded values are the stored ones at every pixel, not just the model's say-so.
  const Harness fresh(default_geometry(), 91);
  for (int p = 0; p < h.model.pixels; p += 97) {
    REQUIRE(h.arr.read(p, a2) == fresh.model.get(p, a));
    REQUIRE(h.arr.read(p, b) == fresh.model.get(p, b));
  }
  REQUIRE_THROWS_AS(h.arr.store_to_backing(c, blocks), std::out_of_range);
  REQUIRE_THROWS_AS(h.arr.store_to_backing(Field{0, 33, false}, blocks - 1), std::out_of_range);
  REQUIRE_THROWS_AS(h.arr.store_to_backing(c, -1), std::out_of_range);
  REQUIRE_THROWS_AS(h.arr.load_from_backing(c, blocks), std::out_of_range);
  REQUIRE_THROWS_AS(h.arr.load_from_backing(Field{0, 33, false}, blocks - 1), std::out_of_range);
  REQUIRE_THROWS_AS(h.arr.load_from_backing(c, -1), std::out_of_range);
  REQUIRE(h.mismatch() == "");
}

TEST_CASE("pixel array: fields and geometry are validated", "[pixel_array]") {
  PixelArray a(default_geometry());
  const Bits one = a.bits_of_constant(1);
  for (const Field f : {Field{0, 0, false}, Field{0, 65, false}, Field{-1, 8, false},
                        Field{200, 9, false}, Field{208, 1, false}}) {
    INFO("field " << describe(f));
    REQUIRE_THROWS_AS(a.bits_of(f), std::out_of_range);
    REQUIRE_THROWS_AS(a.assign(f, one), std::out_of_range);
    REQUIRE_THROWS_AS(a.add(f, one, one), std::out_of_range);
    REQUIRE_THROWS_AS(a.sub(f, one, one), std::out_of_range);
    REQUIRE_THROWS_AS(a.logic(f, one, one, Logic::and_), std::out_of_range);
    REQUIRE_THROWS_AS(a.invert(f), std::out_of_range);
    REQUIRE_THROWS_AS(a.multiply(f, one, one), std::out_of_range);
    REQUIRE_THROWS_AS(a.multiply_accumulate(f, one, 1), std::out_of_range);
    REQUIRE_THROWS_AS(a.write(0, f, 1), std::out_of_range);
    REQUIRE_THROWS_AS(a.store_to_backing(f, 0), std::out_of_range);
  }
  REQUIRE_THROWS_AS(a.bits_of_planes(a.zeros(), 0, false), std::out_of_range);
  REQUIRE_THROWS_AS(a.bits_of_planes(a.zeros(), 65, false), std::out_of_range);
  PixelArrayGeometry g;
  g.width = 100;
  REQUIRE_THROWS_AS(PixelArray(g), std::invalid_argument);
  g = PixelArrayGeometry{};
  g.height = 0;
  REQUIRE_THROWS_AS(PixelArray(g), std::invalid_argument);
  g = PixelArrayGeometry{};
  g.memory_bits = 0;
  REQUIRE_THROWS_AS(PixelArray(g), std::invalid_argument);
}
