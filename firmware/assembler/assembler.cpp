#include "firmware/assembler/assembler.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>

#include "common/escape.hpp"
#include "common/read_file.hpp"

namespace pp5 {

namespace {

// A field operand before layout: which declared field, and which of its bits.
struct FieldUse {
  int field = -1;
  int offset = 0;
  int width = 0;
  bool whole = true;
};

struct ParsedInstruction {
  Instruction ins;
  std::array<FieldUse, 3> uses{};
};

std::string trim(const std::string& s) {
  std::size_t b = 0;
  std::size_t e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> split_words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

bool parse_integer(const std::string& s, std::int64_t& out) {
  if (s.empty()) return false;
  try {
    std::size_t used = 0;
    const bool neg = s[0] == '-';
    const std::string body = neg ? s.substr(1) : s;
    if (body.empty() || !std::isdigit(static_cast<unsigned char>(body[0]))) return false;
    // Decimal, or hexadecimal after 0x; a leading zero does not mean octal.
    const bool hex = body.size() > 2 && body[0] == '0' && (body[1] == 'x' || body[1] == 'X');
    const unsigned long long v = std::stoull(body, &used, hex ? 16 : 10);
    if (used != body.size()) return false;
    if (v > static_cast<unsigned long long>(INT64_MAX)) return false;
    out = neg ? -static_cast<std::int64_t>(v) : static_cast<std::int64_t>(v);
    return true;
  } catch (...) {
    return false;
  }
}

class Assembler {
 public:
  Assembler(const std::string& name, const AssemblerOptions& options) : options_(options) {
    program_.name = name;
    program_.memory_bits = options.memory_bits;
  }

  Program run(const std::string& source) {
    // A UTF-8 byte-order mark, as some editors write one, is not part of the program.
    const bool bom = source.compare(0, 3, "\xEF\xBB\xBF") == 0;
    std::istringstream in(bom ? source.substr(3) : source);
    std::string raw;
    int line = 0;
    while (std::getline(in, raw)) {
      ++line;
      line_ = line;
      const auto cut = raw.find_first_of(";#");
      const std::string text = trim(cut == std::string::npos ? raw : raw.substr(0, cut));
      if (!text.empty()) statement(text);
    }
    line_ = line;
    if (current_ >= 0) fail("procedure '{}' has no 'end'", kProcedureNames[current_]);
    finish();
    return program_;
  }

 private:
  bool accepted_statement_ = false;  // whether any statement has been read without error

  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) {
    // Words from the file are untrusted: escaped and cut short (common/escape.hpp), so that
    // a binary file or a 1 MB word prints as one readable line.
    throw AssemblyError(
        fmt::format("{}:{}: {}", escape_for_message(program_.name, 200), line_,
                    escape_for_message(fmt::format(f, std::forward<Args>(args)...), 300)));
  }

  void statement(const std::string& text) {
    statement_once(text);
    accepted_statement_ = true;
  }

  void statement_once(const std::string& text) {
    const auto words = split_words(text);
    const std::string& head = words[0];
    if (head == "field" || head == "scratch") return declare_field(words);
    if (head == "output") return declare_output(words);
    if (head == "option") return declare_option(words);
    if (head == "proc") return begin_procedure(words);
    if (head == "end") {
      if (current_ < 0) fail("'end' outside a procedure");
      if (depth_ != 0)
        fail("procedure '{}' ends with {} unmatched epush", kProcedureNames[current_], depth_);
      current_ = -1;
      return;
    }
    if (current_ < 0) {
      // A first statement whose first word is not even a name: the file is not a program (a
      // file named as firmware by mistake), and its first line is not printed back.
      const bool name_like =
          head.size() <= 32 &&
          (std::isalpha(static_cast<unsigned char>(head[0])) || head[0] == '_') &&
          std::all_of(head.begin(), head.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
          });
      if (!accepted_statement_ && !name_like) {
        fail(
            "not a firmware program: its first statement is not field, scratch, output, option "
            "or proc");
      }
      fail("'{}' outside a procedure: expected field, scratch, output, option or proc", head);
    }
    instruction(text);
  }

