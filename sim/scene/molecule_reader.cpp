// Molecule files through gemmi (Debian's gemmi-dev, header-only; mmCIF's parser needs
// tao-pegtl-dev). gemmi's PDB reader forgives a malformed coordinate (it reads "11.1x4" as
// 11.1), so the fixed columns of every ATOM/HETATM record are checked here first, naming the
// line; mmCIF syntax errors come from gemmi's parser with its line number.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <gemmi/cif.hpp>
#include <gemmi/mmcif.hpp>
#include <gemmi/pdb.hpp>
#include <string>
#include <string_view>

#include "common/escape.hpp"
#include "common/read_file.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/scene/sphere_scenes.hpp"

namespace pp5 {

namespace {

constexpr std::uint64_t kMaxMoleculeBytes = std::uint64_t{512} << 20;
constexpr std::size_t kMaxAtoms = 4'000'000;

bool ends_with(const std::string& s, const char* suffix) {
  const std::string_view v(suffix);
  if (s.size() < v.size()) return false;
  std::string tail = s.substr(s.size() - v.size());
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == v;
}

// A PDB coordinate field (Fortran F8.3): optional blanks, then an optional sign, digits and
// at most one decimal point. strtod alone also took "0x1p3" (a hexadecimal float, which
// gemmi then read as 0), "1e5" and "infinity".
bool pdb_number(std::string_view field) {
  while (!field.empty() && field.front() == ' ') field.remove_prefix(1);
  while (!field.empty() && field.back() == ' ') field.remove_suffix(1);
  if (!field.empty() && (field.front() == '-' || field.front() == '+')) field.remove_prefix(1);
  bool digits = false, point = false;
  for (const char c : field) {
    if (c >= '0' && c <= '9') {
      digits = true;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      return false;
    }
  }
  return digits;
}

// The records a space-filling model reads: the only ones given to gemmi.
bool reaches_gemmi(std::string_view rec) {
  const std::string_view name = rec.substr(0, 6);
  return name == "ATOM  " || name == "HETATM" || name.substr(0, 5) == "MODEL" ||
         name.substr(0, 6) == "ENDMDL";
}

void check_pdb_records(const std::string& text, const std::string& path) {
  std::size_t line = 0, start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view rec(text.data() + start, end - start);
    if (!rec.empty() && rec.back() == '\r') rec.remove_suffix(1);
    ++line;
    // Only the records that reach gemmi (below) must be ASCII: gemmi 0.5 shifts a record
    // name's bytes as signed chars, which a byte past 0x7F turns into undefined behaviour
    // (found by fuzzing). Other records (a REMARK or an AUTHOR with UTF-8 names) are
    // blanked before gemmi reads the file.
    if (!reaches_gemmi(rec)) {
      start = end + 1;
      continue;
    }
    for (std::size_t k = 0; k < rec.size(); ++k) {
      const auto c = static_cast<unsigned char>(rec[k]);
      if (c > 0x7E || (c < 0x20 && c != '\t')) {
        throw SceneError(
            fmt::format("{}:{}: byte 0x{:02X} in column {} of an {} record, which is ASCII text",
                        path, line, c, k + 1, escape_for_message(rec.substr(0, 6))));
      }
    }
    if (rec.substr(0, 6) == "ATOM  " || rec.substr(0, 6) == "HETATM") {
      if (rec.size() < 54) {
        throw SceneError(
            fmt::format("{}:{}: {} record of {} columns; x, y and z take columns 31-54", path, line,
                        std::string(rec.substr(0, 6)), rec.size()));
      }
      static const char* kAxes[] = {"x", "y", "z"};
      for (int k = 0; k < 3; ++k) {
        const std::string_view f = rec.substr(30 + 8 * static_cast<std::size_t>(k), 8);
        if (!pdb_number(f)) {
          throw SceneError(fmt::format(
              "{}:{}: {} coordinate '{}' (columns {}-{}) is not a decimal number (expected "
              "digits with an optional sign and point, as in -12.345)",
              path, line, kAxes[k], escape_for_message(f), 31 + 8 * k, 38 + 8 * k));
        }
      }
    }
    start = end + 1;
  }
}

// gemmi 0.5 reads mmCIF integers (sequence ids, model numbers, serials, charges) with an
// int that a larger number overflows (found by fuzzing: undefined behaviour). Its reader
// takes an integer from the digits at the start of a value (after an optional quote and
// sign), so only such a run whose value exceeds 2^31 - 1 is refused, with its place. Digits
// inside a value (a ten-digit deposition id "D_1292123456", a date, a DOI) never reach an
// integer and are left alone; so are text fields (between lines starting with ';') and
// comments.
void check_cif_integers(const std::string& text, const std::string& path) {
  constexpr unsigned long long kIntMax = 2147483647;
  std::size_t line = 1;
  bool text_field = false;
  for (std::size_t start = 0; start < text.size(); ++line) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view rec(text.data() + start, end - start);
    start = end + 1;
    if (!rec.empty() && rec[0] == ';') {
      text_field = !text_field;
      continue;
    }
    if (text_field) continue;
    for (std::size_t k = 0; k < rec.size(); ++k) {
      if (k > 0 && rec[k - 1] != ' ' && rec[k - 1] != '\t') continue;  // not a value's start
      if (rec[k] == '#') break;                                        // a comment
      std::size_t j = k;
      if (j < rec.size() && (rec[j] == '\'' || rec[j] == '"')) ++j;
      if (j < rec.size() && (rec[j] == '-' || rec[j] == '+')) ++j;
      unsigned long long value = 0;
      const std::size_t first = j;
      for (; j < rec.size() && rec[j] >= '0' && rec[j] <= '9' && value <= kIntMax; ++j) {
        value = value * 10 + static_cast<unsigned>(rec[j] - '0');
      }
      if (value > kIntMax) {
        throw SceneError(fmt::format(
            "{}:{}: the value at column {} starts with a number larger than {} ('{}'); an "
            "mmCIF integer field (a sequence id, serial or model number) cannot hold it",
            path, line, first + 1, kIntMax,
            escape_for_message(rec.substr(k, rec.find_first_of(" \t", k) - k), 40)));
      }
    }
  }
}

}  // namespace

