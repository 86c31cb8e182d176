#include "sim/analysis/csg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <stdexcept>

#include "common/parallel_for.hpp"
#include "models/gp/pass_plan.hpp"
#include "models/gp/sphere.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/scene/csg_expression.hpp"
#include "sim/scene/sphere_scenes.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

void add_quad(Mesh& mesh, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 color) {
  const auto base = static_cast<unsigned>(mesh.vertices.size());
  for (const glm::vec3& p : {a, b, c, d}) mesh.vertices.push_back({p, glm::vec3(0, 1, 0), color});
  mesh.triangles.emplace_back(base, base + 1, base + 2);
  mesh.triangles.emplace_back(base, base + 2, base + 3);
}

// A closed box: centre, half extents, turned by `degrees` about y; 12 triangles.
void add_box(Mesh& mesh, glm::vec3 centre, glm::vec3 half, float degrees,
             glm::vec3 color = glm::vec3(0.8f)) {
  const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0, 1, 0));
  auto corner = [&](int i) {
    const glm::vec3 s((i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f);
    return centre + glm::vec3(turn * glm::vec4(s * half, 1.0f));
  };
  const auto base = static_cast<unsigned>(mesh.vertices.size());
  for (int i = 0; i < 8; ++i) mesh.vertices.push_back({corner(i), glm::vec3(0, 1, 0), color});
  // Faces wound outward, corners by bit (x, y, z).
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
    mesh.triangles.emplace_back(base + f[0], base + f[2], base + f[3]);
  }
}

// The tilted plane of points: y = sx x + sz z + c over [-e, e]^2, two triangles.
void add_plane(Mesh& mesh, float sx, float sz, float c, float e) {
  auto at = [&](float x, float z) { return glm::vec3(x, sx * x + sz * z + c, z); };
  add_quad(mesh, at(-e, -e), at(-e, e), at(e, e), at(e, -e), glm::vec3(0.75f, 0.75f, 0.8f));
}

// A closed ring torus about the y axis turned by `degrees` about x: radii R and r, 48 x 16
// quads.
void add_torus(Mesh& mesh, float big, float small, float degrees, glm::vec3 color) {
  const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(1, 0, 0));
  const int nu = 48, nv = 16;
  const auto base = static_cast<unsigned>(mesh.vertices.size());
  for (int i = 0; i < nu; ++i) {
    const float u = 6.2831853f * static_cast<float>(i) / nu;
    for (int j = 0; j < nv; ++j) {
      const float v = 6.2831853f * static_cast<float>(j) / nv;
      const glm::vec3 p((big + small * std::cos(v)) * std::cos(u), small * std::sin(v),
                        (big + small * std::cos(v)) * std::sin(u));
      mesh.vertices.push_back({glm::vec3(turn * glm::vec4(p, 1.0f)), glm::vec3(0, 1, 0), color});
    }
  }
  auto at = [&](int i, int j) { return base + static_cast<unsigned>((i % nu) * nv + j % nv); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
}

}  // namespace

std::vector<std::string> parity_scene_names() { return {"plane-sphere", "plane-boxes"}; }

std::vector<std::string> epsilon_scene_names() {
  return {"plane-sphere", "plane-boxes", "plane-slab", "plane-in-box", "plane-over-box"};
}

std::vector<std::string> interference_scene_names() {
  return {"boxes-overlap", "boxes-apart", "boxes-touching"};
}

std::vector<std::string> section_scene_names() { return {"section-sphere", "section-torus"}; }

std::vector<std::string> csg_scene_names() {
  return {"box-minus-ball", "ball-and-ball", "box-or-ball", "box-minus-two", "pair-minus-bar"};
}

std::vector<std::string> csg_quadric_scene_names() { return {"box-minus-quadric", "quadric-lens"}; }

