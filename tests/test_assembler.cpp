// The firmware assembler: the shipped programs, field layout, error messages (file, line,
// what was expected), and spilling, which must be invisible in the pixels a program computes.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/analysis/csg.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

using namespace pp5;

namespace {

const std::string kSpillProgram = PP5_SOURCE_DIR "/tests/data/firmware/spill.pp5";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

AssemblerOptions options_with_memory(int memory_bits) {
  AssemblerOptions o;
  o.memory_bits = memory_bits;
  return o;
}

// The 1-based line of the first line of `source` containing `marker`.
int line_of(const std::string& source, const std::string& marker) {
  std::istringstream in(source);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.find(marker) != std::string::npos) return n;
  }
  FAIL("marker '" << marker << "' not in the source");
  return -1;
}

int line_count(const std::string& source) {
  std::istringstream in(source);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) ++n;
  return n;
}

std::string assembly_error(const std::string& source, const AssemblerOptions& options = {}) {
  try {
    assemble(source, "bad.pp5", options);
  } catch (const AssemblyError& e) {
    return e.what();
  }
  FAIL("the program assembled:\n" << source);
  return "";
}

// Asserts that `source` is rejected at line `line` with a message containing `expected`.
void check_error_at(const std::string& source, int line, const std::string& expected,
                    const AssemblerOptions& options = {}) {
  const std::string message = assembly_error(source, options);
  INFO("message: " << message);
  CHECK(message.rfind("bad.pp5:" + std::to_string(line) + ": ", 0) == 0);
  CHECK(message.find(expected) != std::string::npos);
}

// A valid program around `body`, the triangle procedure's code; the bad line of a test
// carries the comment "; HERE".
std::string with_triangle(const std::string& body, const std::string& extra_procs = "") {
  return "field z 24\n"
         "field red 8\n"
         "field green 8\n"
         "field blue 8\n"
         "field s 16 signed\n"
         "output red green blue\n" +
         extra_procs +
         "proc triangle\n"
         "  eall\n" +
         body + "end\n";
}

void check_error_here(const std::string& source, const std::string& expected,
                      const AssemblerOptions& options = {}) {
  check_error_at(source, line_of(source, "; HERE"), expected, options);
}

std::set<std::string> expression_names(const std::bitset<static_cast<int>(Expression::count)>& b) {
  std::set<std::string> names;
  for (int i = 0; i < static_cast<int>(Expression::count); ++i) {
    if (b[i]) names.insert(kExpressions[i].name);
  }
  return names;
}

std::set<std::string> parameter_names(const std::bitset<static_cast<int>(Parameter::count)>& b) {
  std::set<std::string> names;
  for (int i = 0; i < static_cast<int>(Parameter::count); ++i) {
    if (b[i]) names.insert(kParameters[i].name);
  }
  return names;
}

// The expressions and parameters a procedure's instructions actually name.
void used_operands(const ProcedureCode& code, std::set<std::string>& expressions,
                   std::set<std::string>& parameters) {
  for (const Instruction& ins : code.code) {
    for (const Operand& o : ins.operands) {
      if (o.kind == Operand::Kind::expression) expressions.insert(kExpressions[o.index].name);
      if (o.kind == Operand::Kind::parameter) parameters.insert(kParameters[o.index].name);
    }
  }
}

std::string field_name_of(const Operand& o) { return o.text.substr(0, o.text.find('[')); }

RendererBoardParams board_params(int memory_bits) {
  RendererBoardParams p;
  p.array.width = 64;
  p.array.height = 16;
  p.array.memory_bits = memory_bits;
  return p;
}

OwnedValues spill_test_values(int variant) {
  OwnedValues v;
  const std::int64_t one = std::int64_t{1} << TimingParams{}.fraction_bits;
  v.expressions[static_cast<int>(Expression::red)] =
      QuadraticCoefficients::linear(one * (1 + variant), 3 * one, 0);
  v.expressions[static_cast<int>(Expression::green)] =
      QuadraticCoefficients::linear(5 * one, -one, (100 + 37 * variant) * one);
  v.parameters[static_cast<int>(Parameter::background_red)] = 10;
  v.parameters[static_cast<int>(Parameter::background_green)] = 20;
  v.parameters[static_cast<int>(Parameter::background_blue)] = 30;
  v.parameters[static_cast<int>(Parameter::ambient)] = 40;
  v.parameters[static_cast<int>(Parameter::diffuse)] = 3;
  return v;
}

// Runs a region's stream over two triangles (no lights); returns the output pixels and adds
// up the cycles.
std::vector<std::uint8_t> run_spill_test(const Program& program, int memory_bits,
                                         std::uint64_t& cycles) {
  RendererBoard board(board_params(memory_bits));
  board.begin_region(0, 0);
  FrameValues frame;
  frame.frame = spill_test_values(0);
  std::vector<Packet> packets(2);
  packets[0].values.expressions = spill_test_values(0).expressions;
  packets[1].values.expressions = spill_test_values(1).expressions;
  cycles = 0;
  RegionStream(program, frame).for_each(packets, [&](const RegionStep& step) {
    cycles += board.run_step(step).count;
  });
  std::vector<std::uint8_t> rgb;
  board.read_outputs(program, rgb);
  return rgb;
}

}  // namespace

