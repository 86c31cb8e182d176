#include "sim/scene/mesh_loader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/read_file.hpp"
#include "sim/scene/assimp_reader.hpp"

namespace pp5 {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string extension_of(const std::string& path) {
  const auto slash = path.find_last_of("/\\");
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot + 1));
}

// Text from a file as a message can show it: at most `max` characters, '?' for bytes that
// are not printable ASCII.
std::string printable(std::string word, std::size_t max = 32) {
  if (word.size() > max) word = word.substr(0, max) + "...";
  for (char& c : word) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return word;
}

void check_limits(unsigned long long vertices, unsigned long long faces, const std::string& where,
                  const LoadLimits& limits) {
  if (vertices > limits.max_vertices) {
    throw MeshError(fmt::format("{} declares {} vertices; the limit is {}", where, vertices,
                                limits.max_vertices));
  }
  if (faces > limits.max_triangles) {
    throw MeshError(
        fmt::format("{} declares {} faces; the limit is {}", where, faces, limits.max_triangles));
  }
}

// What both strtod and assimp's fast_atof read whole: no hex, no "nan(...)", no "1.5x".
bool is_number(const std::string& t) {
  if (t.empty()) return false;
  const std::string bare = lower(t.substr(t[0] == '-' || t[0] == '+'));
  if (bare == "nan" || bare == "inf" || bare == "infinity") return true;
  char* end = nullptr;
  std::strtod(t.c_str(), &end);
  return *end == '\0' && t.find_first_not_of("0123456789+-.eE") == std::string::npos;
}

// Guards, run before assimp sees the bytes, against what assimp 5.2 (Debian 12) does with
// some files: allocate what a header declares, crash, hang or leak. Each says which.

// The text formats (OBJ, OFF, ASCII PLY and ASCII STL) hold text: a NUL or another control
// byte (other than tab, line feed, vertical tab, form feed and carriage return) means the
// file is not what its name says (a binary file, UTF-16 without a byte-order mark, a file a
// crash wrote into), and assimp's readers stop at a NUL without a word, dropping the rest.
// `first_line` is the line number of data's first byte in the file.
void check_text(std::string_view data, const std::string& origin, const char* format,
                int first_line = 1) {
  int line = first_line;
  std::size_t line_start = 0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    const auto c = static_cast<unsigned char>(data[k]);
    if (c == '\n') {
      ++line;
      line_start = k + 1;
    } else if ((c < 0x20 && c != '\t' && c != '\v' && c != '\f' && c != '\r') || c == 0x7F) {
      throw MeshError(fmt::format(
          "{}:{}: byte 0x{:02X} at column {} is not text; {} is a text format (is it a binary "
          "file, or UTF-16?)",
          origin, line, c, k - line_start + 1, format));
    }
  }
}

// OFF: assimp 5.2 reserves the declared vertex and face counts (a count of 10^12 is a
// bad_alloc, a smaller absurd one gigabytes): each vertex needs at least "0 0 0\n" and each face
// "3 0 0 0\n". Its face reader also crashes (a face count that wraps around below zero) on a
// face line whose size is not 1 to 9, clamps indices out of range to the last vertex, and
// overruns its line buffer on lines of 4096 characters or more. So the lines are checked: the
// vertex lines are counted, each face line must be a size from 3 to 9 and that many indices.
// Each line's '#' comment and the spaces before it removed; a line that held only a comment
// (or spaces) becomes empty, which both check_off and assimp skip.
std::string strip_off_comments(std::string_view data) {
  std::string out;
  out.reserve(data.size());
  std::size_t pos = 0;
  while (pos < data.size()) {
    const std::size_t end = std::min(data.find_first_of("\r\n", pos), data.size());
    std::string_view line = data.substr(pos, end - pos);
    line = line.substr(0, line.find('#'));
    const std::size_t last = line.find_last_not_of(" \t");
    out.append(last == std::string_view::npos ? std::string_view() : line.substr(0, last + 1));
    if (end < data.size()) out += data[end];
    pos = end + 1;
  }
  return out;
}

