// The instruction table: complete, in Opcode order, unique mnemonics; disassembly that
// re-assembles to the same instructions; cycle costs that follow the documented formulas,
// and the Renderer board charging exactly those costs. The table executes through the
// PixelBackend interface: every registered backend gives, for random instruction streams,
// the state that direct bit-sliced PixelArray / ExpressionEvaluator operations give.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/pixel_array/backends.hpp"
#include "models/pixel_array/bit_sliced_backend.hpp"
#include "models/pixel_array/pixel_array.hpp"
#include "models/renderer/renderer_board.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

// Field declarations and output line that give `p`'s layout again.
std::string declarations_of(const Program& p) {
  std::string text;
  for (const FieldDecl& f : p.fields) {
    text +=
        "field " + f.name + " " + std::to_string(f.width) + (f.is_signed ? " signed" : "") + "\n";
  }
  text += "output";
  for (const Field& out : p.outputs) {
    for (const FieldDecl& f : p.fields) {
      if (f.lo == out.lo && f.width == out.width) text += " " + f.name;
    }
  }
  return text + "\n";
}

void check_same_operand(const Operand& a, const Operand& b) {
  CHECK(a.kind == b.kind);
  CHECK(a.text == b.text);
  switch (a.kind) {
    case Operand::Kind::field:
      CHECK(a.field.lo == b.field.lo);
      CHECK(a.field.width == b.field.width);
      CHECK(a.field.is_signed == b.field.is_signed);
      break;
    case Operand::Kind::expression:
    case Operand::Kind::parameter:
      CHECK(a.index == b.index);
      break;
    case Operand::Kind::literal:
      CHECK(a.literal == b.literal);
      break;
    case Operand::Kind::none:
      break;
  }
}

TimingParams unusual_timing() {
  TimingParams t;
  t.fraction_bits = 10;
  t.result_bits = 48;
  t.evaluator_latency = 5;
  t.block_bits = 16;
  t.backing_store_cycles_per_block = 100;
  return t;
}

// Sum over j in [0, n) of (w - j): the shift-and-add steps of a product of width w.
std::uint64_t steps(int w, int n) {
  std::uint64_t s = 0;
  for (int j = 0; j < n; ++j) s += static_cast<std::uint64_t>(w - j);
  return s;
}

}  // namespace

TEST_CASE("the instruction table is complete, ordered and unambiguous", "[isa]") {
  const auto& table = instruction_table();
  REQUIRE(table.size() == static_cast<std::size_t>(Opcode::count));
  std::set<std::string> mnemonics;
  for (std::size_t k = 0; k < table.size(); ++k) {
    const InstructionInfo& info = table[k];
    INFO("entry " << k << " " << info.mnemonic);
    CHECK(static_cast<std::size_t>(info.op) == k);
    CHECK(&instruction_info(info.op) == &info);
    CHECK(find_instruction(info.mnemonic) == &info);
    CHECK(mnemonics.insert(info.mnemonic).second);
    // The syntax line starts with the mnemonic (and its condition suffix, if any).
    const std::string syntax = info.syntax;
    const std::string head = std::string(info.mnemonic) + (info.conditional ? ".cond" : "");
    CHECK(syntax.rfind(head, 0) == 0);
    CHECK((syntax.size() == head.size() || syntax[head.size()] == ' '));
    CHECK(std::strspn(info.operands, "FRVKEB") == std::strlen(info.operands));
    CHECK(std::strlen(info.operands) <= 3);
    CHECK(std::strlen(info.effect) > 0);
    CHECK(std::strlen(info.cycles) > 0);
    CHECK(info.cost != nullptr);
    CHECK(info.execute != nullptr);
    const bool compares =
        info.op == Opcode::qtest || info.op == Opcode::qcmp || info.op == Opcode::cmp;
    CHECK(info.conditional == compares);
  }
  CHECK(find_instruction("frob") == nullptr);
  CHECK(find_instruction("and_") == nullptr);
  CHECK(find_instruction("and")->op == Opcode::and_);
  CHECK(find_instruction("not")->op == Opcode::not_);

  for (int c = 0; c < 6; ++c) {
    Compare parsed = Compare::eq;
    CHECK(parse_condition(condition_name(static_cast<Compare>(c)), parsed));
    CHECK(static_cast<int>(parsed) == c);
  }
  Compare unused;
  CHECK_FALSE(parse_condition("lte", unused));
  CHECK_FALSE(parse_condition("", unused));
}