Scene make_parity_scene(const std::string& name) {
  Mesh mesh;
  std::vector<Solid> solids;
  auto solid = [&](const std::string& n, auto&& add) {
    const int first = static_cast<int>(mesh.triangles.size());
    add();
    solids.push_back({n, first, static_cast<int>(mesh.triangles.size())});
  };
  std::string description;
  CsgProducts csg;
  const glm::vec3 sand(0.85f, 0.7f, 0.45f), teal(0.3f, 0.65f, 0.7f), rose(0.8f, 0.4f, 0.45f);
  auto ball = [&](const std::string& n, glm::vec3 centre, float radius, glm::vec3 color) {
    solid(n, [&] { append_tessellated_spheres({Sphere{centre, radius, color}}, 24, 12, mesh); });
  };
  // A solid that is one quadric sphere, drawn by the quadratic evaluator.
  std::vector<Sphere> spheres;
  auto quadric = [&](const std::string& n, glm::vec3 centre, float radius, glm::vec3 color) {
    const int t = static_cast<int>(mesh.triangles.size());
    const int i = static_cast<int>(spheres.size());
    spheres.push_back(Sphere{centre, radius, color});
    solids.push_back({n, t, t, i, i + 1});
  };
  const CsgLiteral a{0, false}, b{1, false}, not_b{1, true}, not_c{2, true};
  // The two quadric scenes are box-minus-ball and ball-and-ball with quadric spheres.
  const bool quadrics = name == "box-minus-quadric" || name == "quadric-lens";
  auto round = [&](const std::string& n, glm::vec3 centre, float radius, glm::vec3 color) {
    if (quadrics) {
      quadric(n, centre, radius, color);
    } else {
      ball(n, centre, radius, color);
    }
  };
  if (name == "box-minus-ball" || name == "box-minus-quadric") {
    description = quadrics ? "box-minus-ball with a quadric sphere for the ball (a & !b)"
                           : "a box minus a ball that bites its top corner (a & !b)";
    solid("box", [&] { add_box(mesh, {0.0f, 0.0f, 0.0f}, {0.8f, 0.6f, 0.7f}, 20.0f, sand); });
    round("ball", {0.45f, 0.55f, 0.4f}, 0.6f, teal);
    csg = {{a, not_b}};
  } else if (name == "ball-and-ball" || name == "quadric-lens") {
    description = quadrics ? "ball-and-ball with quadric spheres (a & b)"
                           : "the lens where two balls overlap (a & b)";
    round("left", {-0.35f, 0.0f, 0.0f}, 0.8f, sand);
    round("right", {0.35f, 0.1f, 0.1f}, 0.7f, teal);
    csg = {{a, b}};
  } else if (name == "box-or-ball") {
    description = "a box and a ball through it (a | b)";
    solid("box", [&] { add_box(mesh, {-0.2f, 0.0f, 0.0f}, {0.7f, 0.4f, 0.6f}, 20.0f, sand); });
    ball("ball", {0.5f, 0.2f, 0.2f}, 0.55f, teal);
    csg = {{a}, {b}};
  } else if (name == "box-minus-two") {
    description = "a box minus a ball and a bar through it (a & !b & !c)";
    solid("box", [&] { add_box(mesh, {0.0f, 0.0f, 0.0f}, {0.8f, 0.5f, 0.7f}, 20.0f, sand); });
    ball("ball", {-0.4f, 0.5f, 0.3f}, 0.5f, teal);
    solid("bar", [&] { add_box(mesh, {0.35f, 0.1f, 0.0f}, {0.2f, 0.9f, 0.25f}, 35.0f, rose); });
    csg = {{a, not_b, not_c}};
  } else if (name == "pair-minus-bar") {
    description =
        "two slabs, one solid (not convex), minus a bar through the upper one only (a & !b)";
    solid("slabs", [&] {
      add_box(mesh, {0.0f, 0.45f, 0.0f}, {0.8f, 0.15f, 0.7f}, 0.0f, sand);
      add_box(mesh, {0.0f, -0.45f, 0.0f}, {0.8f, 0.15f, 0.7f}, 0.0f, sand);
    });
    solid("bar", [&] { add_box(mesh, {0.1f, 0.5f, 0.1f}, {0.3f, 0.35f, 0.3f}, 10.0f, rose); });
    csg = {{a, not_b}};
  } else if (name == "section-sphere" || name == "section-torus") {
    // A plane tilted across the solid, 1.9 each way: wider than the solid's outline.
    description = name == "section-sphere"
                      ? "a closed tessellated sphere (24 x 12) cut by a tilted plane"
                      : "a closed ring torus (48 x 16, not convex) cut by a tilted plane";
    add_plane(mesh, 0.3f, -0.25f, 0.15f, 1.9f);
    if (name == "section-sphere") {
      ball("ball", glm::vec3(0.0f), 1.0f, sand);
    } else {
      solid("torus", [&] { add_torus(mesh, 0.75f, 0.3f, 30.0f, sand); });
    }
  } else if (name == "plane-sphere") {
    description = "a tilted plane of points through a closed tessellated sphere (24 x 12)";
    add_plane(mesh, 0.25f, 0.2f, 0.1f, 1.8f);
    solid("ball", [&] {
      append_tessellated_spheres({Sphere{glm::vec3(0.0f), 1.0f}}, 24, 12, mesh);
    });
  } else if (name == "plane-boxes") {
    description = "a tilted plane of points through two overlapping closed boxes";
    add_plane(mesh, 0.15f, 0.3f, 0.05f, 2.0f);
    solid("box-a", [&] { add_box(mesh, {-0.4f, 0.0f, 0.0f}, {0.8f, 0.6f, 0.6f}, 20.0f); });
    solid("box-b", [&] { add_box(mesh, {0.5f, 0.1f, 0.1f}, {0.6f, 0.7f, 0.5f}, -15.0f); });
  } else if (name == "plane-slab") {
    description = "the plane of plane-boxes through a slab 0.008 thick, 6 degrees off the plane";
    add_plane(mesh, 0.15f, 0.3f, 0.05f, 2.0f);
    solid("slab", [&] {
      const glm::vec3 n = glm::normalize(glm::vec3(-0.15f, 1.0f, -0.3f) + glm::vec3(0.1f, 0, 0));
      const glm::vec3 u = glm::normalize(glm::cross(n, glm::vec3(0, 0, 1)));
      const glm::vec3 v = glm::cross(n, u);
      const glm::vec3 c(0.3f, 0.15f * 0.3f + 0.3f * 0.2f + 0.05f, 0.2f);
      const auto base = static_cast<unsigned>(mesh.vertices.size());
      for (int i = 0; i < 8; ++i) {
        const glm::vec3 p = c + ((i & 1) ? 0.8f : -0.8f) * u + ((i & 2) ? 0.8f : -0.8f) * v +
                            ((i & 4) ? 0.004f : -0.004f) * n;
        mesh.vertices.push_back({p, n, glm::vec3(0.8f)});
      }
      const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                               {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
      for (const auto& f : faces) {
        mesh.triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
        mesh.triangles.emplace_back(base + f[0], base + f[2], base + f[3]);
      }
    });
  } else if (name == "box-minus-apart") {
    description =
        "box-minus-ball, also minus a bar apart from the box, or the bar and the ball (which "
        "never meet): (a & !b & !c) | (c & b)";
    solid("box", [&] { add_box(mesh, {0.0f, 0.0f, 0.0f}, {0.8f, 0.6f, 0.7f}, 20.0f, sand); });
    ball("ball", {0.45f, 0.55f, 0.4f}, 0.6f, teal);
    solid("bar", [&] { add_box(mesh, {-1.6f, -0.2f, 0.2f}, {0.2f, 0.5f, 0.2f}, 0.0f, rose); });
    csg = {{a, not_b, not_c}, {CsgLiteral{2, false}, b}};
  } else if (name == "plane-in-box" || name == "plane-over-box") {
    // The points lie 0.001 below the box's top face or 0.0005 above it (along the rays, less
    // than the default epsilon in depth): inside a thick solid near its surface, or just
    // outside it (nearly coincident faces, Rossignac's figure 9.4).
    const bool in = name == "plane-in-box";
    description = in ? "a level plane of points 0.001 inside a thick box, below its top face"
                     : "a level plane of points 0.0005 above a thick box's top face";
    add_plane(mesh, 0.0f, 0.0f, in ? 0.499f : 0.5005f, 1.3f);
    solid("box", [&] { add_box(mesh, {0.0f, 0.0f, 0.0f}, {0.8f, 0.5f, 0.7f}, 20.0f, sand); });
  } else if (name == "boxes-overlap" || name == "boxes-apart" || name == "boxes-touching") {
    // Two boxes side by side along x; the second starts 0.3 inside the first, 0.1 past it, or
    // 0.0002 past it (closer than the default epsilon along the rays through both).
    const float gap = name == "boxes-overlap" ? -0.3f : name == "boxes-apart" ? 0.1f : 0.0002f;
    description = fmt::format("two closed boxes side by side, {} apart along x", gap);
    solid("left", [&] { add_box(mesh, {-0.6f, 0.0f, 0.0f}, {0.6f, 0.5f, 0.5f}, 0.0f); });
    solid("right", [&] { add_box(mesh, {0.6f + gap, 0.1f, 0.1f}, {0.6f, 0.5f, 0.5f}, 0.0f); });
  } else {
    // Every scene this function makes, not only the defaults of one application.
    std::vector<std::string> all = parity_scene_names();
    all.push_back("plane-slab");
    for (const std::string& n : interference_scene_names()) all.push_back(n);
    for (const std::string& n : csg_scene_names()) all.push_back(n);
    for (const std::string& n : csg_quadric_scene_names()) all.push_back(n);
    all.push_back("box-minus-apart");
    for (const std::string& n : section_scene_names()) all.push_back(n);
    for (const std::string& n : epsilon_scene_names()) {
      if (std::find(all.begin(), all.end(), n) == all.end()) all.push_back(n);
    }
    throw std::invalid_argument(
        fmt::format("no parity scene '{}' (there are: {})", name, fmt::join(all, ", ")));
  }
  compute_smooth_normals(mesh);
  Scene scene;
  scene.name = name;
  scene.description = description;
  // Framed with the quadric spheres as tessellated stand-ins.
  Mesh framed = mesh;
  append_tessellated_spheres(spheres, 24, 12, framed);
  scene.camera = frame_mesh(framed, glm::vec3(0.3f, 1.6f, 1.0f), 40.0f, 0.8f);
  scene.mesh = std::move(mesh);
  scene.spheres = std::move(spheres);
  scene.lights = {default_light(scene.camera)};
  scene.background = glm::vec3(0.05f, 0.05f, 0.08f);
  scene.solids = std::move(solids);
  scene.csg = std::move(csg);
  return scene;
}

namespace {

struct Ray {
  glm::dvec3 origin, direction;
};

// The solid of each triangle of the mesh (-1: none).
std::vector<int> solid_of_triangles(const Scene& scene) {
  std::vector<int> out(scene.mesh.triangles.size(), -1);
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    for (int t = scene.solids[s].first; t < scene.solids[s].last; ++t)
      out[static_cast<std::size_t>(t)] = static_cast<int>(s);
  }
  return out;
}

struct Caster {
  const Scene& scene;
  glm::dmat4 to_clip;  // world to clip space, the GP's camera
  glm::dmat4 inverse;
  int width, height;
  std::vector<int> solid_of;  // per triangle

  Caster(const MachineConfig& config, const Scene& s)
      : scene(s),
        width(config.screen.width),
        height(config.screen.height),
        solid_of(solid_of_triangles(s)) {
    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    to_clip = glm::dmat4(projection_matrix(s.camera, aspect)) * glm::dmat4(view_matrix(s.camera));
    inverse = glm::inverse(to_clip);
  }

  Ray ray(double x, double y) const {
    const double nx = x / width * 2.0 - 1.0, ny = 1.0 - y / height * 2.0;
    glm::dvec4 a = inverse * glm::dvec4(nx, ny, -1.0, 1.0);
    glm::dvec4 b = inverse * glm::dvec4(nx, ny, 1.0, 1.0);
    const glm::dvec3 p = glm::dvec3(a) / a.w, q = glm::dvec3(b) / b.w;
    return {p, q - p};
  }

  // Moller-Trumbore: the ray parameter of the hit (t > 0), or -1; `edge` is set when the hit
  // lies within 1e-9 of an edge.
  double hit(const Ray& r, int t, bool& edge) const {
    const glm::uvec3 tri = scene.mesh.triangles[static_cast<std::size_t>(t)];
    const glm::dvec3 v0(scene.mesh.vertices[tri.x].position);
    const glm::dvec3 v1(scene.mesh.vertices[tri.y].position);
    const glm::dvec3 v2(scene.mesh.vertices[tri.z].position);
    const glm::dvec3 e1 = v1 - v0, e2 = v2 - v0;
    const glm::dvec3 p = glm::cross(r.direction, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) return -1;
    const glm::dvec3 s = r.origin - v0;
    const double u = glm::dot(s, p) / det;
    const glm::dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(r.direction, q) / det;
    const double w = 1.0 - u - v;
    if (u < -1e-9 || v < -1e-9 || w < -1e-9) return -1;
    const double tt = glm::dot(e2, q) / det;
    if (tt <= 0) return -1;
    if (u < 1e-9 || v < 1e-9 || w < 1e-9) edge = true;
    return tt;
  }

  // -1 no point, else 1 if inside any solid, 0 if not.
  int classify(double x, double y, bool& edge) const {
    const Ray r = ray(x, y);
    double point = -1;
    const int n = static_cast<int>(scene.mesh.triangles.size());
    for (int t = 0; t < n; ++t) {
      if (solid_of[static_cast<std::size_t>(t)] >= 0) continue;
      bool e = false;
      const double h = hit(r, t, e);
      if (h > 0 && (point < 0 || h < point)) point = h;
    }
    if (point < 0) return -1;
    std::vector<int> parity(scene.solids.size(), 0);
    for (int t = 0; t < n; ++t) {
      const int s = solid_of[static_cast<std::size_t>(t)];
      if (s < 0) continue;
      const double h = hit(r, t, edge);
      if (h > point) parity[static_cast<std::size_t>(s)] ^= 1;
    }
    return std::any_of(parity.begin(), parity.end(), [](int p) { return p != 0; }) ? 1 : 0;
  }
};

}  // namespace

