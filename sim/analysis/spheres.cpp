#include "sim/analysis/spheres.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/parallel_for.hpp"
#include "models/machine.hpp"
#include "sim/analysis/analysis_firmware.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/analysis/visible_surface.hpp"
#include "sim/simulation.hpp"

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

std::vector<int> shown_spheres(const MachineConfig& config, const Scene& drawn,
                               const std::vector<int>& triangle_sphere, int threads) {
  const std::string text = zbuffer_colour_firmware(
                               "Visibility with spheres: each pixel keeps the nearest "
                               "primitive's index, z-buffered on depth and sphere_depth.",
                               config.gp.depth_bits, "depth", "base") +
                           R"(
proc sphere
  eall
  qtest.ge sphere_inside
  qcmp.lt z, sphere_depth
  qload z, sphere_depth
  qload red, sphere_red
  qload green, sphere_green
  qload blue, sphere_blue
end
)";
  const Program program = assemble(text, "visibility-spheres", assembler_options(config));
  return shown_spheres_by(config, drawn, triangle_sphere, program, threads);
}

std::vector<int> shown_spheres_by(const MachineConfig& config, const Scene& drawn,
                                  const std::vector<int>& triangle_sphere, const Program& program,
                                  int threads) {
  const int triangles = static_cast<int>(drawn.mesh.triangles.size());
  if (static_cast<std::size_t>(triangles) + drawn.spheres.size() >= (std::size_t{1} << 24) - 1)
    throw std::invalid_argument(
        fmt::format("scene '{}': too many primitives for 24-bit visibility colours", drawn.name));
  // Triangles coloured t + 1 (visibility_scene), spheres triangles + k + 1; colours exact
  // multiples of 1/255, so the GP's constant is the byte itself.
  Scene ids = visibility_scene(drawn, {});
  for (std::size_t k = 0; k < ids.spheres.size(); ++k) {
    const auto id = static_cast<unsigned>(triangles) + static_cast<unsigned>(k) + 1;
    ids.spheres[k].color = glm::vec3(static_cast<float>(id & 0xFF) / 255.0f,
                                     static_cast<float>((id >> 8) & 0xFF) / 255.0f,
                                     static_cast<float>((id >> 16) & 0xFF) / 255.0f);
  }
  const IdImage id = decode_visibility(simulate_frame(config, ids, program, threads).image.flat());
  std::vector<int> out(id.id.size(), -1);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int v = id.id[i];
    if (v < 0) continue;
    if (v < triangles) {
      const auto t = static_cast<std::size_t>(v);
      out[i] = t < triangle_sphere.size() && triangle_sphere[t] >= 0 ? triangle_sphere[t] : -2;
    } else {
      out[i] = v - triangles;
    }
  }
  return out;
}

SphereAccuracy measure_spheres(const MachineConfig& config, const Scene& scene,
                               const RayCast& truth, const DrawnSpheres& drawn,
                               const std::vector<int>& shown) {
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
      if (truth.what[i] < -1) {
        ++a.triangle_pixels;
        a.triangle_depth_max_error = std::max(a.triangle_depth_max_error, dz);
      }
      if (truth.spheres[i] >= 2 && truth.what[i] >= 0) {
        ++a.overlap_pixels;
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
        if (nearest != truth.what[i]) ++a.overlap_depth_wrong;
        if (!shown.empty() && shown[i] != truth.what[i]) ++a.overlap_shown_wrong;
      }
    }
  }
  // What the pixels show, against the ray cast's visible primitive.
  if (!shown.empty()) {
    for (std::size_t i = 0; i < shown.size(); ++i) {
      if (truth.what[i] < -1 && shown[i] != -2) ++a.triangle_shown_wrong;
    }
  }
  // Intersection-curve pixels, from the ray cast alone.
  auto depth_of = [&](int k, int x, int y) { return sphere_depth_at(config, scene, k, x, y); };
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      const int a0 = truth.what[i];
      if (a0 < 0 || truth.spheres[i] < 2) continue;
      bool curve = false;
      for (const auto& [dx, dy] :
           {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        const int qx = x + dx, qy = y + dy;
        if (curve || qx < 0 || qy < 0 || qx >= truth.width || qy >= truth.height) continue;
        const std::size_t j = static_cast<std::size_t>(qy) * truth.width + qx;
        const int b0 = truth.what[j];
        if (b0 < 0 || b0 == a0 || truth.spheres[j] < 2) continue;
        // Both surfaces at both centres, nearer first at one and second at the other.
        const double za_p = depth_of(a0, x, y), zb_p = depth_of(b0, x, y);
        const double za_q = depth_of(a0, qx, qy), zb_q = depth_of(b0, qx, qy);
        curve = std::isfinite(zb_p) && std::isfinite(za_q) && za_p <= zb_p && zb_q <= za_q;
      }
      if (!curve) continue;
      ++a.curve_pixels;
      if (!shown.empty() && shown[i] != a0) ++a.curve_shown_wrong;
    }
  }
  if (both > 0) {
    a.depth_mean_error = depth_sum / static_cast<double>(both);
    a.normal_mean_error_degrees = normal_sum / static_cast<double>(both);
  }
  return a;
}

}  // namespace pp5
