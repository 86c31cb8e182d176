#pragma once
// The Renderer's micro-instruction set: one table that gives every instruction its
// mnemonic, operands, effect, cycle cost and executor. The assembler parses with it, the
// disassembler prints with it, the Renderer times and executes with it, and
// `pp5sim isa` documents it; nothing about an instruction is written anywhere else.
//
// Every instruction is bit-serial: it runs over its operands LSB first, one array cycle per
// bit, on all pixel processors at once; memory writes happen only where Enable = 1. The
// cost formulas charge that; the executors carry out the effect through the PixelBackend
// interface (firmware/isa/backend.hpp), one call per instruction, so any backend runs
// firmware.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "firmware/isa/backend.hpp"
#include "firmware/isa/interface.hpp"
#include "firmware/isa/types.hpp"

namespace pp5 {

enum class Opcode {
  eall,
  epush,
  epop,
  eelse,
  qtest,
  qload,
  qcmp,
  mov,
  add,
  sub,
  cmp,
  and_,
  or_,
  xor_,
  not_,
  mul,
  mac,
  bsld,
  bsst,
  count
};

struct Operand {
  enum class Kind { none, field, expression, literal, parameter };
  Kind kind = Kind::none;
  Field field;     // Kind::field: bits of pixel memory
  int index = -1;  // Kind::expression / Kind::parameter: index in firmware/isa/interface.hpp
  std::int64_t literal = 0;
  std::string text;  // the operand as written, for listings and messages
};

struct Instruction {
  Opcode op = Opcode::eall;
  Compare condition = Compare::eq;  // for the conditional instructions (qtest, qcmp, cmp)
  std::array<Operand, 3> operands{};
  int line = 0;  // source line; 0 for instructions the assembler inserted
};

// Machine timing the cost formulas depend on (from the machine configuration).
struct TimingParams {
  int fraction_bits = 12;
  int result_bits = 40;
  int evaluator_latency = 8;
  int block_bits = 32;
  int backing_store_cycles_per_block = 64;
  // renderer.multiply_microcode = window: mul adds only the partial product's window.
  bool multiply_window = false;
  // evaluator.bit_order = msb_first: the evaluator delivers the sign first (qtest, qload and
  // qcmp cost as InstructionInfo::cycles says for that order).
  bool msb_first = false;
};

using ExpressionValues = std::array<QuadraticCoefficients, static_cast<int>(Expression::count)>;
using ParameterValues = std::array<std::int64_t, static_cast<int>(Parameter::count)>;

// Where expression e is, or would go, among the carried ones (bit k of `carried`: expression k
// is carried): the number of carried expressions below it.
inline std::size_t carried_slot(std::uint64_t carried, std::size_t e) {
  return static_cast<std::size_t>(__builtin_popcountll(carried & ((std::uint64_t{1} << e) - 1)));
}

// Coefficients held for some of the expressions, in expression order: only those that are
// carried take room (a packet holds the expressions its procedure uses, as the GP sends
// them, not a slot for every expression there is). Indexed like ExpressionValues: an
// expression not carried reads as all-zero coefficients, and writing one carries it.
class CarriedExpressions {
 public:
  CarriedExpressions() = default;
  // Carries every expression (a whole table, as tests and region-wide procedures hold it).
  explicit CarriedExpressions(const ExpressionValues& all)
      : carried_(kAll), values_(all.begin(), all.end()) {}
  CarriedExpressions& operator=(const ExpressionValues& all) {
    return *this = CarriedExpressions(all);
  }

  const QuadraticCoefficients& operator[](std::size_t e) const;  // read as ExpressionView does
  QuadraticCoefficients& operator[](std::size_t e) {
    const auto at = carried_slot(carried_, e);
    if (!carries(e)) {
      values_.insert(values_.begin() + static_cast<std::ptrdiff_t>(at), QuadraticCoefficients{});
      carried_ |= std::uint64_t{1} << e;
    }
    return values_[at];
  }
  bool carries(std::size_t e) const { return ((carried_ >> e) & 1) != 0; }
  std::uint64_t carried() const { return carried_; }  // bit e: expression e
  const QuadraticCoefficients* data() const { return values_.data(); }
  std::size_t size() const { return values_.size(); }
  void reserve(std::size_t n) { values_.reserve(n); }
  // Carries nothing again, keeping the storage (a reused packet's).
  void clear() {
    carried_ = 0;
    values_.clear();
  }

  static constexpr std::uint64_t kAll = (std::uint64_t{1} << ExpressionValues{}.size()) - 1;
  static_assert(ExpressionValues{}.size() < 64, "one bit per expression");

 private:
  std::uint64_t carried_ = 0;
  std::vector<QuadraticCoefficients> values_;
};

// What a packet carries: the coefficients of its expressions. The frame's parameters are not
// in it: they are bound when the packet runs (PacketValues).
struct PacketExpressions {
  CarriedExpressions expressions;
};

// A read-only view of expression coefficients: a whole table or the carried ones.
class ExpressionView {
 public:
  ExpressionView(const ExpressionValues& all)  // NOLINT(google-explicit-constructor): a view
      : data_(all.data()), carried_(CarriedExpressions::kAll) {}
  ExpressionView(const CarriedExpressions& c)  // NOLINT(google-explicit-constructor): a view
      : data_(c.data()), carried_(c.carried()) {}
  const QuadraticCoefficients& operator[](std::size_t e) const {
    if (((carried_ >> e) & 1) == 0) return kNone;
    return data_[carried_slot(carried_, e)];
  }
  // The carried coefficients, in expression order.
  const QuadraticCoefficients* begin() const { return data_; }
  const QuadraticCoefficients* end() const { return data_ + __builtin_popcountll(carried_); }

