#include "sim/scene/mesh_loader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

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

// Text split into lines and whitespace-separated tokens, with '#' comments removed when
// asked, and the line number of every token for messages.
class Tokens {
 public:
  Tokens(std::string_view data, std::string origin, bool hash_comments)
      : data_(data), origin_(std::move(origin)), comments_(hash_comments) {}

  // Moves to the next line that holds a token; false at the end of the data.
  bool next_line() {
    while (pos_ < data_.size() || !started_) {
      started_ = true;
      if (pos_ >= data_.size()) return false;
      const auto end = data_.find('\n', pos_);
      std::string_view line =
          data_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
      pos_ = end == std::string_view::npos ? data_.size() : end + 1;
      ++line_no_;
      if (comments_) {
        const auto hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
      }
      split(line);
      if (!tokens_.empty()) return true;
    }
    return false;
  }
  // The current line's tokens.
  const std::vector<std::string_view>& line() const { return tokens_; }
  int line_no() const { return line_no_; }
  // The next token, crossing lines; throws at the end of the data.
  std::string_view next(const char* what) {
    while (index_ >= tokens_.size()) {
      if (!next_line()) fail(fmt::format("unexpected end of file, expected {}", what));
    }
    return tokens_[index_++];
  }
  bool at_end() {
    while (index_ >= tokens_.size()) {
      if (!next_line()) return true;
    }
    return false;
  }
  // Discards what is left of the current line.
  void end_line() { index_ = tokens_.size(); }
  std::size_t bytes_left() const { return data_.size() - pos_; }

  [[noreturn]] void fail(const std::string& what) const {
    throw MeshError(fmt::format("{}:{}: {}", origin_, line_no_, what));
  }

  double number(std::string_view token, const char* what) const {
    const std::string s(token);
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size()) {
      fail(fmt::format("expected {} (a number), got '{}'", what, s));
    }
    if (!std::isfinite(v)) fail(fmt::format("{} '{}' is not a finite number", what, s));
    return v;
  }
  long long integer(std::string_view token, const char* what) const {
    const std::string s(token);
    errno = 0;
    char* end = nullptr;
    const long long v = std::strtoll(s.c_str(), &end, 10);
    if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE) {
      fail(fmt::format("expected {} (an integer), got '{}'", what, s));
    }
    return v;
  }

 private:
  void split(std::string_view line) {
    tokens_.clear();
    index_ = 0;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      std::size_t j = i;
      while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
      if (j > i) tokens_.push_back(line.substr(i, j - i));
      i = j;
    }
  }

  std::string_view data_;
  std::string origin_;
  bool comments_;
  std::size_t pos_ = 0;
  bool started_ = false;
  int line_no_ = 0;
  std::vector<std::string_view> tokens_;
  std::size_t index_ = 0;
};

// Collects positions, colours and polygons, then checks and triangulates them.
class Builder {
 public:
  Builder(std::string origin, const LoadLimits& limits, glm::vec3 default_color)
      : origin_(std::move(origin)), limits_(limits), default_color_(default_color) {}

  void check_counts(std::size_t vertices, std::size_t faces, const std::string& where) const {
    if (vertices > limits_.max_vertices) {
      throw MeshError(fmt::format("{} declares {} vertices; the limit is {}", where, vertices,
                                  limits_.max_vertices));
    }
    if (faces > limits_.max_triangles) {
      throw MeshError(fmt::format("{} declares {} faces; the limit is {}", where, faces,
                                  limits_.max_triangles));
    }
  }
  void add_vertex(glm::vec3 p, const std::string& where) {
    if (positions_.size() >= limits_.max_vertices) {
      throw MeshError(
          fmt::format("{}: more than {} vertices (the limit)", where, limits_.max_vertices));
    }
    positions_.push_back(p);
  }
  void set_color(glm::vec3 c) {
    if (colors_.size() < positions_.size()) colors_.resize(positions_.size(), default_color_);
    colors_.back() = glm::clamp(c, glm::vec3(0.0f), glm::vec3(1.0f));
  }
  std::size_t vertex_count() const { return positions_.size(); }
  // A face whose indices are already checked against vertex_count().
  void add_face(const std::vector<unsigned>& face, const std::string& where) {
    if (face.size() < 3) {
      throw MeshError(
          fmt::format("{}: a face needs at least 3 vertices, got {}", where, face.size()));
    }
    if (face.size() > limits_.max_polygon_vertices) {
      throw MeshError(fmt::format("{}: a face with {} vertices; the limit is {}", where,
                                  face.size(), limits_.max_polygon_vertices));
    }
    ++report_.polygons;
    if (face.size() == 3) {
      push({face[0], face[1], face[2]}, where);
      return;
    }
    ++report_.triangulated;
    scratch_.clear();
    triangulate_polygon(positions_, face, scratch_);
    for (const glm::uvec3& t : scratch_) push(t, where);
  }

