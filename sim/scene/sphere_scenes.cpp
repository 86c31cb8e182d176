#include "sim/scene/sphere_scenes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace pp5 {

namespace {

constexpr double kPi = 3.14159265358979323846;

Scene finish(std::string name, std::string description, Mesh mesh, std::vector<Sphere> spheres,
             glm::vec3 view_direction) {
  Scene scene;
  scene.name = std::move(name);
  scene.description = std::move(description);
  scene.mesh = std::move(mesh);
  scene.spheres = std::move(spheres);
  scene.camera = frame_scene(scene.mesh, scene.spheres, view_direction, kBuiltinFovYDegrees);
  scene.lights = {default_light(scene.camera)};
  scene.background = kBuiltinBackground;
  return scene;
}

Scene make_spheres() {
  // Four spheres, each piercing at least one other: the intersection curves are circles.
  std::vector<Sphere> s = {
      {{0.0f, 0.0f, 0.0f}, 1.0f, {0.9f, 0.25f, 0.2f}},
      {{1.2f, 0.35f, 0.15f}, 0.8f, {0.25f, 0.8f, 0.3f}},
      {{-0.75f, 0.8f, 0.45f}, 0.6f, {0.25f, 0.4f, 0.95f}},
      {{0.3f, -0.95f, 0.55f}, 0.7f, {0.95f, 0.85f, 0.25f}},
  };
  return finish("spheres", "Four interpenetrating spheres (sphere primitives)", Mesh{},
                std::move(s), glm::vec3(0.2f, 0.3f, 1.0f));
}

// NeRF: the atom bonded to c at `bond`, angle b-c-d `angle` and torsion a-b-c-d `torsion`
// (degrees).
glm::dvec3 place(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, double bond,
                 double angle, double torsion) {
  const double an = angle * kPi / 180.0, to = torsion * kPi / 180.0;
  const glm::dvec3 bc = glm::normalize(c - b);
  const glm::dvec3 n = glm::normalize(glm::cross(b - a, bc));
  const glm::dvec3 m = glm::cross(n, bc);
  return c + bc * (-bond * std::cos(an)) + m * (bond * std::sin(an) * std::cos(to)) +
         n * (bond * std::sin(an) * std::sin(to));
}

struct Atom {
  glm::dvec3 p;
  char element;
};

// An ideal right-handed alpha helix of poly-alanine, heavy atoms (N, CA, C, O, CB), from
// internal coordinates: bonds N-CA 1.458, CA-C 1.525, C-N 1.329, C=O 1.231, CA-CB 1.530
// Angstrom; angles N-CA-C 111.2, CA-C-N 116.2, C-N-CA 121.7, CA-C-O 120.5, N-CA-CB 110.5
// degrees; torsions phi -57, psi -47, omega 180 (Engh and Huber's geometry, Pauling's helix).
std::vector<Atom> alpha_helix(int residues) {
  std::vector<Atom> atoms;
  glm::dvec3 n(0.0), ca(1.458, 0.0, 0.0);
  const double a = (180.0 - 111.2) * kPi / 180.0;
  glm::dvec3 c = ca + glm::dvec3(1.525 * std::cos(a), 1.525 * std::sin(a), 0.0);
  for (int i = 0; i < residues; ++i) {
    const glm::dvec3 next_n = place(n, ca, c, 1.329, 116.2, -47.0);
    const glm::dvec3 o = place(next_n, ca, c, 1.231, 120.5, 180.0);
    const glm::dvec3 cb = place(c, n, ca, 1.530, 110.5, -122.6);
    atoms.push_back({n, 'N'});
    atoms.push_back({ca, 'C'});
    atoms.push_back({c, 'C'});
    atoms.push_back({o, 'O'});
    atoms.push_back({cb, 'C'});
    const glm::dvec3 next_ca = place(ca, c, next_n, 1.458, 121.7, 180.0);
    const glm::dvec3 next_c = place(c, next_n, next_ca, 1.525, 111.2, -57.0);
    n = next_n;
    ca = next_ca;
    c = next_c;
  }
  return atoms;
}

Scene make_molecule() {
  // Sixteen 40-residue helices (3,200 atoms) standing in a 4 x 4 bundle 10 Angstrom apart,
  // neighbours antiparallel and each turned about its own axis.
  constexpr int kResidues = 40;
  const std::vector<Atom> helix = alpha_helix(kResidues);
  // The helix axis: from the mean of the first turn's CA atoms to the last turn's (3.6
  // residues a turn; 4 residues average it well enough to stand the helix upright).
  glm::dvec3 first(0.0), last(0.0);
  for (int r = 0; r < 4; ++r) {
    first += helix[static_cast<std::size_t>(5 * r + 1)].p / 4.0;
    last += helix[static_cast<std::size_t>(5 * (kResidues - 4 + r) + 1)].p / 4.0;
  }
  const glm::dvec3 axis = glm::normalize(last - first);
  const glm::dvec3 mid = 0.5 * (first + last);
  // A frame with the axis as y.
  const glm::dvec3 x = glm::normalize(glm::cross(axis, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 z = glm::cross(x, axis);
  std::vector<Sphere> spheres;
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) {
      const int k = row * 4 + col;
      const double turn = 0.7 * k;
      const double flip = (row + col) % 2 == 0 ? 1.0 : -1.0;
      const glm::dvec3 offset(10.0 * (col - 1.5), 0.0, 10.0 * (row - 1.5));
      for (const Atom& atom : helix) {
        const glm::dvec3 q = atom.p - mid;
        const double lx = glm::dot(q, x), ly = glm::dot(q, axis), lz = glm::dot(q, z);
        const double rx = lx * std::cos(turn) - lz * std::sin(turn);
        const double rz = lx * std::sin(turn) + lz * std::cos(turn);
        const glm::dvec3 p = offset + glm::dvec3(rx, flip * ly, flip * rz);
        const ElementStyle style = element_style(std::string(1, atom.element));
        spheres.push_back({glm::vec3(p), style.radius, style.color});
      }
    }
  }
  return finish("molecule",
                "A space-filling model of 16 ideal poly-alanine alpha helices in a 4 x 4 bundle: "
                "3,200 atoms as spheres (Bondi radii, CPK colours)",
                Mesh{}, std::move(spheres), glm::vec3(0.45f, 0.35f, 1.0f));
}

Scene make_spheres_and_triangles() {
  // A floor of 8 x 8 quads (128 triangles) that three spheres sink into: their circles of
  // intersection with it come from the z-buffer comparing quadratic and linear depth.
  Mesh mesh;
  constexpr int kCells = 8;
  const glm::vec3 normal(0.0f, 1.0f, 0.0f);
  for (int i = 0; i <= kCells; ++i) {
    for (int j = 0; j <= kCells; ++j) {
      const float x = -2.0f + 4.0f * static_cast<float>(j) / kCells;
      const float z = -2.0f + 4.0f * static_cast<float>(i) / kCells;
      const bool dark = ((i + j) % 2) == 0;
      mesh.vertices.push_back(
          {{x, 0.0f, z},
           normal,
           dark ? glm::vec3(0.35f, 0.4f, 0.45f) : glm::vec3(0.7f, 0.72f, 0.75f)});
    }
  }
  for (int i = 0; i < kCells; ++i) {
    for (int j = 0; j < kCells; ++j) {
      const auto a = static_cast<unsigned>(i * (kCells + 1) + j);
      const unsigned b = a + 1, c = a + kCells + 2, d = a + kCells + 1;
      mesh.triangles.emplace_back(a, d, c);
      mesh.triangles.emplace_back(a, c, b);
    }
  }
  std::vector<Sphere> s = {
      {{-0.8f, 0.3f, 0.2f}, 0.7f, {0.9f, 0.25f, 0.2f}},
      {{0.7f, 0.1f, -0.4f}, 0.9f, {0.25f, 0.45f, 0.95f}},
      {{0.5f, 0.35f, 1.0f}, 0.5f, {0.95f, 0.8f, 0.2f}},
  };
  return finish("spheres-and-triangles",
                "Three spheres sinking into a floor of 128 triangles (sphere and triangle "
                "primitives in one z-buffer)",
                std::move(mesh), std::move(s), glm::vec3(0.3f, 0.8f, 1.0f));
}

}  // namespace