  // field NAME WIDTH [signed] [cold], or scratch NAME WIDTH [signed].
  void declare_field(const std::vector<std::string>& w) {
    const bool scratch = w[0] == "scratch";
    if (current_ >= 0) fail("{} declarations belong before the procedures", w[0]);
    if (w.size() < 3 || w.size() > 5) {
      fail(scratch ? "expected 'scratch NAME WIDTH [signed]'"
                   : "expected 'field NAME WIDTH [signed] [cold]'");
    }
    const std::string& name = w[1];
    if (!is_identifier(name)) fail("'{}' is not a valid field name", name);
    if (field_index(name) >= 0) fail("field '{}' is declared twice", name);
    if (parameter_index(name) >= 0) {
      // A 'V' operand could be either; expressions are told apart by operand position.
      fail("field name '{}' is a frame parameter's name", name);
    }
    std::int64_t width = 0;
    if (!parse_integer(w[2], width) || width < 1 || width > kMaxFieldBits) {
      fail("field width must be an integer from 1 to {} (got '{}')", kMaxFieldBits, w[2]);
    }
    FieldDecl decl{name, static_cast<int>(width), false, line_};
    decl.scratch = scratch;
    for (std::size_t k = 3; k < w.size(); ++k) {
      if (w[k] == "signed" && !decl.is_signed) {
        decl.is_signed = true;
      } else if (w[k] == "cold" && !scratch && !decl.cold) {
        decl.cold = true;
      } else if (w[k] == "cold" && scratch) {
        fail("a scratch field never spills: 'cold' is for fields");
      } else {
        fail("expected {} after the width, got '{}'", scratch ? "'signed'" : "'signed' or 'cold'",
             w[k]);
      }
    }
    field_by_name_.emplace(name, static_cast<int>(program_.fields.size()));
    program_.fields.push_back(decl);
  }

  void declare_output(const std::vector<std::string>& w) {
    if (have_output_) fail("'output' given twice");
    if (w.size() != 4) fail("expected 'output RED GREEN BLUE' (three 8-bit fields)");
    for (int k = 0; k < 3; ++k) {
      const int f = field_index(w[k + 1]);
      if (f < 0) fail("output field '{}' is not declared", w[k + 1]);
      if (program_.fields[f].width != 8) {
        fail("output field '{}' must be 8 bits wide (it is {})", w[k + 1],
             program_.fields[f].width);
      }
      output_fields_[k] = f;
    }
    have_output_ = true;
  }

  void declare_option(const std::vector<std::string>& w) {
    if (w.size() == 2 && w[1] == "spill") {
      program_.spill_allowed = true;
      return;
    }
    if (w.size() == 3 && w[1] == "passes") {
      std::int64_t n = 0;
      if (const int k = parameter_index(w[2]); k >= 0) {
        program_.passes_parameter = k;
        return;
      }
      if (!parse_integer(w[2], n) || n < 1 || n > kMaxPasses) {
        fail("option passes: expected an integer from 1 to {} or a frame parameter (got '{}')",
             kMaxPasses, w[2]);
      }
      program_.passes = static_cast<int>(n);
      return;
    }
    fail("unknown option: expected 'option spill' or 'option passes N'");
  }

  void begin_procedure(const std::vector<std::string>& w) {
    if (current_ >= 0)
      fail("'proc' inside procedure '{}': missing 'end'", kProcedureNames[current_]);
    if (w.size() != 2) fail("expected 'proc NAME'");
    const int p = procedure_index(w[1]);
    if (p < 0) fail("unknown procedure '{}': expected clear, triangle, pass, light or shade", w[1]);
    if (program_.procedures[p].defined) fail("procedure '{}' is defined twice", w[1]);
    program_.procedures[p].defined = true;
    program_.procedures[p].line = line_;
    current_ = p;
    depth_ = 0;
  }

  int field_index(const std::string& name) const {
    const auto it = field_by_name_.find(name);
    return it == field_by_name_.end() ? -1 : it->second;
  }

  // NAME, NAME[hi:lo] or NAME[bit].
  bool parse_field(const std::string& text, FieldUse& use) {
    const auto bracket = text.find('[');
    const std::string name = text.substr(0, bracket);
    const int f = field_index(name);
    if (f < 0) return false;
    const FieldDecl& decl = program_.fields[f];
    use = {f, 0, decl.width, true};
    if (bracket == std::string::npos) return true;
    if (text.back() != ']') fail("bad slice '{}': expected NAME[hi:lo]", text);
    const std::string inner = text.substr(bracket + 1, text.size() - bracket - 2);
    const auto colon = inner.find(':');
    std::int64_t hi = 0;
    std::int64_t lo = 0;
    if (!parse_integer(trim(inner.substr(0, colon)), hi) ||
        (colon != std::string::npos && !parse_integer(trim(inner.substr(colon + 1)), lo))) {
      fail("bad slice '{}': expected NAME[hi:lo] with integer bounds", text);
    }
    if (colon == std::string::npos) lo = hi;
    if (lo < 0 || hi < lo || hi >= decl.width) {
      fail("slice '{}' is outside field '{}' of {} bits", text, name, decl.width);
    }
    use = {f, static_cast<int>(lo), static_cast<int>(hi - lo + 1), false};
    return true;
  }

