#include "sim/analysis/spheres.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/parallel_for.hpp"
#include "sim/analysis/field_render.hpp"

namespace pp5 {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// World-space rays through pixel centres, and the depth buffer's mapping of a world point.
struct Rays {
  glm::dmat4 view, vp, inverse;
  double depth_max;
  int width, height;

  Rays(const MachineConfig& config, const Camera& camera)
      : depth_max(std::ldexp(1.0, config.gp.depth_bits) - 1.0),
        width(config.screen.width),
        height(config.screen.height) {
    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    view = glm::dmat4(view_matrix(camera));
    vp = glm::dmat4(projection_matrix(camera, aspect)) * view;
    inverse = glm::inverse(vp);
  }
  void ray(int x, int y, glm::dvec3& origin, glm::dvec3& direction) const {
    const double nx = 2.0 * (x + 0.5) / width - 1.0;
    const double ny = 1.0 - 2.0 * (y + 0.5) / height;
    const glm::dvec4 a = inverse * glm::dvec4(nx, ny, -1.0, 1.0);
    const glm::dvec4 b = inverse * glm::dvec4(nx, ny, 1.0, 1.0);
    origin = glm::dvec3(a) / a.w;
    direction = glm::dvec3(b) / b.w - origin;
  }
  double depth(const glm::dvec3& p) const {
    const glm::dvec4 c = vp * glm::dvec4(p, 1.0);
    return (c.z / c.w * 0.5 + 0.5) * depth_max;
  }
};

// The nearest s >= 0 with |o + s d - c| = r, or -1.
double hit_sphere(const glm::dvec3& o, const glm::dvec3& d, const Sphere& s) {
  const glm::dvec3 oc = o - glm::dvec3(s.center);
  const double a = glm::dot(d, d);
  const double b = glm::dot(oc, d);
  const double c = glm::dot(oc, oc) - double(s.radius) * double(s.radius);
  const double disc = b * b - a * c;
  if (disc < 0) return -1;
  const double q = std::sqrt(disc);
  const double s0 = (-b - q) / a;
  if (s0 >= 0) return s0;
  const double s1 = (-b + q) / a;
  return s1 >= 0 ? s1 : -1;
}

// Moller-Trumbore: s >= 0 where the ray meets triangle (p0, p1, p2), or -1.
double hit_triangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& p0,
                    const glm::dvec3& p1, const glm::dvec3& p2) {
  const glm::dvec3 e1 = p1 - p0, e2 = p2 - p0;
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (std::fabs(det) < 1e-300) return -1;
  const double inv = 1.0 / det;
  const glm::dvec3 t = o - p0;
  const double u = glm::dot(t, p) * inv;
  if (u < 0 || u > 1) return -1;
  const glm::dvec3 q = glm::cross(t, e1);
  const double v = glm::dot(d, q) * inv;
  if (v < 0 || u + v > 1) return -1;
  const double s = glm::dot(e2, q) * inv;
  return s >= 0 ? s : -1;
}

}  // namespace

RayCast ray_cast(const MachineConfig& config, const Scene& scene) {
  const Rays rays(config, scene.camera);
  RayCast out;
  out.width = rays.width;
  out.height = rays.height;
  const auto n = static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height);
  out.depth.assign(n, kInf);
  out.what.assign(n, -1);
  out.nx.assign(n, 0);
  out.ny.assign(n, 0);
  out.nz.assign(n, 0);
  out.spheres.assign(n, 0);
  const glm::dmat3 rotate(rays.view);
  parallel_for(out.height, 2, [&](int y, int) {
    for (int x = 0; x < out.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * out.width + x;
      glm::dvec3 o, d;
      rays.ray(x, y, o, d);
      for (std::size_t k = 0; k < scene.spheres.size(); ++k) {
        const double s = hit_sphere(o, d, scene.spheres[k]);
        if (s < 0) continue;
        if (out.spheres[i] < 255) ++out.spheres[i];
        const glm::dvec3 p = o + s * d;
        const double z = rays.depth(p);
        if (z < out.depth[i]) {
          out.depth[i] = z;
          out.what[i] = static_cast<int>(k);
          const glm::dvec3 nrm = rotate * ((p - glm::dvec3(scene.spheres[k].center)) /
                                           double(scene.spheres[k].radius));
          out.nx[i] = nrm.x;
          out.ny[i] = nrm.y;
          out.nz[i] = nrm.z;
        }
      }
      const Mesh& m = scene.mesh;
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const glm::uvec3 tri = m.triangles[t];
        const double s = hit_triangle(o, d, glm::dvec3(m.vertices[tri[0]].position),
                                      glm::dvec3(m.vertices[tri[1]].position),
                                      glm::dvec3(m.vertices[tri[2]].position));
        if (s < 0) continue;
        const double z = rays.depth(o + s * d);
        if (z < out.depth[i]) {
          out.depth[i] = z;
          out.what[i] = -2 - static_cast<int>(t);
        }
      }
    }
  });
  return out;
}