TEST_CASE("a packet carries only the expressions written to it, read like a whole table", "[isa]") {
  std::mt19937_64 rng(7);
  ExpressionValues table{};
  CarriedExpressions carried;
  // Written in a scrambled order, some twice: each lands in its own slot.
  std::vector<std::size_t> order;
  for (std::size_t e = 0; e < table.size(); e += 3) order.push_back(e);
  std::shuffle(order.begin(), order.end(), rng);
  order.push_back(order.front());
  for (const std::size_t e : order) {
    const auto v = static_cast<std::int64_t>(rng() >> 8);
    table[e] = QuadraticCoefficients{v, v + 1, v + 2, v + 3, v + 4, v + 5};
    carried[e] = table[e];
  }
  CHECK(carried.size() == (table.size() + 2) / 3);
  const CarriedExpressions& read = carried;
  const ExpressionView view(carried), whole(table);
  for (std::size_t e = 0; e < table.size(); ++e) {
    INFO("expression " << e);
    CHECK(read.carries(e) == (e % 3 == 0));
    CHECK(read[e] == table[e]);  // absent: all zero, as in the table
    CHECK(view[e] == table[e]);
    CHECK(whole[e] == table[e]);
  }
  CHECK(static_cast<std::size_t>(view.end() - view.begin()) == carried.size());
  CHECK(static_cast<std::size_t>(whole.end() - whole.begin()) == table.size());
  CHECK(CarriedExpressions(table).size() == table.size());
}

TEST_CASE("disassembly re-assembles to the same instructions", "[isa]") {
  Instruction by_hand;
  by_hand.op = Opcode::cmp;
  by_hand.condition = Compare::le;
  by_hand.operands[0].text = "level";
  by_hand.operands[1].kind = Operand::Kind::literal;
  by_hand.operands[1].literal = -7;
  CHECK(disassemble(by_hand) == "cmp.le level, -7");

  for (const char* file : {"flat.pp5", "gouraud.pp5", "phong.pp5"}) {
    SECTION(file) {
      const Program original = assemble_file(test::kProgramsDir + file, AssemblerOptions{});
      std::string text = declarations_of(original);
      for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
        if (!original.procedures[proc].defined) continue;
        text += std::string("proc ") + kProcedureNames[proc] + "\n";
        for (const Instruction& ins : original.procedures[proc].code) {
          text += "  " + disassemble(ins) + "\n";
        }
        text += "end\n";
      }
      const Program again = assemble(text, "disassembly", AssemblerOptions{});
      for (int k = 0; k < 3; ++k) {
        CHECK(again.outputs[k].lo == original.outputs[k].lo);
        CHECK(again.outputs[k].width == original.outputs[k].width);
      }
      for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
        const auto& a = original.procedures[proc];
        const auto& b = again.procedures[proc];
        CHECK(a.defined == b.defined);
        CHECK(a.expressions == b.expressions);
        CHECK(a.parameters == b.parameters);
        REQUIRE(a.code.size() == b.code.size());
        for (std::size_t i = 0; i < a.code.size(); ++i) {
          INFO(kProcedureNames[proc] << " #" << i << ": " << disassemble(a.code[i]));
          CHECK(a.code[i].op == b.code[i].op);
          if (instruction_info(a.code[i].op).conditional) {
            CHECK(a.code[i].condition == b.code[i].condition);
          }
          for (int k = 0; k < 3; ++k)
            check_same_operand(a.code[i].operands[k], b.code[i].operands[k]);
          CHECK(disassemble(a.code[i]) == disassemble(b.code[i]));
        }
      }
    }
  }
}