std::vector<std::string> sphere_scene_names() {
  return {"spheres", "molecule", "spheres-and-triangles"};
}

Scene make_sphere_scene(const std::string& name) {
  if (name == "spheres") return make_spheres();
  if (name == "molecule") return make_molecule();
  if (name == "spheres-and-triangles") return make_spheres_and_triangles();
  throw std::invalid_argument(fmt::format("'{}' is not a sphere scene", name));
}

ElementStyle element_style(const std::string& symbol) {
  struct Row {
    const char* symbol;
    float radius;
    float r, g, b;
  };
  // Bondi's radii (J. Phys. Chem. 68, 441, 1964); Jmol's CPK colours.
  static const Row kTable[] = {
      {"H", 1.20f, 1.0f, 1.0f, 1.0f},        {"C", 1.70f, 0.565f, 0.565f, 0.565f},
      {"N", 1.55f, 0.188f, 0.314f, 0.973f},  {"O", 1.52f, 1.0f, 0.051f, 0.051f},
      {"F", 1.47f, 0.565f, 0.878f, 0.314f},  {"P", 1.80f, 1.0f, 0.502f, 0.0f},
      {"S", 1.80f, 1.0f, 1.0f, 0.188f},      {"CL", 1.75f, 0.122f, 0.941f, 0.122f},
      {"BR", 1.85f, 0.651f, 0.161f, 0.161f}, {"I", 1.98f, 0.580f, 0.0f, 0.580f},
      {"SE", 1.90f, 1.0f, 0.631f, 0.0f},     {"NA", 2.27f, 0.671f, 0.361f, 0.949f},
      {"MG", 1.73f, 0.541f, 1.0f, 0.0f},     {"K", 2.75f, 0.561f, 0.251f, 0.831f},
      {"ZN", 1.39f, 0.490f, 0.502f, 0.690f}, {"CU", 1.40f, 0.784f, 0.502f, 0.200f},
      {"NI", 1.63f, 0.314f, 0.816f, 0.314f}, {"FE", 1.80f, 0.878f, 0.4f, 0.2f},
  };
  std::string s;
  for (char ch : symbol) s += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  for (const Row& row : kTable) {
    if (s == row.symbol) return {row.radius, {row.r, row.g, row.b}};
  }
  return {1.80f, {1.0f, 0.078f, 0.576f}};
}

