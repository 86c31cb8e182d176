#include "sim/scene/scene_loader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "common/escape.hpp"
#include "common/memory_note.hpp"
#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "models/config/machine_config.hpp"
#include "sim/scene/csg_expression.hpp"
#include "sim/scene/sphere_scenes.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

using nlohmann::json;

// A JSON value with its path, for messages that name the key.
struct Node {
  const json& value;
  std::string path;
  const std::string& origin;

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(fmt::format("{}: key '{}' {}", origin, escape_for_message(path, 200), what));
  }
  Node at(const std::string& key) const {
    return {value.at(key), path.empty() ? key : path + "." + key, origin};
  }
  Node at(std::size_t i) const { return {value.at(i), fmt::format("{}[{}]", path, i), origin}; }
  bool has(const std::string& key) const { return value.contains(key); }

  void check_keys(std::initializer_list<const char*> allowed) const {
    if (!value.is_object()) fail(fmt::format("must be an object (got {})", value.type_name()));
    const std::set<std::string> ok(allowed.begin(), allowed.end());
    for (const auto& item : value.items()) {
      if (!ok.count(item.key())) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        throw SceneError(
            fmt::format("{}: unknown key '{}' (expected one of: {})", origin,
                        escape_for_message((path.empty() ? "" : path + ".") + item.key()), list));
      }
    }
  }
  double number(double lo, double hi) const {
    if (!value.is_number()) fail(fmt::format("must be a number (got {})", value.type_name()));
    const double v = value.get<double>();
    if (!std::isfinite(v) || v < lo || v > hi) {
      fail(fmt::format("must be in [{}, {}] (got {})", lo, hi, v));
    }
    return v;
  }
  std::string string() const {
    if (!value.is_string()) fail(fmt::format("must be a string (got {})", value.type_name()));
    return value.get<std::string>();
  }
  glm::dvec3 vec3(double lo = -1e30, double hi = 1e30) const {
    if (!value.is_array() || value.size() != 3) {
      fail(fmt::format("must be an array of 3 numbers (got {})",
                       value.is_array() ? fmt::format("{} elements", value.size())
                                        : std::string(value.type_name())));
    }
    return {at(std::size_t{0}).number(lo, hi), at(std::size_t{1}).number(lo, hi),
            at(std::size_t{2}).number(lo, hi)};
  }
  const json& array() const {
    if (!value.is_array()) fail(fmt::format("must be an array (got {})", value.type_name()));
    return value;
  }
};

// Bounds every coordinate so that transformed positions stay finite in single precision.
constexpr double kMaxCoordinate = 1e15;

Mesh inline_mesh(const Node& node, const LoadLimits& limits, glm::vec3 color) {
  const Node vs = node.at("vertices");
  const Node ts = node.at("triangles");
  if (vs.array().size() > limits.max_vertices) {
    vs.fail(fmt::format("has {} vertices; the limit is {}", vs.value.size(), limits.max_vertices));
  }
  if (ts.array().size() > limits.max_triangles) {
    ts.fail(
        fmt::format("has {} triangles; the limit is {}", ts.value.size(), limits.max_triangles));
  }
  Mesh mesh;
  for (std::size_t i = 0; i < vs.value.size(); ++i) {
    Vertex v{};
    v.position = glm::vec3(vs.at(i).vec3(-kMaxCoordinate, kMaxCoordinate));
    v.color = color;
    mesh.vertices.push_back(v);
  }
  for (std::size_t i = 0; i < ts.value.size(); ++i) {
    const Node t = ts.at(i);
    if (!t.value.is_array() || t.value.size() != 3) t.fail("must be an array of 3 vertex indices");
    glm::uvec3 tri;
    for (int k = 0; k < 3; ++k) {
      const Node e = t.at(static_cast<std::size_t>(k));
      if (!e.value.is_number_integer()) e.fail("must be an integer vertex index");
      // Shown as written: 2^64 - 1 read as a signed number would print as -1.
      if (e.value.is_number_unsigned() ? e.value.get<std::uint64_t>() >= mesh.vertices.size()
                                       : e.value.get<std::int64_t>() < 0 ||
                                             e.value.get<std::uint64_t>() >= mesh.vertices.size()) {
        e.fail(fmt::format("is {}, outside [0, {})", e.value.dump(), mesh.vertices.size()));
      }
      tri[k] = e.value.get<unsigned>();
    }
    mesh.triangles.push_back(tri);
  }
  if (mesh.triangles.empty()) ts.fail("must hold at least one triangle");
  compute_smooth_normals(mesh);
  return mesh;
}