void check_off(std::string_view data, const std::string& origin, const LoadLimits& limits) {
  data = data.substr(0, data.find('\0'));  // assimp reads the text up to a NUL
  std::istringstream in{std::string(data)};
  std::string line, magic;
  int line_no = 0;
  std::vector<long long> counts;
  while (counts.size() < 3 && std::getline(in, line)) {
    ++line_no;
    std::istringstream words(line.substr(0, line.find('#')));
    std::string w;
    while (counts.size() < 3 && words >> w) {
      if (magic.empty()) {
        magic = w;
        if (magic != "OFF" && magic != "COFF") {
          throw MeshError(fmt::format("{}:{}: expected 'OFF' or 'COFF' at the start, got '{}'",
                                      origin, line_no, printable(magic)));
        }
        continue;
      }
      char* end = nullptr;
      const long long n = std::strtoll(w.c_str(), &end, 10);
      if (*end != '\0' || n < 0) {
        throw MeshError(fmt::format("{}:{}: expected the vertex, face and edge counts, got '{}'",
                                    origin, line_no, printable(w)));
      }
      counts.push_back(n);
    }
    if (counts.size() == 3 && (words >> w)) {
      throw MeshError(
          fmt::format("{}:{}: unexpected '{}' after the counts", origin, line_no, printable(w)));
    }
  }
  if (counts.size() < 3) {
    throw MeshError(
        fmt::format("{}: unexpected end of file, expected the vertex, face and edge "
                    "counts after '{}'",
                    origin, magic.empty() ? "OFF" : magic));
  }
  const std::string where = fmt::format("{}:{}:", origin, line_no);
  check_limits(counts[0], counts[1], where, limits);
  const std::streamoff at = in.tellg();
  std::size_t pos = at < 0 ? data.size() : static_cast<std::size_t>(at);
  if (static_cast<unsigned long long>(counts[0]) * 6 + counts[1] * 8ull > data.size() - pos + 8) {
    throw MeshError(
        fmt::format("{} declares {} vertices and {} faces, more than the {} bytes that follow "
                    "can hold (truncated file?)",
                    where, counts[0], counts[1], data.size() - pos));
  }
  // The vertex and face lines, as assimp splits them: at '\n' or '\r', skipping empty ones.
  // getline took the counts' line break, so pos is at the start of the next line.
  ++line_no;
  for (long long item = 0; item < counts[0] + counts[1]; ++item) {
    for (; pos < data.size() && (data[pos] == '\n' || data[pos] == '\r'); ++pos) {
      line_no += data[pos] == '\n';
    }
    const std::size_t end = std::min(data.find_first_of("\r\n", pos), data.size());
    if (pos >= data.size()) {
      throw MeshError(fmt::format("{}:{}: unexpected end of file, expected {} {}", origin, line_no,
                                  item < counts[0] ? "vertex" : "face",
                                  item < counts[0] ? item : item - counts[0]));
    }
    if (end - pos >= 4000) {
      throw MeshError(
          fmt::format("{}:{}: a line of {} characters (assimp's OFF reader takes "
                      "fewer than 4000)",
                      origin, line_no, end - pos));
    }
    std::istringstream words{std::string(data.substr(pos, end - pos))};
    pos = end;
    if (item < counts[0]) {
      // x y z, then (COFF) a colour: numbers, which assimp would refuse only in its own words.
      std::string w;
      int n = 0;
      for (; words >> w; ++n) {
        if (!is_number(w)) {
          throw MeshError(fmt::format("{}:{}: vertex {}: expected a number, got '{}'", origin,
                                      line_no, item, printable(w)));
        }
      }
      if (n < 3) {
        throw MeshError(fmt::format("{}:{}: vertex {}: expected x, y and z, got {} numbers", origin,
                                    line_no, item, n));
      }
      continue;
    }
    unsigned long long size = 0, index = 0;
    const bool sized = (words >> size) && size >= 3 && size <= 9;
    for (unsigned long long k = 0; sized && k < size; ++k) {
      // Read as a word: an unsigned read takes "-1" as 2^64 - 1.
      std::string w;
      if (!(words >> w)) {
        throw MeshError(fmt::format("{}:{}: face {}: expected {} vertex indices", origin, line_no,
                                    item - counts[0], size));
      }
      const auto [stop, ec] = std::from_chars(w.data(), w.data() + w.size(), index);
      if (w[0] == '-' || stop != w.data() + w.size() || ec != std::errc()) {
        throw MeshError(fmt::format(
            "{}:{}: face {}: vertex index '{}' is not an index from 0 to {} (OFF counts the "
            "vertices from 0)",
            origin, line_no, item - counts[0], printable(w), counts[0] - 1));
      }
      if (index >= static_cast<unsigned long long>(counts[0])) {
        throw MeshError(
            fmt::format("{}:{}: face {}: vertex index {} out of range (the file has "
                        "{} vertices)",
                        origin, line_no, item - counts[0], index, counts[0]));
      }
    }
    if (!sized) {
      throw MeshError(
          fmt::format("{}:{}: face {}: expected a vertex count from 3 to 9 (assimp's "
                      "OFF reader takes no more) and the indices",
                      origin, line_no, item - counts[0]));
    }
  }
}

// PLY: assimp 5.2 reserves what "element NAME COUNT" declares and what a list's count says
// (a face of 2^31 indices took 16 GB), loops forever on a header without "end_header", leaks
// its half-built mesh when a word in an ASCII body is not a number, and reads a body that ends
// early as zeros (text) or whatever follows (binary). So the header lines must be ones PLY
// knows, and the body is walked as assimp will read it: every value present, every word a
// number, every list at most max_polygon_vertices long.
constexpr int kMaxPlyHeaderLines = 1000;