TEST_CASE("shipped programs assemble with contiguous layouts", "[assembler]") {
  struct Expected {
    const char* file;
    std::set<std::string> triangle_expressions;
    std::set<std::string> parameters;  // over all procedures
    int bits;
  };
  const std::vector<Expected> programs = {
      {"flat.pp5",
       {"edge0", "edge1", "edge2", "depth", "flat_red", "flat_green", "flat_blue"},
       {"background_red", "background_green", "background_blue"},
       48},
      {"gouraud.pp5",
       {"edge0", "edge1", "edge2", "depth", "red", "green", "blue"},
       {"background_red", "background_green", "background_blue"},
       48},
      {"phong.pp5",
       {"edge0", "edge1", "edge2", "depth", "base_red", "base_green", "base_blue", "nx", "ny",
        "nz"},
       {"background_red", "background_green", "background_blue", "light_x", "light_y", "light_z",
        "half_x", "half_y", "half_z", "ambient", "diffuse", "specular"},
       155},
      {"transparent.pp5",
       {"edge0", "edge1", "edge2", "depth", "red", "green", "blue", "opacity"},
       {"background_red", "background_green", "background_blue"},
       173},
  };
  for (const Expected& e : programs) {
    SECTION(e.file) {
      const Program p = assemble_file(test::kProgramsDir + e.file, AssemblerOptions{});
      CHECK(p.name == test::kProgramsDir + e.file);
      CHECK(p.memory_bits == 208);
      CHECK_FALSE(p.spill_allowed);

      // Fields in declaration order from bit 0; scratch fields after them or in bits of
      // fields dead in shade, within the budget.
      int lo = 0;
      for (const FieldDecl& f : p.fields) {
        INFO("field " << f.name);
        CHECK_FALSE(f.spilled);
        CHECK(f.block == -1);
        CHECK(p.find_field(f.name) == &f);
        if (f.scratch) {
          CHECK(f.lo >= 0);
          CHECK(f.lo + f.width <= p.resident_bits);
          continue;
        }
        CHECK(f.lo == lo);
        lo += f.width;
      }
      CHECK(lo + p.overlay_bits == e.bits);
      CHECK(p.resident_bits == e.bits);
      CHECK(p.staging_bits == 0);
      CHECK(p.bits_used() == e.bits);
      CHECK(p.find_field("no_such_field") == nullptr);

      const char* output_names[] = {"red", "green", "blue"};
      for (int k = 0; k < 3; ++k) {
        const FieldDecl* f = p.find_field(output_names[k]);
        REQUIRE(f);
        CHECK(p.outputs[k].lo == f->lo);
        CHECK(p.outputs[k].width == 8);
        CHECK_FALSE(p.outputs[k].is_signed);
      }

      std::set<std::string> all_parameters;
      for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
        const ProcedureCode& code = p.procedures[proc];
        INFO("proc " << kProcedureNames[proc]);
        CHECK(code.spill_transfers == 0);
        std::set<std::string> expressions;
        std::set<std::string> parameters;
        used_operands(code, expressions, parameters);
        CHECK(expression_names(code.expressions) == expressions);
        CHECK(parameter_names(code.parameters) == parameters);
        all_parameters.insert(parameters.begin(), parameters.end());
        if (proc == static_cast<int>(Procedure::triangle)) {
          CHECK(expressions == e.triangle_expressions);
        } else if (proc == static_cast<int>(Procedure::sphere)) {
          // A sphere procedure reads only the sphere's expressions (models/gp/sphere.hpp).
          for (const std::string& x : expressions) CHECK(x.rfind("sphere_", 0) == 0);
        } else {
          CHECK(expressions.empty());
        }
        for (const Instruction& ins : code.code) {
          CHECK(ins.line > 0);
          CHECK(ins.op != Opcode::bsld);
          CHECK(ins.op != Opcode::bsst);
        }
      }
      CHECK(all_parameters == e.parameters);
      CHECK(p.procedure(Procedure::clear).defined);
      CHECK(p.procedure(Procedure::triangle).defined);
      const std::string file = e.file;
      CHECK(p.procedure(Procedure::shade).defined ==
            (file == "phong.pp5" || file == "transparent.pp5"));
      CHECK(p.procedure(Procedure::light).defined == (file == "phong.pp5"));
      CHECK(p.procedure(Procedure::pass).defined == (file == "transparent.pp5"));
      // The transparency program's pass count is the frame parameter `layers` (4 by default).
      CHECK(p.passes_parameter ==
            (file == "transparent.pp5" ? static_cast<int>(Parameter::layers) : -1));
      CHECK(p.multipass() == (file == "transparent.pp5"));
      ParameterValues frame{};
      frame[static_cast<int>(Parameter::layers)] = 6;
      CHECK(p.pass_count(frame) == (file == "transparent.pp5" ? 6 : 1));
      frame[static_cast<int>(Parameter::layers)] = 0;
      if (file == "transparent.pp5") {
        CHECK_THROWS_WITH(p.pass_count(frame), Catch::Contains("option passes layers") &&
                                                   Catch::Contains("expected 1 to 64"));
      }
    }
  }
}

TEST_CASE("operands resolve to their declared bits", "[assembler]") {
  const Program p = assemble(with_triangle("  mov s[11:4], z[7]\n"
                                           "  add s, -3\n"
                                           "  mov red, 0x1F\n"
                                           "  mov green, ambient\n"),
                             "ops.pp5", AssemblerOptions{});
  const auto& code = p.procedure(Procedure::triangle).code;
  REQUIRE(code.size() == 5);
  const int s_lo = p.find_field("s")->lo;
  // A slice is unsigned even of a signed field; the whole field keeps its signedness.
  CHECK(code[1].operands[0].field.lo == s_lo + 4);
  CHECK(code[1].operands[0].field.width == 8);
  CHECK_FALSE(code[1].operands[0].field.is_signed);
  CHECK(code[1].operands[1].field.lo == 7);
  CHECK(code[1].operands[1].field.width == 1);
  CHECK(code[2].operands[0].field.is_signed);
  CHECK(code[2].operands[1].kind == Operand::Kind::literal);
  CHECK(code[2].operands[1].literal == -3);
  CHECK(code[3].operands[1].literal == 31);
  CHECK(code[4].operands[1].kind == Operand::Kind::parameter);
  CHECK(code[4].operands[1].index == static_cast<int>(Parameter::ambient));
  CHECK(code[4].line == 12);
}

