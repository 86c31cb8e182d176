// The instruction table: complete, in Opcode order, unique mnemonics; disassembly that
// re-assembles to the same instructions; cycle costs that follow the documented formulas,
// and the Renderer board charging exactly those costs.
#include <catch2/catch.hpp>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/renderer/renderer_board.hpp"

using namespace pp5;

namespace {

const std::string kPrograms = PP5_SOURCE_DIR "/firmware/programs/";

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
      const Program original = assemble_file(kPrograms + file, AssemblerOptions{});
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
}

TEST_CASE("the Renderer board charges the table's costs", "[isa]") {
  const Program p = assemble_file(kPrograms + "phong.pp5", AssemblerOptions{});
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