  void instruction(const std::string& text) {
    const auto space = text.find_first_of(" \t");
    std::string mnemonic = text.substr(0, space);
    const std::string rest = space == std::string::npos ? "" : trim(text.substr(space));
    std::string cond;
    if (const auto dot = mnemonic.find('.'); dot != std::string::npos) {
      cond = mnemonic.substr(dot + 1);
      mnemonic = mnemonic.substr(0, dot);
    }
    const InstructionInfo* info = find_instruction(mnemonic);
    if (!info) fail("unknown instruction '{}' (pp5sim isa lists them)", mnemonic);
    ParsedInstruction p;
    p.ins.op = info->op;
    p.ins.line = line_;
    if (info->conditional) {
      if (cond.empty())
        fail("'{}' needs a condition: {}.lt, .le, .eq, .ne, .ge or .gt", mnemonic, mnemonic);
      if (!parse_condition(cond, p.ins.condition)) {
        fail("unknown condition '.{}': expected lt, le, eq, ne, ge or gt", cond);
      }
    } else if (!cond.empty()) {
      fail("'{}' takes no condition", mnemonic);
    }
    std::vector<std::string> ops;
    if (!rest.empty()) {
      std::string item;
      std::istringstream in(rest);
      while (std::getline(in, item, ',')) ops.push_back(trim(item));
    }
    const std::string kinds = info->operands;
    if (ops.size() != kinds.size()) {
      fail("'{}' takes {} operand{} ({}), got {}", mnemonic, kinds.size(),
           kinds.size() == 1 ? "" : "s", info->syntax, ops.size());
    }
    ProcedureCode& proc = program_.procedures[current_];
    for (std::size_t k = 0; k < ops.size(); ++k) {
      operand(ops[k], kinds[k], p, static_cast<int>(k), proc, mnemonic);
    }
    check_aliasing(p, *info);
    check_literal_fits(p, *info);
    check_enable_nesting(info->op);
    parsed_[current_].push_back(p);
  }

  // Expressions come with a primitive's packet: only its kind's procedures see them.
  void require_primitive_procedure(const std::string& expression) {
    if (current_ != static_cast<int>(Procedure::triangle) &&
        current_ != static_cast<int>(Procedure::sphere) &&
        current_ != static_cast<int>(Procedure::parity) &&
        current_ != static_cast<int>(Procedure::surface) &&
        current_ != static_cast<int>(Procedure::sphere_surface) &&
        current_ != static_cast<int>(Procedure::sphere_parity)) {
      fail(
          "expression '{}' is only available in procedure 'triangle', 'sphere', 'parity', "
          "'surface', 'sphere_surface' or 'sphere_parity'",
          expression);
    }
  }