TEST_CASE("errors name the file, the line and what was expected", "[assembler]") {
  SECTION("unknown instruction") {
    check_error_here(with_triangle("  frob z ; HERE\n"), "unknown instruction 'frob'");
  }
  SECTION("wrong operand count") {
    check_error_here(with_triangle("  mov z ; HERE\n"), "'mov' takes 2 operands");
    check_error_here(with_triangle("  add z, 1, 2 ; HERE\n"), "got 3");
    check_error_here(with_triangle("  eall z ; HERE\n"), "'eall' takes 0 operands");
    check_error_here(with_triangle("  mov z, ; HERE\n"), "'mov' takes 2 operands");
    check_error_here(with_triangle("  mov , z ; HERE\n"), "operand 1 is empty");
  }
  SECTION("undeclared field") {
    check_error_here(with_triangle("  mov q, 1 ; HERE\n"), "must be a declared field, got 'q'");
    check_error_here(
        with_triangle("  mov z, q ; HERE\n"),
        "must be a field, a constant expression, an integer or a frame parameter, got 'q'");
    check_error_here(with_triangle("  mul z, s, 3 ; HERE\n"), "must be a declared field, got '3'");
    check_error_here(with_triangle("  mac z, s, red ; HERE\n"),
                     "must be an integer or a frame parameter, got 'red'");
  }
  SECTION("bad slice") {
    check_error_here(with_triangle("  mov z[24:0], 1 ; HERE\n"), "outside field 'z' of 24 bits");
    check_error_here(with_triangle("  mov z[24], 1 ; HERE\n"), "outside field 'z' of 24 bits");
    check_error_here(with_triangle("  mov z[3:5], 1 ; HERE\n"), "outside field 'z'");
    check_error_here(with_triangle("  mov z[a:0], 1 ; HERE\n"), "integer bounds");
    check_error_here(with_triangle("  mov z[3:], 1 ; HERE\n"), "integer bounds");
    check_error_here(with_triangle("  mov z[3:0, 1 ; HERE\n"), "expected NAME[hi:lo]");
  }
  SECTION("expression outside proc triangle") {
    const std::string clear = "proc clear\n  qload z, depth ; HERE\nend\n";
    check_error_here(
        with_triangle("", clear),
        "expression 'depth' is only available in procedure 'triangle', 'sphere', 'parity', "
        "'surface', 'sphere_surface' or 'sphere_parity'");
    check_error_here(with_triangle("  qload z, bogus ; HERE\n"),
                     "'bogus' is not an expression the GP supplies");
  }
  SECTION("conditions") {
    check_error_here(with_triangle("  qtest edge0 ; HERE\n"), "'qtest' needs a condition");
    check_error_here(with_triangle("  cmp z, 1 ; HERE\n"), "'cmp' needs a condition");
    check_error_here(with_triangle("  qtest.xx edge0 ; HERE\n"), "unknown condition '.xx'");
    check_error_here(with_triangle("  mov.eq z, 1 ; HERE\n"), "'mov' takes no condition");
  }
  SECTION("enable stack") {
    check_error_here(with_triangle("  epop ; HERE\n"), "epop without a matching epush");
    check_error_here(with_triangle("  eelse ; HERE\n"), "eelse outside an epush/epop pair");
    check_error_here(with_triangle("  epush\n  epop\n  eelse ; HERE\n"), "eelse outside");
    const std::string unclosed = with_triangle("  epush\n  epush\n  epop\n");
    check_error_at(unclosed, line_count(unclosed), "ends with 1 unmatched epush");

    AssemblerOptions shallow;
    shallow.enable_stack_depth = 2;
    check_error_here(with_triangle("  epush\n  epush\n  epush ; HERE\n  epop\n  epop\n  epop\n"),
                     "epush nests 3 deep; the enable stack holds 2", shallow);
    std::string deepest;
    for (int k = 0; k < 8; ++k) deepest += "  epush\n";
    for (int k = 0; k < 8; ++k) deepest += "  epop\n";
    CHECK_NOTHROW(assemble(with_triangle(deepest), "ok.pp5", AssemblerOptions{}));
    std::string too_deep;
    for (int k = 0; k < 8; ++k) too_deep += "  epush\n";
    too_deep += "  epush ; HERE\n";
    for (int k = 0; k < 9; ++k) too_deep += "  epop\n";
    check_error_here(with_triangle(too_deep), "epush nests 9 deep; the enable stack holds 8");
  }
  SECTION("duplicates") {
    check_error_here("field a 8\nfield a 4 ; HERE\n" + with_triangle(""),
                     "field 'a' is declared twice");
    check_error_here(with_triangle("", "proc shade\nend\nproc shade ; HERE\nend\n"),
                     "procedure 'shade' is defined twice");
    check_error_here("output red red red ; HERE\n" + with_triangle(""), "not declared");
    check_error_here(with_triangle("") + "output red green blue ; HERE\n", "'output' given twice");
  }
  SECTION("declarations") {
    check_error_here("field a ; HERE\n" + with_triangle(""),
                     "expected 'field NAME WIDTH [signed] [cold]'");
    check_error_here("field a 0 ; HERE\n" + with_triangle(""), "from 1 to 64");
    check_error_here("field a 65 ; HERE\n" + with_triangle(""), "from 1 to 64");
    check_error_here("field a 8 unsigned ; HERE\n" + with_triangle(""), "expected 'signed'");
    check_error_here("field 9a 8 ; HERE\n" + with_triangle(""), "not a valid field name");
    check_error_here("field ambient 8 ; HERE\n" + with_triangle(""), "frame parameter");
    check_error_here("option fast ; HERE\n" + with_triangle(""), "expected 'option spill'");
    check_error_here(with_triangle("", "proc draw ; HERE\nend\n"), "unknown procedure 'draw'");
    check_error_here(with_triangle("  field t 8 ; HERE\n"), "before the procedures");
    check_error_here("end ; HERE\n" + with_triangle(""), "'end' outside a procedure");
    check_error_here("mov z, 1 ; HERE\n" + with_triangle(""), "outside a procedure");
  }
  SECTION("missing 'end'") {
    check_error_here(with_triangle("", "proc clear\n  eall\nproc shade ; HERE\nend\n"),
                     "'proc' inside procedure 'clear': missing 'end'");
    const std::string unterminated =
        "field red 8\nfield green 8\nfield blue 8\n"
        "output red green blue\nproc triangle\n  eall\n\n";
    check_error_at(unterminated, 7, "procedure 'triangle' has no 'end'");
  }
  SECTION("missing triangle or output") {
    const std::string no_triangle =
        "field red 8\nfield green 8\nfield blue 8\noutput red green blue\nproc clear\nend\n";
    const std::string message = assembly_error(no_triangle);
    CHECK(message.rfind("bad.pp5:", 0) == 0);
    CHECK(message.find("no 'proc triangle'") != std::string::npos);
    const std::string no_output = "field red 8\nfield green 8\nfield blue 8\nproc triangle\nend\n";
    const std::string message2 = assembly_error(no_output);
    CHECK(message2.rfind("bad.pp5:", 0) == 0);
    CHECK(message2.find("no 'output RED GREEN BLUE'") != std::string::npos);
  }
  SECTION("output field not 8 bits") {
    check_error_here(
        "field red 8\nfield green 9\nfield blue 8\noutput red green blue ; HERE\n"
        "proc triangle\nend\n",
        "output field 'green' must be 8 bits wide (it is 9)");
  }
  SECTION("mul and mac destinations must not overlap a source") {
    check_error_here(with_triangle("  mul s, s[7:0], z[7:0] ; HERE\n"),
                     "'mul': the destination must not overlap a source");
    check_error_here(with_triangle("  mul z[15:8], red, z[8:1] ; HERE\n"),
                     "'mul': the destination must not overlap a source");
    check_error_here(with_triangle("  mac s[15:8], s[8:1], 3 ; HERE\n"), "'mac'");
    CHECK_NOTHROW(assemble(with_triangle("  mul z[23:16], z[7:0], z[15:8]\n"
                                         "  mac s[15:8], s[7:0], -3\n"),
                           "ok.pp5", AssemblerOptions{}));
  }
  SECTION("overlapping source at a different alignment") {
    check_error_here(with_triangle("  add z[15:0], z[23:8] ; HERE\n"),
                     "'add': a source overlapping the destination must start at the same bit");
    check_error_here(with_triangle("  mov z[7:1], z[6:0] ; HERE\n"), "'mov'");
    CHECK_NOTHROW(assemble(with_triangle("  add z, z[7:0]\n  xor z[15:8], z[15:8]\n"
                                         "  mov z[7:0], z[23:16]\n"),
                           "ok.pp5", AssemblerOptions{}));
  }
}