Camera frame_scene(const Mesh& mesh, const std::vector<Sphere>& spheres, glm::vec3 view_direction,
                   float fov_y_degrees) {
  Mesh points;
  points.vertices = mesh.vertices;
  for (const Sphere& s : spheres) {
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 corner((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f,
                             (k & 4) ? 1.0f : -1.0f);
      points.vertices.push_back({s.center + corner * s.radius, glm::vec3(0, 1, 0), s.color});
    }
  }
  return frame_mesh(points, view_direction, fov_y_degrees, 1.05f);
}

void append_tessellated_spheres(const std::vector<Sphere>& spheres, int u, int v, Mesh& mesh) {
  if (u < 3 || v < 2) {
    throw std::invalid_argument(
        fmt::format("a tessellated sphere needs u >= 3 and v >= 2, got {} x {}", u, v));
  }
  for (const Sphere& s : spheres) {
    const auto base = static_cast<unsigned>(mesh.vertices.size());
    auto add = [&](glm::dvec3 n) {
      mesh.vertices.push_back({s.center + s.radius * glm::vec3(n), glm::vec3(n), s.color});
    };
    add({0.0, 1.0, 0.0});
    for (int k = 1; k < v; ++k) {
      const double theta = kPi * k / v;
      for (int i = 0; i < u; ++i) {
        const double phi = 2.0 * kPi * i / u;
        add({std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi)});
      }
    }
    const auto south = static_cast<unsigned>(mesh.vertices.size());
    add({0.0, -1.0, 0.0});
    auto ring = [&](int k, int i) { return base + static_cast<unsigned>(1 + (k - 1) * u + i % u); };
    for (int i = 0; i < u; ++i) mesh.triangles.emplace_back(base, ring(1, i), ring(1, i + 1));
    for (int k = 1; k + 1 < v; ++k) {
      for (int i = 0; i < u; ++i) {
        mesh.triangles.emplace_back(ring(k, i), ring(k + 1, i), ring(k + 1, i + 1));
        mesh.triangles.emplace_back(ring(k, i), ring(k + 1, i + 1), ring(k, i + 1));
      }
    }
    for (int i = 0; i < u; ++i)
      mesh.triangles.emplace_back(south, ring(v - 1, i + 1), ring(v - 1, i));
  }
}

}  // namespace pp5
