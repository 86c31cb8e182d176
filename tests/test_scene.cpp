#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/scene/scene.hpp"
#include "sim/scene/sphere_scenes.hpp"

using pp5::make_builtin_scene;
using pp5::Mesh;
using pp5::Scene;
using pp5::SceneOptions;

namespace {

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

glm::vec3 face_cross(const Mesh& mesh, const glm::uvec3& t) {
  const glm::vec3 a = mesh.vertices[t.x].position;
  return glm::cross(mesh.vertices[t.y].position - a, mesh.vertices[t.z].position - a);
}

// Checks the invariants every built-in scene promises, whatever its tessellation.
void check_mesh_invariants(const Scene& scene) {
  const Mesh& mesh = scene.mesh;
  REQUIRE_FALSE(mesh.vertices.empty());
  REQUIRE_FALSE(mesh.triangles.empty());
  const pp5::BoundingSphere sphere = pp5::bounding_sphere(mesh);
  REQUIRE(sphere.radius > 0.0f);
  for (const pp5::Vertex& v : mesh.vertices) {
    REQUIRE(finite(v.position));
    REQUIRE(finite(v.normal));
    REQUIRE(finite(v.color));
    REQUIRE(glm::length(v.normal) == Approx(1.0f).margin(1e-5));
    for (int c = 0; c < 3; ++c) {
      REQUIRE(v.color[c] >= 0.0f);
      REQUIRE(v.color[c] <= 1.0f);
    }
  }
  // Areas are compared with the object's size so the check means the same at any scale.
  const float min_area = 1e-7f * sphere.radius * sphere.radius;
  for (const glm::uvec3& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) REQUIRE(t[k] < mesh.vertices.size());
    REQUIRE(t.x != t.y);
    REQUIRE(t.y != t.z);
    REQUIRE(t.z != t.x);
    REQUIRE(0.5f * glm::length(face_cross(mesh, t)) > min_area);
  }
}

// Every vertex must project strictly inside the view volume: -w < x, y, z < w with w > 0.
void check_in_frustum(const Scene& scene, float aspect) {
  const glm::mat4 m = pp5::projection_matrix(scene.camera, aspect) * pp5::view_matrix(scene.camera);
  for (const pp5::Vertex& v : scene.mesh.vertices) {
    const glm::vec4 c = m * glm::vec4(v.position, 1.0f);
    REQUIRE(c.w > 0.0f);
    REQUIRE(std::abs(c.x) < c.w);
    REQUIRE(std::abs(c.y) < c.w);
    REQUIRE(std::abs(c.z) < c.w);
  }
}

// Largest |ndc x| or |ndc y| over all vertices: how much of the frame the object reaches.
float ndc_extent(const Scene& scene, float aspect) {
  const glm::mat4 m = pp5::projection_matrix(scene.camera, aspect) * pp5::view_matrix(scene.camera);
  float extent = 0.0f;
  for (const pp5::Vertex& v : scene.mesh.vertices) {
    const glm::vec4 c = m * glm::vec4(v.position, 1.0f);
    extent = std::max({extent, std::abs(c.x / c.w), std::abs(c.y / c.w)});
  }
  return extent;
}

// A closed, consistently wound surface uses each directed edge exactly once and its reverse
// exactly once, so every undirected edge is shared by exactly two triangles.
void check_closed_and_consistent(const Mesh& mesh) {
  std::map<std::pair<unsigned, unsigned>, int> directed;
  for (const glm::uvec3& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    REQUIRE(count == 1);
    const auto reverse = directed.find({edge.second, edge.first});
    REQUIRE(reverse != directed.end());
    REQUIRE(reverse->second == 1);
  }
}

// The vertex farthest along +x lies on the convex hull, so an outward normal there points +x.
void check_outward_at_extreme(const Mesh& mesh) {
  const auto extreme = std::max_element(
      mesh.vertices.begin(), mesh.vertices.end(),
      [](const pp5::Vertex& a, const pp5::Vertex& b) { return a.position.x < b.position.x; });
  CHECK(extreme->normal.x > 0.5f);
}