TEST_CASE("a program larger than pixel memory is rejected unless it may spill", "[assembler]") {
  const std::string with_option = read_text(kSpillProgram);
  std::string without_option = with_option;
  const auto at = without_option.find("option spill\n");
  REQUIRE(at != std::string::npos);
  without_option.erase(at, std::string("option spill\n").size());

  const std::string message = assembly_error(without_option);
  INFO(message);
  CHECK(message.rfind("bad.pp5: the fields need 225 bits but pixel memory has 208", 0) == 0);
  for (const char* name :
       {"red", "green", "blue", "seed", "acc", "prod", "k", "s1", "s2", "s3", "flag"}) {
    CHECK(message.find(std::string("\n  ") + name + " ") != std::string::npos);
  }
  CHECK(message.find("option spill") != std::string::npos);

  // Without the option, more memory is the only way; then nothing moves.
  const Program roomy = assemble(without_option, "roomy", options_with_memory(225));
  CHECK(roomy.bits_used() == 225);
  CHECK(roomy.staging_bits == 0);
}

TEST_CASE("spilled fields are bracketed by backing-store transfers", "[assembler]") {
  const std::string source = read_text(kSpillProgram);
  const Program p = assemble(source, "spill.pp5", AssemblerOptions{});
  CHECK(p.spill_allowed);

  // The resident fields keep contiguous bits in declaration order; spilled ones get disjoint
  // blocks.
  int lo = 0;
  int resident = 0;
  std::set<std::pair<int, int>> blocks;  // [first, end) of every spilled field
  std::set<std::string> spilled_names;
  for (std::size_t k = 0; k < p.fields.size(); ++k) {
    const FieldDecl& f = p.fields[k];
    INFO("field " << f.name);
    if (f.spilled) {
      spilled_names.insert(f.name);
      CHECK(f.block >= 0);
      const int n = (f.width + 31) / 32;
      CHECK((f.block + n) * 32 <= 4096);
      for (const auto& [b, e] : blocks) CHECK((f.block >= e || f.block + n <= b));
      blocks.insert({f.block, f.block + n});
    } else {
      CHECK(f.lo == lo);
      lo += f.width;
      resident += f.width;
    }
  }
  CHECK(p.resident_bits == resident);
  CHECK(p.staging_bits > 0);
  CHECK(p.bits_used() == p.resident_bits + p.staging_bits);
  CHECK(p.bits_used() <= p.memory_bits);
  // The cold fields spill first (k, s1, s2, s3 and flag), the least used of them first
  // (flag 514, s1 770, k 771, s2 772, s3 more: static uses weighted by procedure frequency),
  // and spilling stops as soon as the rest fits: 225 - 1 - 24 - 32 - 32 = 136 resident bits
  // and 64 staging bits (its instructions use at most two spilled fields).
  CHECK(spilled_names == std::set<std::string>{"flag", "s2", "k", "s1"});
  CHECK(p.resident_bits == 136);
  CHECK(p.staging_bits == 64);
  // The listing says why.
  CHECK(listing(p, TimingParams{}, ParameterValues{}, "no scene").find("spilled s1: marked cold") !=
        std::string::npos);

  int total_transfers = 0;
  for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
    const ProcedureCode& code = p.procedures[proc];
    INFO("proc " << kProcedureNames[proc]);
    int inserted = 0;
    for (const Instruction& ins : code.code) inserted += ins.line == 0;
    CHECK(code.spill_transfers == inserted);
    total_transfers += inserted;

    for (std::size_t at = 0; at < code.code.size(); ++at) {
      const Instruction& ins = code.code[at];
      if (ins.line == 0) continue;
      INFO("line " << ins.line << ": " << disassemble(ins));
      const InstructionInfo& info = instruction_info(ins.op);
      // The distinct spilled fields this instruction names, in operand order.
      std::vector<const FieldDecl*> spilled;
      for (int k = 0; info.operands[k]; ++k) {
        if (ins.operands[k].kind != Operand::Kind::field) continue;
        const FieldDecl* f = p.find_field(field_name_of(ins.operands[k]));
        REQUIRE(f);
        if (!f->spilled) {
          CHECK(ins.operands[k].field.lo >= f->lo);
          CHECK(ins.operands[k].field.lo + ins.operands[k].field.width <= f->lo + f->width);
          continue;
        }
        if (std::find(spilled.begin(), spilled.end(), f) == spilled.end()) spilled.push_back(f);
      }
      // bsld of each, immediately before, into a staging slot past the resident fields.
      REQUIRE(at >= spilled.size());
      for (std::size_t j = 0; j < spilled.size(); ++j) {
        const Instruction& load = code.code[at - spilled.size() + j];
        const FieldDecl* f = spilled[j];
        CHECK(load.line == 0);
        CHECK(load.op == Opcode::bsld);
        CHECK(load.operands[0].text == f->name);
        CHECK(load.operands[0].field.width == f->width);
        CHECK(load.operands[0].field.lo >= p.resident_bits);
        CHECK(load.operands[0].field.lo + f->width <= p.bits_used());
        CHECK(load.operands[1].literal == f->block);
        // The instruction's operands of this field point into its slot.
        for (int k = 0; info.operands[k]; ++k) {
          if (ins.operands[k].kind != Operand::Kind::field ||
              field_name_of(ins.operands[k]) != f->name) {
            continue;
          }
          CHECK(ins.operands[k].field.lo >= load.operands[0].field.lo);
          CHECK(ins.operands[k].field.lo + ins.operands[k].field.width <=
                load.operands[0].field.lo + f->width);
        }
      }
      if (at > spilled.size()) CHECK(code.code[at - spilled.size() - 1].op != Opcode::bsld);
      // bsst after it exactly when it writes a spilled field.
      const bool writes_spilled = info.operands[0] == 'F' &&
                                  ins.operands[0].kind == Operand::Kind::field &&
                                  p.find_field(field_name_of(ins.operands[0]))->spilled;
      const bool next_is_store = at + 1 < code.code.size() && code.code[at + 1].line == 0 &&
                                 code.code[at + 1].op == Opcode::bsst;
      CHECK(next_is_store == writes_spilled);
      if (writes_spilled) {
        const Instruction& store = code.code[at + 1];
        const FieldDecl* f = p.find_field(field_name_of(ins.operands[0]));
        CHECK(store.operands[0].text == f->name);
        CHECK(store.operands[0].field.width == f->width);
        CHECK(store.operands[1].literal == f->block);
        const auto j = std::find(spilled.begin(), spilled.end(), f) - spilled.begin();
        CHECK(store.operands[0].field.lo ==
              code.code[at - spilled.size() + j].operands[0].field.lo);
      }
    }
  }
  CHECK(total_transfers > 10);
}