glm::dmat4 mesh_transform(const Node& m) {
  glm::dmat4 t(1.0);
  if (m.has("translate")) t = glm::translate(t, m.at("translate").vec3());
  if (m.has("rotate_degrees")) {
    const glm::dvec3 r = glm::radians(m.at("rotate_degrees").vec3(-36000, 36000));
    t = glm::rotate(t, r.z, glm::dvec3(0, 0, 1));
    t = glm::rotate(t, r.y, glm::dvec3(0, 1, 0));
    t = glm::rotate(t, r.x, glm::dvec3(1, 0, 0));
  }
  if (m.has("scale")) {
    const Node s = m.at("scale");
    const glm::dvec3 k =
        s.value.is_array() ? s.vec3(-1e12, 1e12) : glm::dvec3(s.number(-1e12, 1e12));
    if (k.x == 0 || k.y == 0 || k.z == 0) s.fail("must not be zero (it would flatten the mesh)");
    t = glm::scale(t, k);
  }
  return t;
}

void append(Mesh& scene_mesh, const Mesh& part, const glm::dmat4& transform, const Node& where,
            const LoadLimits& limits) {
  if (scene_mesh.vertices.size() + part.vertices.size() > limits.max_vertices ||
      scene_mesh.triangles.size() + part.triangles.size() > limits.max_triangles) {
    where.fail(fmt::format(
        "({} triangles, {} vertices) makes the scene {} triangles and {} vertices; a scene holds "
        "at most {} triangles and {} vertices (docs/inputs-and-outputs.md)",
        part.triangles.size(), part.vertices.size(),
        scene_mesh.triangles.size() + part.triangles.size(),
        scene_mesh.vertices.size() + part.vertices.size(), limits.max_triangles,
        limits.max_vertices));
  }
  const auto base = static_cast<unsigned>(scene_mesh.vertices.size());
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  // A mirroring transform turns the winding around; swap two corners to keep it.
  const bool mirrored = glm::determinant(glm::dmat3(transform)) < 0;
  for (const Vertex& v : part.vertices) {
    Vertex out = v;
    const glm::dvec3 p = glm::dvec3(transform * glm::dvec4(glm::dvec3(v.position), 1.0));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
        glm::length(p) > kMaxCoordinate * 1e3) {
      where.fail("places a vertex beyond the finite range");
    }
    out.position = glm::vec3(p);
    const glm::dvec3 n = normal_matrix * glm::dvec3(v.normal);
    out.normal = glm::length(n) > 0 ? glm::vec3(glm::normalize(n)) : v.normal;
    scene_mesh.vertices.push_back(out);
  }
  for (const glm::uvec3& t : part.triangles) {
    scene_mesh.triangles.push_back(mirrored ? glm::uvec3(t.x + base, t.z + base, t.y + base)
                                            : t + glm::uvec3(base));
  }
}

// A surface's material: its colour (absent: a mesh file's own colours, or 0.8 grey) and
// opacity.
struct Material {
  std::optional<glm::vec3> color;
  float opacity = 1.0f;
};

Material parse_material(const Node& m) {
  m.check_keys({"color", "opacity"});
  Material out;
  if (m.has("color")) out.color = glm::vec3(m.at("color").vec3(0.0, 1.0));
  if (m.has("opacity")) out.opacity = static_cast<float>(m.at("opacity").number(0, 1));
  return out;
}

// A mesh's "material" (a name from "materials" or an inline material) or its "color".
Material mesh_material(const Node& m, const std::map<std::string, Material>& materials) {
  if (m.has("material") && m.has("color")) {
    m.at("color").fail("cannot be given with 'material' (give the material a 'color')");
  }
  if (m.has("color")) return {glm::vec3(m.at("color").vec3(0.0, 1.0)), 1.0f};
  if (!m.has("material")) return {};
  const Node mat = m.at("material");
  if (mat.value.is_object()) return parse_material(mat);
  const std::string name = mat.string();
  const auto it = materials.find(name);
  if (it == materials.end()) {
    std::string known;
    for (const auto& [k, v] : materials) {
      known += (known.empty() ? "" : ", ") + escape_for_message(k);
      if (known.size() > 400) {
        known += ", ...";
        break;
      }
    }
    mat.fail(fmt::format("names an unknown material '{}' (the file's 'materials': {})",
                         escape_for_message(name), known.empty() ? "none" : known));
  }
  return it->second;
}