  void operand(const std::string& text, char kind, ParsedInstruction& p, int k, ProcedureCode& proc,
               const std::string& mnemonic) {
    Operand& o = p.ins.operands[k];
    o.text = text;
    if (text.empty()) fail("'{}': operand {} is empty", mnemonic, k + 1);
    FieldUse use;
    std::int64_t literal = 0;
    if (kind == 'F' || kind == 'R' || kind == 'V') {
      if (parse_field(text, use)) {
        o.kind = Operand::Kind::field;
        p.uses[k] = use;
        return;
      }
      if (kind != 'V')
        fail("'{}': operand {} must be a declared field, got '{}'", mnemonic, k + 1, text);
    }
    if (kind == 'V' || kind == 'K') {
      if (parse_integer(text, literal)) {
        o.kind = Operand::Kind::literal;
        o.literal = literal;
        return;
      }
      if (const int i = parameter_index(text); i >= 0) {
        o.kind = Operand::Kind::parameter;
        o.index = i;
        proc.parameters.set(i);
        return;
      }
      // A constant expression (one value per primitive) is broadcast like a literal; only
      // where the cost does not depend on its value ('V'), so a listing prices it.
      if (const int i = expression_index(text); kind == 'V' && i >= 0) {
        if (!kExpressions[i].constant) {
          fail(
              "'{}': expression '{}' varies across the primitive: load it with qload (only a "
              "constant expression is broadcast as an operand)",
              mnemonic, text);
        }
        require_primitive_procedure(text);
        o.kind = Operand::Kind::expression;
        o.index = i;
        proc.expressions.set(i);
        return;
      }
      fail("'{}': operand {} must be {}an integer or a frame parameter, got '{}'", mnemonic, k + 1,
           kind == 'V' ? "a field, a constant expression, " : "", text);
    }
    if (kind == 'E') {
      const int i = expression_index(text);
      if (i < 0)
        fail("'{}': '{}' is not an expression the GP supplies (pp5sim isa lists them)", mnemonic,
             text);
      require_primitive_procedure(text);
      o.kind = Operand::Kind::expression;
      o.index = i;
      proc.expressions.set(i);
      return;
    }
    if (kind == 'B') {
      if (!parse_integer(text, literal) || literal < 0) {
        fail("'{}': operand {} must be a backing-store block number, got '{}'", mnemonic, k + 1,
             text);
      }
      // The transfer moves the whole first operand: every block it covers must exist.
      const int blocks = options_.backing_store_bits / options_.block_bits;
      const int used = (p.uses[0].width + options_.block_bits - 1) / options_.block_bits;
      // Compared without adding to the literal, which may be near 2^63.
      if (literal > blocks - used) {
        // The last block in unsigned arithmetic: a literal near 2^63 plus the blocks it
        // spans would overflow a signed one (UBSan found it).
        fail("backing-store blocks {}..{} are past the end of the store ({} blocks)", literal,
             static_cast<std::uint64_t>(literal) + static_cast<std::uint64_t>(used) - 1, blocks);
      }
      o.kind = Operand::Kind::literal;
      o.literal = literal;
      explicit_end_block_ = std::max(explicit_end_block_, static_cast<int>(literal) + used);
      return;
    }
    fail("internal: unknown operand kind");
  }

  void check_aliasing(const ParsedInstruction& p, const InstructionInfo& info) {
    const FieldUse& dst = p.uses[0];
    if (dst.field < 0 || info.operands[0] != 'F') return;  // only a written operand can clash
    const bool strict = info.op == Opcode::mul || info.op == Opcode::mac;
    for (int k = 1; k < 3; ++k) {
      const FieldUse& src = p.uses[k];
      if (src.field != dst.field) continue;
      const bool overlap =
          src.offset < dst.offset + dst.width && dst.offset < src.offset + src.width;
      if (!overlap) continue;
      if (strict) fail("'{}': the destination must not overlap a source", info.mnemonic);
      if (src.offset != dst.offset) {
        fail("'{}': a source overlapping the destination must start at the same bit",
             info.mnemonic);
      }
    }
  }

  // A literal written into (or combined with) a field must be representable in its width,
  // read as unsigned or as two's complement; anything else would be silently truncated.
  void check_literal_fits(const ParsedInstruction& p, const InstructionInfo& info) {
    // A block number (bsld's second operand) is an address, not a value for the field.
    if (info.operands[0] != 'F' || std::string(info.operands) != std::string("F") + "V") return;
    const Operand& o = p.ins.operands[1];
    if (o.kind != Operand::Kind::literal || p.uses[0].field < 0) return;
    const int w = p.uses[0].width;
    const __int128 lo = -(static_cast<__int128>(1) << (w - 1));
    const __int128 hi = (static_cast<__int128>(1) << w) - 1;
    if (o.literal < lo || o.literal > hi) {
      fail("'{}': constant {} does not fit the {}-bit destination", info.mnemonic, o.literal, w);
    }
  }

  void check_enable_nesting(Opcode op) {
    if (op == Opcode::epush) {
      if (++depth_ > options_.enable_stack_depth) {
        fail("epush nests {} deep; the enable stack holds {}", depth_, options_.enable_stack_depth);
      }
    } else if (op == Opcode::epop) {
      if (--depth_ < 0) fail("epop without a matching epush");
    } else if (op == Opcode::eelse && depth_ == 0) {
      fail("eelse outside an epush/epop pair");
    }
  }

  // Distinct spilled fields one instruction uses, and the staging bits they need.
  int staging_need(const ParsedInstruction& p, const std::vector<bool>& spilled) const {
    int need = 0;
    std::vector<int> seen;
    for (const FieldUse& u : p.uses) {
      if (u.field < 0 || !spilled[u.field]) continue;
      if (std::find(seen.begin(), seen.end(), u.field) != seen.end()) continue;
      seen.push_back(u.field);
      need += round_to_block(program_.fields[u.field].width);
    }
    return need;
  }