TEST_CASE("cycle costs follow the documented formulas", "[isa]") {
  const TimingParams t = unusual_timing();
  OwnedValues values;
  values.parameters[static_cast<int>(Parameter::diffuse)] = 0b1011;  // bits 0, 1, 3
  values.parameters[static_cast<int>(Parameter::specular)] = -6;     // |k| bits 1, 2

  const std::uint64_t fetch = t.fraction_bits + t.evaluator_latency;
  struct Case {
    const char* line;
    std::uint64_t cycles;
  };
  // Widths: a 9, b 16, c 8 signed, d 20, z 24, w 40, red 8.
  const std::vector<Case> cases = {
      {"eall", 1},
      {"epush", 1},
      {"eelse", 1},
      {"epop", 1},
      {"qtest.ge edge0", static_cast<std::uint64_t>(t.result_bits + t.evaluator_latency)},
      {"qload z, depth", fetch + 24},
      {"qload z[7:0], depth", fetch + 8},
      {"qload c, nx", fetch + 8},
      {"qcmp.lt z, depth", fetch + 24 + 1},
      {"qcmp.ge a[3:0], depth", fetch + 4 + 1},
      {"mov b, 3", 16},
      {"mov z[23:20], a", 4},
      {"add b, a", 16},
      {"add a[3:0], 1", 4},
      {"sub z, b", 24},
      {"and b, 1", 16},
      {"or w, ambient", 40},
      {"xor red, c", 8},
      {"not w", 40},
      {"not w[0]", 1},
      {"cmp.lt a, 255", 10},
      {"cmp.lt a, b", 17},
      {"cmp.eq b[3:0], a[1:0]", 5},
      {"cmp.ne w, z", 41},
      // mul: width(dst) + the steps for min(width(dst), width(b)) bits of b, or
      // width(dst) of them when b is signed (its sign extends up to the top of dst).
      {"mul b, red, green", 16 + steps(16, 8)},
      {"mul b, red, c", 16 + steps(16, 16)},
      {"mul b, red, c[7:0]", 16 + steps(16, 8)},
      {"mul b, red, d", 16 + steps(16, 16)},
      {"mul red, b, a[2:0]", 8 + steps(8, 3)},
      {"mul w, d, z", 40 + steps(40, 24)},
      // mac: 1 + (width(dst) - j) for each set bit j of |k| below width(dst).
      {"mac b, red, 0", 1},
      {"mac b, red, 1", 1 + 16},
      {"mac b, red, 5", 1 + 16 + 14},
      {"mac b, red, -5", 1 + 16 + 14},
      {"mac b, red, 65536", 1},
      {"mac b, red, 65537", 1 + 16},
      {"mac b, red, diffuse", 1 + 16 + 15 + 13},
      {"mac b, red, specular", 1 + 15 + 14},
      {"mac w, red, -1", 1 + 40},
      {"mac b, red, 65535", 1 + steps(16, 16)},
      {"mac b, red, -65535", 1 + steps(16, 16)},
      // Backing store: whole blocks of renderer.block_bits.
      {"bsld z, 0", 2 * 100},
      {"bsst w, 3", 3 * 100},
      {"bsld red, 9", 1 * 100},
      {"bsst b, 9", 1 * 100},
      {"bsld b[8:0], 9", 1 * 100},
      {"bsst d[16:0], 9", 2 * 100},
  };
  std::string text =
      "field a 9\nfield b 16\nfield c 8 signed\nfield d 20\nfield z 24\nfield w 40\n"
      "field red 8\nfield green 8\nfield blue 8\noutput red green blue\nproc triangle\n";
  for (const Case& c : cases) text += std::string("  ") + c.line + "\n";
  text += "end\n";
  const Program p = assemble(text, "costs", AssemblerOptions{});
  const auto& code = p.procedure(Procedure::triangle).code;
  REQUIRE(code.size() == cases.size());
  std::uint64_t total = 0;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    INFO(cases[k].line);
    CHECK(instruction_cost(code[k], t, values).count == cases[k].cycles);
    CHECK(instruction_info(code[k].op).cost(code[k], t, values).count == cases[k].cycles);
    total += cases[k].cycles;
  }
  CHECK(procedure_cost(p.procedure(Procedure::triangle), t, values).count == total);

  // The default timing gives the figures quoted in the documentation.
  const TimingParams defaults;
  auto cost_of = [&](const std::string& line) {
    for (std::size_t k = 0; k < cases.size(); ++k) {
      if (line == cases[k].line) return instruction_cost(code[k], defaults, values).count;
    }
    FAIL("no case " << line);
    return std::uint64_t{0};
  };
  CHECK(cost_of("qload z, depth") == 12 + 24 + 8);
  CHECK(cost_of("qtest.ge edge0") == 40 + 8);
  CHECK(cost_of("bsld z, 0") == 1 * 64);  // 32-bit blocks
  CHECK(cost_of("bsst w, 3") == 2 * 64);

  // evaluator.bit_order=msb_first: the sign first (an edge test is one bit), a load or
  // compare streams the integer bits from the top down (40 - 12 of them).
  TimingParams msb;
  msb.msb_first = true;
  auto msb_cost_of = [&](const std::string& line) {
    for (std::size_t k = 0; k < cases.size(); ++k) {
      if (line == cases[k].line) return instruction_cost(code[k], msb, values).count;
    }
    FAIL("no case " << line);
    return std::uint64_t{0};
  };
  CHECK(msb_cost_of("qtest.ge edge0") == 1 + 8);
  CHECK(msb_cost_of("qload z, depth") == 40 - 12 + 8);
  CHECK(msb_cost_of("qload z[7:0], depth") == 40 - 12 + 8);
  CHECK(msb_cost_of("qcmp.lt z, depth") == 40 - 12 + 8 + 1);
  CHECK(msb_cost_of("bsld z, 0") == 1 * 64);
}

TEST_CASE("the windowed multiply adds only the partial product's window", "[isa]") {
  // renderer.multiply_microcode: the issue's figures, a 14 x 14 square into 29 bits and a
  // 16 x 16 one into 32; a signed a needs the full pass (its sign reaches the top); mac is
  // the same under both.
  const Program p = assemble(
      "field a 14\nfield b 14\nfield s 29\nfield x 16\nfield y 16\nfield t 32\n"
      "field c 8 signed\nfield d 20\nfield red 8\nfield green 8\nfield blue 8\n"
      "output red green blue\nproc triangle\n  mul s, a, b\n  mul t, x, y\n"
      "  mul d, c, red\n  mul d, red, c\n  mac d, red, 255\nend\n",
      "window", AssemblerOptions{});
  const auto& code = p.procedure(Procedure::triangle).code;
  REQUIRE(code.size() == 5);
  TimingParams full;
  TimingParams window;
  window.multiply_window = true;
  const OwnedValues values;
  auto cost = [&](int k, const TimingParams& t) {
    return instruction_cost(code[k], t, values).count;
  };
  CHECK(cost(0, full) == 344);
  CHECK(cost(0, window) == 29 + 14 * 15);  // 239
  CHECK(cost(1, full) == 424);
  CHECK(cost(1, window) == 32 + 16 * 17);   // 304
  CHECK(cost(2, window) == cost(2, full));  // signed a
  // An unsigned a by a signed b: 20 passes (b's sign extends), each at most 9 bits.
  std::uint64_t passes = 20;
  for (int j = 0; j < 20; ++j) passes += static_cast<std::uint64_t>(std::min(20 - j, 9));
  CHECK(cost(3, window) == passes);
  CHECK(cost(3, full) == 20 + steps(20, 20));
  CHECK(cost(4, window) == cost(4, full));
}