bool same_scene(const Scene& a, const Scene& b) {
  if (a.name != b.name || a.description != b.description) return false;
  if (a.mesh.vertices.size() != b.mesh.vertices.size()) return false;
  if (a.mesh.triangles != b.mesh.triangles) return false;
  for (std::size_t i = 0; i < a.mesh.vertices.size(); ++i) {
    const pp5::Vertex& u = a.mesh.vertices[i];
    const pp5::Vertex& v = b.mesh.vertices[i];
    if (u.position != v.position || u.normal != v.normal || u.color != v.color) return false;
  }
  return a.camera.eye == b.camera.eye && a.camera.target == b.camera.target &&
         a.camera.near_plane == b.camera.near_plane && a.camera.far_plane == b.camera.far_plane &&
         a.lights.size() == b.lights.size() && a.lights[0].direction == b.lights[0].direction &&
         a.background == b.background;
}

}  // namespace

TEST_CASE("builtin_scene_names lists the scenes", "[scene]") {
  CHECK(pp5::builtin_scene_names() ==
        std::vector<std::string>{"torus", "two-triangles", "sphere", "figure-eight",
                                 "crossing-quads", "receding-pairs", "cyclic-overlap",
                                 "pierced-quad", "long-thin", "folded-slab", "spheres", "molecule",
                                 "spheres-and-triangles"});
}

TEST_CASE("every built-in scene is well formed, lit and framed", "[scene]") {
  for (const std::string& name : pp5::builtin_scene_names()) {
    CAPTURE(name);
    Scene scene = make_builtin_scene(name);
    CHECK(scene.name == name);
    // A scene of sphere primitives (sim/scene/sphere_scenes.hpp) is checked through its
    // spheres tessellated: they must be as well formed and framed as a mesh.
    pp5::append_tessellated_spheres(scene.spheres, 16, 8, scene.mesh);
    CHECK_FALSE(scene.description.empty());
    check_mesh_invariants(scene);
    for (float aspect : {1.0f, 1.25f, 1.6f}) {
      CAPTURE(aspect);
      check_in_frustum(scene, aspect);
    }
    // Fitted, not merely contained: the object reaches most of the way to the frame's edge.
    CHECK(ndc_extent(scene, 1.0f) > 0.85f);
    CHECK(scene.camera.near_plane > 0.0f);
    CHECK(scene.camera.near_plane < scene.camera.far_plane);
    CHECK(scene.camera.fov_y_degrees > 10.0f);
    CHECK(scene.camera.fov_y_degrees < 90.0f);
    REQUIRE(scene.lights.size() == 1);
    const pp5::Light& light = scene.lights[0];
    CHECK(glm::length(light.direction) == Approx(1.0f).margin(1e-5));
    // The light comes from in front of the object, from above, from the viewer's left.
    const glm::vec3 back = glm::normalize(scene.camera.eye - scene.camera.target);
    const glm::vec3 right = glm::normalize(glm::cross(scene.camera.up, back));
    CHECK(glm::dot(light.direction, back) > 0.0f);
    CHECK(glm::dot(light.direction, scene.camera.up) > 0.0f);
    CHECK(glm::dot(light.direction, right) < 0.0f);
    CHECK(scene.ambient == Approx(0.15f));
    CHECK(light.diffuse == Approx(0.8f));
    CHECK(light.specular == Approx(0.3f));
    CHECK(light.shininess == Approx(16.0f));
    for (int c = 0; c < 3; ++c) CHECK(scene.background[c] < 0.2f);
  }
}

TEST_CASE("built-in scenes are deterministic", "[scene]") {
  for (const std::string& name : pp5::builtin_scene_names()) {
    CAPTURE(name);
    CHECK(same_scene(make_builtin_scene(name), make_builtin_scene(name)));
  }
}

