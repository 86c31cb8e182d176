#include "sim/scene/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <vector>

namespace pp5 {

BoundingSphere bounding_sphere(const Mesh& mesh) {
  if (mesh.vertices.empty()) return {glm::vec3(0.0f), 0.0f};
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  for (const Vertex& v : mesh.vertices) {
    lo = glm::min(lo, v.position);
    hi = glm::max(hi, v.position);
  }
  const glm::vec3 center = 0.5f * (lo + hi);
  float radius = 0.0f;
  for (const Vertex& v : mesh.vertices) radius = std::max(radius, glm::length(v.position - center));
  return {center, radius};
}

namespace {

// The camera's orthonormal basis: right, up, and back (from the target toward the eye).
struct ViewBasis {
  glm::dvec3 right, up, back;
};

ViewBasis view_basis(glm::dvec3 back, glm::dvec3 world_up) {
  ViewBasis basis;
  basis.back = glm::normalize(back);
  basis.right = glm::normalize(glm::cross(world_up, basis.back));
  basis.up = glm::cross(basis.back, basis.right);
  return basis;
}

}  // namespace

Camera frame_mesh(const Mesh& mesh, glm::vec3 view_direction, float fov_y_degrees, float margin) {
  const BoundingSphere sphere = bounding_sphere(mesh);
  const glm::dvec3 center(sphere.center);
  const double radius = std::max(static_cast<double>(sphere.radius), 1e-6);
  const ViewBasis basis = view_basis(glm::dvec3(view_direction), glm::dvec3(0.0, 1.0, 0.0));
  // Vertices in the camera basis, relative to the sphere's centre.
  std::vector<glm::dvec3> local;
  local.reserve(mesh.vertices.size());
  for (const Vertex& v : mesh.vertices) {
    const glm::dvec3 d = glm::dvec3(v.position) - center;
    local.emplace_back(glm::dot(d, basis.right), glm::dot(d, basis.up), glm::dot(d, basis.back));
  }
  // With the eye at (sx, sy, dist) in this basis, a vertex (a, b, c) lands at normalised device
  // coordinates ((a - sx), (b - sy)) / ((dist - c) * tan_half); it is inside the central
  // 1/margin of the frame iff dist >= c + max(|a - sx|, |b - sy|) * margin / tan_half. The
  // smallest such dist is therefore exact for any shift, and the shift only needs to centre the
  // image, which a few fixed-point steps do.
  const double tan_half = std::tan(0.5 * glm::radians(static_cast<double>(fov_y_degrees)));
  const double scale = static_cast<double>(margin) / tan_half;
  double sx = 0.0, sy = 0.0, dist = 0.0;
  auto fit_distance = [&] {
    double d = 0.0;
    for (const glm::dvec3& p : local) {
      d = std::max(d, p.z + std::max(std::abs(p.x - sx), std::abs(p.y - sy)) * scale);
      // Keeps every vertex a positive distance in front of the eye even on the view axis.
      d = std::max(d, p.z + 0.05 * radius);
    }
    return d;
  };
  for (int step = 0; step < 8; ++step) {
    dist = fit_distance();
    glm::dvec2 lo(std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::lowest());
    for (const glm::dvec3& p : local) {
      const glm::dvec2 ndc = glm::dvec2(p.x - sx, p.y - sy) / ((dist - p.z) * tan_half);
      lo = glm::min(lo, ndc);
      hi = glm::max(hi, ndc);
    }
    // Moving the eye sideways by s moves points at the centre's depth by s / (dist * tan_half).
    const glm::dvec2 mid = 0.5 * (lo + hi);
    sx += mid.x * dist * tan_half;
    sy += mid.y * dist * tan_half;
  }
  dist = fit_distance();
  double nearest = std::numeric_limits<double>::max(), farthest = 0.0;
  for (const glm::dvec3& p : local) {
    nearest = std::min(nearest, dist - p.z);
    farthest = std::max(farthest, dist - p.z);
  }
  if (local.empty()) nearest = farthest = dist = radius;
  const glm::dvec3 target = center + sx * basis.right + sy * basis.up;
  Camera camera;
  camera.eye = glm::vec3(target + dist * basis.back);
  camera.target = glm::vec3(target);
  camera.up = glm::vec3(0.0f, 1.0f, 0.0f);
  camera.fov_y_degrees = fov_y_degrees;
  camera.near_plane = static_cast<float>(0.9 * nearest);
  camera.far_plane = static_cast<float>(1.1 * farthest);
  return camera;
}

Light default_light(const Camera& camera) {
  const glm::vec3 back = glm::normalize(camera.eye - camera.target);
  const glm::vec3 right = glm::normalize(glm::cross(camera.up, back));
  const glm::vec3 up = glm::cross(back, right);
  Light light;
  light.direction = glm::normalize(-0.6f * right + 0.7f * up + 0.8f * back);
  light.diffuse = 0.8f;
  light.specular = 0.3f;
  light.shininess = 16.0f;
  return light;
}

void compute_smooth_normals(Mesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  std::vector<glm::dvec3> sum(n, glm::dvec3(0.0));
  std::vector<glm::dvec3> largest(n, glm::dvec3(0.0));
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::dvec3 a(mesh.vertices[t.x].position);
    const glm::dvec3 b(mesh.vertices[t.y].position);
    const glm::dvec3 c(mesh.vertices[t.z].position);
    // The cross product's length is twice the triangle's area, so summing it weights by area.
    const glm::dvec3 face = glm::cross(b - a, c - a);
    for (unsigned i : {t.x, t.y, t.z}) {
      sum[i] += face;
      if (glm::dot(face, face) > glm::dot(largest[i], largest[i])) largest[i] = face;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    glm::dvec3 normal = sum[i];
    // Opposite faces can cancel (a pinch point of an immersed surface); fall back to one face.
    if (glm::length(normal) <= 1e-9 * glm::length(largest[i])) normal = largest[i];
    mesh.vertices[i].normal =
        glm::length(normal) > 0.0 ? glm::vec3(glm::normalize(normal)) : glm::vec3(0.0f, 0.0f, 1.0f);
  }
}

}  // namespace pp5