TEST_CASE("a spilled program computes the same pixels as a resident one", "[assembler]") {
  const std::string source = read_text(kSpillProgram);
  const Program spilled = assemble(source, "spill.pp5", AssemblerOptions{});
  const Program resident = assemble(source, "spill.pp5", options_with_memory(512));
  REQUIRE(spilled.staging_bits > 0);
  REQUIRE(resident.staging_bits == 0);
  for (const FieldDecl& f : resident.fields) CHECK_FALSE(f.spilled);

  std::uint64_t spilled_cycles = 0;
  std::uint64_t resident_cycles = 0;
  const auto a = run_spill_test(spilled, 208, spilled_cycles);
  const auto b = run_spill_test(resident, 512, resident_cycles);
  REQUIRE(a.size() == b.size());
  CHECK(a == b);

  // The test means something only if the pixels differ from each other.
  std::set<std::uint32_t> colours;
  for (std::size_t i = 0; i < b.size(); i += 3) {
    colours.insert(b[i] | (b[i + 1] << 8) | (b[i + 2] << 16));
  }
  CHECK(colours.size() > 100);

  // Spilling costs exactly its transfers (triangle runs twice).
  const TimingParams timing;
  const OwnedValues values = spill_test_values(0);
  std::uint64_t transfer_cycles = 0;
  for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
    const int runs = proc == static_cast<int>(Procedure::triangle) ? 2 : 1;
    for (const Instruction& ins : spilled.procedures[proc].code) {
      if (ins.line == 0) transfer_cycles += runs * instruction_cost(ins, timing, values).count;
    }
  }
  CHECK(transfer_cycles > 0);
  CHECK(spilled_cycles == resident_cycles + transfer_cycles);
}

TEST_CASE("spilling fails cleanly when even spilling cannot fit", "[assembler]") {
  const std::string source = read_text(kSpillProgram);
  // Two spilled fields of one 32-bit block each need 64 staging bits: more than 40.
  const std::string tiny = assembly_error(source, options_with_memory(40));
  CHECK(tiny.rfind("bad.pp5: even with every field but the outputs spilled", 0) == 0);
  AssemblerOptions no_store;
  no_store.backing_store_bits = 64;
  const std::string full = assembly_error(source, no_store);
  CHECK(full.find("backing-store blocks; the store has 2") != std::string::npos);
}