TEST_CASE("the Renderer board charges the table's costs", "[isa]") {
  const Program p = assemble_file(test::kProgramsDir + "phong.pp5", AssemblerOptions{});
  RendererBoardParams params;
  params.array.width = 64;
  params.array.height = 8;
  params.timing = unusual_timing();
  params.timing.fraction_bits = 12;  // the evaluator and the assembler agree on 12
  RendererBoard board(params);
  board.begin_region(0, 0);

  OwnedValues values;
  const char* const names[] = {"light_x", "light_y", "light_z", "half_x",  "half_y",
                               "half_z",  "ambient", "diffuse", "specular"};
  std::int64_t k = 13;
  for (const char* name : names) {
    values.parameters[parameter_index(name)] = k;
    k = k * 7 % 127 - 40;
  }
  const std::int64_t one = std::int64_t{1} << 12;
  values.expressions[static_cast<int>(Expression::nx)] =
      QuadraticCoefficients::linear(one, 0, -30 * one);
  values.expressions[static_cast<int>(Expression::nz)] = QuadraticCoefficients::constant(90 * one);

  std::uint64_t total = 0;
  std::uint64_t instructions = 0;
  for (const Procedure proc :
       {Procedure::clear, Procedure::triangle, Procedure::light, Procedure::shade}) {
    const ProcedureCode& code = p.procedure(proc);
    INFO("proc " << kProcedureNames[static_cast<int>(proc)]);
    std::uint64_t expected = 0;
    for (const Instruction& ins : code.code) {
      expected += instruction_cost(ins, params.timing, values).count;
    }
    CHECK(procedure_cost(code, params.timing, values).count == expected);
    CHECK(board.run(code, values).count == expected);
    total += expected;
    instructions += code.code.size();
  }
  CHECK(board.cycles_executed().count == total);
  CHECK(board.instructions_executed() == instructions);

  // mac costs follow the parameters a packet binds: other values, other cost.
  const OwnedValues zero;
  CHECK(procedure_cost(p.procedure(Procedure::light), params.timing, zero).count <
        procedure_cost(p.procedure(Procedure::light), params.timing, values).count);
}

namespace {

// The reference: each instruction as direct operations on the bit-sliced PixelArray and the
// ExpressionEvaluator (what the executors did before the backend interface existed).
struct Reference {
  PixelArray array;
  ExpressionEvaluator evaluator;
  int fraction_bits;
  std::vector<Word> scratch;

  explicit Reference(const PixelBackendParams& p)
      : array(p.array),
        evaluator(p.evaluator, p.array.width, p.array.height),
        fraction_bits(p.fraction_bits),
        scratch(static_cast<std::size_t>(Bits::kMaxBits) * array.words()) {}

  Bits source(const Operand& o, const PacketValues& v) {
    if (o.kind == Operand::Kind::field) return array.bits_of(o.field);
    // A broadcast constant expression: what the evaluator would deliver at every pixel.
    if (o.kind == Operand::Kind::expression) return expression(o, Field{0, 62, true}, v);
    return array.bits_of_constant(constant_value(o, v));
  }
  Bits expression(const Operand& e, const Field& as, const PacketValues& v) {
    evaluator.planes(v.expressions[e.index], fraction_bits, as.width, array.active_words(),
                     scratch.data());
    return array.bits_of_planes(scratch.data(), as.width, as.is_signed);
  }