void check_ply(std::string_view data, const std::string& origin, const LoadLimits& limits) {
  static const std::pair<const char*, int> sizes[] = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  auto size_of = [](const std::string& type) {
    for (const auto& [name, size] : sizes) {
      if (type == name) return size;
    }
    return 0;
  };
  struct Property {
    int count_size = 0, size = 0;  // count_size 0: not a list
    bool count_signed = false, integer = false;
    bool value_signed = false;  // an integer type that is not u...: char, short, int
  };
  auto integral = [](const std::string& type) {
    return type.find("float") == std::string::npos && type != "double";
  };
  struct Element {
    std::string name;
    unsigned long long count = 0, min_bytes = 0;
    std::vector<Property> properties;
    int line = 0;  // where it is declared
  };
  std::vector<Element> elements;
  bool text = true, big_endian = false;
  int line = 0, format_line = 0;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t start = pos, end = data.find('\n', pos);
    if (end == std::string_view::npos) {
      throw MeshError(origin + ": no 'end_header' line (truncated header?)");
    }
    std::istringstream words{std::string(data.substr(pos, end - pos))};
    pos = end + 1;
    std::string key, a, b, c, name;
    words >> key >> a >> b >> c >> name;
    ++line;
    // assimp's header reader takes super-quadratic time in its lines (a 2 MB header of
    // comments ran for minutes); exporters write a few dozen.
    if (line > kMaxPlyHeaderLines) {
      throw MeshError(fmt::format(
          "{}: the header has more than {} lines before 'end_header' (comments included); "
          "assimp's PLY reader slows super-quadratically with them",
          origin, kMaxPlyHeaderLines));
    }
    if (data.substr(start, end - start).find('\0') != std::string_view::npos) {
      throw MeshError(fmt::format("{}:{}: a NUL byte in the header", origin, line));
    }
    if (key == "end_header") break;
    const bool list = key == "property" && a == "list";
    const bool known =
        line == 1 ? key == "ply"
        : key == "format"
            ? (a == "ascii" || a == "binary_little_endian" || a == "binary_big_endian")
        : key == "element" ? !b.empty() && c.empty()
        : key == "property"
            ? !elements.empty() && (list ? size_of(b) > 0 && b.find("float") == std::string::npos &&
                                               b != "double" && size_of(c) > 0 && !name.empty()
                                         : size_of(a) > 0 && !b.empty() && c.empty())
            // Any other line is a comment, as assimp reads it: some exporters write their
            // name there without the 'comment' keyword. An empty line too.
            : key != "ply" && key != "end_header";
    if (!known) {
      throw MeshError(
          fmt::format("{}:{}: expected 'ply', then 'format', 'element', 'property', "
                      "'comment' or 'end_header' lines; got '{}'",
                      origin, line, printable(std::string(data.substr(start, end - start)))));
    }
    if (key == "format") {
      // assimp 5.2 frees memory it did not allocate (or leaks it) when a header declares a
      // second format or a second element of one name: both are malformed PLY.
      if (format_line != 0) {
        throw MeshError(fmt::format("{}:{}: a second 'format' line (the first is line {})", origin,
                                    line, format_line));
      }
      format_line = line;
      text = a == "ascii";
      big_endian = a == "binary_big_endian";
    }
    if (key == "element") {
      char* stop = nullptr;
      const unsigned long long n = std::strtoull(b.c_str(), &stop, 10);
      if (*stop != '\0' || b[0] == '-') {
        throw MeshError(fmt::format("{}:{}: element '{}' has count '{}', expected an integer",
                                    origin, line, printable(a), printable(b)));
      }
      for (const Element& e : elements) {
        if (e.name == a) {
          throw MeshError(fmt::format("{}:{}: a second element '{}' (the first is line {})", origin,
                                      line, printable(a), e.line));
        }
      }
      elements.push_back({a, n, 0, {}, line});
    }
    if (key == "property") {
      Element& e = elements.back();
      e.properties.push_back(
          list ? Property{size_of(b), size_of(c), b[0] != 'u', integral(c), c[0] != 'u'}
               : Property{0, size_of(a), false, integral(a), a[0] != 'u'});
      // Text takes at least two bytes a number ("0 "); a face's list at least 3 indices.
      const bool face = list && e.name == "face";
      e.min_bytes += text   ? (face ? 8 : 2)
                     : list ? size_of(b) + (face ? 3 * size_of(c) : 0)
                            : size_of(a);
    }
  }
  if (text) check_text(data.substr(pos), origin, "an ASCII PLY (format ascii)", line + 1);
  const std::size_t bytes = data.size() - pos;
  unsigned long long used = 0;
  for (const Element& e : elements) {
    if (e.name == "vertex") check_limits(e.count, 0, origin + ": the header", limits);
    if (e.name == "face") check_limits(0, e.count, origin + ": the header", limits);
    if (e.count > limits.max_vertices + limits.max_triangles ||
        (e.min_bytes > 0 &&
         e.count > (bytes + 2 - std::min<unsigned long long>(used, bytes)) / e.min_bytes)) {
      throw MeshError(
          fmt::format("{}: element '{}' declares {} items, more than the {} bytes of data can "
                      "hold (truncated file?)",
                      origin, e.name, e.count, bytes - std::min<unsigned long long>(bytes, used)));
    }
    used += e.count * e.min_bytes;
  }
  // The body. Binary: values of the declared sizes. Text: as assimp reads it, an item a line,
  // its values separated by spaces or tabs, integers where the type is one.
  ++line;  // the body's first line
  std::string where;
  auto ends = [&] {
    throw MeshError(text ? fmt::format("{}:{}: unexpected end of file in {} (truncated file?)",
                                       origin, line, where)
                         : fmt::format("{}: the data ends in {}, at byte {} of {} (truncated "
                                       "file?)",
                                       origin, where, pos, data.size()));
  };
  auto blank = [&](char ch) { return ch == ' ' || ch == '\t'; };
  auto word = [&](bool first, bool integer) -> std::string {
    int lines = 0;
    for (; pos < data.size() &&
           (blank(data[pos]) ||
            (first && (data[pos] == '\r' || data[pos] == '\n' || data[pos] == '\f')));
         ++pos) {
      lines += data[pos] == '\n';
    }
    if (pos >= data.size()) ends();
    line += lines;
    if (std::isspace(static_cast<unsigned char>(data[pos]))) {
      throw MeshError(
          fmt::format("{}:{}: {}: the line ends before the values the header "
                      "declares",
                      origin, line, where));
    }
    const std::size_t start = pos;
    while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    std::string w(data.substr(start, pos - start));
    const std::size_t sign = w[0] == '-' || w[0] == '+';
    const bool whole =
        w.size() > sign && w.find_first_not_of("0123456789", sign) == std::string::npos;
    if (integer ? !whole : !is_number(w)) {
      throw MeshError(fmt::format("{}:{}: {}: expected {}, got '{}'", origin, line, where,
                                  integer ? "an integer" : "a number", printable(w)));
    }
    return w;
  };
  bool first = true;
  auto list_size = [&](const Property& p) -> unsigned long long {
    if (text) {
      const std::string w = word(first, true);
      char* stop = nullptr;
      const long long n = std::strtoll(w.c_str(), &stop, 10);
      return *stop == '\0' && n >= 0 ? static_cast<unsigned long long>(n) : ~0ull;
    }
    if (data.size() - pos < static_cast<std::size_t>(p.count_size)) ends();
    unsigned char raw[4] = {0, 0, 0, 0};
    for (int k = 0; k < p.count_size; ++k)
      raw[big_endian ? p.count_size - 1 - k : k] = data[pos + k];
    pos += p.count_size;
    const std::uint32_t u = raw[0] | raw[1] << 8 | raw[2] << 16 | std::uint32_t{raw[3]} << 24;
    const bool negative = p.count_signed && (raw[p.count_size - 1] & 0x80);
    return negative ? ~0ull : u;
  };
  for (const Element& e : elements) {
    for (unsigned long long item = 0; item < e.count; ++item) {
      where = fmt::format("{} {}", printable(e.name), item);
      first = true;
      for (const Property& p : e.properties) {
        unsigned long long n = 1;
        if (p.count_size > 0) {
          n = list_size(p);
          first = false;
          if (n > limits.max_polygon_vertices) {
            throw MeshError(fmt::format("{}: {}: a list of {} entries; the limit is {}", origin,
                                        where, static_cast<long long>(n),
                                        limits.max_polygon_vertices));
          }
        }
        // A face's vertex index is a count from 0: assimp takes a negative one (or one
        // past its type) as a huge unsigned number and says only that it is out of range.
        const bool indices = p.count_size > 0 && p.integer && e.name == "face";
        if (text) {
          for (unsigned long long k = 0; k < n; ++k) {
            const std::string w = word(first && k == 0, p.integer);
            if (!indices) continue;
            unsigned long long index = 0;
            const auto [stop, ec] = std::from_chars(w.data(), w.data() + w.size(), index);
            const unsigned long long top =
                p.size >= 4 ? (p.value_signed ? 0x7FFFFFFFull : 0xFFFFFFFFull)
                            : (1ull << (8 * p.size - (p.value_signed ? 1 : 0))) - 1;
            if (w[0] == '-' || ec != std::errc() || stop != w.data() + w.size() || index > top) {
              throw MeshError(fmt::format(
                  "{}:{}: {}: vertex index '{}' is not an index from 0 to {} (the header's "
                  "type for it)",
                  origin, line, where, printable(w), top));
            }
          }
        } else if (n * p.size > data.size() - pos) {
          ends();
        } else {
          if (indices && p.value_signed) {
            for (unsigned long long k = 0; k < n; ++k) {
              const auto top = static_cast<unsigned char>(
                  data[pos + k * p.size + (big_endian ? 0 : p.size - 1)]);
              if (top & 0x80) {
                throw MeshError(
                    fmt::format("{}: {}: vertex index {} of the list is negative (at byte {})",
                                origin, where, k, pos + k * p.size));
              }
            }
          }
          pos += n * p.size;
        }
        if (n > 0) first = false;
      }
      while (text && pos < data.size() && blank(data[pos])) ++pos;
      if (text && pos < data.size() && data[pos] != '\n' && data[pos] != '\r') {
        throw MeshError(fmt::format("{}:{}: {}: more values on the line than the header declares",
                                    origin, line, where));
      }
    }
  }
  // Text after the last element's values: assimp ignores it, so a file with more items than
  // its header declares (or two files run together) would lose them without a word.
  if (text) {
    const std::size_t rest = data.find_first_not_of(" \t\r\n\v\f", pos);
    if (rest != std::string_view::npos) {
      for (std::size_t k = pos; k < rest; ++k) line += data[k] == '\n';
      throw MeshError(fmt::format(
          "{}:{}: text after the last element the header declares ('{}'): more items than "
          "the header's counts?",
          origin, line,
          printable(std::string(data.substr(rest, data.find_first_of("\r\n", rest) - rest)))));
    }
  }
}