ParityReference parity_reference(const MachineConfig& config, const Scene& scene, double margin) {
  const Caster caster(config, scene);
  ParityReference ref;
  ref.width = caster.width;
  ref.height = caster.height;
  const auto pixels = static_cast<std::size_t>(ref.width) * static_cast<std::size_t>(ref.height);
  ref.inside.assign(pixels, -1);
  ref.uncertain.assign(pixels, 0);
  for (int y = 0; y < ref.height; ++y) {
    for (int x = 0; x < ref.width; ++x) {
      const double cx = x + 0.5, cy = y + 0.5;
      bool edge = false;
      const int c = caster.classify(cx, cy, edge);
      bool differs = false;
      for (const auto& [dx, dy] : {std::pair{margin, 0.0}, std::pair{-margin, 0.0},
                                   std::pair{0.0, margin}, std::pair{0.0, -margin}}) {
        bool e = false;
        differs = differs || caster.classify(cx + dx, cy + dy, e) != c;
      }
      const std::size_t i = static_cast<std::size_t>(y) * ref.width + x;
      ref.inside[i] = static_cast<std::int8_t>(c);
      ref.uncertain[i] = (differs || edge) ? 1 : 0;
    }
  }
  return ref;
}

ParityMeasure measure_parity(const MachineConfig& config, const Scene& scene,
                             const Program& program, int threads) {
  if (!program.procedure(Procedure::parity).defined) {
    throw std::invalid_argument(
        fmt::format("{}: point in solid needs a program that defines 'parity'", program.name));
  }
  ParityMeasure m;
  m.scene = scene.name;
  m.program = program.name;
  const FieldFrame field = render_field(config, scene, program, "inside", threads);
  const ParityReference ref = parity_reference(config, scene);
  m.image = field.image;
  m.difference.width = ref.width;
  m.difference.height = ref.height;
  m.difference.rgb.assign(ref.inside.size() * 3, 0);
  for (std::size_t i = 0; i < ref.inside.size(); ++i) {
    std::uint8_t shade = 0;
    if (ref.uncertain[i]) {
      ++m.uncertain;
      shade = 96;
      m.edge_disagree += (field.values[i] != 0) != (ref.inside[i] == 1);
    } else {
      ++m.compared;
      m.points += ref.inside[i] >= 0;
      m.inside += ref.inside[i] == 1;
      const bool machine = field.values[i] != 0;
      m.machine_inside += machine;
      if (machine != (ref.inside[i] == 1)) {
        ++m.disagree;
        ++(machine ? m.gained : m.lost);
        shade = 255;
      }
    }
    for (int k = 0; k < 3; ++k) m.difference.rgb[i * 3 + k] = shade;
  }
  const std::size_t passes = make_pass_plan(program, scene).size();
  m.passes = passes == 0 ? 1 : static_cast<int>(passes);
  m.bits = program.bits_used();
  m.cost = frame_cost(config, scene, program, threads);
  return m;
}