std::vector<Sphere> read_molecule_file(const std::string& path) {
  std::string text;
  try {
    text = read_regular_file(path, kMaxMoleculeBytes, "a molecule file (PDB or mmCIF)");
  } catch (const FileError& e) {
    throw SceneError(e.what());
  }
  return parse_molecule(text, path, ends_with(path, ".cif") || ends_with(path, ".mmcif"));
}

namespace {

// PDB and mmCIF are text: a NUL or another control byte (other than tab, line feed, form
// feed and carriage return) means the file is not one (a binary file, UTF-16), and the
// PDB reader would skip the line it is on without a word.
void check_molecule_text(const std::string& text, const std::string& path, bool cif) {
  std::size_t line = 1, line_start = 0;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c == '\n') {
      ++line;
      line_start = k + 1;
    } else if ((c < 0x20 && c != '\t' && c != '\f' && c != '\r' && c != '\v') || c == 0x7F) {
      throw SceneError(fmt::format(
          "{}:{}: byte 0x{:02X} at column {} is not text; {} is a text format (is it a binary "
          "file, or UTF-16?)",
          path, line, c, k - line_start + 1, cif ? "mmCIF" : "PDB"));
    }
  }
}

// gemmi 0.5's mmCIF reader finds its atom table only when every column it needs is there;
// without one it reads no atom and says nothing. The columns it needs, named when missing.
void check_atom_site_columns(const gemmi::cif::Document& doc, const std::string& path) {
  if (doc.blocks.empty()) return;
  const gemmi::cif::Block& block = doc.blocks[0];
  static const char* const kRequired[] = {
      "id",      "type_symbol", "label_alt_id", "label_asym_id",  "Cartn_x",
      "Cartn_y", "Cartn_z",     "occupancy",    "B_iso_or_equiv", "auth_seq_id"};
  bool any = false;
  std::vector<std::string> missing;
  for (const char* column : kRequired) {
    const bool has = block.has_tag(std::string("_atom_site.") + column);
    any = any || has;
    if (!has) missing.push_back(std::string("_atom_site.") + column);
  }
  if (!any || missing.empty()) return;  // no atom table at all: "no atoms" below
  std::string list;
  for (const std::string& m : missing) list += (list.empty() ? "" : ", ") + m;
  throw SceneError(fmt::format(
      "{}: the _atom_site table lacks {} {} (the mmCIF reader needs _atom_site.id, type_symbol, "
      "label_alt_id, label_asym_id, Cartn_x, Cartn_y, Cartn_z, occupancy, B_iso_or_equiv and "
      "auth_seq_id)",
      path, missing.size() == 1 ? "the column" : "the columns", list));
}

}  // namespace