  Mesh finish(MeshLoadReport* report) {
    if (positions_.empty()) throw MeshError(fmt::format("{}: the file has no vertices", origin_));
    if (triangles_.empty()) {
      throw MeshError(fmt::format(
          "{}: the file has no faces with area ({} faces read, {} dropped as degenerate)", origin_,
          report_.polygons, report_.dropped_degenerate));
    }
    std::unordered_map<std::uint64_t, int> edges;
    edges.reserve(triangles_.size() * 3);
    for (const glm::uvec3& t : triangles_) {
      for (int e = 0; e < 3; ++e) {
        std::uint64_t a = t[e], b = t[(e + 1) % 3];
        if (a > b) std::swap(a, b);
        if (++edges[(a << 32) | b] == 3) ++report_.non_manifold_edges;
      }
    }
    Mesh mesh;
    mesh.vertices.resize(positions_.size());
    colors_.resize(positions_.size(), default_color_);
    for (std::size_t i = 0; i < positions_.size(); ++i) {
      mesh.vertices[i].position = positions_[i];
      mesh.vertices[i].color = colors_[i];
    }
    mesh.triangles = std::move(triangles_);
    compute_smooth_normals(mesh);
    if (report) *report = report_;
    return mesh;
  }

  MeshLoadReport& report() { return report_; }
  const std::string& origin() const { return origin_; }

 private:
  void push(glm::uvec3 t, const std::string& where) {
    const glm::vec3 a = positions_[t.x], b = positions_[t.y], c = positions_[t.z];
    const glm::dvec3 n = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
    if (t.x == t.y || t.y == t.z || t.x == t.z || glm::dot(n, n) == 0.0) {
      ++report_.dropped_degenerate;
      return;
    }
    if (triangles_.size() >= limits_.max_triangles) {
      throw MeshError(
          fmt::format("{}: more than {} triangles (the limit)", where, limits_.max_triangles));
    }
    triangles_.push_back(t);
  }

  std::string origin_;
  LoadLimits limits_;
  glm::vec3 default_color_;
  std::vector<glm::vec3> positions_;
  std::vector<glm::vec3> colors_;
  std::vector<glm::uvec3> triangles_;
  std::vector<glm::uvec3> scratch_;
  MeshLoadReport report_;
};

// A face index from a file, checked against the vertices read so far.
unsigned checked_index(long long index, std::size_t count, const Tokens& in) {
  if (index < 0 || static_cast<unsigned long long>(index) >= count) {
    in.fail(fmt::format("vertex index {} out of range (the file has {} vertices)", index, count));
  }
  return static_cast<unsigned>(index);
}

// Three numbers in file order (function arguments have no evaluation order).
glm::vec3 read3(Tokens& in, const char* a, const char* b, const char* c) {
  const double x = in.number(in.next(a), a);
  const double y = in.number(in.next(b), b);
  const double z = in.number(in.next(c), c);
  return glm::vec3(x, y, z);
}

std::string at_line(const Tokens& in, const std::string& origin) {
  return fmt::format("{}:{}", origin, in.line_no());
}