  void execute(const Instruction& i, const PacketValues& v) {
    const Operand& a = i.operands[0];
    const Operand& b = i.operands[1];
    switch (i.op) {
      case Opcode::eall:
        return array.enable_all();
      case Opcode::epush:
        return array.push_enable();
      case Opcode::epop:
        return array.pop_enable();
      case Opcode::eelse:
        return array.else_enable();
      case Opcode::qtest:
        evaluator.test_plane(v.expressions[a.index], i.condition, array.active_words(),
                             scratch.data());
        return array.and_enable(scratch.data());
      case Opcode::qload: {
        const Bits x = expression(b, a.field, v);
        return array.assign(a.field, x);
      }
      case Opcode::qcmp: {
        const Bits x = expression(b, a.field, v);
        return array.compare(x, array.bits_of(a.field), i.condition);
      }
      case Opcode::mov:
        return array.assign(a.field, source(b, v));
      case Opcode::add:
        return array.add(a.field, array.bits_of(a.field), source(b, v));
      case Opcode::sub:
        return array.sub(a.field, array.bits_of(a.field), source(b, v));
      case Opcode::cmp:
        return array.compare(array.bits_of(a.field), source(b, v), i.condition);
      case Opcode::and_:
        return array.logic(a.field, array.bits_of(a.field), source(b, v), Logic::and_);
      case Opcode::or_:
        return array.logic(a.field, array.bits_of(a.field), source(b, v), Logic::or_);
      case Opcode::xor_:
        return array.logic(a.field, array.bits_of(a.field), source(b, v), Logic::xor_);
      case Opcode::not_:
        return array.invert(a.field);
      case Opcode::mul:
        return array.multiply(a.field, array.bits_of(b.field), array.bits_of(i.operands[2].field));
      case Opcode::mac:
        return array.multiply_accumulate(a.field, array.bits_of(b.field),
                                         constant_value(i.operands[2], v));
      case Opcode::bsld:
        return array.load_from_backing(a.field, static_cast<int>(b.literal));
      case Opcode::bsst:
        return array.store_to_backing(a.field, static_cast<int>(b.literal));
      case Opcode::count:
        break;
    }
    FAIL("no such opcode");
  }
};

PixelBackendParams small_backend_params() {
  PixelBackendParams p;
  p.array.width = 128;
  p.array.height = 6;
  p.array.memory_bits = 120;
  p.array.enable_stack_depth = 3;
  p.array.backing_store_bits = 256;
  p.array.block_bits = 16;
  p.evaluator.coefficient_bits = 40;
  p.evaluator.result_bits = 40;
  p.fraction_bits = 7;
  return p;
}

// Random instructions that are valid on `p` (fields inside memory, mul/mac destinations
// apart from their sources, blocks inside the store, the enable stack used within its depth)
// with random packet values: expressions, linear and quadratic, and parameters.
class StreamMaker {
 public:
  StreamMaker(const PixelBackendParams& p, unsigned seed) : p_(p), rng_(seed) {}

  OwnedValues values() {
    OwnedValues v;
    for (auto& e : v.expressions) {
      if (kExpressions[&e - v.expressions.data()].constant) {
        e.F = pick(-(std::int64_t{1} << 30), std::int64_t{1} << 30);  // one value, as the GP sends
        continue;
      }
      const bool quadratic = pick(0, 3) == 0;
      e.D = pick(-(1 << 14), 1 << 14);
      e.E = pick(-(1 << 14), 1 << 14);
      e.F = pick(-(std::int64_t{1} << 30), std::int64_t{1} << 30);
      if (quadratic) {
        e.A = pick(-300, 300);
        e.B = pick(-300, 300);
        e.C = pick(-300, 300);
      }
    }
    for (auto& k : v.parameters) k = pick(-1000, 1000);
    return v;
  }

  Instruction next(int depth) {
    Instruction i;
    i.condition = static_cast<Compare>(pick(0, 5));
    for (;;) {
      i.op = static_cast<Opcode>(pick(0, static_cast<int>(Opcode::count) - 1));
      if (i.op == Opcode::epush && depth >= p_.array.enable_stack_depth) continue;
      if ((i.op == Opcode::epop || i.op == Opcode::eelse) && depth == 0) continue;
      break;
    }
    auto& o = i.operands;
    switch (i.op) {
      case Opcode::qtest:
        o[0] = expression();
        break;
      case Opcode::qload:
      case Opcode::qcmp:
        o[0] = field(1, 40);
        o[1] = expression();
        break;
      case Opcode::mov:
      case Opcode::add:
      case Opcode::sub:
      case Opcode::cmp:
      case Opcode::and_:
      case Opcode::or_:
      case Opcode::xor_:
        o[0] = field(1, 40);
        o[1] =
            pick(0, 2) == 0 ? (pick(0, 2) == 0 ? constant_expression() : constant()) : field(1, 40);
        break;
      case Opcode::not_:
        o[0] = field(1, 40);
        break;
      case Opcode::mul:
        // dst in the upper half of memory, sources in the lower: never overlapping.
        o[0] = field(1, 24, p_.array.memory_bits / 2, p_.array.memory_bits);
        o[1] = field(1, 24, 0, p_.array.memory_bits / 2);
        o[2] = field(1, 24, 0, p_.array.memory_bits / 2);
        break;
      case Opcode::mac:
        o[0] = field(1, 24, p_.array.memory_bits / 2, p_.array.memory_bits);
        o[1] = field(1, 24, 0, p_.array.memory_bits / 2);
        o[2] = constant();
        break;
      case Opcode::bsld:
      case Opcode::bsst: {
        o[0] = field(1, 40);
        const int blocks_needed =
            (o[0].field.width + p_.array.block_bits - 1) / p_.array.block_bits;
        const int last = p_.array.backing_store_bits / p_.array.block_bits - blocks_needed;
        o[1].kind = Operand::Kind::literal;
        o[1].literal = pick(0, last);
        break;
      }
      default:
        break;
    }
    return i;
  }