// One directional light; absent keys keep the standard key light's.
Light parse_light(const Node& l, const Camera& camera, bool allow_ambient) {
  if (allow_ambient) {
    l.check_keys({"direction", "ambient", "diffuse", "specular", "shininess"});
  } else {
    l.check_keys({"direction", "diffuse", "specular", "shininess"});
  }
  Light light = default_light(camera);
  if (l.has("direction")) {
    const glm::dvec3 d = l.at("direction").vec3();
    if (glm::length(d) == 0.0) l.at("direction").fail("must not be the zero vector");
    light.direction = glm::vec3(glm::normalize(d));
  }
  if (l.has("diffuse")) light.diffuse = static_cast<float>(l.at("diffuse").number(0, 1));
  if (l.has("specular")) light.specular = static_cast<float>(l.at("specular").number(0, 1));
  if (l.has("shininess")) light.shininess = static_cast<float>(l.at("shininess").number(1, 1024));
  return light;
}

}  // namespace

// One entry of "spheres": a sphere ("center", "radius", and "color" or an opaque "material")
// or a molecule file's atoms ("molecule", with "translate", "rotate_degrees" and a uniform
// "scale", which also scales the radii).
// A "csg" expression: a mesh name, or an object with one operator over two or more operands.
constexpr int kMaxCsgDepth = 32;
CsgNode parse_csg(const Node& n, const std::map<std::string, int>& solids,
                  const std::vector<std::string>& names, int depth) {
  if (depth > kMaxCsgDepth) n.fail(fmt::format("nests deeper than {} operators", kMaxCsgDepth));
  CsgNode node;
  if (n.value.is_string()) {
    const std::string name = n.value.get<std::string>();
    const auto it = solids.find(name);
    if (it == solids.end()) {
      std::string known;
      for (const std::string& k : names) {
        known += (known.empty() ? "" : ", ") + escape_for_message(k);
        if (known.size() > 400) {
          known += ", ...";
          break;
        }
      }
      n.fail(fmt::format("names no mesh '{}' (the named meshes: {})", escape_for_message(name),
                         names.empty() ? std::string("none; give a mesh a \"name\"") : known));
    }
    node.solid = it->second;
    return node;
  }
  if (!n.value.is_object()) {
    n.fail(
        fmt::format("must be a mesh name or an object with one of union, intersection, "
                    "difference (got {})",
                    n.value.type_name()));
  }
  n.check_keys({"union", "intersection", "difference"});
  if (n.value.size() != 1) {
    n.fail(fmt::format("must hold exactly one operator (got {})", n.value.size()));
  }
  const std::string op = n.value.begin().key();
  node.op = op == "union"          ? CsgNode::Op::union_
            : op == "intersection" ? CsgNode::Op::intersection
                                   : CsgNode::Op::difference;
  const Node operands = n.at(op);
  if (operands.array().size() < 2) {
    operands.fail(fmt::format("must hold at least two operands (got {})", operands.value.size()));
  }
  for (std::size_t k = 0; k < operands.value.size(); ++k) {
    node.operands.push_back(parse_csg(operands.at(k), solids, names, depth + 1));
  }
  return node;
}