Mesh parse_obj(std::string_view data, const std::string& origin, Builder& b,
               MeshLoadReport* report) {
  Tokens in(data, origin, true);
  std::vector<unsigned> face;
  while (in.next_line()) {
    const auto& t = in.line();
    const std::string_view key = t[0];
    if (key == "v") {
      if (t.size() != 4 && t.size() != 5 && t.size() != 7) {
        in.fail(fmt::format("'v' takes x y z [w] or x y z r g b, got {} values", t.size() - 1));
      }
      b.add_vertex(glm::vec3(in.number(t[1], "x"), in.number(t[2], "y"), in.number(t[3], "z")),
                   at_line(in, origin));
      if (t.size() == 7) {
        b.set_color(
            glm::vec3(in.number(t[4], "red"), in.number(t[5], "green"), in.number(t[6], "blue")));
      }
    } else if (key == "f") {
      face.clear();
      for (std::size_t k = 1; k < t.size(); ++k) {
        const std::string_view corner = t[k].substr(0, t[k].find('/'));
        long long index = in.integer(corner, "a vertex index");
        // 1-based, or negative: relative to the end of the vertices read so far.
        if (index > 0) {
          index -= 1;
        } else if (index < 0) {
          index += static_cast<long long>(b.vertex_count());
        } else {
          in.fail("vertex index 0: OBJ indices start at 1");
        }
        face.push_back(checked_index(index, b.vertex_count(), in));
      }
      b.add_face(face, at_line(in, origin));
    } else if (key == "vt" || key == "vn" || key == "vp" || key == "g" || key == "o" ||
               key == "s" || key == "usemtl" || key == "mtllib" || key == "l" || key == "p") {
      ++b.report().ignored_statements;
    } else {
      in.fail(
          fmt::format("unknown OBJ statement '{}' (expected v, f, vt, vn, g, o, s, usemtl, "
                      "mtllib, l or p)",
                      std::string(key)));
    }
  }
  return b.finish(report);
}

Mesh parse_off(std::string_view data, const std::string& origin, Builder& b,
               MeshLoadReport* report) {
  Tokens in(data, origin, true);
  if (!in.next_line()) in.fail("empty file, expected an 'OFF' header");
  const std::string_view magic = in.line()[0];
  const bool colored = magic == "COFF";
  if (magic != "OFF" && magic != "COFF") {
    in.fail(
        fmt::format("expected 'OFF' or 'COFF' on the first line, got '{}'", std::string(magic)));
  }
  in.next("OFF");
  const long long nv = in.integer(in.next("the vertex count"), "the vertex count");
  const long long nf = in.integer(in.next("the face count"), "the face count");
  in.integer(in.next("the edge count"), "the edge count");
  if (nv < 0 || nf < 0) in.fail("negative vertex or face count");
  b.check_counts(static_cast<std::size_t>(nv), static_cast<std::size_t>(nf), at_line(in, origin));
  // Each vertex needs at least "0 0 0\n"; each face at least "3 0 0 0\n".
  if (static_cast<unsigned long long>(nv) * 6 + static_cast<unsigned long long>(nf) * 8 >
      in.bytes_left() + 8) {
    in.fail(
        fmt::format("declares {} vertices and {} faces, more than the {} bytes that follow "
                    "can hold (truncated file?)",
                    nv, nf, in.bytes_left()));
  }
  in.end_line();
  for (long long i = 0; i < nv; ++i) {
    const glm::vec3 p = read3(in, "x", "y", "z");
    b.add_vertex(p, at_line(in, origin));
    if (colored) {
      glm::vec3 c = read3(in, "red", "green", "blue");
      if (c.r > 1.0f || c.g > 1.0f || c.b > 1.0f) c /= 255.0f;
      b.set_color(c);
    }
    in.end_line();
  }
  std::vector<unsigned> face;
  for (long long i = 0; i < nf; ++i) {
    const long long n = in.integer(in.next("a face's vertex count"), "a face's vertex count");
    if (n < 3 || n > 1'000'000) {
      in.fail(fmt::format("a face needs at least 3 vertices, got {}", n));
    }
    face.clear();
    for (long long k = 0; k < n; ++k) {
      face.push_back(
          checked_index(in.integer(in.next("a vertex index"), "a vertex index"), nv, in));
      if (face.size() > 4096) break;
    }
    b.add_face(face, at_line(in, origin));
    in.end_line();  // optional face colour
  }
  if (!in.at_end()) in.fail("unexpected data after the last face");
  return b.finish(report);
}

