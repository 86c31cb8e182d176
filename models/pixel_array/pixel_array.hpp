#pragma once
// The Renderer board's SIMD array of bit-serial pixel processors, stored bit-sliced: the
// pixel memory of the "bit" backend (models/pixel_array/bit_sliced_backend.hpp). Its
// geometry and operand types (Field, Compare, Logic) are the instruction set's
// (firmware/isa/types.hpp).
//
// Each pixel processor has `memory_bits` bits of local memory, a 1-bit ALU with a carry
// register, an Enable register E and a stack of saved Enable values for nested
// conditionals, and `backing_store_bits` of slow backing store moved in blocks.
//
// Contract:
//  - Every ALU operation below is bit-serial: it walks its operands least significant bit
//    first, one bit-plane per array cycle, exactly as the hardware would; the cost in cycles
//    is the instruction table's business (firmware/isa), not this class's.
//  - Memory writes happen only where E = 1. Backing-store transfers ignore E (they are
//    block moves between two memories, not ALU operations).
//  - Operations touch only the words where E has a set bit, which is exact (a word with
//    E = 0 is never written) and makes the cost proportional to the rows a primitive covers.
//  - A destination may alias a source only at the same bit alignment (the LSB-first walk
//    reads bit i of every source before it writes bit i of the destination).
#include <array>
#include <cstdint>
#include <vector>

#include "firmware/isa/types.hpp"
#include "models/common/bitplane.hpp"

namespace pp5 {

// A source operand seen as a stream of bit-planes, LSB first; bits at or above `width`
// read `extension` (the zero plane, or the operand's own sign plane).
struct Bits {
  static constexpr int kMaxBits = kMaxFieldBits;
  std::array<const Word*, kMaxBits> plane{};
  int width = 0;
  const Word* extension = nullptr;
  const Word* bit(int i) const { return i < width ? plane[i] : extension; }
};

class PixelArray {
 public:
  explicit PixelArray(const PixelArrayGeometry& geometry);

  const PixelArrayGeometry& geometry() const { return geometry_; }
  int width() const { return geometry_.width; }
  int height() const { return geometry_.height; }
  int pixels() const { return geometry_.width * geometry_.height; }
  int words() const { return words_; }

  Word* plane(int bit) { return &memory_[static_cast<std::size_t>(bit) * words_]; }
  const Word* plane(int bit) const { return &memory_[static_cast<std::size_t>(bit) * words_]; }
  const Word* enable() const { return enable_.data(); }
  const Word* zeros() const { return zeros_.data(); }
  const Word* ones() const { return ones_.data(); }

  // Operand views. `bits_of_constant` broadcasts a value to every pixel.
  Bits bits_of(const Field& field) const;
  Bits bits_of_constant(std::int64_t value) const;
  // Planes laid out as `count` consecutive planes of words() words each (the evaluator's
  // output); extension by the top plane when is_signed, by zeros otherwise.
  Bits bits_of_planes(const Word* planes, int count, bool is_signed) const;

  // Enable register and its stack.
  void enable_all();
  void and_enable(const Word* mask);          // E &= mask
  void clear_enable_outside(WordRange keep);  // E = 0 in every word outside keep
  void push_enable();
  void pop_enable();
  void else_enable();  // E = (saved E) & ~E: the other branch of the innermost conditional
  int enable_depth() const { return stack_top_; }
  int count_enabled() const;
  // The smallest word range holding every set bit of E.
  WordRange active_words() const;

  // ALU operations, all under E.
  void assign(const Field& dst, const Bits& src);
  void add(const Field& dst, const Bits& a, const Bits& b);
  void sub(const Field& dst, const Bits& a, const Bits& b);  // dst = a - b
  void logic(const Field& dst, const Bits& a, const Bits& b, Logic op);
  void invert(const Field& dst);
  // dst = a * b (modulo 2^dst.width); dst must not overlap a or b. A pass for bit j of b adds
  // over dst's bits j and up, or, with window > 0, over bits j to j + window - 1 only (the
  // carry out of the window is dropped: multiply_window_bits says when none can arise).
  void multiply(const Field& dst, const Bits& a, const Bits& b, int window = 0);
  // dst += a * k for a broadcast constant k, as shift-and-add over the set bits of |k|;
  // dst must not overlap a.
  void multiply_accumulate(const Field& dst, const Bits& a, std::int64_t k);
  // E &= (a <cmp> b), both operands read at max(width) + 1 bits with their own extension,
  // so the comparison is exact for any mix of widths and signedness.
  void compare(const Bits& a, const Bits& b, Compare cmp);

  // Backing store: block `block` of every pixel's slow memory <-> `field` (ceil(width /
  // block_bits) consecutive blocks). Throws std::out_of_range past the end of the store.
  void store_to_backing(const Field& field, int block);
  void load_from_backing(const Field& field, int block);

  // Scalar access for tests, readout and inspection; not an ALU path.
  std::uint64_t read(int pixel, const Field& field) const;
  std::int64_t read_signed(int pixel, const Field& field) const;
  void write(int pixel, const Field& field, std::uint64_t value);
  bool enabled(int pixel) const;
  std::uint64_t carry_bit(int pixel) const;

  // Whether every bit of state an instruction can observe is the same: pixel memory, Enable
  // and its stack, carries and backing store. Two arrays in the same state give the same
  // results for the same instruction stream.
  bool same_state(const PixelArray& other) const;

 private:
  // E changed to a subset of what it was: its set bits still lie within bound_.
  void mark_enable_shrunk() { active_valid_ = false; }
  void check_no_overlap(const Field& dst, const Bits& src, const char* what) const;
  // `src`, with its extension plane copied aside if it lies inside `dst` (slot 0 or 1).
  Bits stable(const Bits& src, const Field& dst, int slot);
  void add_walk(const Field& dst, const Bits& a, const Bits& b, bool subtract);
  // Bits j to end - 1 of dst (end <= 0: to its top).
  void shifted_add(const Field& dst, const Bits& a, int j, const Word* gate, bool negate,
                   int end = 0);
  Word* backing_plane(int bit);

  PixelArrayGeometry geometry_;
  int words_;
  std::vector<Word> memory_;
  std::vector<Word> enable_;
  std::vector<Word> carry_;
  std::vector<Word> stack_;
  int stack_top_ = 0;
  std::vector<Word> zeros_;
  std::vector<Word> ones_;
  std::vector<Word> sign_copy_;  // two planes: saved extension planes, or compare's state
  std::vector<Word> backing_;    // allocated on first use: only programs that spill pay for it
  // active_ is exact when active_valid_; otherwise every set bit of E lies in bound_, and
  // active_words() scans only that (operations that clear bits of E keep the old range as
  // the bound, so a primitive's tests rescan its rows, not the whole region).
  mutable WordRange active_{};
  mutable WordRange bound_{};
  mutable bool active_valid_ = false;
  std::vector<WordRange> stack_bound_;  // bound_ of each saved Enable
};

}  // namespace pp5