void append_spheres(const Node& e, const std::map<std::string, Material>& materials,
                    const std::string& base_dir, std::vector<Sphere>& out) {
  if (e.has("molecule")) {
    e.check_keys({"molecule", "translate", "rotate_degrees", "scale"});
    if (e.has("scale") && !e.at("scale").value.is_number()) {
      e.at("scale").fail("must be a number (spheres scale uniformly)");
    }
    const double k = e.has("scale") ? e.at("scale").number(1e-6, 1e6) : 1.0;
    const glm::dmat4 t = mesh_transform(e);
    fs::path file = e.at("molecule").string();
    if (file.is_relative()) file = fs::path(base_dir) / file;
    for (Sphere s : read_molecule_file(file.string())) {
      s.center = glm::vec3(t * glm::dvec4(glm::dvec3(s.center), 1.0));
      s.radius = static_cast<float>(s.radius * k);
      out.push_back(s);
    }
    return;
  }
  e.check_keys({"center", "radius", "color", "material"});
  if (!e.has("center") || !e.has("radius")) {
    e.fail("needs 'center' and 'radius' (or 'molecule': a PDB or mmCIF file)");
  }
  const Material material = mesh_material(e, materials);
  if (material.opacity < 1.0f) e.fail("is a transparent material; spheres are opaque");
  Sphere s;
  s.center = glm::vec3(e.at("center").vec3());
  s.radius = static_cast<float>(e.at("radius").number(1e-6, 1e12));
  s.color = material.color.value_or(glm::vec3(0.8f));
  out.push_back(s);
}