// Identical positions (bit for bit, with -0 folded into +0) become one vertex, so STL's
// unshared triangles form a connected surface with smooth normals.
class VertexMerger {
 public:
  explicit VertexMerger(Builder& b) : b_(b) {}
  unsigned add(glm::vec3 p, const std::string& where) {
    std::uint32_t k[3];
    for (int i = 0; i < 3; ++i) {
      const float v = p[i] == 0.0f ? 0.0f : p[i];
      std::memcpy(&k[i], &v, 4);
    }
    const std::uint64_t h = (static_cast<std::uint64_t>(k[0]) * 0x9E3779B97F4A7C15ull) ^
                            (static_cast<std::uint64_t>(k[1]) * 0xC2B2AE3D27D4EB4Full) ^ k[2];
    auto& bucket = map_[h];
    for (unsigned index : bucket) {
      if (std::memcmp(&keys_[index], k, sizeof k) == 0) return index;
    }
    const auto index = static_cast<unsigned>(b_.vertex_count());
    b_.add_vertex(p, where);
    keys_.push_back({k[0], k[1], k[2]});
    bucket.push_back(index);
    return index;
  }

 private:
  Builder& b_;
  std::unordered_map<std::uint64_t, std::vector<unsigned>> map_;
  std::vector<std::array<std::uint32_t, 3>> keys_;
};

Mesh parse_stl_binary(std::string_view data, const std::string& origin, Builder& b,
                      MeshLoadReport* report) {
  std::uint32_t n = 0;
  std::memcpy(&n, data.data() + 80, 4);
  b.check_counts(0, n, origin + ": the binary STL header");
  VertexMerger merge(b);
  std::vector<unsigned> face(3);
  for (std::uint32_t i = 0; i < n; ++i) {
    const char* rec = data.data() + 84 + static_cast<std::size_t>(i) * 50;
    const std::string where = fmt::format("{}: triangle {} (byte {})", origin, i, 84 + i * 50ull);
    for (int v = 0; v < 3; ++v) {
      float xyz[3];
      std::memcpy(xyz, rec + 12 + v * 12, 12);
      for (float c : xyz) {
        if (!std::isfinite(c)) throw MeshError(where + ": a coordinate is not a finite number");
      }
      face[v] = merge.add(glm::vec3(xyz[0], xyz[1], xyz[2]), where);
    }
    b.add_face(face, where);
  }
  return b.finish(report);
}

Mesh parse_stl_ascii(std::string_view data, const std::string& origin, Builder& b,
                     MeshLoadReport* report) {
  Tokens in(data, origin, false);
  auto expect = [&](const char* word) {
    const std::string_view t = in.next(word);
    if (t != word) in.fail(fmt::format("expected '{}', got '{}'", word, std::string(t)));
  };
  if (in.at_end() || in.line()[0] != "solid") in.fail("expected 'solid' at the start");
  in.end_line();  // the solid's name
  VertexMerger merge(b);
  std::vector<unsigned> face;
  for (;;) {
    const std::string_view word = in.next("'facet' or 'endsolid'");
    if (word == "endsolid") break;
    if (word != "facet") {
      in.fail(fmt::format("expected 'facet' or 'endsolid', got '{}'", std::string(word)));
    }
    expect("normal");
    for (int k = 0; k < 3; ++k) in.number(in.next("a normal component"), "normal component");
    expect("outer");
    expect("loop");
    face.clear();
    for (;;) {
      const std::string_view t = in.next("'vertex' or 'endloop'");
      if (t == "endloop") break;
      if (t != "vertex") in.fail(fmt::format("expected 'vertex' or 'endloop', got '{}'", t));
      const glm::vec3 p = read3(in, "x", "y", "z");
      face.push_back(merge.add(p, at_line(in, origin)));
      if (face.size() > 4096) in.fail("a facet with more than 4096 vertices");
    }
    b.add_face(face, at_line(in, origin));
    expect("endfacet");
  }
  return b.finish(report);
}