// ASCII STL: assimp 5.2's reader leaks its mesh and node (about 2.5 kB, which fails the fuzz
// target's leak check) whenever it throws halfway: a word where a number belongs, a file cut
// short, a facet without its normal or with fewer than three vertices. It also drops a facet's
// fourth and later vertices. So the structure is checked first: "solid NAME", then facets of
// "facet normal N N N", "outer loop", three "vertex X Y Z", "endloop", "endfacet" (a normal or
// vertex on one line), then "endsolid NAME"; more solids may follow.
void check_ascii_stl(std::string_view data, const std::string& origin) {
  check_text(data, origin, "an ASCII STL (one that starts with 'solid')");
  std::size_t pos = 0;
  int line = 1;
  auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  auto next = [&] {
    int lines = 0;  // counted only up to a word, so the end of the file is on the last line
    for (; pos < data.size() && space(data[pos]); ++pos) lines += data[pos] == '\n';
    if (pos < data.size()) line += lines;
    const std::size_t start = pos;
    while (pos < data.size() && !space(data[pos])) ++pos;
    return std::string(data.substr(start, pos - start));
  };
  auto fail = [&](const std::string& what) {
    throw MeshError(fmt::format("{}:{}: {}", origin, line, what));
  };
  auto expect = [&](const std::string& word) {
    const std::string t = next();
    if (t.empty()) fail(fmt::format("unexpected end of file, expected '{}'", word));
    if (t != word) fail(fmt::format("expected '{}', got '{}'", word, printable(t)));
  };
  // assimp reads a facet's normal and a vertex's numbers from the keyword's line, skipping
  // only spaces and tabs.
  auto on_line = [&](const char* what) {
    while (pos < data.size() && (data[pos] == ' ' || data[pos] == '\t')) ++pos;
    if (pos < data.size() && space(data[pos])) {
      if (data.find_first_not_of(" \t\r\n\v\f", pos) == std::string_view::npos) {
        fail(fmt::format("unexpected end of file, expected {}", what));
      }
      fail(fmt::format("expected {} on the same line", what));
    }
    return next();
  };
  auto number = [&](const char* what) {
    const std::string t = on_line(what);
    if (t.empty()) fail(fmt::format("unexpected end of file, expected {}", what));
    if (!is_number(t)) fail(fmt::format("expected {} (a number), got '{}'", what, printable(t)));
  };
  // Like assimp: "solid" may run into the name, "endsolid" ends the line.
  for (std::string word = next(); word.compare(0, 5, "solid") == 0;) {
    const std::size_t eol = std::min(data.find('\n', pos), data.size());
    pos -= word.size() - 5;
    std::string_view name = data.substr(pos, eol - pos);
    while (!name.empty() && space(name.front())) name.remove_prefix(1);
    std::size_t length = 0;
    while (length < name.size() && !space(name[length])) ++length;
    if (length >= 1024) fail("a solid's name of 1024 or more characters");
    pos = eol;
    for (word = next(); word == "facet"; word = next()) {
      if (on_line("'normal'") != "normal") fail("expected 'normal' after 'facet'");
      for (const char* c : {"the normal's x", "the normal's y", "the normal's z"}) number(c);
      expect("outer");
      expect("loop");
      for (int v = 0; v < 3; ++v) {
        expect("vertex");
        for (const char* c : {"x", "y", "z"}) number(c);
      }
      expect("endloop");
      expect("endfacet");
    }
    if (word.empty()) fail("unexpected end of file, expected 'facet' or 'endsolid'");
    if (word != "endsolid") {
      fail(fmt::format("expected 'facet' or 'endsolid', got '{}'", printable(word)));
    }
    pos = std::min(data.find('\n', pos), data.size());
    word = next();
    // After a solid, only another solid or the end: assimp ignores anything else.
    if (!word.empty() && word.compare(0, 5, "solid") != 0) {
      fail(fmt::format("expected 'solid' or the end of the file after 'endsolid', got '{}'",
                       printable(word)));
    }
  }
}