TEST_CASE("without cold fields the least used spill first, weighted by procedure frequency",
          "[assembler]") {
  // Uses, counted by hand: a 1 in triangle (256); b 3 in shade (3); c 2 in clear and 1 in
  // shade (3); d 2 in triangle (512). 216 bits: two 32-bit fields must go, with one staging
  // block: c and b (equal weights: the last declared first), though a and d come first and
  // last in the declarations.
  const std::string source =
      "option spill\nfield a 32\nfield b 32\nfield c 32\nfield red 8\nfield green 8\n"
      "field blue 8\nfield d 32\nfield e 64\noutput red green blue\n"
      "proc clear\n  mov c, 0\n  mov c, 1\nend\n"
      "proc triangle\n  mov a, 1\n  mov d, 1\n  add d, 2\n  mov e, 9\nend\n"
      "proc shade\n  mov b, 1\n  add b, 2\n  add red, b[7:0]\n  add green, c[7:0]\nend\n";
  const Program p = assemble(source, "weights.pp5", AssemblerOptions{});
  CHECK(p.find_field("a")->weight == 256);
  CHECK(p.find_field("b")->weight == 3);
  CHECK(p.find_field("c")->weight == 3);
  CHECK(p.find_field("d")->weight == 512);
  CHECK(p.find_field("c")->spilled);
  CHECK(p.find_field("b")->spilled);
  for (const char* name : {"a", "d", "e", "red", "green", "blue"})
    CHECK_FALSE(p.find_field(name)->spilled);
  CHECK(p.bits_used() == 216 - 64 + 32);
  CHECK(listing(p, TimingParams{}, ParameterValues{}, "no scene")
            .find("spilled c: among the least used (weighted uses 3 = 2 in clear x 1 + 1 in shade "
                  "x 1)") != std::string::npos);
}

TEST_CASE("output fields never spill, cold fields spill first", "[assembler]") {
  // The outputs are declared last, where spilling used to start; a marked field goes first
  // even though it is used more than the others.
  const std::string source =
      "option spill\nfield a 32 cold\nfield e 32 cold\nfield b 64\nfield c 64\nfield red 8\n"
      "field green 8\nfield blue 8\noutput red green blue\nproc triangle\n  mov a, 1\n"
      "  add a, 2\n  mov e, 1\n  mov b, 1\n  mov c, 1\nend\n";
  const Program p = assemble(source, "cold.pp5", AssemblerOptions{});
  CHECK(p.find_field("a")->spilled);
  CHECK(p.find_field("e")->spilled);
  CHECK_FALSE(p.find_field("b")->spilled);
  CHECK_FALSE(p.find_field("c")->spilled);
  for (const char* name : {"red", "green", "blue"}) CHECK_FALSE(p.find_field(name)->spilled);
  const std::string text = listing(p, TimingParams{}, ParameterValues{}, "no scene");
  CHECK(text.find("spilled a: marked cold (weighted uses 512 = 2 in triangle x 256)") !=
        std::string::npos);
  // Without room for the outputs themselves, the error says so.
  CHECK(assembly_error(source, options_with_memory(20))
            .rfind("bad.pp5: even with every field but the outputs spilled", 0) == 0);
}

TEST_CASE("cmp may compare overlapping slices of one field", "[assembler]") {
  // cmp writes no field, so the alignment rule for a destination and its sources does not
  // apply to it.
  CHECK_NOTHROW(assemble(with_triangle("  cmp.eq z[7:0], z[8:1]\n"), "ok", AssemblerOptions{}));
}

TEST_CASE("backing-store block numbers past the end are rejected", "[assembler]") {
  // 4096 bits of 32-bit blocks: blocks 0..127.
  CHECK_NOTHROW(assemble(with_triangle("  bsst z, 127\n  bsld z, 127\n"), "ok", {}));
  check_error_here(with_triangle("  bsst z, 128 ; HERE\n"),
                   "past the end of the store (128 blocks)");
  check_error_here(with_triangle("  bsld z, 4000 ; HERE\n"), "past the end");
  check_error_here(with_triangle("  bsld z, -1 ; HERE\n"), "must be a backing-store block number");
  check_error_here(with_triangle("  bsld z, light_x ; HERE\n"),
                   "must be a backing-store block number");
}

TEST_CASE("a multi-block transfer must fit before the end of the store", "[assembler]") {
  // A 40-bit field takes two 32-bit blocks, so it cannot start at the last block 127.
  const std::string source = "field w 40\n" + with_triangle("  bsst w, 127 ; HERE\n");
  check_error_here(source, "past the end");
}

TEST_CASE("spilled fields do not share blocks with explicit transfers", "[assembler]") {
  // With 8-bit blocks, `bsst acc, 0` of the 48-bit acc occupies blocks 0..5; the spilled
  // fields must start after them.
  std::string source = read_text(kSpillProgram);
  const std::string anchor = "  qload seed, red";
  const auto at = source.find(anchor);
  REQUIRE(at != std::string::npos);
  source.insert(at, "  bsst acc, 0\n");
  AssemblerOptions small_blocks;
  small_blocks.block_bits = 8;
  const Program p = assemble(source, "spill.pp5", small_blocks);
  int spilled = 0;
  for (const FieldDecl& f : p.fields) {
    if (!f.spilled) continue;
    ++spilled;
    INFO("field " << f.name << " at block " << f.block);
    CHECK(f.block >= 6);
  }
  CHECK(spilled >= 2);
}

TEST_CASE("the listing shows every field and instruction", "[assembler]") {
  for (const char* file : {"phong.pp5", "flat.pp5"}) {
    const Program p = assemble_file(test::kProgramsDir + file, AssemblerOptions{});
    const std::string text = listing(p, TimingParams{}, ParameterValues{}, "no scene");
    CHECK(text.find(p.name) != std::string::npos);
    for (const FieldDecl& f : p.fields) {
      CHECK(text.find("  " + f.name + " ") != std::string::npos);
    }
    for (const ProcedureCode& code : p.procedures) {
      for (const Instruction& ins : code.code) {
        INFO(disassemble(ins));
        CHECK(text.find(disassemble(ins)) != std::string::npos);
      }
    }
  }
  const Program spilled = assemble(read_text(kSpillProgram), "spill.pp5", AssemblerOptions{});
  const std::string text = listing(spilled, TimingParams{}, ParameterValues{}, "no scene");
  CHECK(text.find("spill staging") != std::string::npos);
  CHECK(text.find("backing store block") != std::string::npos);
  CHECK(text.find("(spill)") != std::string::npos);
}