 private:
  std::int64_t pick(std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng_);
  }
  Operand field(int min_width, int max_width, int lo = 0, int hi = -1) {
    if (hi < 0) hi = p_.array.memory_bits;
    Operand o;
    o.kind = Operand::Kind::field;
    o.field.width = static_cast<int>(pick(min_width, std::min(max_width, hi - lo)));
    o.field.lo = static_cast<int>(pick(lo, hi - o.field.width));
    o.field.is_signed = pick(0, 1) == 1;
    return o;
  }
  Operand expression() {
    Operand o;
    o.kind = Operand::Kind::expression;
    o.index = static_cast<int>(pick(0, static_cast<int>(Expression::count) - 1));
    return o;
  }
  // A constant expression broadcast as a 'V' operand (slope_x, flat_red, ...).
  Operand constant_expression() {
    std::vector<int> constants;
    for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
      if (kExpressions[e].constant) constants.push_back(e);
    }
    Operand o;
    o.kind = Operand::Kind::expression;
    o.index = constants[static_cast<std::size_t>(pick(0, static_cast<int>(constants.size()) - 1))];
    return o;
  }
  Operand constant() {
    Operand o;
    if (pick(0, 1) == 0) {
      o.kind = Operand::Kind::parameter;
      o.index = static_cast<int>(pick(0, static_cast<int>(Parameter::count) - 1));
    } else {
      o.kind = Operand::Kind::literal;
      const int bits = static_cast<int>(pick(1, 63));
      o.literal = pick(-(std::int64_t{1} << (bits - 1)), (std::int64_t{1} << (bits - 1)) - 1);
    }
    return o;
  }

  PixelBackendParams p_;
  std::mt19937_64 rng_;
};

// Every bit of local memory, E and the stack depth of a backend against the reference.
void check_same(const PixelBackend& b, const Reference& r) {
  REQUIRE(b.enable_depth() == r.array.enable_depth());
  std::vector<std::uint64_t> planes;
  b.read_memory_planes(planes);
  const auto bits = static_cast<std::size_t>(r.array.geometry().memory_bits);
  REQUIRE(planes.size() == bits * r.array.words());
  for (std::size_t bit = 0; bit < bits; ++bit) {
    for (int w = 0; w < r.array.words(); ++w) {
      INFO("bit " << bit << " word " << w);
      REQUIRE(planes[bit * r.array.words() + w] == r.array.plane(static_cast<int>(bit))[w]);
    }
  }
  int enabled = 0;
  for (int p = 0; p < r.array.pixels(); ++p) {
    INFO("pixel " << p);
    REQUIRE(b.enabled(p) == r.array.enabled(p));
    enabled += r.array.enabled(p) ? 1 : 0;
  }
  REQUIRE(b.count_enabled() == enabled);
}

}  // namespace

TEST_CASE("every registered backend runs the instruction table as the bit-sliced reference",
          "[isa][backend]") {
  const PixelBackendParams params = small_backend_params();
  REQUIRE(find_pixel_backend("bit") != nullptr);
  for (const PixelBackendInfo& info : pixel_backends()) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      INFO("backend " << info.name << " seed " << seed);
      auto backend = make_pixel_backend(info.name, params);
      REQUIRE(std::string(backend->name()) == info.name);
      REQUIRE(backend->geometry() == params.array);
      Reference ref(params);
      StreamMaker make(params, seed);
      const int x0 = 128 * static_cast<int>(seed), y0 = 6 * static_cast<int>(seed) - 20;
      backend->set_origin(x0, y0);
      ref.evaluator.set_origin(x0, y0);
      // Start from random memory, the same on both (write ignores E).
      std::mt19937_64 fill(seed);
      for (int p = 0; p < ref.array.pixels(); ++p) {
        for (int lo = 0; lo + 60 <= params.array.memory_bits; lo += 60) {
          const std::uint64_t v = fill();
          backend->write(p, Field{lo, 60, false}, v);
          ref.array.write(p, Field{lo, 60, false}, v);
        }
      }
      check_same(*backend, ref);
      std::vector<int> ops(static_cast<std::size_t>(Opcode::count), 0);
      for (int packet = 0; packet < 8; ++packet) {
        const OwnedValues values = make.values();
        for (int n = 0; n < 60; ++n) {
          const Instruction ins = make.next(ref.array.enable_depth());
          INFO("packet " << packet << " instruction " << n << ": " << ins.operands[0].field.lo
                         << " " << static_cast<int>(ins.op));
          // Even seeds run mul's windowed microcode: the reference's full product must come
          // out all the same.
          ExecutionContext ctx{*backend, values, params.fraction_bits, seed % 2 == 0};
          instruction_info(ins.op).execute(ins, ctx);
          ref.execute(ins, values);
          ++ops[static_cast<std::size_t>(ins.op)];
          check_same(*backend, ref);
        }
      }
      for (std::size_t op = 0; op < ops.size(); ++op) {
        INFO("opcode " << instruction_info(static_cast<Opcode>(op)).mnemonic);
        CHECK(ops[op] > 0);  // the stream exercised every instruction
      }
      for (int p = 0; p < ref.array.pixels(); p += 37) {
        const Field f{3, 17, true};
        CHECK(backend->read(p, f) == ref.array.read(p, f));
        CHECK(backend->read_signed(p, f) == ref.array.read_signed(p, f));
      }
      // The interface's generic whole-memory read (for backends that hold no bit-planes)
      // agrees with the backend's own.
      std::vector<std::uint64_t> own, generic;
      backend->read_memory_planes(own);
      backend->PixelBackend::read_memory_planes(generic);
      CHECK(own == generic);
      std::vector<std::uint64_t> values(static_cast<std::size_t>(ref.array.pixels()));
      backend->read_field(Field{10, 33, false}, values.data());
      for (int p = 0; p < ref.array.pixels(); ++p) {
        REQUIRE(values[static_cast<std::size_t>(p)] == ref.array.read(p, Field{10, 33, false}));
      }
    }
  }
}

