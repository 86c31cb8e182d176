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

// A PDB coordinate field: optional blanks, then a decimal number filling the rest.
bool pdb_number(std::string_view field) {
  while (!field.empty() && field.front() == ' ') field.remove_prefix(1);
  while (!field.empty() && field.back() == ' ') field.remove_suffix(1);
  if (field.empty()) return false;
  const std::string s(field);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(v);
}

void check_pdb_records(const std::string& text, const std::string& path) {
  std::size_t line = 0, start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view rec(text.data() + start, end - start);
    if (!rec.empty() && rec.back() == '\r') rec.remove_suffix(1);
    ++line;
    // PDB is ASCII text; gemmi 0.5 shifts a record name's bytes as signed chars, which a
    // byte past 0x7F turns into undefined behaviour (found by fuzzing).
    for (std::size_t k = 0; k < rec.size(); ++k) {
      const auto c = static_cast<unsigned char>(rec[k]);
      if (c > 0x7E || (c < 0x20 && c != '\t')) {
        throw SceneError(fmt::format("{}:{}: byte 0x{:02X} in column {}; a PDB file is ASCII text",
                                     path, line, c, k + 1));
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
          throw SceneError(fmt::format("{}:{}: {} coordinate '{}' (columns {}-{}) is not a number",
                                       path, line, kAxes[k], std::string(f), 31 + 8 * k,
                                       38 + 8 * k));
        }
      }
    }
    start = end + 1;
  }
}

// gemmi 0.5 reads mmCIF integers (sequence ids, model numbers, serials) with an int that a
// run of ten or more digits overflows (found by fuzzing: undefined behaviour). No field of a
// real file needs such a run before a decimal point, so it is refused with its place; digits
// after a '.' (a coordinate's fraction) may run on.
void check_cif_digit_runs(const std::string& text, const std::string& path) {
  constexpr std::size_t kMaxDigits = 9;
  std::size_t line = 1, column = 0, run = 0;
  bool fraction = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    ++column;
    if (c >= '0' && c <= '9') {
      if (run == 0) fraction = k > 0 && text[k - 1] == '.';
      if (++run > kMaxDigits && !fraction) {
        throw SceneError(fmt::format(
            "{}:{}: a number with more than {} digits at column {}; no mmCIF field of a "
            "molecule needs one (it would overflow the reader's integers)",
            path, line, kMaxDigits, column - run + 1));
      }
      continue;
    }
    run = 0;
    if (c == '\n') {
      ++line;
      column = 0;
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

std::vector<Sphere> parse_molecule(const std::string& text, const std::string& path, bool cif) {
  gemmi::Structure st;
  try {
    if (cif) {
      check_cif_digit_runs(text, path);
      st = gemmi::make_structure(gemmi::cif::read_memory(text.data(), text.size(), path.c_str()));
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
        const std::string_view name = rec.substr(0, 6);
        if (name == "ATOM  " || name == "HETATM" || name.substr(0, 5) == "MODEL" ||
            name.substr(0, 6) == "ENDMDL") {
          atoms.append(rec);
        }
        atoms += '\n';
        start = end + 1;
      }
      st = gemmi::read_pdb_from_memory(atoms.data(), atoms.size(), path);
    }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    // gemmi's messages name the file and line ("FILE:12:...") for syntax errors.
    const std::string what = e.what();
    throw SceneError(what.rfind(path, 0) == 0 ? what : fmt::format("{}: {}", path, what));
  }
  std::vector<Sphere> spheres;
  if (!st.models.empty()) {
    for (const gemmi::Chain& chain : st.models[0].chains) {
      for (const gemmi::Residue& residue : chain.residues) {
        for (const gemmi::Atom& atom : residue.atoms) {
          const gemmi::Position& p = atom.pos;
          if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw SceneError(fmt::format("{}: atom {} of residue {} {} has a non-finite position",
                                         path, atom.name, residue.name, residue.seqid.str()));
          }
          // PDB's own columns hold at most 9999.999; past a million angstroms a position
          // would not survive the single-precision scene and the camera that frames it.
          constexpr double kMaxCoordinate = 1e6;
          if (std::abs(p.x) > kMaxCoordinate || std::abs(p.y) > kMaxCoordinate ||
              std::abs(p.z) > kMaxCoordinate) {
            throw SceneError(fmt::format(
                "{}: atom {} of residue {} {} lies at ({}, {}, {}); coordinates are limited to "
                "+-{:g} angstroms",
                path, atom.name, residue.name, residue.seqid.str(), p.x, p.y, p.z, kMaxCoordinate));
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