Scene parse_scene_json(const std::string& text, const std::string& origin,
                       const std::string& base_dir, const LoadLimits& limits, SceneParts* parts) {
  json doc;
  try {
    // Syntax errors, numbers beyond double's range and duplicate keys (in the scene, its
    // materials, anywhere).
    doc = parse_strict_json(text, origin);
  } catch (const std::runtime_error& e) {
    throw SceneError(e.what());
  }
  const Node root{doc, "", origin};
  if (!doc.is_object()) {
    throw SceneError(
        fmt::format("{}: a scene file must be a JSON object (got {})", origin, doc.type_name()));
  }
  root.check_keys({"name", "description", "meshes", "spheres", "materials", "camera", "ambient",
                   "light", "lights", "background", "firmware", "parameters", "csg", "animation"});
  if (!root.has("meshes") && !root.has("spheres")) {
    throw SceneError(origin + ": missing key 'meshes' (an array of meshes) or 'spheres'");
  }
  static const json kNone = json::array();
  const Node meshes = root.has("meshes") ? root.at("meshes") : Node{kNone, "meshes", origin};
  if (root.has("meshes") && meshes.array().empty()) meshes.fail("must hold at least one mesh");

  Scene scene;
  scene.name = root.has("name") ? root.at("name").string() : fs::path(origin).stem().string();
  // The name becomes the default output folder, out/NAME: keep it a plain file name.
  const bool plain =
      !scene.name.empty() && scene.name[0] != '.' &&
      std::all_of(scene.name.begin(), scene.name.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.';
      });
  if (!plain && root.has("name")) {
    root.at("name").fail("must be a plain name of letters, digits, '-', '_' and '.'");
  }
  if (!plain) scene.name = "scene";
  scene.description = root.has("description") ? root.at("description").string()
                                              : fmt::format("scene file {}", origin);
  std::map<std::string, Material> materials;
  if (root.has("materials")) {
    const Node ms = root.at("materials");
    if (!ms.value.is_object()) {
      ms.fail(fmt::format("must be an object of named materials (got {})", ms.value.type_name()));
    }
    for (const auto& item : ms.value.items())
      materials[item.key()] = parse_material(ms.at(item.key()));
  }
  // A built-in mesh is made once per name, however often the file names it: the scene's
  // bound (append) is then checked before each copy, not after building it.
  std::map<std::string, Mesh> builtin_meshes;
  std::map<std::string, int> solid_index;  // named meshes: their solid
  std::vector<std::size_t> solid_mesh;     // each solid's mesh index
  for (std::size_t i = 0; i < meshes.value.size(); ++i) {
    const Node m = meshes.at(i);
    m.check_keys({"file", "builtin", "vertices", "triangles", "translate", "rotate_degrees",
                  "scale", "color", "material", "name"});
    const Material material = mesh_material(m, materials);
    const glm::vec3 color = material.color.value_or(glm::vec3(0.8f));
    const int sources = m.has("file") + m.has("builtin") + m.has("vertices");
    if (sources != 1) {
      m.fail("needs exactly one of 'file', 'builtin' or 'vertices' (with 'triangles')");
    }
    Mesh part;
    if (m.has("file")) {
      fs::path file = m.at("file").string();
      if (file.is_relative()) file = fs::path(base_dir) / file;
      part = load_mesh(file.string(), nullptr, limits, color);
    } else if (m.has("builtin")) {
      const std::string builtin = m.at("builtin").string();
      auto it = builtin_meshes.find(builtin);
      if (it == builtin_meshes.end()) {
        try {
          it = builtin_meshes.emplace(builtin, make_builtin_scene(builtin).mesh).first;
        } catch (const std::invalid_argument& e) {
          m.at("builtin").fail(e.what());
        }
      }
      part = it->second;
      if (material.color) {
        for (Vertex& v : part.vertices) v.color = color;
      }
    } else {
      if (!m.has("triangles")) m.fail("has 'vertices' but no 'triangles'");
      part = inline_mesh(m, limits, color);
    }
    for (Vertex& v : part.vertices) v.opacity = material.opacity;
    const int first = static_cast<int>(scene.mesh.triangles.size());
    const int first_vertex = static_cast<int>(scene.mesh.vertices.size());
    append(scene.mesh, part, mesh_transform(m), m, limits);
    if (parts != nullptr) {
      parts->mesh_vertices.emplace_back(first_vertex, static_cast<int>(scene.mesh.vertices.size()));
    }
    // A named mesh is a closed solid for point in solid and CSG.
    if (m.has("name")) {
      const std::string name = m.at("name").string();
      if (name.empty()) m.at("name").fail("must not be empty");
      if (const auto it = solid_index.find(name); it != solid_index.end()) {
        m.at("name").fail(fmt::format("repeats the name '{}' of mesh {}", escape_for_message(name),
                                      solid_mesh[static_cast<std::size_t>(it->second)]));
      }
      solid_index[name] = static_cast<int>(scene.solids.size());
      solid_mesh.push_back(i);
      scene.solids.push_back({name, first, static_cast<int>(scene.mesh.triangles.size())});
    }
  }
  if (root.has("csg")) {
    std::vector<std::string> names;
    for (const Solid& solid : scene.solids) names.push_back(solid.name);
    const Node csg = root.at("csg");
    const CsgNode tree = parse_csg(csg, solid_index, names, 0);
    try {
      scene.csg = normalise_csg(tree, names);
    } catch (const CsgError& e) {
      csg.fail(e.what());
    }
  }

  if (root.has("spheres")) {
    const Node spheres = root.at("spheres");
    if (spheres.array().empty()) spheres.fail("must hold at least one sphere");
    for (std::size_t i = 0; i < spheres.value.size(); ++i) {
      const int first_sphere = static_cast<int>(scene.spheres.size());
      append_spheres(spheres.at(i), materials, base_dir, scene.spheres);
      if (parts != nullptr) {
        parts->spheres.emplace_back(first_sphere, static_cast<int>(scene.spheres.size()));
      }
    }
  }

  if (root.has("camera")) {
    const Node c = root.at("camera");
    if (c.has("view_direction")) {
      c.check_keys({"view_direction", "fov_y_degrees"});
      const glm::dvec3 dir = c.at("view_direction").vec3();
      if (glm::length(glm::dvec2(dir.x, dir.z)) < 1e-6 * glm::length(dir) ||
          glm::length(dir) == 0) {
        c.at("view_direction").fail("must not be zero or parallel to the y axis");
      }
      const double fov = c.has("fov_y_degrees") ? c.at("fov_y_degrees").number(1, 170) : 40.0;
      scene.camera =
          frame_scene(scene.mesh, scene.spheres, glm::vec3(dir), static_cast<float>(fov));
    } else {
      c.check_keys({"eye", "target", "up", "fov_y_degrees", "near", "far"});
      for (const char* k : {"eye", "target", "near", "far"}) {
        if (!c.has(k))
          c.fail(fmt::format("needs '{}' (or 'view_direction' to frame the meshes)", k));
      }
      scene.camera.eye = glm::vec3(c.at("eye").vec3());
      scene.camera.target = glm::vec3(c.at("target").vec3());
      scene.camera.up = c.has("up") ? glm::vec3(c.at("up").vec3()) : glm::vec3(0, 1, 0);
      scene.camera.fov_y_degrees =
          c.has("fov_y_degrees") ? static_cast<float>(c.at("fov_y_degrees").number(1, 170)) : 40.f;
      scene.camera.near_plane = static_cast<float>(c.at("near").number(1e-9, 1e30));
      scene.camera.far_plane = static_cast<float>(c.at("far").number(1e-9, 1e30));
      if (!(scene.camera.far_plane > scene.camera.near_plane)) {
        c.at("far").fail("must be greater than 'near'");
      }
      const glm::vec3 back = scene.camera.eye - scene.camera.target;
      if (glm::length(back) == 0.0f) c.at("target").fail("must differ from 'eye'");
      if (glm::length(glm::cross(scene.camera.up, back)) == 0.0f) {
        c.at("up").fail("must not be zero or parallel to the view direction");
      }
    }
  } else {
    scene.camera = frame_scene(scene.mesh, scene.spheres, glm::vec3(0.3f, 0.4f, 1.0f), 40.0f);
  }

  if (root.has("light") && root.has("lights")) {
    root.at("lights").fail("cannot be given with 'light' (put that light in 'lights')");
  }
  const bool light_ambient = root.has("light") && root.at("light").has("ambient");
  if (light_ambient && root.has("ambient")) {
    root.at("ambient").fail("cannot be given with 'light.ambient'");
  }
  if (root.has("ambient")) scene.ambient = static_cast<float>(root.at("ambient").number(0, 1));
  if (light_ambient) {
    scene.ambient = static_cast<float>(root.at("light").at("ambient").number(0, 1));
  }
  if (root.has("lights")) {
    const Node ls = root.at("lights");
    const std::size_t n = ls.array().size();
    if (n < 1 || n > static_cast<std::size_t>(kMaxLights)) {
      ls.fail(fmt::format("holds {} lights; a scene has 1 to {}", n, kMaxLights));
    }
    for (std::size_t k = 0; k < n; ++k) {
      scene.lights.push_back(parse_light(ls.at(k), scene.camera, false));
    }
  } else if (root.has("light")) {
    scene.lights = {parse_light(root.at("light"), scene.camera, true)};
  } else {
    scene.lights = {default_light(scene.camera)};
  }
  scene.background = root.has("background") ? glm::vec3(root.at("background").vec3(0.0, 1.0))
                                            : glm::vec3(0.05f, 0.05f, 0.08f);
  if (root.has("firmware")) {
    const Node f = root.at("firmware");
    fs::path program = f.string();
    if (program.empty()) f.fail("must name a program (e.g. \"transparent\") or a .pp5 file");
    // A .pp5 path is relative to the scene file, like mesh files; a name is looked up in
    // firmware/programs.
    if (program.extension() == ".pp5" && program.is_relative()) {
      program = fs::path(base_dir) / program;
    }
    scene.firmware = program.string();
  }
  if (root.has("parameters")) {
    // Frame parameters by name, as --param takes them; the range of each is checked when the
    // frame is built (some depend on gp.depth_bits), the rest here.
    const Node ps = root.at("parameters");
    if (!ps.value.is_object()) {
      ps.fail(
          fmt::format("must be an object of frame parameters, e.g. {{\"threshold\": 8192}} "
                      "(got {})",
                      ps.value.type_name()));
    }
    for (const auto& item : ps.value.items()) {
      const Node v = ps.at(item.key());
      const int k = parameter_index(item.key());
      if (k < 0) v.fail("is not a frame parameter (pp5sim isa lists them)");
      if (frame_parameter_computed(static_cast<Parameter>(k))) {
        v.fail("cannot be set: the GP computes it (pp5sim isa says from what)");
      }
      if (!v.value.is_number_integer()) {
        v.fail(fmt::format("must be an integer (got {})", v.value.dump()));
      }
      if (v.value.is_number_unsigned() &&
          v.value.get<std::uint64_t>() > static_cast<std::uint64_t>(INT64_MAX)) {
        v.fail(
            fmt::format("is {}, out of range (no frame parameter reaches 2^63)", v.value.dump()));
      }
      scene.parameters[item.key()] = v.value.get<std::int64_t>();
    }
  }
  return scene;
}