Mesh parse_stl(std::string_view data, const std::string& origin, Builder& b,
               MeshLoadReport* report) {
  if (data.empty()) throw MeshError(origin + ": empty file, expected an STL mesh");
  const bool solid = data.substr(0, 5) == "solid";
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    const unsigned long long need = 84ull + 50ull * n;
    if (need == data.size()) return parse_stl_binary(data, origin, b, report);
    if (!solid) {
      throw MeshError(fmt::format(
          "{}: binary STL declares {} triangles, which need {} bytes, but the file has {} "
          "(truncated or not an STL file)",
          origin, n, need, data.size()));
    }
  }
  if (!solid) {
    throw MeshError(
        fmt::format("{}: {} bytes is too short for a binary STL (84-byte header) and "
                    "it does not start with 'solid'",
                    origin, data.size()));
  }
  return parse_stl_ascii(data, origin, b, report);
}

// PLY: a header of elements and their properties, then the data in ASCII or binary.
enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<PlyType> ply_type(std::string_view s) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::i8},    {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},   {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16}, {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},  {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},  {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64}};
  for (const auto& [name, type] : names) {
    if (s == name) return type;
  }
  return std::nullopt;
}

int ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 1;
}

bool ply_is_float(PlyType t) { return t == PlyType::f32 || t == PlyType::f64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;
  bool is_list = false;
  PlyType count_type = PlyType::u8;
};
struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

// Reads PLY values, from text tokens or from bytes.
class PlyReader {
 public:
  PlyReader(std::string_view body, const std::string& origin, int format, int header_lines)
      : body_(body), origin_(origin), format_(format), tokens_(body, origin, false) {
    (void)header_lines;
  }
  double read(PlyType type, const std::string& what) {
    if (format_ == 0) {
      const std::string_view t = tokens_.next(what.c_str());
      const double v = tokens_.number(t, what.c_str());
      if (!ply_is_float(type) && v != std::floor(v)) {
        tokens_.fail(fmt::format("{} must be an integer, got '{}'", what, std::string(t)));
      }
      return v;
    }
    const int size = ply_size(type);
    if (pos_ + size > body_.size()) {
      throw MeshError(
          fmt::format("{}: binary data ends at byte {} of the body while reading {} "
                      "(truncated file)",
                      origin_, body_.size(), what));
    }
    unsigned char bytes[8];
    std::memcpy(bytes, body_.data() + pos_, size);
    pos_ += size;
    if (format_ == 2) std::reverse(bytes, bytes + size);
    double v = 0;
    switch (type) {
      case PlyType::i8:
        v = static_cast<std::int8_t>(bytes[0]);
        break;
      case PlyType::u8:
        v = bytes[0];
        break;
      case PlyType::i16:
        v = load<std::int16_t>(bytes);
        break;
      case PlyType::u16:
        v = load<std::uint16_t>(bytes);
        break;
      case PlyType::i32:
        v = load<std::int32_t>(bytes);
        break;
      case PlyType::u32:
        v = load<std::uint32_t>(bytes);
        break;
      case PlyType::f32:
        v = load<float>(bytes);
        break;
      case PlyType::f64:
        v = load<double>(bytes);
        break;
    }
    if (!std::isfinite(v)) {
      throw MeshError(
          fmt::format("{}: {} at body byte {} is not a finite number", origin_, what, pos_ - size));
    }
    return v;
  }
  std::size_t bytes_left() const {
    return format_ == 0 ? tokens_.bytes_left() : body_.size() - pos_;
  }
  std::string where() const {
    return format_ == 0 ? fmt::format("{}: body line {}", origin_, tokens_.line_no())
                        : fmt::format("{}: body byte {}", origin_, pos_);
  }
  void finish() {
    if (format_ == 0 ? !tokens_.at_end() : pos_ != body_.size()) {
      throw MeshError(fmt::format("{}: unexpected data after the last element", where()));
    }
  }