TEST_CASE("an expression evaluated by qcmp is reused by qload only while E only loses bits",
          "[isa][backend]") {
  // The bit backend keeps an expression's planes between a qcmp and a qload of the same
  // expression and width. Each step below puts between them one thing after which the planes
  // must be evaluated again (a wider field, E gaining bits, another origin, scratch used by a
  // test, a state taken from elsewhere); every backend must match the reference, which
  // evaluates every expression afresh. The region is tall enough that a run of eight dead
  // words is skipped by the evaluator, so planes kept from a narrower E would be wrong there.
  PixelBackendParams params = small_backend_params();
  params.array.height = 32;
  const Field z{0, 24, false}, red{24, 8, false};
  for (const PixelBackendInfo& info : pixel_backends()) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      INFO("backend " << info.name << " seed " << seed);
      auto b = make_pixel_backend(info.name, params);
      Reference ref(params);
      const int x0 = 64 * static_cast<int>(seed), y0 = 100 * static_cast<int>(seed);
      b->set_origin(x0, y0);
      ref.evaluator.set_origin(x0, y0);
      std::mt19937_64 rng(seed);
      for (int p = 0; p < ref.array.pixels(); ++p) {
        const std::uint64_t v = rng();
        b->write(p, Field{0, 60, false}, v);
        ref.array.write(p, Field{0, 60, false}, v);
      }
      auto coef = [&rng] {
        return static_cast<std::int64_t>(rng() % (std::uint64_t{1} << 31)) -
               (std::int64_t{1} << 30);
      };
      // A plane through the region's middle at a random slope: qcmp splits E.
      auto expression = [&] {
        const std::int64_t d = coef(), e = coef();
        return QuadraticCoefficients::linear(d, e, -d * (x0 + 64) - e * (y0 + 16) + (coef() >> 8));
      };
      auto qtest = [&](const QuadraticCoefficients& c, Compare cond) {
        b->qtest(c, cond);
        ref.evaluator.test_plane(c, cond, ref.array.active_words(), ref.scratch.data());
        ref.array.and_enable(ref.scratch.data());
      };
      auto first_rows = [&] { qtest(QuadraticCoefficients::linear(0, -1, y0 + 3), Compare::ge); };
      auto qcmp = [&](const Field& f, const QuadraticCoefficients& c, Compare cond) {
        b->qcmp(f, c, cond);
        ref.evaluator.planes(c, params.fraction_bits, f.width, ref.array.active_words(),
                             ref.scratch.data());
        ref.array.compare(ref.array.bits_of_planes(ref.scratch.data(), f.width, f.is_signed),
                          ref.array.bits_of(f), cond);
      };
      auto qload = [&](const Field& f, const QuadraticCoefficients& c) {
        b->qload(f, c);
        ref.evaluator.planes(c, params.fraction_bits, f.width, ref.array.active_words(),
                             ref.scratch.data());
        ref.array.assign(f, ref.array.bits_of_planes(ref.scratch.data(), f.width, f.is_signed));
      };
      auto eall = [&] {
        b->enable_all();
        ref.array.enable_all();
      };
      {
        INFO("qcmp then qload: the planes kept");
        eall();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        qload(z, c);
        check_same(*b, ref);
        qload(z, c);  // and kept again
        check_same(*b, ref);
      }
      {
        INFO("a wider field");
        eall();
        first_rows();
        const auto c = expression();
        qcmp(red, c, Compare::lt);
        qload(z, c);
        check_same(*b, ref);
      }
      {
        INFO("else");
        eall();
        b->push_enable();
        ref.array.push_enable();
        first_rows();
        const auto c = expression();
        qcmp(z, c, Compare::ge);
        b->else_enable();
        ref.array.else_enable();
        qload(z, c);
        check_same(*b, ref);
        b->pop_enable();
        ref.array.pop_enable();
      }
      {
        INFO("eall");
        eall();
        first_rows();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        eall();
        qload(z, c);
        check_same(*b, ref);
      }
      {
        INFO("pop");
        eall();
        b->push_enable();
        ref.array.push_enable();
        first_rows();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        b->pop_enable();
        ref.array.pop_enable();
        qload(z, c);
        check_same(*b, ref);
      }
      {
        INFO("another origin");
        eall();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        b->set_origin(x0 + 128, y0 + 32);
        ref.evaluator.set_origin(x0 + 128, y0 + 32);
        qload(z, c);
        check_same(*b, ref);
        b->set_origin(x0, y0);
        ref.evaluator.set_origin(x0, y0);
      }
      {
        INFO("a test between");
        eall();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        qtest(QuadraticCoefficients::linear(1, 0, -(x0 + 5)), Compare::ge);
        qload(z, c);
        check_same(*b, ref);
      }
      {
        INFO("a state taken from another backend");
        eall();
        const auto all_on = b->clone();
        const PixelArray kept = ref.array;
        first_rows();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        b->copy_state_from(*all_on);
        ref.array = kept;
        qload(z, c);
        check_same(*b, ref);
      }
      if (auto* bit = dynamic_cast<BitSlicedBackend*>(b.get())) {
        INFO("E changed through array()");
        eall();
        first_rows();
        const auto c = expression();
        qcmp(z, c, Compare::lt);
        bit->array().enable_all();
        ref.array.enable_all();
        qload(z, c);
        check_same(*b, ref);
      }
    }
  }
}