// OBJ: assimp 5.2 leaks its mesh when a face names a vertex, texture coordinate or normal
// that does not exist, so the indices are checked first, against what the file declares
// ("v" lines of 3, 4 or 6 numbers, "vt" and "vn" lines of numbers). Positive indices may
// point forward (as in assimp), negative ones count back from the line they are on. Lines
// ending in '\\' continue on the next, as in assimp.
// Returns the face statements with no vertex at all (an empty `f` line), which assimp drops
// without a word: they are counted as ignored statements.
std::size_t check_obj(std::string_view data, const std::string& origin) {
  std::size_t empty_faces = 0;
  struct Use {
    long long index;
    int kind, line;
  };
  long long counts[3] = {0, 0, 0};  // v, vt, vn
  std::vector<Use> uses;
  std::string text;
  int line = 0, first = 0;
  for (std::size_t pos = 0; pos < data.size();) {
    const std::size_t end = std::min(data.find('\n', pos), data.size());
    std::string_view piece = data.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    if (text.empty()) first = line;
    if (!piece.empty() && piece.back() == '\r') piece.remove_suffix(1);
    if (!piece.empty() && piece.back() == '\\') {
      text.append(piece.substr(0, piece.size() - 1)).push_back(' ');
      if (pos < data.size()) continue;
    } else {
      text.append(piece);
    }
    std::istringstream words(text.substr(0, text.find('#')));
    text.clear();
    std::string key, word;
    if (!(words >> key)) continue;
    auto fail = [&](const std::string& what) {
      throw MeshError(fmt::format("{}:{}: {}", origin, first, what));
    };
    if (key == "v" || key == "vt" || key == "vn") {
      int n = 0;
      for (; words >> word; ++n) {
        if (!is_number(word)) {
          fail(fmt::format("expected '{}' to be followed by numbers, got '{}'", key,
                           printable(word)));
        }
      }
      if (key == "v" && n != 3 && n != 4 && n != 6) {
        fail(fmt::format("'v' takes x y z, x y z w or x y z r g b, got {} numbers", n));
      }
      ++counts[key == "v" ? 0 : key == "vt" ? 1 : 2];
    } else if (key[0] == 'f' || key[0] == 'l' || key[0] == 'p') {
      bool any = false;
      while (words >> word) {
        any = true;
        std::istringstream parts(word + "/");
        std::string part;
        for (int kind = 0; kind < 3 && std::getline(parts, part, '/'); ++kind) {
          if (part.empty() && kind > 0) continue;
          char* stop = nullptr;
          const long long index = std::strtoll(part.c_str(), &stop, 10);
          if (part.empty() || *stop != '\0' || index == 0) {
            fail(fmt::format("expected a vertex index (from 1, or negative), got '{}'",
                             printable(word)));
          }
          if (index < 0 && -index > counts[kind]) {
            fail(fmt::format("vertex index {} out of range ({} {} lines so far)", index,
                             counts[kind],
                             kind == 0   ? "v"
                             : kind == 1 ? "vt"
                                         : "vn"));
          }
          if (index > 0) uses.push_back({index, kind, first});
        }
      }
      if (!any && key == "f") ++empty_faces;
    }
  }
  for (const Use& use : uses) {
    if (use.index > counts[use.kind]) {
      throw MeshError(
          fmt::format("{}:{}: vertex index {} out of range (the file has {} '{}' "
                      "lines)",
                      origin, use.line, use.index, counts[use.kind],
                      use.kind == 0   ? "v"
                      : use.kind == 1 ? "vt"
                                      : "vn"));
    }
  }
  return empty_faces;
}

// STL: assimp checks a binary file's size against its triangle count itself, but says only
// "Failed to determine STL storage representation"; this says what is wrong.
void check_stl_header(std::string_view data, const std::string& origin, const LoadLimits& limits) {
  const bool solid = data.substr(0, 5) == "solid";
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    const unsigned long long need = 84ull + 50ull * n;
    if (need == data.size()) {
      check_limits(0, n, origin + ": the binary STL header", limits);
      return;
    }
    if (!solid) {
      throw MeshError(fmt::format(
          "{}: binary STL declares {} triangles, which need {} bytes, but the file has {} "
          "(truncated or not an STL file)",
          origin, n, need, data.size()));
    }
  }
  if (!solid) {
    throw MeshError(
        fmt::format("{}: {} bytes is too short for a binary STL (84-byte header) and it does not "
                    "start with 'solid'",
                    origin, data.size()));
  }
  check_ascii_stl(data, origin);
}

