#include "firmware/isa/isa.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace pp5 {

namespace {

int width_of(const Operand& o) { return o.kind == Operand::Kind::field ? o.field.width : 0; }

// The ALU source an operand stands for: a field, or a literal, frame parameter or constant
// expression broadcast.
Source source_of(const Operand& o, const ExecutionContext& c) {
  if (o.kind == Operand::Kind::field) return Source::of(o.field);
  if (o.kind == Operand::Kind::expression) {
    return Source::of(broadcast_value(o, c.values, c.fraction_bits));
  }
  return Source::of(constant_value(o, c.values));
}

const QuadraticCoefficients& expression_of(const Operand& o, const PacketValues& values) {
  return values.expressions[o.index];
}

ArrayCycles one(const Instruction&, const TimingParams&, const PacketValues&) {
  return ArrayCycles(1);
}
ArrayCycles dst_width(const Instruction& i, const TimingParams&, const PacketValues&) {
  return ArrayCycles(width_of(i.operands[0]));
}

// The bits one pass of mul adds over (PixelBackend::multiply).
int multiply_pass_width(int dst_width, const Field& a, int j, bool window) {
  const int rest = dst_width - j;
  const int bits = multiply_window_bits(a, window);
  return bits > 0 ? std::min(rest, bits) : rest;
}

std::uint64_t magnitude(std::int64_t k) {
  return k < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(k) : static_cast<std::uint64_t>(k);
}

// The bits a load or compare of a `width`-bit field streams from the evaluator: LSB first, the
// fraction and then the field's bits; MSB first, the integer bits from the top down to the
// field's lowest (those above the field first, discarded).
std::uint64_t evaluator_stream(const TimingParams& t, int width) {
  return static_cast<std::uint64_t>(t.msb_first ? t.result_bits - t.fraction_bits
                                                : t.fraction_bits + width);
}

// The unpublished properties some costs rest on (InstructionInfo::basis).
constexpr const char* kEvaluatorOrder =
    "the evaluator's bit order and latency (assumed: evaluator.bit_order, by default the "
    "fraction bits first, LSB first, after evaluator.latency_cycles; not published)";
constexpr const char* kMultiplyMicrocode =
    "the multiply's microcode (a choice of the simulator, renderer.multiply_microcode: "
    "shift-and-add, one pass per multiplier bit over the destination from that bit up, or over "
    "the partial product's window only; mac skips a constant's zero bits; not published)";
constexpr const char* kBackingStore =
    "the backing-store transfer time per block (assumed: "
    "renderer.backing_store_cycles_per_block)";

std::vector<InstructionInfo> make_table() {
  using I = Instruction;
  using T = TimingParams;
  using P = PacketValues;
  using X = ExecutionContext;
  return {
      {Opcode::eall, "eall", false, "", "eall", "E <- 1 in every pixel", "1", one,
       [](const I&, X& c) { c.pixels.enable_all(); }},
      {Opcode::epush, "epush", false, "", "epush",
       "push E on the pixel's enable stack (start of a conditional)", "1", one,
       [](const I&, X& c) { c.pixels.push_enable(); }},
      {Opcode::epop, "epop", false, "", "epop", "E <- pop (end of a conditional)", "1", one,
       [](const I&, X& c) { c.pixels.pop_enable(); }},
      {Opcode::eelse, "eelse", false, "", "eelse",
       "E <- top & ~E: the pixels of the enclosing condition that the current one excluded", "1",
       one, [](const I&, X& c) { c.pixels.else_enable(); }},

      {Opcode::qtest, "qtest", true, "E", "qtest.cond expr",
       "E <- E & (expr cond 0); every result bit streams through the comparator",
       "evaluator.result_bits + evaluator.latency_cycles (evaluator.bit_order=msb_first: 1 + "
       "evaluator.latency_cycles for ge and lt, the sign alone)",
       [](const I& i, const T& t, const P&) {
         const bool sign = i.condition == Compare::ge || i.condition == Compare::lt;
         return ArrayCycles((t.msb_first && sign ? 1 : t.result_bits) + t.evaluator_latency);
       },
       [](const I& i, X& c) {
         c.pixels.qtest(expression_of(i.operands[0], c.values), i.condition);
       },
       kEvaluatorOrder},
      {Opcode::qload, "qload", false, "FE", "qload dst, expr",
       "dst <- floor(expr) modulo 2^width(dst)",
       "evaluator.fraction_bits + width(dst) + evaluator.latency_cycles (evaluator.bit_order="
       "msb_first: evaluator.result_bits - evaluator.fraction_bits + evaluator.latency_cycles)",
       [](const I& i, const T& t, const P&) {
         return ArrayCycles(evaluator_stream(t, width_of(i.operands[0])) + t.evaluator_latency);
       },
       [](const I& i, X& c) {
         c.pixels.qload(i.operands[0].field, expression_of(i.operands[1], c.values));
       },
       kEvaluatorOrder},
      {Opcode::qcmp, "qcmp", true, "RE", "qcmp.cond field, expr",
       "E <- E & (floor(expr) cond field), expr taken to width(field) with field's signedness",
       "evaluator.fraction_bits + width(field) + evaluator.latency_cycles + 1 "
       "(evaluator.bit_order=msb_first: evaluator.result_bits - evaluator.fraction_bits + "
       "evaluator.latency_cycles + 1)",
       [](const I& i, const T& t, const P&) {
         return ArrayCycles(evaluator_stream(t, width_of(i.operands[0])) + t.evaluator_latency + 1);
       },
       [](const I& i, X& c) {
         c.pixels.qcmp(i.operands[0].field, expression_of(i.operands[1], c.values), i.condition);
       },
       kEvaluatorOrder},

      {Opcode::mov, "mov", false, "FV", "mov dst, src", "dst <- src", "width(dst)", dst_width,
       [](const I& i, X& c) { c.pixels.mov(i.operands[0].field, source_of(i.operands[1], c)); }},
      {Opcode::add, "add", false, "FV", "add dst, src", "dst <- dst + src modulo 2^width(dst)",
       "width(dst)", dst_width,
       [](const I& i, X& c) { c.pixels.add(i.operands[0].field, source_of(i.operands[1], c)); }},
      {Opcode::sub, "sub", false, "FV", "sub dst, src", "dst <- dst - src modulo 2^width(dst)",
       "width(dst)", dst_width,
       [](const I& i, X& c) { c.pixels.sub(i.operands[0].field, source_of(i.operands[1], c)); }},
      {Opcode::cmp, "cmp", true, "RV", "cmp.cond a, b",
       "E <- E & (a cond b), exact for any widths and signedness", "max(width(a), width(b)) + 1",
       [](const I& i, const T&, const P&) {
         return ArrayCycles(std::max(width_of(i.operands[0]), width_of(i.operands[1])) + 1);
       },
       [](const I& i, X& c) {
         c.pixels.compare(i.operands[0].field, source_of(i.operands[1], c), i.condition);
       }},
      {Opcode::and_, "and", false, "FV", "and dst, src", "dst <- dst & src", "width(dst)",
       dst_width,
       [](const I& i, X& c) {
         c.pixels.logic(i.operands[0].field, source_of(i.operands[1], c), Logic::and_);
       }},
      {Opcode::or_, "or", false, "FV", "or dst, src", "dst <- dst | src", "width(dst)", dst_width,
       [](const I& i, X& c) {
         c.pixels.logic(i.operands[0].field, source_of(i.operands[1], c), Logic::or_);
       }},
      {Opcode::xor_, "xor", false, "FV", "xor dst, src", "dst <- dst ^ src", "width(dst)",
       dst_width,
       [](const I& i, X& c) {
         c.pixels.logic(i.operands[0].field, source_of(i.operands[1], c), Logic::xor_);
       }},
      {Opcode::not_, "not", false, "F", "not dst", "dst <- ~dst", "width(dst)", dst_width,
       [](const I& i, X& c) { c.pixels.invert(i.operands[0].field); }},
      {Opcode::mul, "mul", false, "FRR", "mul dst, a, b",
       "dst <- a * b modulo 2^width(dst), by shift-and-add over the bits of b; dst must not "
       "overlap a or b",
       "width(dst) + sum over the n bits j of b that reach dst of the pass's width: width(dst) - "
       "j (renderer.multiply_microcode = full, or a signed a), else min(width(dst) - j, "
       "width(a) + 1) (window); n = min(width(dst), width(b)), or width(dst) if b is signed",
       [](const I& i, const T& t, const P&) {
         const int w = width_of(i.operands[0]);
         const Field& a = i.operands[1].field;
         const Field& b = i.operands[2].field;
         const int n = b.is_signed ? w : std::min(w, b.width);
         std::uint64_t cycles = static_cast<std::uint64_t>(w);
         for (int j = 0; j < n; ++j) {
           cycles += static_cast<std::uint64_t>(multiply_pass_width(w, a, j, t.multiply_window));
         }
         return ArrayCycles(cycles);
       },
       [](const I& i, X& c) {
         c.pixels.multiply(i.operands[0].field, i.operands[1].field, i.operands[2].field,
                           c.multiply_window);
       },
       kMultiplyMicrocode},
      {Opcode::mac, "mac", false, "FRK", "mac dst, a, k",
       "dst <- dst + a * k modulo 2^width(dst), k a broadcast constant; dst must not overlap a",
       "1 + sum over the set bits j of |k| below width(dst) of (width(dst) - j)",
       [](const I& i, const T&, const P& v) {
         const int w = width_of(i.operands[0]);
         const std::uint64_t k = magnitude(constant_value(i.operands[2], v));
         std::uint64_t cycles = 1;
         for (int j = 0; j < w && j < 64; ++j) {
           if ((k >> j) & 1) cycles += static_cast<std::uint64_t>(w - j);
         }
         return ArrayCycles(cycles);
       },
       [](const I& i, X& c) {
         c.pixels.multiply_accumulate(i.operands[0].field, i.operands[1].field,
                                      constant_value(i.operands[2], c.values));
       },
       kMultiplyMicrocode},

      {Opcode::bsld, "bsld", false, "FB", "bsld dst, block",
       "dst <- backing store from block `block` on (every pixel, ignoring E)",
       "ceil(width(dst) / renderer.block_bits) * renderer.backing_store_cycles_per_block",
       [](const I& i, const T& t, const P&) {
         const int blocks = (width_of(i.operands[0]) + t.block_bits - 1) / t.block_bits;
         return ArrayCycles(static_cast<std::uint64_t>(blocks) * t.backing_store_cycles_per_block);
       },
       [](const I& i, X& c) {
         c.pixels.load_from_backing(i.operands[0].field, static_cast<int>(i.operands[1].literal));
       },
       kBackingStore},
      {Opcode::bsst, "bsst", false, "RB", "bsst src, block",
       "backing store from block `block` on <- src (every pixel, ignoring E)",
       "ceil(width(src) / renderer.block_bits) * renderer.backing_store_cycles_per_block",
       [](const I& i, const T& t, const P&) {
         const int blocks = (width_of(i.operands[0]) + t.block_bits - 1) / t.block_bits;
         return ArrayCycles(static_cast<std::uint64_t>(blocks) * t.backing_store_cycles_per_block);
       },
       [](const I& i, X& c) {
         c.pixels.store_to_backing(i.operands[0].field, static_cast<int>(i.operands[1].literal));
       },
       kBackingStore},
  };
}

}  // namespace

