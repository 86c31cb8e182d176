#pragma once
// The pixel backend: what the instruction table executes against. A backend models a
// Renderer's SIMD array of pixel processors together with its expression evaluator, at the
// level of the instruction set's semantics: fields, broadcast constants, expression
// coefficients and the Enable stack, never bit-planes. Each instruction's executor (in
// firmware/isa/isa.cpp) makes one call here; how the backend stores pixel memory and walks
// it is its own business.
//
// Contract (every backend, so that all give bit-identical pixel memory):
//  - Pixel p = y * width + x of the region; each has memory_bits of local memory, an Enable
//    bit E, a stack of enable_stack_depth saved E values and backing_store_bits of backing
//    store moved in blocks of block_bits. A new backend has memory, stack and backing store
//    all 0 and E = 1 everywhere.
//  - Writes to local memory happen only where E = 1; backing-store transfers ignore E.
//  - Arithmetic wraps modulo 2^width(dst); a field reads as unsigned or two's complement by
//    its is_signed; comparisons are exact for any mix of widths and signedness (operands are
//    extended by their own signedness, never truncated). A destination may alias a source
//    field exactly (add x, x); mul and mac require dst not to overlap their field sources.
//  - Expressions: the evaluator delivers every pixel the value of its QuadraticCoefficients at
//    the pixel's screen coordinates (region origin + (x, y)), exact modulo 2^result_bits and
//    read as two's complement of that width; bits above result_bits copy its sign. qload and
//    qcmp use the integer bits [fraction_bits, fraction_bits + width(field)), i.e.
//    floor(value / 2^fraction_bits) modulo 2^width(field).
//  - Errors: a field outside pixel memory (or wider than 64 bits) throws std::out_of_range; a
//    backing-store block past the store throws std::out_of_range; pushing a full stack
//    throws std::overflow_error; popping or else-ing an empty one std::underflow_error; mul
//    or mac with dst overlapping a source throws std::invalid_argument.
//  - Cost is not a backend's business: the instruction table charges cycles.
//  - Calls are per instruction. A backend may defer a call's per-pixel work and do it
//    together with later calls' (the word backend writes a run of qloads in one walk), as
//    long as every read, comparison, copy and clone of its state sees it as it would be after
//    each call in turn.
#include <cstdint>
#include <memory>
#include <vector>

#include "firmware/isa/types.hpp"

namespace pp5 {

// A source operand of an ALU instruction: a field of pixel memory, or a constant broadcast
// to every pixel (a literal or a frame parameter), read as a signed 64-bit value.
struct Source {
  bool is_field = false;
  Field field;
  std::int64_t constant = 0;

  static Source of(const Field& f) { return {true, f, 0}; }
  static Source of(std::int64_t k) { return {false, Field{}, k}; }
};

// What a backend is built from: the board's parameters.
struct PixelBackendParams {
  PixelArrayGeometry array;
  EvaluatorParams evaluator;
  int fraction_bits = 12;  // evaluator.fraction_bits: the fraction of every expression
};

// The bits one pass of a windowed mul adds over (PixelBackend::multiply): width(a) + 1 for an
// unsigned a, or 0 where the pass must run to the destination's top (no window, or a signed
// a, whose sign extension reaches every bit above it).
inline int multiply_window_bits(const Field& a, bool window) {
  return window && !a.is_signed ? a.width + 1 : 0;
}

class PixelBackend {
 public:
  virtual ~PixelBackend() = default;

  // The registry name of this kind of backend ("bit", ...).
  virtual const char* name() const = 0;
  virtual const PixelArrayGeometry& geometry() const = 0;
  int width() const { return geometry().width; }
  int height() const { return geometry().height; }
  int pixels() const { return geometry().width * geometry().height; }

  // Screen coordinates of region pixel (0, 0), for the evaluator. Pixel memory keeps
  // whatever it held.
  virtual void set_origin(int x0, int y0) = 0;