// "" for a finite position, else which coordinate is what.
std::string non_finite(const glm::vec3& p) {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(p[c])) {
      return fmt::format("{} is {}, expected a finite number", "xyz"[c],
                         std::isnan(p[c]) ? "NaN" : "infinite");
    }
  }
  return "";
}

}  // namespace

// Corners with the same position and colour bits become one vertex, in the order of their
// first use; the faces are renumbered.
void join_exactly_identical_corners(ImportedMesh& mesh) {
  struct Key {
    std::array<std::uint32_t, 7> bits;
    bool operator==(const Key& o) const { return bits == o.bits; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;
      for (std::uint32_t b : k.bits) h = (h ^ b) * 1099511628211ull;
      return static_cast<std::size_t>(h);
    }
  };
  auto key_of = [&](std::size_t i) {
    Key k{};
    const float values[7] = {mesh.positions[i].x,
                             mesh.positions[i].y,
                             mesh.positions[i].z,
                             mesh.colors.empty() ? 0.0f : mesh.colors[i].r,
                             mesh.colors.empty() ? 0.0f : mesh.colors[i].g,
                             mesh.colors.empty() ? 0.0f : mesh.colors[i].b,
                             mesh.colors.empty() ? 0.0f : mesh.colors[i].a};
    for (int c = 0; c < 7; ++c) {
      // +0 and -0 are one position.
      const float v = values[c] == 0.0f ? 0.0f : values[c];
      std::memcpy(&k.bits[static_cast<std::size_t>(c)], &v, sizeof v);
    }
    return k;
  };
  std::unordered_map<Key, std::uint32_t, KeyHash> index_of;
  index_of.reserve(mesh.positions.size());
  std::vector<std::uint32_t> renumber(mesh.positions.size());
  ImportedMesh joined;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const auto [it, added] =
        index_of.emplace(key_of(i), static_cast<std::uint32_t>(joined.positions.size()));
    if (added) {
      joined.positions.push_back(mesh.positions[i]);
      if (!mesh.colors.empty()) joined.colors.push_back(mesh.colors[i]);
    }
    renumber[i] = it->second;
  }
  for (std::uint32_t& i : mesh.indices) i = renumber[i];
  mesh.positions = std::move(joined.positions);
  mesh.colors = std::move(joined.colors);
}

bool is_mesh_file(const std::string& path) {
  const std::string ext = extension_of(path);
  return ext == "obj" || ext == "ply" || ext == "stl" || ext == "off";
}

bool triangulate_polygon(const std::vector<glm::vec3>& positions,
                         const std::vector<unsigned>& polygon, std::vector<glm::uvec3>& out) {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  // Newell's normal picks the projection plane: drop its largest component.
  glm::dvec3 normal(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 a(positions[polygon[i]]);
    const glm::dvec3 b(positions[polygon[(i + 1) % n]]);
    normal +=
        glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  const glm::dvec3 mag = glm::abs(normal);
  const int drop = mag.x >= mag.y && mag.x >= mag.z ? 0 : (mag.y >= mag.z ? 1 : 2);
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  // Projected with (u, v) as a right-handed pair, a counter-clockwise polygon (seen from its
  // normal) has positive signed area whatever the dropped axis's sign, once flipped below.
  const double sign = normal[drop] >= 0 ? 1.0 : -1.0;
  std::vector<glm::dvec2> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 q = positions[polygon[i]];
    p[i] = glm::dvec2(q[u], q[v] * sign);
  }
  auto cross = [&](std::size_t a, std::size_t b, std::size_t c) {
    return (p[b].x - p[a].x) * (p[c].y - p[a].y) - (p[b].y - p[a].y) * (p[c].x - p[a].x);
  };
  std::vector<std::size_t> ring(n);
  for (std::size_t i = 0; i < n; ++i) ring[i] = i;
  auto inside = [&](std::size_t a, std::size_t b, std::size_t c, std::size_t q) {
    // Strictly inside or on the boundary of triangle abc (counter-clockwise), q distinct.
    return cross(a, b, q) >= 0 && cross(b, c, q) >= 0 && cross(c, a, q) >= 0;
  };
  bool simple = true;
  while (ring.size() > 3) {
    const std::size_t m = ring.size();
    bool clipped = false;
    for (int pass = 0; pass < 2 && !clipped; ++pass) {
      for (std::size_t i = 0; i < m; ++i) {
        const std::size_t a = ring[(i + m - 1) % m], b = ring[i], c = ring[(i + 1) % m];
        const double turn = cross(a, b, c);
        // First pass: strictly convex ears; second: also flat ones (collinear vertices).
        if (pass == 0 ? turn <= 0 : turn < 0) continue;
        bool empty = true;
        for (std::size_t j = 0; j < m && empty; ++j) {
          const std::size_t q = ring[j];
          if (q == a || q == b || q == c) continue;
          if (p[q] == p[a] || p[q] == p[b] || p[q] == p[c]) continue;
          if (turn > 0 && inside(a, b, c, q)) empty = false;
        }
        if (!empty) continue;
        out.emplace_back(polygon[a], polygon[b], polygon[c]);
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
        clipped = true;
        break;
      }
    }
    if (!clipped) {
      // Not a simple polygon: fan what is left so that no part of the face is lost.
      simple = false;
      for (std::size_t i = 1; i + 1 < ring.size(); ++i) {
        out.emplace_back(polygon[ring[0]], polygon[ring[i]], polygon[ring[i + 1]]);
      }
      return false;
    }
  }
  out.emplace_back(polygon[ring[0]], polygon[ring[1]], polygon[ring[2]]);
  return simple;
}