namespace {

// The solids' triangles binned by the screen tiles their projected bounding box (grown by a
// pixel for round-off) touches, each bin in increasing triangle order. A ray through a screen point
// meets only triangles whose projection contains that point, so its bin holds every triangle it can
// hit. A triangle with a corner at or behind the eye's plane goes to every bin.
class ScreenBins {
 public:
  ScreenBins(const Scene& scene, const glm::dmat4& to_clip, int width, int height)
      : tiles_x_((width + kTile - 1) / kTile), tiles_y_((height + kTile - 1) / kTile) {
    bins_.resize(static_cast<std::size_t>(tiles_x_) * tiles_y_);
    for (const Solid& solid : scene.solids) {
      for (int t = solid.first; t < solid.last; ++t) {
        const glm::uvec3 tri = scene.mesh.triangles[static_cast<std::size_t>(t)];
        double lo_x = kHuge, lo_y = kHuge, hi_x = -kHuge, hi_y = -kHuge;
        bool behind = false;
        for (int k = 0; k < 3; ++k) {
          const glm::dvec4 c =
              to_clip * glm::dvec4(glm::dvec3(scene.mesh.vertices[tri[k]].position), 1.0);
          if (!(c.w > 1e-9)) {
            behind = true;
            break;
          }
          const double x = (c.x / c.w + 1.0) * 0.5 * width, y = (1.0 - c.y / c.w) * 0.5 * height;
          lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
          lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
        }
        const double grow = 1.0;
        int x0 = 0, x1 = tiles_x_ - 1, y0 = 0, y1 = tiles_y_ - 1;
        if (!behind) {
          if (hi_x < -grow || hi_y < -grow || lo_x > width + grow || lo_y > height + grow) continue;
          x0 = std::clamp(static_cast<int>(std::floor((lo_x - grow) / kTile)), 0, tiles_x_ - 1);
          x1 = std::clamp(static_cast<int>(std::floor((hi_x + grow) / kTile)), 0, tiles_x_ - 1);
          y0 = std::clamp(static_cast<int>(std::floor((lo_y - grow) / kTile)), 0, tiles_y_ - 1);
          y1 = std::clamp(static_cast<int>(std::floor((hi_y + grow) / kTile)), 0, tiles_y_ - 1);
        }
        for (int ty = y0; ty <= y1; ++ty) {
          for (int tx = x0; tx <= x1; ++tx)
            bins_[static_cast<std::size_t>(ty) * tiles_x_ + tx].push_back(t);
        }
      }
    }
  }
  // The triangles a ray through screen point (x, y) may meet.
  const std::vector<int>& at(double x, double y) const {
    const int tx = std::clamp(static_cast<int>(std::floor(x / kTile)), 0, tiles_x_ - 1);
    const int ty = std::clamp(static_cast<int>(std::floor(y / kTile)), 0, tiles_y_ - 1);
    return bins_[static_cast<std::size_t>(ty) * tiles_x_ + tx];
  }

 private:
  static constexpr int kTile = 16;
  static constexpr double kHuge = std::numeric_limits<double>::max();
  int tiles_x_, tiles_y_;
  std::vector<std::vector<int>> bins_;
};

// csg_first_surface over the given triangles of the solids (every one the ray may meet).
CsgSurface first_surface(const Scene& scene, const std::vector<int>& solid_of,
                         const std::vector<int>& triangles, glm::dvec3 origin,
                         glm::dvec3 direction) {
  struct Hit {
    double t;
    int solid, triangle;
  };
  std::vector<Hit> hits;
  std::vector<bool> inside(scene.solids.size(), false);
  for (const int t : triangles) {
    const int s = solid_of[static_cast<std::size_t>(t)];
    const glm::uvec3 tri = scene.mesh.triangles[static_cast<std::size_t>(t)];
    const glm::dvec3 v0(scene.mesh.vertices[tri.x].position);
    const glm::dvec3 e1 = glm::dvec3(scene.mesh.vertices[tri.y].position) - v0;
    const glm::dvec3 e2 = glm::dvec3(scene.mesh.vertices[tri.z].position) - v0;
    const glm::dvec3 p = glm::cross(direction, e2);
    const double det = glm::dot(e1, p);
    if (det == 0) continue;
    const glm::dvec3 o = origin - v0;
    const double u = glm::dot(o, p) / det;
    const glm::dvec3 q = glm::cross(o, e1);
    const double v = glm::dot(direction, q) / det;
    if (u < 0 || v < 0 || u + v > 1) continue;
    const double h = glm::dot(e2, q) / det;
    if (h <= 0) continue;
    hits.push_back({h, s, t});
    inside[static_cast<std::size_t>(s)] = !inside[static_cast<std::size_t>(s)];  // odd: inside
  }
  // The quadric spheres of solids, met exactly: each crossing of the surface is a hit, as a
  // face's is ("triangle" -1 - i for sphere i).
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    for (int i = scene.solids[s].first_sphere; i < scene.solids[s].last_sphere; ++i) {
      const Sphere& sphere = scene.spheres[static_cast<std::size_t>(i)];
      const glm::dvec3 o = origin - glm::dvec3(sphere.center);
      const double a = glm::dot(direction, direction), b = glm::dot(o, direction);
      const double disc = b * b - a * (glm::dot(o, o) - double{sphere.radius} * sphere.radius);
      if (!(disc > 0)) continue;  // missed, or grazing: no crossing
      const double root = std::sqrt(disc);
      for (const double h : {(-b - root) / a, (-b + root) / a}) {
        if (h <= 0) continue;
        hits.push_back({h, static_cast<int>(s), -1 - i});
        inside[s] = !inside[s];
      }
    }
  }
  std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) {
    return a.t != b.t ? a.t < b.t : a.triangle < b.triangle;
  });
  bool in = csg_contains(scene.csg, inside);
  for (const Hit& h : hits) {
    inside[static_cast<std::size_t>(h.solid)] = !inside[static_cast<std::size_t>(h.solid)];
    const bool now = csg_contains(scene.csg, inside);
    if (now && !in) return {h.t, h.solid, h.triangle};
    in = now;
  }
  return {};
}

}  // namespace