std::vector<Sphere> parse_molecule(const std::string& text, const std::string& path, bool cif) {
  gemmi::Structure st;
  check_molecule_text(text, path, cif);
  try {
    if (cif) {
      check_cif_integers(text, path);
      const gemmi::cif::Document doc =
          gemmi::cif::read_memory(text.data(), text.size(), path.c_str());
      check_atom_site_columns(doc, path);
      st = gemmi::make_structure(doc);
    } else {
      check_pdb_records(text, path);
      // Only the records a space-filling model reads reach gemmi: its 0.5 reader overflows
      // integers on long numbers in other records (LINK, CONECT, REMARK; found by fuzzing).
      // Other lines are emptied, so gemmi's line numbers still match the file's.
      std::string atoms;
      atoms.reserve(text.size());
      for (std::size_t start = 0; start < text.size();) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        const std::string_view rec(text.data() + start, end - start);
        if (reaches_gemmi(rec)) atoms.append(rec);
        atoms += '\n';
        start = end + 1;
      }
      st = gemmi::read_pdb_from_memory(atoms.data(), atoms.size(), path);
    }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    // gemmi's messages name the file and line ("FILE:12:...") for syntax errors; its others
    // (a column the _atom_site table needs is missing) are said to be the reader's.
    const std::string what = escape_for_message(e.what(), 300);
    throw SceneError(what.rfind(path, 0) == 0
                         ? what
                         : fmt::format("{}: the {} reader (gemmi) cannot read it: {}", path,
                                       cif ? "mmCIF" : "PDB", what));
  }
  std::vector<Sphere> spheres;
  if (!st.models.empty()) {
    for (const gemmi::Chain& chain : st.models[0].chains) {
      for (const gemmi::Residue& residue : chain.residues) {
        for (const gemmi::Atom& atom : residue.atoms) {
          const gemmi::Position& p = atom.pos;
          if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw SceneError(fmt::format("{}: atom {} of residue {} {} has a non-finite position",
                                         path, escape_for_message(atom.name),
                                         escape_for_message(residue.name),
                                         escape_for_message(residue.seqid.str())));
          }
          // PDB's own columns hold at most 9999.999; past a million angstroms a position
          // would not survive the single-precision scene and the camera that frames it.
          constexpr double kMaxCoordinate = 1e6;
          if (std::abs(p.x) > kMaxCoordinate || std::abs(p.y) > kMaxCoordinate ||
              std::abs(p.z) > kMaxCoordinate) {
            throw SceneError(fmt::format(
                "{}: atom {} of residue {} {} lies at ({}, {}, {}); coordinates are limited to "
                "+-{:g} angstroms",
                path, escape_for_message(atom.name), escape_for_message(residue.name),
                escape_for_message(residue.seqid.str()), p.x, p.y, p.z, kMaxCoordinate));
          }
          if (spheres.size() >= kMaxAtoms) {
            throw SceneError(fmt::format("{}: more than {} atoms", path, kMaxAtoms));
          }
          const ElementStyle style = element_style(atom.element.name());
          spheres.push_back(
              {glm::vec3(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)),
               style.radius, style.color});
        }
      }
    }
  }
  if (spheres.empty()) {
    throw SceneError(
        fmt::format("{}: no atoms (expected ATOM/HETATM records or an mmCIF "
                    "_atom_site table)",
                    path));
  }
  return spheres;
}

}  // namespace pp5