double sphere_depth_at(const MachineConfig& config, const Scene& scene, int index, int x, int y) {
  const Rays rays(config, scene.camera);
  glm::dvec3 o, d;
  rays.ray(x, y, o, d);
  const double s = hit_sphere(o, d, scene.spheres.at(static_cast<std::size_t>(index)));
  return s < 0 ? kInf : rays.depth(o + s * d);
}

DrawnSpheres draw_spheres(const MachineConfig& config, const Scene& scene, const Program& program,
                          int threads) {
  DrawnSpheres out;
  auto as_signed = [&](const std::vector<std::uint64_t>& v, const char* field) {
    const FieldDecl* f = program.find_field(field);
    std::vector<std::int64_t> r(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::int64_t x = static_cast<std::int64_t>(v[i]);
      if (f->is_signed && f->width < 64 && (x >> (f->width - 1)) & 1)
        x -= std::int64_t{1} << f->width;
      r[i] = x;
    }
    return r;
  };
  out.covered = render_field(config, scene, program, "covered", threads).values;
  out.z = as_signed(render_field(config, scene, program, "z", threads).values, "z");
  out.nx = as_signed(render_field(config, scene, program, "nx", threads).values, "nx");
  out.ny = as_signed(render_field(config, scene, program, "ny", threads).values, "ny");
  out.nz = as_signed(render_field(config, scene, program, "nz", threads).values, "nz");
  return out;
}

SphereAccuracy measure_spheres(const MachineConfig& config, const Scene& scene,
                               const RayCast& truth, const DrawnSpheres& drawn) {
  const Rays rays(config, scene.camera);
  SphereAccuracy a;
  double depth_sum = 0, normal_sum = 0;
  std::uint64_t both = 0;
  const double kDegrees = 180.0 / 3.14159265358979323846;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      const bool covered = truth.what[i] != -1;
      const bool is_drawn = drawn.covered[i] != 0;
      a.pixels += covered;
      if (is_drawn && !covered) ++a.coverage_extra;
      if (covered && !is_drawn) ++a.coverage_missing;
      if (!(covered && is_drawn)) continue;
      ++both;
      const double dz = std::fabs(static_cast<double>(drawn.z[i]) - truth.depth[i]);
      a.depth_max_error = std::max(a.depth_max_error, dz);
      depth_sum += dz;
      if (truth.what[i] >= 0) {
        const glm::dvec3 n(static_cast<double>(drawn.nx[i]), static_cast<double>(drawn.ny[i]),
                           static_cast<double>(drawn.nz[i]));
        const double len = glm::length(n);
        const double c =
            len > 0 ? glm::dot(n / len, glm::dvec3(truth.nx[i], truth.ny[i], truth.nz[i])) : -1.0;
        const double angle = std::acos(std::clamp(c, -1.0, 1.0)) * kDegrees;
        a.normal_max_error_degrees = std::max(a.normal_max_error_degrees, angle);
        normal_sum += angle;
      }
      if (truth.spheres[i] >= 2 && truth.what[i] >= 0) {
        ++a.curve_pixels;
        // The sphere the drawn depth belongs to: the one whose exact depth is nearest it.
        int nearest = -1;
        double best = kInf;
        glm::dvec3 o, d;
        rays.ray(x, y, o, d);
        for (std::size_t k = 0; k < scene.spheres.size(); ++k) {
          const double s = hit_sphere(o, d, scene.spheres[k]);
          const double zk = s < 0 ? kInf : rays.depth(o + s * d);
          const double gap = std::fabs(zk - static_cast<double>(drawn.z[i]));
          if (gap < best) {
            best = gap;
            nearest = static_cast<int>(k);
          }
        }
        if (nearest != truth.what[i]) ++a.curve_wrong;
      }
    }
  }
  if (both > 0) {
    a.depth_mean_error = depth_sum / static_cast<double>(both);
    a.normal_mean_error_degrees = normal_sum / static_cast<double>(both);
  }
  return a;
}

}  // namespace pp5