  int round_to_block(int bits) const {
    return (bits + options_.block_bits - 1) / options_.block_bits * options_.block_bits;
  }

  void finish() {
    line_ = 0;
    if (!program_.procedure(Procedure::triangle).defined) {
      throw AssemblyError(program_.name + ": the program defines no 'proc triangle'");
    }
    if (!have_output_) {
      throw AssemblyError(program_.name + ": the program has no 'output RED GREEN BLUE' line");
    }
    for (int k = 0; k < 3; ++k) {
      const FieldDecl& f = program_.fields[output_fields_[k]];
      if (f.scratch) {
        line_ = f.line;
        fail(
            "output field '{}' is scratch; the frame buffer reads it after the procedures, so "
            "declare it with 'field'",
            f.name);
      }
    }
    count_uses();
    check_scratch_liveness();
    layout();
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) emit(p);
    for (int k = 0; k < 3; ++k) {
      const FieldDecl& f = program_.fields[output_fields_[k]];
      program_.outputs[k] = Field{f.lo, f.width, false};
    }
  }

  // Static uses of every field, by procedure, their weighted sum (the spill order) and the
  // first and last instruction of each procedure that names the field (its live range there).
  void count_uses() {
    ranges_.assign(program_.fields.size(), {});
    for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
      const auto& code = parsed_[proc];
      for (int i = 0; i < static_cast<int>(code.size()); ++i) {
        const ParsedInstruction& p = code[i];
        int seen[3] = {-1, -1, -1};
        for (int k = 0; k < 3; ++k) {
          const int f = p.uses[k].field;
          if (f < 0 || f == seen[0] || f == seen[1]) continue;
          seen[k] = f;
          ++program_.fields[f].uses[proc];
          program_.fields[f].weight += static_cast<std::uint64_t>(kProcedureWeight[proc]);
          Range& r = ranges_[f][proc];
          if (r.first < 0) r.first = i;
          r.last = i;
        }
      }
    }
  }

  // Whether an instruction's operand k reads its field (a written operand is also read unless
  // the instruction replaces it outright).
  static bool reads(const InstructionInfo& info, int k) {
    const char kind = info.operands[k];
    if (kind == 'R' || kind == 'V') return true;
    if (kind != 'F') return false;
    return info.op != Opcode::mov && info.op != Opcode::qload && info.op != Opcode::mul &&
           info.op != Opcode::bsld;
  }

  // A scratch field starts every procedure run with whatever another procedure's scratch
  // left in its bits: each bit must be written before it is read (program order; a write
  // under a partial Enable counts, as the author keeps the reads under the same condition).
  void check_scratch_liveness() {
    std::vector<std::uint64_t> written(program_.fields.size(), 0);
    auto mask = [](const FieldUse& u) {
      const std::uint64_t ones =
          u.width >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << u.width) - 1;
      return ones << u.offset;
    };
    for (int proc = 0; proc < static_cast<int>(Procedure::count); ++proc) {
      std::fill(written.begin(), written.end(), 0);
      for (const ParsedInstruction& p : parsed_[proc]) {
        const InstructionInfo& info = instruction_info(p.ins.op);
        const int n = static_cast<int>(std::char_traits<char>::length(info.operands));
        for (int k = 0; k < n; ++k) {
          const FieldUse& u = p.uses[k];
          if (u.field < 0 || !program_.fields[u.field].scratch || !reads(info, k)) continue;
          if ((mask(u) & ~written[u.field]) != 0) {
            line_ = p.ins.line;
            fail(
                "scratch field '{}' is read in procedure '{}' before it is written there "
                "(scratch keeps no value between procedures: declare it with 'field' to keep "
                "one)",
                program_.fields[u.field].name, kProcedureNames[proc]);
          }
        }
        const FieldUse& dst = p.uses[0];
        if (dst.field >= 0 && info.operands[0] == 'F') written[dst.field] |= mask(dst);
      }
    }
  }

  // Whether two scratch fields are ever needed at once: some procedure uses both, and their
  // live ranges there (first to last instruction naming them) overlap.
  bool interfere(int f, int g) const {
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      const Range& a = ranges_[f][p];
      const Range& b = ranges_[g][p];
      if (a.first >= 0 && b.first >= 0 && a.first <= b.last && b.first <= a.last) return true;
    }
    return false;
  }

  // Whether the resident field `field` holds a value while scratch field `s` is in use. Only
  // `shade` runs after everything else, so only there can a field be dead: from its last use
  // on, unless the frame buffer reads it (an output). Elsewhere every field is taken as live.
  bool live_during(int field, int s) const {
    const int shade = static_cast<int>(Procedure::shade);
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      if (p != shade && ranges_[s][p].first >= 0) return true;
    }
    if (std::find(output_fields_.begin(), output_fields_.end(), field) != output_fields_.end())
      return true;
    return ranges_[field][shade].last >= ranges_[s][shade].first;
  }

  // Places the resident fields in declaration order from bit 0, then every scratch field at
  // the lowest offset where it overlaps no scratch field it interferes with and (with `holes`)
  // no resident field live while it is in use, or (without) nothing resident at all. Returns
  // the bits used (the highest end).
  int place(const std::vector<bool>& spilled, bool holes) {
    auto& fields = program_.fields;
    int lo = 0;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (fields[k].scratch || spilled[k]) continue;
      fields[k].lo = lo;
      lo += fields[k].width;
    }
    const int resident_end = lo;
    int end = resident_end;
    std::vector<int> placed;
    std::vector<std::pair<int, int>> busy;  // [lo, end) the current field must avoid
    for (int f = 0; f < static_cast<int>(fields.size()); ++f) {
      if (!fields[f].scratch) continue;
      busy.clear();
      if (!holes) busy.push_back({0, resident_end});
      for (int g = 0; holes && g < static_cast<int>(fields.size()); ++g) {
        if (!fields[g].scratch && !spilled[g] && live_during(g, f))
          busy.push_back({fields[g].lo, fields[g].lo + fields[g].width});
      }
      for (int g : placed) {
        if (interfere(f, g)) busy.push_back({fields[g].lo, fields[g].lo + fields[g].width});
      }
      std::sort(busy.begin(), busy.end());
      int offset = 0;
      for (const auto& [b, e] : busy) {
        if (offset + fields[f].width <= b) break;
        offset = std::max(offset, e);
      }
      fields[f].lo = offset;
      placed.push_back(f);
      end = std::max(end, offset + fields[f].width);
    }
    program_.overlay_lo = resident_end;
    program_.overlay_bits = end - resident_end;
    return end;
  }

  void layout() {
    auto& fields = program_.fields;
    std::vector<bool> spilled(fields.size(), false);
    int resident = place(spilled, true);
    if (resident > options_.memory_bits && !program_.spill_allowed) {
      std::string table;
      for (const auto& f : fields) {
        table +=
            fmt::format("\n  {:<12} {:>3} bits{}", f.name, f.width, f.scratch ? " (scratch)" : "");
      }
      throw AssemblyError(fmt::format(
          "{}: the fields need {} bits but pixel memory has {} (renderer.memory_bits);{}\n"
          "add 'option spill' to move fields to the backing store, or shrink them",
          program_.name, resident, options_.memory_bits, table));
    }
    int staging = 0;
    if (resident > options_.memory_bits) {
      // Spilling is decided on the layout without dead-field reuse, whose size only falls
      // by each spilled field's width (the scratch fields then start after the resident ones).
      resident = place(spilled, false);
      // The instructions that use each field: spilling a field changes only their staging
      // need, and no need ever shrinks as more fields spill, so the staging area is a running
      // maximum (linear in the program, not fields x instructions).
      std::vector<std::vector<const ParsedInstruction*>> users(fields.size());
      for (const auto& code : parsed_) {
        for (const auto& p : code) {
          for (const FieldUse& u : p.uses) {
            if (u.field >= 0 && (users[u.field].empty() || users[u.field].back() != &p))
              users[u.field].push_back(&p);
          }
        }
      }
      // The spill order: cold fields first, then the least used, the last declared first
      // among equals. Outputs (the frame buffer reads them) and scratch never move.
      std::vector<int> order;
      for (int f = 0; f < static_cast<int>(fields.size()); ++f) {
        const bool output =
            std::find(output_fields_.begin(), output_fields_.end(), f) != output_fields_.end();
        if (!fields[f].scratch && !output) order.push_back(f);
      }
      std::sort(order.begin(), order.end(), [&](int a, int b) {
        if (fields[a].cold != fields[b].cold) return fields[a].cold;
        if (fields[a].weight != fields[b].weight) return fields[a].weight < fields[b].weight;
        return a > b;
      });
      for (std::size_t next = 0; resident + staging > options_.memory_bits; ++next) {
        if (next == order.size()) {
          throw AssemblyError(fmt::format(
              "{}: even with every field but the outputs spilled, the outputs, the scratch "
              "fields and {} staging bits need {} bits and pixel memory has {}",
              program_.name, staging, resident + staging, options_.memory_bits));
        }
        const int f = order[next];
        spilled[f] = true;
        resident -= fields[f].width;
        for (const ParsedInstruction* p : users[f])
          staging = std::max(staging, staging_need(*p, spilled));
      }
      // Reuse dead fields where that still fits; the layout without reuse always does.
      resident = place(spilled, true);
      if (resident + staging > options_.memory_bits) resident = place(spilled, false);
    }
    int block = explicit_end_block_;  // spilled fields go after blocks the program uses itself
    const int blocks = options_.backing_store_bits / options_.block_bits;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      fields[k].spilled = spilled[k];
      if (!spilled[k]) continue;
      fields[k].lo = -1;
      fields[k].block = block;
      block += round_to_block(fields[k].width) / options_.block_bits;
      if (block > blocks) {
        throw AssemblyError(
            fmt::format("{}: spilled fields need {} backing-store blocks; the store has {}",
                        program_.name, block, blocks));
      }
    }
    program_.resident_bits = resident;
    program_.staging_bits = staging;
  }

  Operand resolve(const Operand& o, const FieldUse& use, int staging_lo) const {
    Operand r = o;
    if (use.field < 0) return r;
    const FieldDecl& f = program_.fields[use.field];
    const int base = f.spilled ? staging_lo : f.lo;
    r.field = Field{base + use.offset, use.width, use.whole && f.is_signed};
    return r;
  }

  void emit(int proc) {
    ProcedureCode& code = program_.procedures[proc];
    const InstructionInfo* info = nullptr;
    for (const ParsedInstruction& p : parsed_[proc]) {
      info = &instruction_info(p.ins.op);
      // Staging slots for this instruction's spilled fields, in order of first use.
      std::vector<std::pair<int, int>> slots;  // field, staging lo
      int next = program_.resident_bits;
      for (const FieldUse& u : p.uses) {
        if (u.field < 0 || !program_.fields[u.field].spilled) continue;
        bool known = false;
        for (const auto& s : slots) known = known || s.first == u.field;
        if (known) continue;
        slots.push_back({u.field, next});
        next += round_to_block(program_.fields[u.field].width);
      }
      auto slot_of = [&](int field) {
        for (const auto& s : slots) {
          if (s.first == field) return s.second;
        }
        return -1;
      };
      for (const auto& [field, lo] : slots) {
        code.code.push_back(transfer(Opcode::bsld, field, lo));
        ++code.spill_transfers;
      }
      Instruction ins = p.ins;
      for (int k = 0; k < 3; ++k)
        ins.operands[k] = resolve(p.ins.operands[k], p.uses[k], slot_of(p.uses[k].field));
      code.code.push_back(ins);
      if (info->operands[0] == 'F' && p.uses[0].field >= 0 &&
          program_.fields[p.uses[0].field].spilled) {
        const int field = p.uses[0].field;
        code.code.push_back(transfer(Opcode::bsst, field, slot_of(field)));
        ++code.spill_transfers;
      }
    }
  }

  Instruction transfer(Opcode op, int field, int staging_lo) const {
    const FieldDecl& f = program_.fields[field];
    Instruction ins;
    ins.op = op;
    ins.operands[0].kind = Operand::Kind::field;
    ins.operands[0].field = Field{staging_lo, f.width, f.is_signed};
    ins.operands[0].text = f.name;
    ins.operands[1].kind = Operand::Kind::literal;
    ins.operands[1].literal = f.block;
    ins.operands[1].text = std::to_string(f.block);
    return ins;
  }

  AssemblerOptions options_;
  Program program_;
  int line_ = 0;
  int current_ = -1;
  int depth_ = 0;
  bool have_output_ = false;
  std::array<int, 3> output_fields_{};
  std::array<std::vector<ParsedInstruction>, static_cast<int>(Procedure::count)> parsed_;
  int explicit_end_block_ = 0;  // one past the last block that explicit bsld/bsst use
  struct Range {
    int first = -1, last = -1;  // instruction indices in one procedure; -1: not used there
  };
  std::vector<std::array<Range, static_cast<int>(Procedure::count)>> ranges_;
  std::unordered_map<std::string, int> field_by_name_;
};

}  // namespace