  // eall, epush, epop, eelse: E <- 1; push E; E <- pop; E <- top & ~E.
  virtual void enable_all() = 0;
  virtual void push_enable() = 0;
  virtual void pop_enable() = 0;
  virtual void else_enable() = 0;

  // qtest: E <- E & (expr cond 0), on the value wrapped to result_bits.
  virtual void qtest(const QuadraticCoefficients& expr, Compare cond) = 0;
  // qload: dst <- floor(expr) modulo 2^width(dst), under E.
  virtual void qload(const Field& dst, const QuadraticCoefficients& expr) = 0;
  // qcmp: E <- E & (floor(expr) cond field), floor(expr) taken to width(field) with field's
  // signedness.
  virtual void qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) = 0;

  // mov, add, sub, and/or/xor, not: dst <- src, dst + src, dst - src, dst op src, ~dst.
  virtual void mov(const Field& dst, const Source& src) = 0;
  virtual void add(const Field& dst, const Source& src) = 0;
  virtual void sub(const Field& dst, const Source& src) = 0;
  virtual void logic(const Field& dst, const Source& src, Logic op) = 0;
  virtual void invert(const Field& dst) = 0;
  // cmp: E <- E & (a cond b).
  virtual void compare(const Field& a, const Source& b, Compare cond) = 0;
  // mul: dst <- a * b; mac: dst <- dst + a * k. Modulo 2^width(dst). With `window`
  // (renderer.multiply_microcode = window), a pass for bit j of b adds over bits j to
  // j + width(a) of dst only, if a is unsigned: the carry out of that window is always 0, as
  // the sum of the passes before is below 2^(j + width(a)).
  virtual void multiply(const Field& dst, const Field& a, const Field& b, bool window) = 0;
  virtual void multiply_accumulate(const Field& dst, const Field& a, std::int64_t k) = 0;

  // bsst / bsld: backing store from block `block` on <-> field, every pixel.
  virtual void store_to_backing(const Field& field, int block) = 0;
  virtual void load_from_backing(const Field& field, int block) = 0;

  // Read side, for readout, observers and tests (not an execution path).
  virtual std::uint64_t read(int pixel, const Field& field) const = 0;
  // The field's value at `pixel`, sign-extended when the field is signed.
  std::int64_t read_signed(int pixel, const Field& field) const;
  // The field's unsigned value at every pixel: out[p] for p in [0, pixels()).
  virtual void read_field(const Field& field, std::uint64_t* out) const = 0;
  // The low 8 bits of each of `count` fields at every pixel, interleaved (a region's colour
  // bytes): out[p * count + k] is fields[k]'s value at pixel p modulo 256. The generic one
  // reads each field with read_field; a backend may do it in one pass.
  virtual void read_bytes(const Field* fields, int count, std::uint8_t* out) const;
  // The whole local memory as memory_bits bit-planes: word p / 64 of plane b holds bit b of
  // pixel p at bit p % 64 (the snapshot layout, whatever the backend's own).
  virtual void read_memory_planes(std::vector<std::uint64_t>& planes) const;
  virtual bool enabled(int pixel) const = 0;
  virtual int count_enabled() const = 0;
  // Saved Enable values on the stack.
  virtual int enable_depth() const = 0;
  // Tests and tools only: set a field of one pixel, ignoring E.
  virtual void write(int pixel, const Field& field, std::uint64_t value) = 0;

  // State, for reusing work (the Renderer's empty regions): a copy of this backend; whether
  // every bit of state an instruction can observe (local memory, E and its stack, backing
  // store) equals another's, false for a backend of another kind or geometry; and taking
  // another's state, which must come from a backend of the same kind and geometry (a clone:
  // std::invalid_argument otherwise). The region origin is not part of the state.
  virtual std::unique_ptr<PixelBackend> clone() const = 0;
  virtual bool same_state(const PixelBackend& other) const = 0;
  virtual void copy_state_from(const PixelBackend& other) = 0;
};

}  // namespace pp5