CsgSurface csg_first_surface(const Scene& scene, glm::dvec3 origin, glm::dvec3 direction) {
  std::vector<int> all;
  for (const Solid& solid : scene.solids) {
    for (int t = solid.first; t < solid.last; ++t) all.push_back(t);
  }
  return first_surface(scene, solid_of_triangles(scene), all, origin, direction);
}

std::vector<int> csg_reference(const MachineConfig& config, const Scene& scene) {
  const Caster caster(config, scene);
  const ScreenBins bins(scene, caster.to_clip, caster.width, caster.height);
  std::vector<int> out(static_cast<std::size_t>(caster.width) * caster.height, -1);
  for (int y = 0; y < caster.height; ++y) {
    for (int x = 0; x < caster.width; ++x) {
      const Ray r = caster.ray(x + 0.5, y + 0.5);
      out[static_cast<std::size_t>(y) * caster.width + x] =
          first_surface(scene, caster.solid_of, bins.at(x + 0.5, y + 0.5), r.origin, r.direction)
              .solid;
    }
  }
  return out;
}

namespace {

// The machine's `z` rendered from `drawn` against the ray caster's first surface of `truth`'s
// expression (the same camera); `truth_solid`, if given, gets per pixel the visible solid of
// the truth at the centre (-1 none), or -2 where the pixel is not compared.
CsgMeasure compare_first_surface(const MachineConfig& config, const Scene& drawn,
                                 const Scene& truth, const Program& program, int threads,
                                 double margin, std::vector<int>* truth_solid) {
  CsgMeasure m;
  m.scene = drawn.name;
  m.program = program.name;
  std::vector<std::string> names;
  for (const Solid& s : truth.solids) names.push_back(s.name);
  m.expression = format_csg(truth.csg, names);
  const FieldFrame field = render_field(config, drawn, program, "z", threads);
  m.image = field.image;
  const Caster caster(config, truth);
  const glm::dmat4& to_clip = caster.to_clip;
  const double depth_max = std::ldexp(1.0, config.gp.depth_bits) - 1.0;
  const std::int64_t background = (std::int64_t{1} << config.gp.depth_bits) - 1;
  // The first surface at a screen point: its solid and depth in the GP's units.
  struct Seen {
    int solid;
    int triangle;
    double depth;
  };
  // The depth bound of each quadric sphere (ScreenSphere::depth_bound; both hemispheres').
  std::vector<double> sphere_bound(truth.spheres.size(), 0.0);
  const SphereProjector projector(geometry_params(config), truth.camera);
  for (std::size_t i = 0; i < truth.spheres.size(); ++i) {
    ScreenSphere screen;
    SetupCounts counts;
    if (projector.project(truth.spheres[i], static_cast<int>(i), screen, counts)) {
      sphere_bound[i] = screen.depth_bound;
    }
  }
  const ScreenBins bins(truth, to_clip, caster.width, caster.height);
  auto seen_at = [&](double x, double y) {
    const Ray r = caster.ray(x, y);
    const CsgSurface s =
        first_surface(truth, caster.solid_of, bins.at(x, y), r.origin, r.direction);
    if (s.solid < 0) return Seen{-1, -1, 0.0};
    const glm::dvec4 c = to_clip * glm::dvec4(r.origin + s.t * r.direction, 1.0);
    return Seen{s.solid, s.triangle, (c.z / c.w * 0.5 + 0.5) * depth_max};
  };
  // Whether the surface seen at `b` continues the one seen at `a`: the same solid, and the
  // same triangle or one touching it (a vertex in common). Otherwise an outline passes
  // between them: of a solid, of the seam of two, or of one part of a solid over another.
  auto continues = [&](const Seen& a, const Seen& b) {
    if (a.solid != b.solid) return false;
    if (a.solid < 0 || a.triangle == b.triangle) return true;
    if (a.triangle < 0 || b.triangle < 0) return false;  // a sphere and a face
    const glm::uvec3 s = truth.mesh.triangles[static_cast<std::size_t>(a.triangle)];
    const glm::uvec3 t = truth.mesh.triangles[static_cast<std::size_t>(b.triangle)];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        if (truth.mesh.vertices[s[i]].position == truth.mesh.vertices[t[j]].position) return true;
      }
    }
    return false;
  };
  const double half_step = std::ldexp(1.0, -(config.gp.subpixel_bits + 1));
  m.difference.width = caster.width;
  m.difference.height = caster.height;
  m.difference.rgb.assign(static_cast<std::size_t>(caster.width) * caster.height * 3, 0);
  // The ray caster's answers, rows spread over the host threads: the centre's, then the four
  // offset centres' (right, left, down, up).
  std::vector<std::array<Seen, 5>> seen(static_cast<std::size_t>(caster.width) * caster.height);
  parallel_for(caster.height, threads, [&](int y) {
    for (int x = 0; x < caster.width; ++x) {
      const double cx = x + 0.5, cy = y + 0.5;
      seen[static_cast<std::size_t>(y) * caster.width + x] = {
          seen_at(cx, cy), seen_at(cx + margin, cy), seen_at(cx - margin, cy),
          seen_at(cx, cy + margin), seen_at(cx, cy - margin)};
    }
  });
  std::vector<double> errors;  // depth errors of the agreeing covered pixels
  for (int y = 0; y < caster.height; ++y) {
    for (int x = 0; x < caster.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * caster.width + x;
      const auto& [centre, right, left, down, up] = seen[i];
      std::uint8_t shade = 0;
      if (!continues(centre, right) || !continues(centre, left) || !continues(centre, down) ||
          !continues(centre, up)) {
        ++m.uncertain;
        shade = 96;
        if (truth_solid) (*truth_solid)[i] = -2;
      } else {
        ++m.compared;
        if (truth_solid) (*truth_solid)[i] = centre.solid;
        const std::int64_t z = static_cast<std::int64_t>(field.values[i]);
        const bool machine = z != background;
        const bool truth = centre.solid >= 0;
        m.surface += truth;
        bool differs = machine != truth;
        if (differs) {
          ++m.coverage;
        } else if (truth) {
          // The steeper side in each direction: across a crease (two faces of one solid)
          // the pixel may be either face's.
          const double d = centre.depth;
          const double slope = (std::max(std::abs(right.depth - d), std::abs(d - left.depth)) +
                                std::max(std::abs(down.depth - d), std::abs(d - up.depth))) /
                               margin;
          // A quadric sphere's depth is the GP's approximation, within its stated bound.
          const double tolerance =
              2.0 + slope * half_step +
              (centre.triangle < 0 ? sphere_bound[static_cast<std::size_t>(-1 - centre.triangle)]
                                   : 0.0);
          const double error = std::abs(static_cast<double>(z) - centre.depth);
          if (error > tolerance) {
            differs = true;
          } else {
            errors.push_back(error);
          }
        }
        if (differs) {
          ++m.disagree;
          shade = 255;
        }
      }
      for (int k = 0; k < 3; ++k) m.difference.rgb[i * 3 + k] = shade;
    }
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    m.median_depth_error = errors[errors.size() / 2];
    m.max_depth_error = errors.back();
  }
  // The plan with the frame's parameters (`layers`, for a program that peels).
  FrameValues values = GeometryEngine(geometry_params(config), drawn).frame_values();
  set_pass_plan(program, drawn, values);
  m.passes = static_cast<int>(values.plan.size());
  m.bits = program.bits_used();
  m.cost = frame_cost(config, drawn, program, threads);
  return m;
}

}  // namespace