TEST_CASE("a backend's state can be cloned, compared and taken back", "[isa][backend]") {
  const PixelBackendParams params = small_backend_params();
  for (const PixelBackendInfo& info : pixel_backends()) {
    INFO("backend " << info.name);
    auto a = make_pixel_backend(info.name, params);
    a->write(5, Field{0, 8, false}, 200);
    const auto kept = a->clone();
    CHECK(a->same_state(*kept));
    CHECK(kept->read(5, Field{0, 8, false}) == 200);

    // Each part of the state counts: memory, E, the stack.
    a->write(7, Field{100, 1, false}, 1);
    CHECK_FALSE(a->same_state(*kept));
    a->copy_state_from(*kept);
    CHECK(a->same_state(*kept));
    CHECK(a->read(7, Field{100, 1, false}) == 0);
    a->push_enable();
    CHECK_FALSE(a->same_state(*kept));
    a->pop_enable();
    a->qtest(QuadraticCoefficients::linear(1, 0, -3), Compare::ge);  // x >= 3
    CHECK_FALSE(a->enabled(2));
    CHECK(a->enabled(3));
    CHECK_FALSE(a->same_state(*kept));
    a->copy_state_from(*kept);
    CHECK(a->enabled(2));
    CHECK(a->same_state(*kept));

    // Another geometry is another state, and cannot be taken.
    PixelBackendParams other = params;
    other.array.height = params.array.height + 1;
    const auto b = make_pixel_backend(info.name, other);
    CHECK_FALSE(a->same_state(*b));
    CHECK_THROWS_AS(a->copy_state_from(*b), std::invalid_argument);
  }
}

TEST_CASE("backends follow the interface's error contract", "[isa][backend]") {
  const PixelBackendParams params = small_backend_params();
  for (const PixelBackendInfo& info : pixel_backends()) {
    INFO("backend " << info.name);
    auto b = make_pixel_backend(info.name, params);
    CHECK_THROWS_AS(b->pop_enable(), std::underflow_error);
    CHECK_THROWS_AS(b->else_enable(), std::underflow_error);
    for (int k = 0; k < params.array.enable_stack_depth; ++k) b->push_enable();
    CHECK_THROWS_AS(b->push_enable(), std::overflow_error);
    CHECK_THROWS_AS(b->mov(Field{params.array.memory_bits - 4, 8, false}, Source::of(1)),
                    std::out_of_range);
    CHECK_THROWS_AS(b->store_to_backing(Field{0, 16, false},
                                        params.array.backing_store_bits / params.array.block_bits),
                    std::out_of_range);
    CHECK_THROWS_AS(b->multiply(Field{0, 8, false}, Field{4, 8, false}, Field{40, 8, false}, false),
                    std::invalid_argument);
    CHECK_THROWS_AS(b->multiply_accumulate(Field{0, 8, false}, Field{4, 8, false}, 3),
                    std::invalid_argument);
  }
}

TEST_CASE("an unknown pixel backend is a clear error", "[isa][backend]") {
  CHECK(find_pixel_backend("bits") == nullptr);
  try {
    make_pixel_backend("bits", small_backend_params());
    FAIL("no exception");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("unknown pixel backend 'bits'") != std::string::npos);
    CHECK(what.find("known: bit") != std::string::npos);
  }
  RendererBoardParams board;
  board.array.width = 64;
  board.array.height = 2;
  board.backend = "nonesuch";
  CHECK_THROWS_WITH(RendererBoard(board), Catch::Contains("unknown pixel backend 'nonesuch'"));
  board.backend = "bit";
  CHECK(std::string(RendererBoard(board).array().name()) == "bit");
}

TEST_CASE("firmware/ includes nothing from models/ or sim/", "[isa][backend]") {
  // The instruction set is the interface the models implement; an include the other way
  // would make firmware depend on one model again.
  int files = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(PP5_SOURCE_DIR "/firmware")) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".hpp" && ext != ".cpp") continue;
    ++files;
    std::ifstream in(entry.path());
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      INFO(entry.path().string() << ":" << number << ": " << line);
      CHECK(line.rfind("#include \"models/", 0) == std::string::npos);
      CHECK(line.rfind("#include \"sim/", 0) == std::string::npos);
    }
  }
  CHECK(files >= 6);
}