TEST_CASE("the torus has 8,192 triangles by default and 2*u*v in general", "[scene][torus]") {
  const Scene standard = make_builtin_scene("torus");
  CHECK(standard.mesh.triangles.size() == 8192);
  CHECK(standard.mesh.vertices.size() == 128 * 32);
  for (auto [u, v] : {std::pair{3, 3}, std::pair{5, 7}, std::pair{64, 16}, std::pair{200, 40}}) {
    CAPTURE(u, v);
    SceneOptions options;
    options.tessellation_u = u;
    options.tessellation_v = v;
    const Scene scene = make_builtin_scene("torus", options);
    CHECK(scene.mesh.triangles.size() == static_cast<std::size_t>(2 * u * v));
    CHECK(scene.mesh.vertices.size() == static_cast<std::size_t>(u * v));
    check_mesh_invariants(scene);
    check_closed_and_consistent(scene.mesh);
    check_in_frustum(scene, 1.25f);
  }
}

TEST_CASE("the torus is a closed, consistently wound, outward-facing surface", "[scene][torus]") {
  const Scene scene = make_builtin_scene("torus");
  check_closed_and_consistent(scene.mesh);
  check_outward_at_extreme(scene.mesh);
  // Smooth normals agree with the faces around them.
  for (const glm::uvec3& t : scene.mesh.triangles) {
    const glm::vec3 face = glm::normalize(face_cross(scene.mesh, t));
    for (int k = 0; k < 3; ++k) REQUIRE(glm::dot(face, scene.mesh.vertices[t[k]].normal) > 0.0f);
  }
  // The hue ramp varies along the knot: the colours are not all the same.
  CHECK(scene.mesh.vertices.front().color != scene.mesh.vertices[64 * 32].color);
}

TEST_CASE("the sphere is a closed UV sphere with outward normals", "[scene][sphere]") {
  const Scene standard = make_builtin_scene("sphere");
  CHECK(standard.mesh.triangles.size() == 2 * 64 * 31);
  for (auto [u, v] : {std::pair{0, 0}, std::pair{3, 2}, std::pair{8, 5}, std::pair{100, 50}}) {
    CAPTURE(u, v);
    SceneOptions options;
    options.tessellation_u = u;
    options.tessellation_v = v;
    const Scene scene = make_builtin_scene("sphere", options);
    const int nu = u == 0 ? 64 : u, nv = v == 0 ? 32 : v;
    CHECK(scene.mesh.triangles.size() == static_cast<std::size_t>(2 * nu * (nv - 1)));
    CHECK(scene.mesh.vertices.size() == static_cast<std::size_t>(2 + nu * (nv - 1)));
    check_mesh_invariants(scene);
    check_closed_and_consistent(scene.mesh);
    check_in_frustum(scene, 1.25f);
    const glm::vec3 color = scene.mesh.vertices.front().color;
    for (const pp5::Vertex& vertex : scene.mesh.vertices) {
      REQUIRE(glm::length(vertex.position) == Approx(1.0f).margin(1e-5));
      REQUIRE(glm::dot(vertex.normal, vertex.position) == Approx(1.0f).margin(1e-5));
      REQUIRE(vertex.color == color);
    }
    for (const glm::uvec3& t : scene.mesh.triangles) {
      REQUIRE(glm::dot(face_cross(scene.mesh, t), scene.mesh.vertices[t.x].position) > 0.0f);
    }
  }
}