 private:
  template <typename T>
  static T load(const unsigned char* bytes) {
    T v;
    std::memcpy(&v, bytes, sizeof v);
    return v;
  }
  std::string_view body_;
  std::string origin_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  Tokens tokens_;
  std::size_t pos_ = 0;
};

Mesh parse_ply(std::string_view data, const std::string& origin, Builder& b,
               MeshLoadReport* report) {
  // The header is text up to and including the "end_header" line.
  Tokens header(data, origin, false);
  if (!header.next_line() || header.line()[0] != "ply") {
    header.fail("expected 'ply' on the first line");
  }
  int format = -1;
  std::vector<PlyElement> elements;
  std::size_t body_start = std::string_view::npos;
  while (header.next_line()) {
    const auto& t = header.line();
    if (t[0] == "format") {
      if (t.size() != 3) header.fail("expected 'format ascii|binary_little_endian|... 1.0'");
      if (t[1] == "ascii")
        format = 0;
      else if (t[1] == "binary_little_endian")
        format = 1;
      else if (t[1] == "binary_big_endian")
        format = 2;
      else
        header.fail(fmt::format("unknown PLY format '{}'", std::string(t[1])));
    } else if (t[0] == "comment" || t[0] == "obj_info") {
    } else if (t[0] == "element") {
      if (t.size() != 3) header.fail("expected 'element NAME COUNT'");
      const long long n = header.integer(t[2], "the element count");
      if (n < 0) header.fail("negative element count");
      elements.push_back({std::string(t[1]), static_cast<std::size_t>(n), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) header.fail("'property' before any 'element'");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        const auto ct = ply_type(t[2]);
        const auto it = ply_type(t[3]);
        if (!ct || !it || ply_is_float(*ct)) {
          header.fail("expected 'property list COUNT_TYPE INDEX_TYPE NAME' with integer types");
        }
        p.is_list = true;
        p.count_type = *ct;
        p.type = *it;
        p.name = std::string(t[4]);
      } else if (t.size() == 3) {
        const auto ty = ply_type(t[1]);
        if (!ty) header.fail(fmt::format("unknown property type '{}'", std::string(t[1])));
        p.type = *ty;
        p.name = std::string(t[2]);
      } else {
        header.fail("expected 'property TYPE NAME' or 'property list COUNT_TYPE INDEX_TYPE NAME'");
      }
      elements.back().properties.push_back(p);
    } else if (t[0] == "end_header") {
      body_start = data.size() - header.bytes_left();
      break;
    } else {
      header.fail(fmt::format("unknown PLY header line '{}'", std::string(t[0])));
    }
  }
  if (body_start == std::string_view::npos) header.fail("no 'end_header' line (truncated header?)");
  if (format < 0) throw MeshError(origin + ": the header has no 'format' line");

  const PlyElement* vertex = nullptr;
  const PlyElement* face = nullptr;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vertex = &e;
    if (e.name == "face") face = &e;
  }
  if (!vertex) throw MeshError(origin + ": the header declares no 'vertex' element");
  if (!face) throw MeshError(origin + ": the header declares no 'face' element");
  b.check_counts(vertex->count, face->count, origin + ": the header");
  auto find = [](const PlyElement& e, const char* name) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      if (e.properties[i].name == name) return static_cast<int>(i);
    }
    return -1;
  };
  const int ix = find(*vertex, "x"), iy = find(*vertex, "y"), iz = find(*vertex, "z");
  if (ix < 0 || iy < 0 || iz < 0) {
    throw MeshError(origin + ": the 'vertex' element needs properties x, y and z");
  }
  for (int i : {ix, iy, iz}) {
    if (vertex->properties[i].is_list) throw MeshError(origin + ": x, y, z must not be lists");
  }
  const int ir = find(*vertex, "red"), ig = find(*vertex, "green"), ib = find(*vertex, "blue");
  const bool colored = ir >= 0 && ig >= 0 && ib >= 0;
  int iface = find(*face, "vertex_indices");
  if (iface < 0) iface = find(*face, "vertex_index");
  if (iface < 0 || !face->properties[iface].is_list) {
    throw MeshError(origin + ": the 'face' element needs a list property 'vertex_indices'");
  }

  PlyReader in(data.substr(body_start), origin, format, header.line_no());
  std::vector<double> values;
  std::vector<unsigned> polygon;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;
    // Every item takes at least one byte in binary and two ("0 ") in text.
    std::size_t min_item = 0;
    for (const PlyProperty& p : e.properties) {
      min_item += format == 0 ? 2 : ply_size(p.is_list ? p.count_type : p.type);
    }
    if (e.count > (in.bytes_left() + 2) / std::max<std::size_t>(min_item, 1)) {
      throw MeshError(
          fmt::format("{}: element '{}' declares {} items, more than the {} bytes of "
                      "data can hold (truncated file?)",
                      origin, e.name, e.count, in.bytes_left()));
    }
    for (std::size_t item = 0; item < e.count; ++item) {
      values.assign(e.properties.size(), 0.0);
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        const std::string what = fmt::format("{} {} '{}'", e.name, item, p.name);
        if (!p.is_list) {
          values[k] = in.read(p.type, what);
          continue;
        }
        const double n = in.read(p.count_type, what + " count");
        if (n < 0 || n > 4096) {
          throw MeshError(
              fmt::format("{}: {} has {} entries; expected 0 to 4096", in.where(), what, n));
        }
        const bool is_face = &e == face && static_cast<int>(k) == iface;
        if (is_face) polygon.clear();
        for (int j = 0; j < static_cast<int>(n); ++j) {
          const double v = in.read(p.type, what);
          if (!is_face) continue;
          if (v < 0 || v >= static_cast<double>(vertex->count) || v != std::floor(v)) {
            throw MeshError(
                fmt::format("{}: {}: vertex index {} out of range (the file has {} "
                            "vertices)",
                            in.where(), what, v, vertex->count));
          }
          polygon.push_back(static_cast<unsigned>(v));
        }
      }
      if (&e == vertex) {
        b.add_vertex(glm::vec3(values[ix], values[iy], values[iz]), in.where());
        if (colored) {
          const double scale = ply_is_float(vertex->properties[ir].type) ? 1.0 : 1.0 / 255.0;
          b.set_color(glm::vec3(values[ir] * scale, values[ig] * scale, values[ib] * scale));
        }
      } else if (&e == face) {
        if (b.vertex_count() < vertex->count) {
          throw MeshError(origin + ": the 'face' element must come after the 'vertex' element");
        }
        b.add_face(polygon, in.where());
      }
    }
  }
  in.finish();
  return b.finish(report);
}

}  // namespace

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
  Builder b(origin, limits, default_color);
  if (format == "obj") return parse_obj(data, origin, b, report);
  if (format == "off") return parse_off(data, origin, b, report);
  if (format == "stl") return parse_stl(data, origin, b, report);
  if (format == "ply") return parse_ply(data, origin, b, report);
  throw MeshError(
      fmt::format("{}: unknown mesh format '{}' (expected obj, ply, stl or off)", origin, format));
}

Mesh load_mesh(const std::string& path, MeshLoadReport* report, const LoadLimits& limits,
               glm::vec3 default_color) {
  const std::string ext = extension_of(path);
  if (!is_mesh_file(path)) {
    throw MeshError(fmt::format("{}: not a mesh file (expected .obj, .ply, .stl or .off)", path));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(fmt::format("{}: cannot open the file", path));
  // Refuse files larger than any mesh within the limits could be, before reading them.
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(std::max<std::streamoff>(0, in.tellg()));
  in.seekg(0);
  const std::uint64_t max_bytes = 200ull * (limits.max_vertices + limits.max_triangles) + 4096;
  if (size > max_bytes) {
    throw MeshError(
        fmt::format("{}: {} bytes is larger than a mesh within the limits ({} "
                    "vertices, {} triangles) can be",
                    path, size, limits.max_vertices, limits.max_triangles));
  }
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (!in) throw MeshError(fmt::format("{}: read error", path));
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