 private:
  static inline const QuadraticCoefficients kNone{};
  const QuadraticCoefficients* data_;
  std::uint64_t carried_;
};

inline const QuadraticCoefficients& CarriedExpressions::operator[](std::size_t e) const {
  return ExpressionView(*this)[e];
}

// Expressions and parameters held together: the values of a region-wide procedure, or of a
// test that builds its own.
struct OwnedValues {
  ExpressionValues expressions{};
  ParameterValues parameters{};
};

// The values a procedure's expression and parameter operands bind to, as a view: a packet's
// expressions and the frame's (or a light's) parameters, wherever each lives.
// Contract: a view, valid while what it refers to lives; never store one beyond the call it
// was made for. Converts implicitly from OwnedValues.
struct PacketValues {
  ExpressionView expressions;
  const ParameterValues& parameters;
  PacketValues(ExpressionView e, const ParameterValues& p) : expressions(e), parameters(p) {}
  PacketValues(const OwnedValues& v)  // NOLINT(google-explicit-constructor): a view of it
      : expressions(v.expressions), parameters(v.parameters) {}
};

// One pass of a frame's pass plan (models/protocol/region_stream.hpp): the region-wide
// procedures that open it, in order, the group of primitives whose packets it draws, which of
// their faces, and the procedure those packets run. A primitive's group is the solid it
// belongs to (Scene::solids), or kNoGroup for one in no solid; a packet's facing is the GP's
// (Packet::back: the triangle turns its back to the eye).
struct PlannedPass {
  static constexpr int kAllGroups = -2;  // every packet, whatever its group
  static constexpr int kNoGroup = -1;    // the packets of primitives in no solid
  enum class Faces { all, front, back };
  std::vector<Procedure> opening{Procedure::pass};  // starts with clear in the first pass
  int group = kAllGroups;
  Procedure packets = Procedure::count;  // Procedure::count: each packet's own procedure
  Faces faces = Faces::all;
  bool draws(int packet_group, bool packet_back) const {
    return (group == kAllGroups || group == packet_group) &&
           (faces == Faces::all || (faces == Faces::back) == packet_back);
  }
};

// The values of a frame's region-wide procedures: `frame` for clear, pass and shade (with the
// first light's parameters), and lights[k] for the `light` procedure of light k; and the
// frame's pass plan: empty for the program's own passes (`option passes`), each drawing every
// packet with its own procedure; with a plan, `closing` lists the region-wide procedures run
// after its last pass, before `light` and `shade`.
struct FrameValues {
  OwnedValues frame;
  std::vector<OwnedValues> lights;
  std::vector<PlannedPass> plan;
  std::vector<Procedure> closing;
};

// What an executor acts on: the board's pixel backend, with the packet's values bound to
// the procedure's expression and parameter operands.
struct ExecutionContext {
  PixelBackend& pixels;
  const PacketValues& values;
  int fraction_bits;             // evaluator.fraction_bits: a broadcast expression's integer part
  bool multiply_window = false;  // renderer.multiply_microcode = window (TimingParams)
};

struct InstructionInfo {
  Opcode op;
  const char* mnemonic;
  bool conditional;      // takes a .lt/.le/.eq/.ne/.ge/.gt suffix
  const char* operands;  // one letter per operand: F field (written), R field (read),
                         // V field or constant, K constant, E expression, B block number
  const char* syntax;
  const char* effect;
  const char* cycles;  // the cost formula in words
  ArrayCycles (*cost)(const Instruction&, const TimingParams&, const PacketValues&);
  void (*execute)(const Instruction&, ExecutionContext&);
  // What the cost formula rests on beyond one array cycle per bit (Fuchs et al. 1989): the
  // unpublished property of the machine it assumes, or "" where it needs none.
  const char* basis = "";
};

const std::vector<InstructionInfo>& instruction_table();
const InstructionInfo& instruction_info(Opcode op);
const InstructionInfo* find_instruction(const std::string& mnemonic);

const char* condition_name(Compare c);
bool parse_condition(const std::string& text, Compare& out);

// The constant an operand stands for in a packet (a literal or a frame parameter).
std::int64_t constant_value(const Operand& operand, const PacketValues& values);
// The integer a constant expression broadcasts: floor(value / 2^fraction_bits), as qload
// would load it at any pixel (ExpressionInfo::constant).
std::int64_t broadcast_value(const Operand& operand, const PacketValues& values, int fraction_bits);

ArrayCycles instruction_cost(const Instruction& ins, const TimingParams& timing,
                             const PacketValues& values);
// One line of assembly for an instruction, e.g. "qcmp.lt z, depth".
std::string disassemble(const Instruction& ins);

}  // namespace pp5