Mesh parse_mesh(std::string_view data, const std::string& format, const std::string& origin,
                MeshLoadReport* report, const LoadLimits& limits, glm::vec3 default_color) {
  if (format != "obj" && format != "ply" && format != "stl" && format != "off") {
    throw MeshError(fmt::format("{}: unknown mesh format '{}' (expected obj, ply, stl or off)",
                                origin, format));
  }
  if (data.empty()) throw MeshError(fmt::format("{}: empty file, expected a mesh", origin));
  // Text saved as UTF-16 (some Windows tools do) reads as words with NULs between them.
  if (data.size() >= 2 &&
      ((data[0] == '\xFF' && data[1] == '\xFE') || (data[0] == '\xFE' && data[1] == '\xFF'))) {
    throw MeshError(fmt::format(
        "{}: UTF-16 text (it starts with a UTF-16 byte-order mark); save it as UTF-8 or ASCII",
        origin));
  }
  if ((format == "obj" || format == "off") && data.size() >= 2 &&
      (data[0] == '\0' || data[1] == '\0')) {
    throw MeshError(
        fmt::format("{}: a NUL byte at the start of a text format (UTF-16 text without a "
                    "byte-order mark?); save it as UTF-8 or ASCII",
                    origin));
  }
  // A UTF-8 byte-order mark (Windows editors write one) is not part of a text format.
  if ((format == "obj" || format == "off" || format == "ply") && data.size() >= 3 &&
      data.substr(0, 3) == "\xEF\xBB\xBF") {
    data.remove_prefix(3);
  }
  if (format == "obj" || format == "off") {
    check_text(data, origin, format == "obj" ? "OBJ" : "OFF");
  }
  // OFF allows a comment, '#' to the end of the line, on any line; assimp's reader takes
  // them only in the header. They are blanked here (the lines stay, so line numbers in
  // messages are the file's).
  std::string off_text;
  if (format == "off") {
    off_text = strip_off_comments(data);
    data = off_text;
  }
  std::size_t empty_faces = 0;
  if (format == "off") check_off(data, origin, limits);
  if (format == "ply") check_ply(data, origin, limits);
  if (format == "stl") check_stl_header(data, origin, limits);
  if (format == "obj") empty_faces = check_obj(data, origin);

  // assimp, loaded on first use (sim/scene/assimp_reader.hpp); its message is printable and
  // at most 300 characters.
  std::unique_ptr<AssimpReader> reader;
  try {
    reader = open_assimp_reader();
  } catch (const MeshError& e) {
    throw MeshError(fmt::format("{}: {}", origin, e.what()));
  }
  std::string error;
  if (!reader->read(data, format, error)) {
    throw MeshError(fmt::format("{}: {}", origin, printable(error, 300)));
  }
  std::vector<ImportedMesh> meshes = reader->meshes();

  // The four importers put every mesh under identity node transforms, so the meshes are
  // taken as they are. Every face is checked before any step of assimp's touches the data.
  const bool per_face = format == "obj" || format == "stl";  // a vertex per face corner
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const ImportedMesh& mesh = meshes[m];
    const std::string where = meshes.size() > 1 ? fmt::format("{}: mesh {}", origin, m) : origin;
    std::size_t at = 0;  // the face's first corner in mesh.indices
    for (std::size_t f = 0; f < mesh.face_sizes.size(); ++f) {
      const std::uint32_t corners = mesh.face_sizes[f];
      // OBJ's points and lines are skipped below; elsewhere a face needs three corners.
      if (corners == 0 || (corners < 3 && format != "obj")) {
        throw MeshError(
            fmt::format("{}: face {} has {} vertices, expected at least 3", where, f, corners));
      }
      if (corners > limits.max_polygon_vertices) {
        throw MeshError(fmt::format("{}: face {} has {} vertices; the limit is {}", where, f,
                                    corners, limits.max_polygon_vertices));
      }
      for (std::uint32_t k = 0; k < corners; ++k) {
        const std::uint32_t i = mesh.indices[at + k];
        if (i >= mesh.positions.size()) {
          throw MeshError(
              fmt::format("{}: face {}: vertex index {} out of range (the file has {} "
                          "vertices)",
                          where, f, i, mesh.positions.size()));
        }
        // OBJ's and STL's vertices are face corners: name the face.
        const std::string bad = per_face ? non_finite(mesh.positions[i]) : "";
        if (!bad.empty()) {
          throw MeshError(fmt::format("{}: face {}, corner {}: {}", where, f, k, bad));
        }
      }
      at += corners;
    }
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const std::string bad = non_finite(mesh.positions[i]);
      if (!bad.empty()) throw MeshError(fmt::format("{}: vertex {}: {}", where, i, bad));
      if (!mesh.colors.empty()) {
        const glm::vec4& col = mesh.colors[i];
        if (!std::isfinite(col.r) || !std::isfinite(col.g) || !std::isfinite(col.b)) {
          throw MeshError(fmt::format("{}: vertex {}: the colour is not finite", where, i));
        }
      }
    }
  }
  // OBJ and STL come with a vertex per face corner: identical positions (and colours) become
  // one vertex, so faces share their corners and the normals come out smooth.
  // Exactly identical, bit for bit: assimp's JoinIdenticalVertices merges corners closer
  // than an epsilon, which collapsed CAD triangles about 1e-5 across to nothing.
  if (per_face) {
    for (ImportedMesh& mesh : meshes) join_exactly_identical_corners(mesh);
  }

  MeshLoadReport r;
  r.ignored_statements = empty_faces;
  Mesh out;
  std::vector<glm::vec3> positions;
  std::vector<unsigned> polygon;
  std::vector<glm::uvec3> triangles;
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const ImportedMesh& mesh = meshes[m];
    const auto base = static_cast<unsigned>(out.vertices.size());
    if (out.vertices.size() + mesh.positions.size() > limits.max_vertices) {
      throw MeshError(fmt::format("{}: {} vertices; the limit is {}", origin,
                                  out.vertices.size() + mesh.positions.size(),
                                  limits.max_vertices));
    }
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      Vertex v;
      v.position = mesh.positions[i];
      v.color = default_color;
      if (!mesh.colors.empty()) {
        const glm::vec4& c = mesh.colors[i];
        glm::vec3 rgb(c.r, c.g, c.b);
        // assimp's OFF importer passes COFF's 0-255 colours through as they are.
        if (format == "off" && (rgb.r > 1.0f || rgb.g > 1.0f || rgb.b > 1.0f)) rgb /= 255.0f;
        v.color = glm::clamp(rgb, glm::vec3(0.0f), glm::vec3(1.0f));
      }
      out.vertices.push_back(v);
      positions.push_back(v.position);
    }
    std::size_t at = 0;  // the face's first corner in mesh.indices
    for (std::size_t f = 0; f < mesh.face_sizes.size(); ++f) {
      const std::uint32_t corners = mesh.face_sizes[f];
      const std::uint32_t* first = mesh.indices.data() + at;
      at += corners;
      if (corners < 3) {  // a point or a line: nothing to fill
        ++r.ignored_statements;
        continue;
      }
      ++r.polygons;
      polygon.assign(first, first + corners);
      for (unsigned& i : polygon) i += base;
      // A corner repeated at once (1 2 2 3, or the last equal to the first) is a collapsed
      // edge: dropped, and the face counted as degenerate if that leaves fewer than three.
      // A vertex visited again later (1 2 3 1 2 3 ...) makes no polygon that can be filled:
      // triangulating it would stack triangles on one another, so it is refused.
      {
        std::vector<unsigned> kept;
        for (std::size_t k = 0; k < polygon.size(); ++k) {
          if (kept.empty() || kept.back() != polygon[k]) kept.push_back(polygon[k]);
        }
        while (kept.size() > 1 && kept.back() == kept.front()) kept.pop_back();
        if (kept.size() < polygon.size()) ++r.collapsed_corners;
        std::vector<unsigned> sorted = kept;
        std::sort(sorted.begin(), sorted.end());
        const auto again = std::adjacent_find(sorted.begin(), sorted.end());
        if (again != sorted.end()) {
          const auto times = std::count(kept.begin(), kept.end(), *again);
          throw MeshError(fmt::format(
              "{}: face {} visits vertex {} {} times ({} corners); a face must be a polygon "
              "that visits each vertex once",
              meshes.size() > 1 ? fmt::format("{}: mesh {}", origin, m) : origin, f, *again - base,
              times, corners));
        }
        if (kept.size() < 3) {
          ++r.dropped_degenerate;
          continue;
        }
        polygon.swap(kept);
      }
      triangles.clear();
      if (polygon.size() == 3) {
        triangles.emplace_back(polygon[0], polygon[1], polygon[2]);
      } else {
        ++r.triangulated;
        triangulate_polygon(positions, polygon, triangles);
      }
      for (const glm::uvec3& t : triangles) {
        const glm::dvec3 a(positions[t.x]), b(positions[t.y]), c(positions[t.z]);
        const glm::dvec3 n = glm::cross(b - a, c - a);
        if (t.x == t.y || t.y == t.z || t.x == t.z || glm::dot(n, n) == 0.0) {
          ++r.dropped_degenerate;
          continue;
        }
        if (out.triangles.size() >= limits.max_triangles) {
          throw MeshError(
              fmt::format("{}: more than {} triangles (the limit)", origin, limits.max_triangles));
        }
        out.triangles.push_back(t);
      }
    }
  }
  if (r.polygons == 0) {
    throw MeshError(
        fmt::format("{}: no faces found, expected at least one triangle{}", origin,
                    r.ignored_statements
                        ? fmt::format(" (faces of 1 or 2 vertices, points or lines, skipped: {})",
                                      r.ignored_statements)
                        : ""));
  }
  if (out.triangles.empty()) {
    throw MeshError(
        fmt::format("{}: the file has no faces with area ({} faces read, {} dropped as degenerate)",
                    origin, r.polygons, r.dropped_degenerate));
  }
  std::unordered_map<std::uint64_t, int> edges;
  edges.reserve(out.triangles.size() * 3);
  for (const glm::uvec3& t : out.triangles) {
    for (int e = 0; e < 3; ++e) {
      std::uint64_t a = t[e], b = t[(e + 1) % 3];
      if (a > b) std::swap(a, b);
      if (++edges[(a << 32) | b] == 3) ++r.non_manifold_edges;
    }
  }
  compute_smooth_normals(out);
  if (report) *report = r;
  return out;
}