CsgMeasure measure_csg(const MachineConfig& config, const Scene& scene, const Program& program,
                       int threads, double margin) {
  if (!program.procedure(Procedure::surface).defined) {
    throw std::invalid_argument(
        fmt::format("{}: CSG rendering needs a program that defines 'surface'", program.name));
  }
  if (scene.csg.empty()) {
    throw std::invalid_argument(
        fmt::format("scene '{}' has no CSG expression to render", scene.name));
  }
  return compare_first_surface(config, scene, scene, program, threads, margin, nullptr);
}

Scene section_truth(const Scene& drawn) {
  // The cutting plane: the triangles in no solid, a quad (add_quad: corners a, b, c, d).
  std::vector<unsigned> corners;
  for (int t = 0; t < static_cast<int>(drawn.mesh.triangles.size()); ++t) {
    if (drawn.solid_of_triangle(t) >= 0) continue;
    const glm::uvec3 tri = drawn.mesh.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) corners.push_back(tri[k]);
  }
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  if (corners.size() != 4 || drawn.solids.size() != 1) {
    throw std::invalid_argument(fmt::format(
        "scene '{}': a cross-section needs one quad in no solid (the plane) and one solid",
        drawn.name));
  }
  std::array<glm::vec3, 4> top;
  for (int k = 0; k < 4; ++k) top[k] = drawn.mesh.vertices[corners[k]].position;
  // Away from the eye, by more than the scene is deep.
  glm::vec3 away = glm::normalize(glm::cross(top[1] - top[0], top[2] - top[0]));
  if (glm::dot(away, top[0] - drawn.camera.eye) < 0) away = -away;
  const float depth = 4.0f * bounding_sphere(drawn.mesh).radius;
  Scene truth = drawn;
  truth.mesh = Mesh{};
  Mesh& mesh = truth.mesh;
  const Solid& cut = drawn.solids[0];
  std::vector<int> index(drawn.mesh.vertices.size(), -1);
  for (int t = cut.first; t < cut.last; ++t) {
    glm::uvec3 tri = drawn.mesh.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      int& i = index[tri[k]];
      if (i < 0) {
        i = static_cast<int>(mesh.vertices.size());
        mesh.vertices.push_back(drawn.mesh.vertices[tri[k]]);
      }
      tri[k] = static_cast<unsigned>(i);
    }
    mesh.triangles.push_back(tri);
  }
  truth.solids = {{cut.name, 0, static_cast<int>(mesh.triangles.size())}};
  // The half-space behind the plane: the quad swept away from the eye, a closed hexahedron.
  const int first = static_cast<int>(mesh.triangles.size());
  const auto base = static_cast<unsigned>(mesh.vertices.size());
  for (int k = 0; k < 8; ++k) {
    mesh.vertices.push_back({top[k % 4] + (k < 4 ? 0.0f : depth) * away, away, glm::vec3(0.5f)});
  }
  const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                           {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
    mesh.triangles.emplace_back(base + f[0], base + f[2], base + f[3]);
  }
  truth.solids.push_back({"behind-plane", first, static_cast<int>(mesh.triangles.size())});
  truth.csg = {{CsgLiteral{0, false}, CsgLiteral{1, false}}};
  return truth;
}

SectionMeasure measure_section(const MachineConfig& config, const Scene& scene,
                               const Program& program, int threads, double margin) {
  if (!program.procedure(Procedure::parity).defined) {
    throw std::invalid_argument(
        fmt::format("{}: a cross-section needs a program that defines 'parity'", program.name));
  }
  if (!program.find_field("inside") || !program.find_field("z")) {
    throw std::invalid_argument(fmt::format(
        "{}: a cross-section program leaves the shown depth in a field 'z' and the cap in a "
        "field 'inside' (as section.pp5 does), which pp5sim csg reads back",
        program.name));
  }
  const Scene truth = section_truth(scene);
  std::vector<int> solid(static_cast<std::size_t>(config.screen.width) * config.screen.height, -2);
  SectionMeasure m;
  m.surface = compare_first_surface(config, scene, truth, program, threads, margin, &solid);
  const FieldFrame inside = render_field(config, scene, program, "inside", threads);
  for (std::size_t i = 0; i < solid.size(); ++i) {
    if (solid[i] == -2) continue;
    const bool cap = solid[i] == 1;  // the plane's face of the half-space is what shows
    m.cap += cap;
    if ((inside.values[i] != 0) != cap) {
      ++m.cap_disagree;
      for (int k = 0; k < 3; ++k)
        m.surface.difference.rgb[i * 3 + static_cast<std::size_t>(k)] = 255;
    }
  }
  return m;
}