Scene load_scene_file(const std::string& path, const LoadLimits& limits, SceneParts* parts,
                      std::string* text_out) {
  std::string text;
  try {
    // A scene file names its meshes; 16 MiB is far beyond any such list.
    text = read_regular_file(path, 16ull << 20, "a scene file (JSON)");
  } catch (const FileError& e) {
    throw SceneError(e.what());
  }
  const std::string base = fs::path(path).parent_path().string();
  Scene scene = parse_scene_json(text, path, base.empty() ? "." : base, limits, parts);
  if (text_out != nullptr) *text_out = std::move(text);
  return scene;
}

namespace {
Scene load_scene_unnoted(const std::string& name_or_path, const SceneOptions& options);
}  // namespace

Scene load_scene(const std::string& name_or_path, const SceneOptions& options) {
  Scene scene = load_scene_unnoted(name_or_path, options);
  // If memory runs out later, the message names this input and the bound (main.cpp).
  set_memory_note(fmt::format(
      "the scene {} holds {} triangles and {} spheres (a scene holds at most {} triangles; "
      "docs/inputs-and-outputs.md)",
      escape_for_message(name_or_path), scene.mesh.triangles.size(), scene.spheres.size(),
      kMaxSceneTriangles));
  return scene;
}

namespace {
Scene load_scene_unnoted(const std::string& name_or_path, const SceneOptions& options) {
  const fs::path p(name_or_path);
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool tessellated = options.tessellation_u != 0 || options.tessellation_v != 0;
  // A bare built-in name is the built-in scene, never a file or folder of that name in the
  // current directory (which once shadowed it and was then refused as "not a mesh file");
  // a file is named by a path (./torus) or its extension. The shadowing entry is said.
  {
    const std::vector<std::string> builtin = builtin_scene_names();
    if (name_or_path.find('/') == std::string::npos &&
        std::find(builtin.begin(), builtin.end(), name_or_path) != builtin.end()) {
      std::error_code error;
      if (fs::exists(name_or_path, error)) {
        std::cerr << fmt::format(
            "warning: '{}' is the built-in scene; the {} of that name in the current "
            "directory is not read (name it ./{} to use it)\n",
            name_or_path, fs::is_directory(name_or_path, error) ? "folder" : "file", name_or_path);
      }
      return make_builtin_scene(name_or_path, options);
    }
  }
  if (tessellated && (ext == ".json" || is_mesh_file(name_or_path))) {
    throw std::invalid_argument(fmt::format(
        "--tessellation: {} is a file, whose geometry is its own; only the built-in torus, "
        "sphere and figure-eight take a tessellation",
        name_or_path));
  }
  if (ext == ".json") return load_scene_file(name_or_path);
  if (ext == ".pdb" || ext == ".ent" || ext == ".cif" || ext == ".mmcif") {
    // A molecule file: its atoms as spheres, framed like a mesh file.
    if (tessellated) throw std::invalid_argument("--tessellation: a molecule file takes none");
    Scene scene;
    scene.name = p.stem().string();
    scene.spheres = read_molecule_file(name_or_path);
    scene.description =
        fmt::format("molecule file {} ({} atoms)", name_or_path, scene.spheres.size());
    scene.camera = frame_scene(scene.mesh, scene.spheres, glm::vec3(0.3f, 0.4f, 1.0f), 40.0f);
    scene.lights = {default_light(scene.camera)};
    scene.background = glm::vec3(0.05f, 0.05f, 0.08f);
    return scene;
  }
  if (is_mesh_file(name_or_path)) {
    MeshLoadReport report;
    Mesh mesh = load_mesh(name_or_path, &report);
    return scene_from_mesh(
        std::move(mesh), p.stem().string(),
        fmt::format("mesh file {} ({} faces, {} triangulated, {} degenerate dropped, {} "
                    "non-manifold edges{})",
                    name_or_path, report.polygons, report.triangulated, report.dropped_degenerate,
                    report.non_manifold_edges,
                    report.ignored_statements
                        ? fmt::format(", {} points, lines and empty faces ignored",
                                      report.ignored_statements)
                        : ""));
  }
  // A path that is neither a mesh nor a scene file (a folder, a device, another format) is
  // named as such rather than looked up as a built-in scene.
  std::error_code error;
  if (name_or_path.find('/') != std::string::npos || fs::exists(name_or_path, error)) {
    throw std::invalid_argument(fmt::format(
        "{}: not a mesh file (.obj .ply .stl .off) or a scene file (.json), nor a built-in scene",
        name_or_path));
  }
  try {
    return make_builtin_scene(name_or_path, options);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format(
        "{} (or give a mesh file .obj .ply .stl .off, or a scene file .json)", e.what()));
  }
}

}  // namespace

}  // namespace pp5