Mesh load_mesh(const std::string& path, MeshLoadReport* report, const LoadLimits& limits,
               glm::vec3 default_color) {
  const std::string ext = extension_of(path);
  if (!is_mesh_file(path)) {
    throw MeshError(fmt::format("{}: not a mesh file (expected .obj, .ply, .stl or .off)", path));
  }
  // Files larger than any mesh within the limits could be are refused before they are read;
  // FIFOs, devices and directories are refused outright (common/read_file.hpp).
  const std::uint64_t max_bytes = 200ull * (limits.max_vertices + limits.max_triangles) + 4096;
  std::string data;
  try {
    data = read_regular_file(path, max_bytes, "a mesh file",
                             fmt::format("a mesh within the limits ({} vertices, {} triangles)",
                                         limits.max_vertices, limits.max_triangles));
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
  if (data.empty()) throw MeshError(fmt::format("{}: empty file, expected a mesh", path));
  return parse_mesh(data, ext, path, report, limits, default_color);
}

Scene scene_from_mesh(Mesh mesh, const std::string& name, const std::string& description) {
  Scene scene;
  scene.name = name;
  scene.description = description;
  scene.mesh = std::move(mesh);
  scene.camera = frame_mesh(scene.mesh, glm::vec3(0.3f, 0.4f, 1.0f), 40.0f, 1.05f);
  scene.lights = {default_light(scene.camera)};
  scene.background = glm::vec3(0.05f, 0.05f, 0.08f);
  return scene;
}

}  // namespace pp5
