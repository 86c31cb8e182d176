#pragma once
// The value types of the micro-instruction set: what an instruction's operands name (fields
// of pixel memory, conditions, logic operations, the coefficients of an expression) and the
// parameters of the machine that give them meaning (the pixel array's geometry, the
// expression evaluator's widths). Firmware, the assembler, the GPs and every pixel backend
// share them; they belong to no particular model of the hardware.
//
// Contract: plain values, no behaviour beyond construction helpers; nothing here depends on
// how a backend stores pixel memory.
#include <cstdint>

namespace pp5 {

// The widest field an instruction operates on.
inline constexpr int kMaxFieldBits = 64;

// Bits [lo, lo + width) of every pixel's local memory, read as unsigned or as two's
// complement (is_signed). Instructions accept 1 <= width <= kMaxFieldBits.
struct Field {
  int lo = 0;
  int width = 0;
  bool is_signed = false;
};

// The conditions of qtest, qcmp and cmp.
enum class Compare { lt, le, eq, ne, ge, gt };
// The evaluator's test of a value against 0 uses the same conditions.
using Condition = Compare;
enum class Logic { and_, or_, xor_ };

// value = A x^2 + B x y + C y^2 + D x + E y + F, over the integer screen coordinates of a
// pixel; any fixed-point scaling belongs to the Graphics Processor.
struct QuadraticCoefficients {
  std::int64_t A = 0, B = 0, C = 0, D = 0, E = 0, F = 0;

  bool is_linear() const { return A == 0 && B == 0 && C == 0; }
  // a x + b y + c, stored in D, E, F.
  static QuadraticCoefficients linear(std::int64_t a, std::int64_t b, std::int64_t c) {
    QuadraticCoefficients q;
    q.D = a;
    q.E = b;
    q.F = c;
    return q;
  }
  static QuadraticCoefficients constant(std::int64_t c) {
    QuadraticCoefficients q;
    q.F = c;
    return q;
  }
  friend bool operator==(const QuadraticCoefficients& a, const QuadraticCoefficients& b) {
    return a.A == b.A && a.B == b.B && a.C == b.C && a.D == b.D && a.E == b.E && a.F == b.F;
  }
  friend bool operator!=(const QuadraticCoefficients& a, const QuadraticCoefficients& b) {
    return !(a == b);
  }
};

// The expression evaluator's arithmetic: coefficients are signed coefficient_bits wide, and
// the value every pixel receives wraps modulo 2^result_bits (two's complement of that width).
struct EvaluatorParams {
  int coefficient_bits = 40;  // signed width of every coefficient the tree accepts (2..62)
  int result_bits = 40;       // width of the delivered result (2..64); wraps modulo 2^result_bits
};

// The SIMD array of pixel processors: one per pixel of a width x height region, pixel
// p = y * width + x.
struct PixelArrayGeometry {
  int width = 128;                // pixel processors per row; a multiple of 64
  int height = 128;               // rows
  int memory_bits = 208;          // local memory per pixel processor
  int enable_stack_depth = 8;     // saved Enable values for nested conditionals
  int backing_store_bits = 4096;  // slow memory per pixel processor; 0 = none
  int block_bits = 32;            // backing-store transfer unit
};
inline bool operator==(const PixelArrayGeometry& a, const PixelArrayGeometry& b) {
  return a.width == b.width && a.height == b.height && a.memory_bits == b.memory_bits &&
         a.enable_stack_depth == b.enable_stack_depth &&
         a.backing_store_bits == b.backing_store_bits && a.block_bits == b.block_bits;
}
inline bool operator!=(const PixelArrayGeometry& a, const PixelArrayGeometry& b) {
  return !(a == b);
}

}  // namespace pp5