const std::vector<InstructionInfo>& instruction_table() {
  static const std::vector<InstructionInfo> table = [] {
    auto t = make_table();
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (static_cast<std::size_t>(t[k].op) != k) throw std::logic_error("isa table out of order");
    }
    if (t.size() != static_cast<std::size_t>(Opcode::count)) {
      throw std::logic_error("isa table incomplete");
    }
    return t;
  }();
  return table;
}

const InstructionInfo& instruction_info(Opcode op) {
  return instruction_table()[static_cast<std::size_t>(op)];
}

const InstructionInfo* find_instruction(const std::string& mnemonic) {
  for (const auto& info : instruction_table()) {
    if (mnemonic == info.mnemonic) return &info;
  }
  return nullptr;
}

const char* condition_name(Compare c) {
  static const char* names[] = {"lt", "le", "eq", "ne", "ge", "gt"};
  return names[static_cast<int>(c)];
}

bool parse_condition(const std::string& text, Compare& out) {
  for (int k = 0; k < 6; ++k) {
    if (text == condition_name(static_cast<Compare>(k))) {
      out = static_cast<Compare>(k);
      return true;
    }
  }
  return false;
}

std::int64_t constant_value(const Operand& operand, const PacketValues& values) {
  if (operand.kind == Operand::Kind::parameter) return values.parameters[operand.index];
  return operand.literal;
}

std::int64_t broadcast_value(const Operand& operand, const PacketValues& values,
                             int fraction_bits) {
  const std::int64_t v = values.expressions[operand.index].F;
  const std::int64_t one = std::int64_t{1} << fraction_bits;
  return v >= 0 ? v / one : -((-v + one - 1) / one);  // floor
}

ArrayCycles instruction_cost(const Instruction& ins, const TimingParams& timing,
                             const PacketValues& values) {
  return instruction_info(ins.op).cost(ins, timing, values);
}

std::string disassemble(const Instruction& ins) {
  const InstructionInfo& info = instruction_info(ins.op);
  std::string s = info.mnemonic;
  if (info.conditional) s += std::string(".") + condition_name(ins.condition);
  const int n = static_cast<int>(std::char_traits<char>::length(info.operands));
  for (int k = 0; k < n; ++k) {
    s += k == 0 ? " " : ", ";
    const Operand& o = ins.operands[k];
    s += o.text.empty() ? std::to_string(o.literal) : o.text;
  }
  return s;
}

}  // namespace pp5