TEST_CASE("the two triangles interpenetrate and face the camera", "[scene]") {
  const Scene scene = make_builtin_scene("two-triangles");
  const Mesh& mesh = scene.mesh;
  REQUIRE(mesh.triangles.size() == 2);
  CHECK(mesh.vertices[mesh.triangles[0].x].color != mesh.vertices[mesh.triangles[1].x].color);
  const glm::vec3 to_eye = scene.camera.eye - scene.camera.target;
  for (const glm::uvec3& t : mesh.triangles) {
    CHECK(glm::dot(face_cross(mesh, t), to_eye) > 0.0f);
  }
  // Interpenetration: an edge of each triangle passes through the interior of the other.
  auto edge_pierces = [&mesh](const glm::uvec3& edges_of, const glm::uvec3& target) {
    const glm::vec3 a = mesh.vertices[target.x].position;
    const glm::vec3 b = mesh.vertices[target.y].position;
    const glm::vec3 c = mesh.vertices[target.z].position;
    const glm::vec3 n = glm::cross(b - a, c - a);
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 p = mesh.vertices[edges_of[k]].position;
      const glm::vec3 q = mesh.vertices[edges_of[(k + 1) % 3]].position;
      const float dp = glm::dot(p - a, n), dq = glm::dot(q - a, n);
      if (dp * dq >= 0.0f) continue;
      const glm::vec3 x = p + (q - p) * (dp / (dp - dq));
      const bool inside = glm::dot(glm::cross(b - a, x - a), n) > 0.0f &&
                          glm::dot(glm::cross(c - b, x - b), n) > 0.0f &&
                          glm::dot(glm::cross(a - c, x - c), n) > 0.0f;
      if (inside) return true;
    }
    return false;
  };
  CHECK(edge_pierces(mesh.triangles[0], mesh.triangles[1]));
  CHECK(edge_pierces(mesh.triangles[1], mesh.triangles[0]));
  // The planes meet at a clearly visible angle.
  const glm::vec3 n0 = glm::normalize(face_cross(mesh, mesh.triangles[0]));
  const glm::vec3 n1 = glm::normalize(face_cross(mesh, mesh.triangles[1]));
  CHECK(std::abs(glm::dot(n0, n1)) < std::cos(glm::radians(30.0f)));
}

TEST_CASE("an unknown scene name throws and lists the valid names", "[scene]") {
  REQUIRE_THROWS_AS(make_builtin_scene("teapot"), std::invalid_argument);
  try {
    make_builtin_scene("teapot");
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    CHECK_THAT(message, Catch::Contains("teapot"));
    for (const std::string& name : pp5::builtin_scene_names()) {
      CHECK_THAT(message, Catch::Contains(name));
    }
  }
}

TEST_CASE("out-of-range tessellations throw", "[scene]") {
  for (const std::string& name : {std::string("torus"), std::string("sphere")}) {
    CAPTURE(name);
    for (auto [u, v] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{-4, 8}, std::pair{8, 100000}}) {
      CAPTURE(u, v);
      SceneOptions options;
      options.tessellation_u = u;
      options.tessellation_v = v;
      CHECK_THROWS_AS(make_builtin_scene(name, options), std::invalid_argument);
    }
  }
}

TEST_CASE("view and projection matrices follow glm's OpenGL conventions", "[scene]") {
  const pp5::Camera camera{
      {1.0f, 2.0f, 5.0f}, {0.0f, 0.5f, 0.0f}, {0.0f, 1.0f, 0.0f}, 45.0f, 0.5f, 20.0f};
  CHECK(pp5::view_matrix(camera) == glm::lookAt(camera.eye, camera.target, camera.up));
  CHECK(pp5::projection_matrix(camera, 1.25f) ==
        glm::perspective(glm::radians(45.0f), 1.25f, 0.5f, 20.0f));
  const glm::vec4 c = pp5::projection_matrix(camera, 1.25f) * pp5::view_matrix(camera) *
                      glm::vec4(camera.target, 1.0f);
  CHECK(c.x / c.w == Approx(0.0f).margin(1e-6));
  CHECK(c.y / c.w == Approx(0.0f).margin(1e-6));
  CHECK(c.z / c.w > -1.0f);
  CHECK(c.z / c.w < 1.0f);
}