// Columns of the csg tables: a count of pixels, a text, a real; each keeps its heading as
// written (no unit appended).
namespace {

report::Column csg_pixels(const std::string& heading, const std::string& description) {
  return report::headed(report::integer_column(heading, "pixels", description), heading);
}

report::Column csg_count(const std::string& heading, const std::string& unit,
                         const std::string& description) {
  return report::headed(report::integer_column(heading, unit, description), heading);
}

report::Column csg_text(const std::string& heading, const std::string& description = {}) {
  return report::headed(report::text_column(heading, description), heading);
}

report::Column csg_depth_error_column() {
  return report::headed(report::real_column("depth error where agreeing", "depth units", 1,
                                            "Median / largest depth error over the agreeing "
                                            "covered pixels"),
                        "depth error where agreeing, median / largest (depth units)",
                        report::Align::right);
}

report::Cell csg_depth_error_cell(const CsgMeasure& m) {
  return report::Cell::shown_as(
      m.max_depth_error, fmt::format("{:.1f} / {:.0f}", m.median_depth_error, m.max_depth_error));
}

}  // namespace

report::Table section_table(const std::vector<SectionMeasure>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-section";
  t.columns = {
      csg_text("application"),
      csg_text("scene"),
      csg_text("program"),
      csg_pixels("pixels compared", "Pixels far from an outline"),
      csg_pixels("with a surface (ray caster)",
                 "Compared pixels where the ray caster finds a surface"),
      csg_pixels("cap (ray caster)", "Compared pixels where the ray caster shows the cap"),
      csg_pixels("cap disagreeing", "Compared pixels where the machine's cap differs"),
      csg_pixels("surface disagreeing",
                 "Compared pixels where coverage or depth differs from the ray caster"),
      csg_pixels("of those, coverage", "Of those, where one shows a surface and the other not"),
      csg_pixels("near an outline (not compared)", "Pixels near an outline"),
      csg_depth_error_column(),
      csg_count("passes", "passes", "Passes of the frame's pass plan"),
      csg_count("bits", "bits", "Pixel-memory bits the program uses")};
  add_cost_columns(t.columns);
  for (const SectionMeasure& s : rows) {
    const CsgMeasure& m = s.surface;
    std::vector<Cell> row = {"cross-section",
                             m.scene,
                             m.program,
                             m.compared,
                             m.surface,
                             s.cap,
                             s.cap_disagree,
                             m.disagree,
                             m.coverage,
                             m.uncertain,
                             csg_depth_error_cell(m),
                             m.passes,
                             m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

report::Table csg_render_table(const std::vector<CsgMeasure>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-render";
  t.columns = {
      csg_text("application"),
      csg_text("scene"),
      headed(code_column("expression", "The CSG expression over the scene's solids"), "expression"),
      csg_text("program"),
      csg_pixels("pixels compared", "Pixels far from an outline"),
      csg_pixels("with a surface (ray caster)",
                 "Compared pixels where the ray caster finds a surface"),
      csg_pixels("disagreeing",
                 "Compared pixels where coverage or depth differs from the ray caster"),
      csg_pixels("of those, coverage", "Of those, where one shows a surface and the other not"),
      csg_pixels("near an outline (not compared)", "Pixels near an outline"),
      csg_depth_error_column(),
      csg_count("passes", "passes", "Passes of the frame's pass plan"),
      csg_count("bits", "bits", "Pixel-memory bits the program uses")};
  add_cost_columns(t.columns);
  for (const CsgMeasure& m : rows) {
    std::vector<Cell> row = {
        "CSG rendering", m.scene,    m.expression, m.program,   m.compared,
        m.surface,       m.disagree, m.coverage,   m.uncertain, csg_depth_error_cell(m),
        m.passes,        m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

InterferenceMeasure measure_interference(const MachineConfig& config, const Scene& scene,
                                         const Program& program, int threads, double margin) {
  if (scene.solids.size() != 2) {
    throw std::invalid_argument(
        fmt::format("scene '{}': interference is measured between two solids (it has {})",
                    scene.name, scene.solids.size()));
  }
  InterferenceMeasure m;
  m.scene = scene.name;
  m.program = program.name;
  const FieldFrame flag = render_field(config, scene, program, "flag", threads);
  const FieldFrame lo = render_field(config, scene, program, "near", threads);
  const FieldFrame hi = render_field(config, scene, program, "far", threads);
  m.image = flag.image;
  Scene both = scene;
  both.csg = {{CsgLiteral{0, false}, CsgLiteral{1, false}}};
  const Caster caster(config, both);
  auto truth_at = [&](double x, double y) {
    const Ray r = caster.ray(x, y);
    return csg_first_surface(both, r.origin, r.direction).solid >= 0;
  };
  m.difference.width = caster.width;
  m.difference.height = caster.height;
  m.difference.rgb.assign(static_cast<std::size_t>(caster.width) * caster.height * 3, 0);
  const double depth_max = std::ldexp(1.0, config.gp.depth_bits) - 1.0;
  m.lo = 1.0;
  m.hi = 0.0;
  for (int y = 0; y < caster.height; ++y) {
    for (int x = 0; x < caster.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * caster.width + x;
      const bool machine = flag.values[i] != 0;
      if (machine) {
        m.lo = std::min(m.lo, static_cast<double>(lo.values[i]) / depth_max);
        m.hi = std::max(m.hi, static_cast<double>(hi.values[i]) / depth_max);
      }
      const bool truth = truth_at(x + 0.5, y + 0.5);
      bool differs = false;
      for (const auto& [dx, dy] : {std::pair{margin, 0.0}, std::pair{-margin, 0.0},
                                   std::pair{0.0, margin}, std::pair{0.0, -margin}}) {
        differs = differs || truth_at(x + 0.5 + dx, y + 0.5 + dy) != truth;
      }
      std::uint8_t shade = 0;
      if (differs) {
        ++m.uncertain;
        m.flagged_uncertain += machine;
        shade = 96;
      } else {
        ++m.compared;
        m.truth += truth;
        m.flagged += machine;
        if (machine != truth) {
          ++m.disagree;
          shade = 255;
        }
      }
      for (int k = 0; k < 3; ++k) m.difference.rgb[i * 3 + k] = shade;
    }
  }
  if (m.flagged + m.flagged_uncertain == 0) m.lo = m.hi = 0;
  m.passes = static_cast<int>(make_pass_plan(program, scene).size());
  m.bits = program.bits_used();
  m.cost = frame_cost(config, scene, program, threads);
  return m;
}

report::Table interference_table(const std::vector<InterferenceMeasure>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-interference";
  t.columns = {csg_text("application"),
               csg_text("scene"),
               csg_text("program"),
               csg_pixels("pixels compared", "Pixels far from an edge of the interference"),
               csg_pixels("of those, interfering (ray caster)",
                          "Compared pixels where the two solids' intersection has a surface"),
               csg_pixels("of those, flagged (machine)", "Compared pixels the machine flags"),
               csg_pixels("of those, disagreeing", "Compared pixels where the two differ"),
               csg_pixels("near an edge (not compared)", "Pixels near an edge of the interference"),
               csg_pixels("of those, flagged", "Of those, the pixels the machine flags"),
               csg_text("overlap depth range",
                        "The depth range of every flagged pixel's overlap, 0 near .. 1 far"),
               csg_count("passes", "passes", "Passes of the frame's pass plan"),
               csg_count("bits", "bits", "Pixel-memory bits the program uses")};
  add_cost_columns(t.columns);
  for (const InterferenceMeasure& m : rows) {
    std::vector<Cell> row = {"interference",
                             m.scene,
                             m.program,
                             m.compared,
                             m.truth,
                             m.flagged,
                             m.disagree,
                             m.uncertain,
                             m.flagged_uncertain,
                             m.flagged + m.flagged_uncertain
                                 ? Cell(fmt::format("{:.5f} .. {:.5f}", m.lo, m.hi))
                                 : Cell::missing(),
                             m.passes,
                             m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

report::Table parity_table(const std::vector<ParityMeasure>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-parity";
  t.columns = {csg_text("application"),
               csg_text("scene"),
               csg_text("program"),
               csg_pixels("pixels compared", "Pixels far from an edge"),
               csg_pixels("with a point", "Compared pixels with a point to classify"),
               csg_pixels("inside", "Compared pixels the ray caster finds inside"),
               csg_pixels("disagreeing with the ray caster",
                          "Compared pixels where the machine's inside differs"),
               csg_pixels("near an edge (not compared)", "Pixels near an edge"),
               csg_pixels("of those, differing from the centre's ray",
                          "Of those, where the machine differs from the ray through the centre"),
               csg_count("passes", "passes", "Passes of the frame's pass plan"),
               csg_count("bits", "bits", "Pixel-memory bits the program uses")};
  add_cost_columns(t.columns);
  for (const ParityMeasure& m : rows) {
    std::vector<Cell> row = {"point in solid", m.scene,  m.program,  m.compared,
                             m.points,         m.inside, m.disagree, m.uncertain,
                             m.edge_disagree,  m.passes, m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

report::Table epsilon_table(const std::vector<ParityMeasure>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-epsilon";
  t.columns = {csg_text("scene"),
               csg_text("program"),
               csg_pixels("pixels compared", "Pixels far from an edge"),
               csg_pixels("with a point", "Compared pixels with a point to classify"),
               csg_pixels("inside (ray caster)", "Compared pixels the ray caster finds inside"),
               csg_pixels("inside (machine)", "Compared pixels the machine finds inside"),
               csg_pixels("lost (inside, taken as outside)",
                          "Inside by the ray caster, outside by the machine"),
               csg_pixels("gained (outside, taken as inside)",
                          "Outside by the ray caster, inside by the machine"),
               csg_count("bits", "bits", "Pixel-memory bits the program uses")};
  add_cost_columns(t.columns);
  for (const ParityMeasure& m : rows) {
    std::vector<Cell> row = {m.scene,          m.program, m.compared, m.points, m.inside,
                             m.machine_inside, m.lost,    m.gained,   m.bits};
    add_cost_cells(row, m.cost);
    t.add_row(std::move(row));
  }
  return t;
}

std::vector<std::string> csg_pruning_scene_names() {
  std::vector<std::string> names = csg_scene_names();
  names.push_back("box-minus-apart");
  return names;
}

CsgPruning measure_csg_pruning(const MachineConfig& config, const Scene& scene,
                               const Program& program, int threads) {
  CsgPruning m;
  m.scene = scene.name;
  m.program = program.name;
  std::vector<std::string> names;
  for (const Solid& s : scene.solids) names.push_back(s.name);
  m.expression = format_csg(scene.csg, names);
  m.pruned_expression = format_csg(pruned_csg(scene), names);
  Scene whole = scene, pruned = scene;
  whole.prune_csg = false;
  pruned.prune_csg = true;
  m.passes_whole = static_cast<int>(make_pass_plan(program, whole).size());
  m.passes_pruned = static_cast<int>(make_pass_plan(program, pruned).size());
  const FieldFrame a = render_field(config, whole, program, "z", threads);
  const FieldFrame b = render_field(config, pruned, program, "z", threads);
  const std::uint64_t background = (std::uint64_t{1} << config.gp.depth_bits) - 1;
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    m.surface += a.values[i] != background;
    m.differing += a.values[i] != b.values[i];
  }
  m.cost_whole = frame_cost(config, whole, program, threads);
  m.cost_pruned = frame_cost(config, pruned, program, threads);
  return m;
}

report::Table csg_pruning_table(const std::vector<CsgPruning>& rows) {
  using namespace report;
  Table t;
  t.id = "csg-pruning";
  t.columns = {
      csg_text("scene"),
      csg_text("program"),
      headed(code_column("expression", "The CSG expression"), "expression"),
      headed(code_column("pruned", "The expression after Goldfeather's pruning"), "pruned"),
      csg_count("passes unpruned", "passes", "Passes of the plan without pruning"),
      csg_count("passes pruned", "passes", "Passes of the pruned plan"),
      csg_count("passes saved", "passes", "Passes the pruning saves"),
      csg_pixels("pixels with a surface", "Pixels where the unpruned plan leaves a surface"),
      csg_pixels("pixels differing (z)", "Pixels whose depth differs between the two plans")};
  add_cost_columns(t.columns, "unpruned: ");
  add_cost_columns(t.columns, "pruned: ");
  for (const CsgPruning& m : rows) {
    std::vector<Cell> row = {m.scene,
                             m.program,
                             m.expression,
                             m.pruned_expression,
                             m.passes_whole,
                             m.passes_pruned,
                             m.passes_whole - m.passes_pruned,
                             m.surface,
                             m.differing};
    add_cost_cells(row, m.cost_whole);
    add_cost_cells(row, m.cost_pruned);
    t.add_row(std::move(row));
  }
  return t;
}

}  // namespace pp5