TEST_CASE("scratch fields share bits unless one procedure needs both at once", "[assembler]") {
  const std::string source =
      "field z 24\nfield red 8\nfield green 8\nfield blue 8\nfield keep 16\n"
      "scratch t 20 signed\nscratch u 12\nscratch v 12\nscratch s 16\n"
      "output red green blue\n"
      "proc triangle\n  qload t, depth\n  mov u, t[11:0]\n  add u, 1\n  mov keep, u\n"
      "  mov v, 3\n  add v, keep[11:0]\n  mov z, v\nend\n"
      "proc shade\n  mov s, keep\n  add s, z[15:0]\n  mov red, s[7:0]\nend\n";
  const Program p = assemble(source, "share.pp5", AssemblerOptions{});
  const FieldDecl& t = *p.find_field("t");
  const FieldDecl& u = *p.find_field("u");
  const FieldDecl& v = *p.find_field("v");
  const FieldDecl& s = *p.find_field("s");
  auto overlap = [](const FieldDecl& a, const FieldDecl& b) {
    return a.lo < b.lo + b.width && b.lo < a.lo + a.width;
  };
  // The fields keep bits 0..63; t and u are live together (u is written from t), v starts
  // after both have died, and s (shade) meets none of them; shade still needs keep and z, so
  // s goes past the fields.
  CHECK(p.find_field("keep")->lo == 48);
  CHECK(t.lo == 64);
  CHECK_FALSE(overlap(t, u));
  CHECK(overlap(v, t));
  CHECK(v.lo == 64);
  CHECK(s.lo == 64);
  CHECK(p.overlay_bits == 32);
  CHECK(p.resident_bits == 96);
  CHECK(p.bits_used() == 96);
  for (const FieldDecl& f : p.fields) CHECK(f.scratch == (f.name.size() == 1 && f.name != "z"));
  const std::string text = listing(p, TimingParams{}, ParameterValues{}, "no scene");
  CHECK(text.find("overlay (triangle)") != std::string::npos);
  CHECK(text.find("scratch: 60 bits of scratch fields in 32 bits past the fields") !=
        std::string::npos);
}

TEST_CASE("scratch fields reuse the bits of fields dead in shade", "[assembler]") {
  // In shade, z and n are read first and never again, and red is an output: a scratch field
  // written after their last use takes their bits; an output's bits are never taken.
  const std::string source =
      "field z 24\nfield n 8\nfield red 8\nfield green 8\nfield blue 8\n"
      "scratch a 24\nscratch b 8\n"
      "output red green blue\n"
      "proc triangle\n  qload z, depth\n  qload n, nx\nend\n"
      "proc shade\n  mov red, n\n  add red, z[7:0]\n  mov a, 7\n  add a, a\n  mov b, a[7:0]\n"
      "  add green, b\nend\n";
  const Program p = assemble(source, "dead.pp5", AssemblerOptions{});
  CHECK(p.find_field("a")->lo == 0);   // z's bits
  CHECK(p.find_field("b")->lo == 24);  // n's bits (a is live while b is written)
  CHECK(p.overlay_bits == 0);
  CHECK(p.bits_used() == 56);
}

TEST_CASE("a scratch field read before it is written in a procedure is refused", "[assembler]") {
  const std::string head =
      "field z 24\nfield red 8\nfield green 8\nfield blue 8\n"
      "scratch t 16\noutput red green blue\n";
  // Read outright, read by a read-modify-write, and a bit range never written.
  check_error_here(head + "proc triangle\n  mov z, t ; HERE\nend\n",
                   "scratch field 't' is read in procedure 'triangle' before it is written there");
  check_error_here(head + "proc triangle\n  mov t, 1\nend\nproc shade\n  add t, 1 ; HERE\nend\n",
                   "scratch field 't' is read in procedure 'shade' before it is written there");
  check_error_here(head + "proc triangle\n  mov t[7:0], 1\n  mov z, t[8:0] ; HERE\nend\n",
                   "scratch field 't' is read in procedure 'triangle'");
  // Written in one procedure and read in another: the value does not survive.
  check_error_here(head + "proc clear\n  mov t, 5\nend\nproc triangle\n  mov z, t ; HERE\nend\n",
                   "scratch keeps no value between procedures");
  // Output fields are read by the frame buffer after shade: they cannot be scratch.
  check_error_here(
      "field z 24\nscratch red 8 ; HERE\nfield green 8\nfield blue 8\n"
      "output red green blue\nproc triangle\n  mov red, 1\nend\n",
      "output field 'red' is scratch");
  // A scratch field does not spill, so 'cold' is refused on it.
  check_error_here("scratch t 8 cold ; HERE\n", "a scratch field never spills");
  CHECK_NOTHROW(assemble(head + "proc triangle\n  mov t, 1\n  add t, 2\n  mov z, t\nend\n",
                         "ok.pp5", AssemblerOptions{}));
}

namespace {

// Each procedure's cycles as `pp5sim asm` lists them: the sum of its instruction lines'
// "; N cycles" (and the "total" line must say the same).
std::map<std::string, std::uint64_t> listed_procedure_cycles(const std::string& text) {
  std::map<std::string, std::uint64_t> cycles;
  std::istringstream in(text);
  std::string line, current;
  std::uint64_t sum = 0;
  const std::regex proc_line(R"(^proc (\w+)$)");
  const std::regex cost_line(R"(; +(\d+) cycles)");
  const std::regex total_line(R"(^  total (\d+) cycles$)");
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_match(line, m, proc_line)) {
      current = m[1];
      sum = 0;
    } else if (!current.empty() && std::regex_match(line, m, total_line)) {
      CHECK(std::stoull(m[1]) == sum);
      cycles[current] = sum;
      current.clear();
    } else if (!current.empty() && std::regex_search(line, m, cost_line)) {
      sum += std::stoull(m[1]);
    }
  }
  return cycles;
}