const FieldDecl* Program::find_field(const std::string& name) const {
  for (const auto& f : fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

int Program::pass_count(const ParameterValues& frame) const {
  if (passes_parameter < 0) return passes;
  const std::int64_t n = frame[static_cast<std::size_t>(passes_parameter)];
  if (n < 1 || n > kMaxPasses) {
    throw std::runtime_error(
        fmt::format("{}: option passes {}: the frame parameter is {}, expected 1 to {}", name,
                    kParameters[passes_parameter].name, n, kMaxPasses));
  }
  return static_cast<int>(n);
}

Program assemble(const std::string& source, const std::string& name,
                 const AssemblerOptions& options) {
  return Assembler(name, options).run(source);
}

Program assemble_file(const std::string& path, const AssemblerOptions& options) {
  std::string source;
  try {
    source = read_regular_file(path, kMaxProgramBytes, "a firmware program");
  } catch (const FileError& e) {
    throw AssemblyError(e.what());
  }
  return assemble(source, path, options);
}

std::string listing(const Program& program, const TimingParams& timing,
                    const ParameterValues& parameters, const std::string& priced_for) {
  std::string out = fmt::format(
      "program {}\ncycles as the Renderer charges them with the frame parameters of {}\n\nfield "
      "map ({} of {} bits used",
      program.name, priced_for, program.bits_used(), program.memory_bits);
  if (program.overlay_bits)
    out += fmt::format(", {} of them scratch overlay", program.overlay_bits);
  if (program.staging_bits) out += fmt::format(", {} of them spill staging", program.staging_bits);
  out += ")\n";
  auto users = [](const FieldDecl& f) {
    std::vector<std::string> names;
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      if (f.uses[p]) names.push_back(kProcedureNames[p]);
    }
    return names.empty() ? std::string("unused") : fmt::format("{}", fmt::join(names, " "));
  };
  for (const auto& f : program.fields) {
    const char* sign = f.is_signed ? " signed" : "       ";
    if (f.spilled) {
      out += fmt::format("  {:<14} {:>3} bits{}  backing store block {}\n", f.name, f.width, sign,
                         f.block);
    } else if (f.scratch) {
      out += fmt::format("  {:<14} {:>3} bits{}  pixel memory [{}:{}], overlay ({})\n", f.name,
                         f.width, sign, f.lo + f.width - 1, f.lo, users(f));
    } else {
      out += fmt::format("  {:<14} {:>3} bits{}  pixel memory [{}:{}]\n", f.name, f.width, sign,
                         f.lo + f.width - 1, f.lo);
    }
  }
  int scratch_bits = 0;
  for (const auto& f : program.fields) scratch_bits += f.scratch ? f.width : 0;
  if (scratch_bits) {
    out += fmt::format(
        "scratch: {} bits of scratch fields in {} bits past the fields [{}:{}] and the bits of "
        "fields dead in shade (scratch fields share bits unless one procedure needs both at "
        "once)\n",
        scratch_bits, program.overlay_bits,
        program.overlay_lo + std::max(program.overlay_bits, 1) - 1, program.overlay_lo);
  }
  // What spilled and why: cold, or the fewest uses weighted by how often each procedure runs.
  for (const auto& f : program.fields) {
    if (!f.spilled) continue;
    std::vector<std::string> terms;
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      if (f.uses[p]) {
        terms.push_back(
            fmt::format("{} in {} x {}", f.uses[p], kProcedureNames[p], kProcedureWeight[p]));
      }
    }
    out += fmt::format("spilled {}: {} (weighted uses {}{}{})\n", f.name,
                       f.cold ? "marked cold" : "among the least used", f.weight,
                       terms.empty() ? "" : " = ", fmt::format("{}", fmt::join(terms, " + ")));
  }
  OwnedValues values{};
  values.parameters = parameters;
  for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
    const ProcedureCode& code = program.procedures[p];
    if (!code.defined) continue;
    std::uint64_t total = 0;
    out += fmt::format("\nproc {}\n", kProcedureNames[p]);
    for (const auto& ins : code.code) {
      const auto cycles = instruction_cost(ins, timing, values).count;
      total += cycles;
      out += fmt::format("  {:>5}  {:<36} ; {:>4} cycles{}\n",
                         ins.line ? std::to_string(ins.line) : "", disassemble(ins), cycles,
                         ins.line ? "" : " (spill)");
    }
    out += fmt::format("  total {} cycles\n", total);
  }
  return out;
}

}  // namespace pp5