// What the simulator charges each packet, summed from the cost of each instruction it runs.
class PacketCycles : public BoardObserver {
 public:
  struct Charged {
    Procedure procedure;
    int light;
    std::size_t instructions;  // the procedure's length, to check it is the one named
    std::uint64_t cycles;
  };
  std::vector<Charged> packets;
  void begin_packet(const PacketContext& packet, const ProcedureCode& procedure,
                    const RendererBoard&) override {
    // A packet of a group the pass does not draw runs no procedure: nothing to price.
    skipping_ = !procedure.defined;
    if (!skipping_) packets.push_back({packet.procedure, packet.light, procedure.code.size(), 0});
  }
  void after_instruction(int, const Instruction&, ArrayCycles cost, const RendererBoard&) override {
    if (!skipping_) packets.back().cycles += cost.count;
  }
  void end_region(int, const RendererBoard&) override {}

 private:
  bool skipping_ = false;
};

}  // namespace

TEST_CASE("the listing prices every procedure of every shipped program as the simulator charges",
          "[assembler][listing]") {
  // Under either multiply microcode: the listing and the Renderer take it from the same key.
  const std::string microcode = GENERATE(as<std::string>{}, "full", "window");
  INFO("renderer.multiply_microcode=" << microcode);
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "gp.count=1", "renderer.count=1",
              "renderer.multiply_microcode=" + microcode});
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(test::kProgramsDir)) {
    if (entry.path().extension() == ".pp5") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  REQUIRE(names.size() >= 20);
  int compared = 0;
  for (const std::string& name : names) {
    INFO("program " << name);
    const Program program = test::load_program(name, config);
    // Scenes that run the program's procedures: a CSG expression for those that draw one
    // (one with quadric spheres for those that draw spheres), solids for the parity programs,
    // sphere primitives for `sphere`, and a plain scene for the rest.
    std::vector<Scene> scenes;
    auto defines = [&](Procedure p) { return program.procedure(p).defined; };
    if (defines(Procedure::sphere_surface))
      scenes.push_back(make_parity_scene("box-minus-quadric"));
    if (defines(Procedure::surface)) scenes.push_back(make_parity_scene("box-minus-ball"));
    if (defines(Procedure::parity) && !defines(Procedure::surface)) {
      scenes.push_back(
          make_parity_scene(program.find_field("lo") ? "boxes-overlap" : "plane-sphere"));
    }
    if (defines(Procedure::sphere)) scenes.push_back(make_builtin_scene("spheres-and-triangles"));
    if (defines(Procedure::triangle)) scenes.push_back(make_builtin_scene("crossing-quads"));
    std::set<std::string> checked;
    for (const Scene& scene : scenes) {
      INFO("scene " << scene.name);
      const auto parameters = GeometryEngine(geometry_params(config), scene).frame_parameters();
      const auto listed = listed_procedure_cycles(
          listing(program, timing_params(config), parameters, "scene " + scene.name));
      PacketCycles charged;
      simulate_frame(config, scene, program, 1, [&](int) -> BoardObserver* { return &charged; });
      for (const auto& packet : charged.packets) {
        if (packet.light > 0) continue;  // the listing prices the first light's parameters
        const std::string proc = kProcedureNames[static_cast<int>(packet.procedure)];
        INFO("procedure " << proc);
        REQUIRE(listed.count(proc) == 1);
        REQUIRE(program.procedure(packet.procedure).code.size() == packet.instructions);
        CHECK(listed.at(proc) == packet.cycles);
        checked.insert(proc);
        ++compared;
      }
    }
    // Every procedure the program defines was charged and compared in some scene.
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      if (!program.procedures[p].defined) continue;
      INFO("procedure " << kProcedureNames[p]);
      CHECK(checked.count(kProcedureNames[p]) == 1);
    }
  }
  CHECK(compared > 0);
}

TEST_CASE("a constant expression is broadcast as an operand, priced as a literal", "[assembler]") {
  const std::string head =
      "field z 24\nfield a 16 signed\nfield red 8\nfield green 8\nfield blue 8\n"
      "output red green blue\n";
  const Program p = assemble(
      head + "proc triangle\n  mov a, slope_x\n  sub a, slope_y\n  cmp.lt a, flat_red\nend\n",
      "ok.pp5", AssemblerOptions{});
  const auto& code = p.procedure(Procedure::triangle).code;
  REQUIRE(code.size() == 3);
  CHECK(code[0].operands[1].kind == Operand::Kind::expression);
  CHECK(expression_names(p.procedure(Procedure::triangle).expressions) ==
        std::set<std::string>{"slope_x", "slope_y", "flat_red"});
  // A V operand's cost is the destination's width, whatever it broadcasts.
  OwnedValues values;
  values.expressions[static_cast<int>(Expression::slope_x)].F = -37 * 4096 + 5;
  CHECK(instruction_cost(code[0], TimingParams{}, values).count == 16);
  CHECK(broadcast_value(code[0].operands[1], values, 12) == -37);  // floor, as qload takes it
  // An interpolated expression must go through the evaluator; none outside a primitive's
  // procedures; and no constant expression where the cost would depend on its value (mac).
  check_error_here(head + "proc triangle\n  mov z, depth ; HERE\nend\n",
                   "expression 'depth' varies across the primitive: load it with qload");
  check_error_here(head + "proc shade\n  mov a, slope_x ; HERE\nend\n",
                   "expression 'slope_x' is only available in procedure 'triangle'");
  check_error_here(head + "proc triangle\n  mac z, a, slope_x ; HERE\nend\n",
                   "must be an integer or a frame parameter, got 'slope_x'");
}
