#include "models/gp/geometry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "models/config/machine_config.hpp"
#include "models/gp/expressions.hpp"
#include "models/gp/primitive_kind.hpp"

namespace pp5 {

namespace {

struct ClipVertex {
  glm::dvec4 clip;
  glm::dvec3 lit;
  glm::dvec3 base;
  glm::dvec3 normal;
  double opacity;
};

ClipVertex mix(const ClipVertex& a, const ClipVertex& b, double t) {
  return {a.clip + (b.clip - a.clip) * t, a.lit + (b.lit - a.lit) * t,
          a.base + (b.base - a.base) * t, a.normal + (b.normal - a.normal) * t,
          a.opacity + (b.opacity - a.opacity) * t};
}

// Signed distance to clip plane k of the view volume -w <= x, y, z <= w.
double plane_distance(const glm::dvec4& c, int k) {
  switch (k) {
    case 0:
      return c.w + c.x;
    case 1:
      return c.w - c.x;
    case 2:
      return c.w + c.y;
    case 3:
      return c.w - c.y;
    case 4:
      return c.w + c.z;
    default:
      return c.w - c.z;
  }
}

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

}  // namespace

// Both below name every field; these fail when one is added, until it joins them.
static_assert(
    sizeof(GeometryParams) ==
        10 * sizeof(int) + sizeof(bool) + 7 /* padding */ +
            sizeof(std::array<std::optional<std::int64_t>, static_cast<int>(Parameter::count)>),
    "a new GeometryParams field must join operator==");
static_assert(sizeof(SetupCounts) == 15 * sizeof(std::uint64_t),
              "a new SetupCounts field must join operator+=");

bool operator==(const GeometryParams& a, const GeometryParams& b) {
  return a.screen_width == b.screen_width && a.screen_height == b.screen_height &&
         a.region_width == b.region_width && a.region_height == b.region_height &&
         a.subpixel_bits == b.subpixel_bits && a.significand_bits == b.significand_bits &&
         a.depth_bits == b.depth_bits && a.fraction_bits == b.fraction_bits &&
         a.coefficient_bits == b.coefficient_bits && a.result_bits == b.result_bits &&
         a.cull_back_faces == b.cull_back_faces && a.frame == b.frame;
}

SetupCounts& operator+=(SetupCounts& a, const SetupCounts& b) {
  a.clipped_away += b.clipped_away;
  a.degenerate += b.degenerate;
  a.no_pixels += b.no_pixels;
  a.overflow += b.overflow;
  a.clip_splits += b.clip_splits;
  a.culled += b.culled;
  for (std::size_t k = 0; k < a.sides.size(); ++k) a.sides[k] += b.sides[k];
  a.sphere_near += b.sphere_near;
  a.sphere_behind += b.sphere_behind;
  a.sphere_far += b.sphere_far;
  return a;
}

GeometryEngine::GeometryEngine(const GeometryParams& params, const Scene& scene)
    : params_(params), scene_(scene), display_list_(make_display_list(scene)) {
  const float aspect =
      static_cast<float>(params.screen_width) / static_cast<float>(params.screen_height);
  view_ = glm::dmat4(view_matrix(scene.camera));
  projection_ = glm::dmat4(projection_matrix(scene.camera, aspect));
  normal_matrix_ = glm::transpose(glm::inverse(glm::dmat3(view_)));
  if (scene.lights.empty() || scene.lights.size() > static_cast<std::size_t>(kMaxLights)) {
    throw std::invalid_argument(fmt::format("scene '{}' has {} lights; 1 to {} are supported",
                                            scene.name, scene.lights.size(), kMaxLights));
  }
  for (const Light& l : scene.lights) {
    light_eye_.push_back(glm::normalize(glm::dmat3(view_) * glm::dvec3(l.direction)));
    half_eye_.push_back(glm::normalize(light_eye_.back() + glm::dvec3(0, 0, 1)));
  }
}

glm::dvec3 GeometryEngine::light_vertex(const glm::dvec3& color, const glm::dvec3& n) const {
  // Every light's diffuse and specular term adds to the scene's ambient.
  double level = scene_.ambient;
  double specular = 0;
  for (std::size_t k = 0; k < light_eye_.size(); ++k) {
    const Light& l = scene_.lights[k];
    level += l.diffuse * std::max(0.0, glm::dot(n, light_eye_[k]));
    specular += l.specular * std::pow(std::max(0.0, glm::dot(n, half_eye_[k])), l.shininess);
  }
  return glm::clamp(color * level + glm::dvec3(specular), 0.0, 1.0);
}

const std::vector<GeometryEngine::VertexView>& GeometryEngine::vertex_views() const {
  std::call_once(vertex_views_once_, [this] {
    const Mesh& mesh = scene_.mesh;
    vertex_views_.resize(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Vertex& src = mesh.vertices[i];
      VertexView& w = vertex_views_[i];
      const glm::dvec4 e = view_ * glm::dvec4(glm::dvec3(src.position), 1.0);
      w.eye = glm::dvec3(e);
      w.clip = projection_ * e;
      w.normal = glm::normalize(normal_matrix_ * glm::dvec3(src.normal));
      w.lit_front = light_vertex(glm::dvec3(src.color), w.normal);
      w.lit_back = light_vertex(glm::dvec3(src.color), -w.normal);
    }
  });
  return vertex_views_;
}

void GeometryEngine::transform(int index, std::vector<ScreenTriangle>& out,
                               SetupCounts& counts) const {
  const Mesh& mesh = scene_.mesh;
  const glm::uvec3 tri = mesh.triangles[index];
  const std::vector<VertexView>& views = vertex_views();
  std::array<glm::dvec3, 3> eye;
  std::array<ClipVertex, 3> v;
  for (int k = 0; k < 3; ++k) {
    const Vertex& src = mesh.vertices[tri[k]];
    const VertexView& w = views[tri[k]];
    eye[k] = w.eye;
    v[k].clip = w.clip;
    v[k].base = glm::dvec3(src.color);
    v[k].normal = w.normal;
    v[k].opacity = src.opacity;
  }
  // Two-sided lighting: the surfaces of interest (the self-intersecting torus) show both
  // sides, so normals are turned toward the viewer.
  glm::dvec3 face = glm::cross(eye[1] - eye[0], eye[2] - eye[0]);
  const double face_length = glm::length(face);
  face = face_length > 0 ? face / face_length : glm::dvec3(0, 0, 1);
  const bool back = glm::dot(face, -eye[0]) < 0;
  if (back) {
    if (params_.cull_back_faces) {
      ++counts.culled;
      return;
    }
    face = -face;
    for (auto& x : v) x.normal = -x.normal;
  }
  const glm::dvec3 centroid_base = (v[0].base + v[1].base + v[2].base) / 3.0;
  const glm::dvec3 flat = light_vertex(centroid_base, face);
  for (int k = 0; k < 3; ++k) v[k].lit = back ? views[tri[k]].lit_back : views[tri[k]].lit_front;

  // The polygon in two buffers kept by the thread (no allocation per triangle once they have
  // grown). Clipping a convex polygon against a plane adds at most one vertex in exact
  // arithmetic, but vertices that rounding leaves on both sides of a plane they lie on can
  // add more, so the buffers grow as needed rather than being bounded.
  thread_local std::vector<ClipVertex> poly_a, poly_b;
  std::vector<ClipVertex>* poly = &poly_a;
  poly->assign(v.begin(), v.end());
  bool inside = true;
  for (const auto& x : v) {
    for (int k = 0; k < 6; ++k) inside = inside && plane_distance(x.clip, k) >= 0;
  }
  if (!inside) {
    std::vector<ClipVertex>* next = &poly_b;
    for (int k = 0; k < 6 && !poly->empty(); ++k) {
      next->clear();
      const std::size_t size = poly->size();
      for (std::size_t i = 0; i < size; ++i) {
        const ClipVertex& a = (*poly)[i];
        const ClipVertex& b = (*poly)[(i + 1) % size];
        const double da = plane_distance(a.clip, k);
        const double db = plane_distance(b.clip, k);
        if (da >= 0) next->push_back(a);
        if ((da >= 0) != (db >= 0)) next->push_back(mix(a, b, da / (da - db)));
      }
      std::swap(poly, next);
    }
    if (poly->size() < 3) {
      ++counts.clipped_away;
      return;
    }
    counts.clip_splits += poly->size() - 3;
  }
  const std::size_t size = poly->size();
  thread_local std::vector<ScreenVertex> screen;
  screen.resize(size);
  for (std::size_t i = 0; i < size; ++i) {
    const ClipVertex& p = (*poly)[i];
    const glm::dvec3 ndc = glm::dvec3(p.clip) / p.clip.w;
    ScreenVertex& s = screen[i];
    s.position = {(ndc.x * 0.5 + 0.5) * params_.screen_width,
                  (0.5 - ndc.y * 0.5) * params_.screen_height};
    s.depth = std::clamp(ndc.z * 0.5 + 0.5, 0.0, 1.0);
    s.eye_depth = p.clip.w;
    s.lit_color = p.lit;
    s.base_color = p.base;
    s.opacity = p.opacity;
    const double n = glm::length(p.normal);
    s.normal = n > 0 ? p.normal / n : face;
  }
  for (std::size_t i = 1; i + 1 < size; ++i) {
    out.push_back({{screen[0], screen[i], screen[i + 1]}, flat, index, back});
  }
}

bool GeometryEngine::setup(const ScreenTriangle& t, const ExpressionSet& needed, SetupResult& out,
                           SetupCounts& counts) const {
  const int s = params_.subpixel_bits;
  out.back = t.back;
  SetupContext c{params_, scene_.camera, t};
  if (needs_frame_parameters(needed)) c.frame = &setup_parameters();
  c.scale = std::int64_t{1} << s;
  c.half = c.scale / 2;
  for (int k = 0; k < 3; ++k) {
    c.xs[k] = std::llround(t.v[k].position.x * static_cast<double>(c.scale));
    c.ys[k] = std::llround(t.v[k].position.y * static_cast<double>(c.scale));
  }
  const auto& xs = c.xs;
  const auto& ys = c.ys;
  c.area2 = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (xs[2] - xs[0]) * (ys[1] - ys[0]);
  // A program that classifies against the unsnapped triangle (ExpressionEntry::widens) still
  // owns the centres of a sliver that snapping flattens; its attribute planes then take their
  // gradients from the unsnapped positions (below).
  const bool widen = widens_bounds(needed);
  const bool flattened = c.area2 == 0;
  if (flattened && !widen) {
    ++counts.degenerate;
    return false;
  }
  // Pixel X is covered only if its centre X * scale + half lies within the triangle's span.
  const std::int64_t scale = c.scale;
  const std::int64_t half = c.half;
  // An expression that classifies against the unsnapped triangle reaches half a snapped unit
  // beyond the snapped one (ExpressionEntry::widens): the box grows by a whole unit.
  const std::int64_t pad = widen ? 1 : 0;
  const std::int64_t x_lo = *std::min_element(xs.begin(), xs.end()) - pad;
  const std::int64_t x_hi = *std::max_element(xs.begin(), xs.end()) + pad;
  const std::int64_t y_lo = *std::min_element(ys.begin(), ys.end()) - pad;
  const std::int64_t y_hi = *std::max_element(ys.begin(), ys.end()) + pad;
  out.x_min = static_cast<int>(std::max<std::int64_t>(0, ceil_div(x_lo - half, scale)));
  out.x_max = static_cast<int>(
      std::min<std::int64_t>(params_.screen_width - 1, floor_div(x_hi - half, scale)));
  out.y_min = static_cast<int>(std::max<std::int64_t>(0, ceil_div(y_lo - half, scale)));
  out.y_max = static_cast<int>(
      std::min<std::int64_t>(params_.screen_height - 1, floor_div(y_hi - half, scale)));
  if (out.x_min > out.x_max || out.y_min > out.y_max) {
    ++counts.no_pixels;
    return false;
  }

  // What every attribute plane shares: the vertices in pixel-index coordinates.
  c.f_scale = std::ldexp(1.0, params_.fraction_bits);
  for (int k = 0; k < 3; ++k) {
    c.u[k] = flattened ? t.v[k].position.x - 0.5
                       : static_cast<double>(xs[k] - half) / static_cast<double>(scale);
    c.w[k] = flattened ? t.v[k].position.y - 0.5
                       : static_cast<double>(ys[k] - half) / static_cast<double>(scale);
  }
  c.det = (c.u[1] - c.u[0]) * (c.w[2] - c.w[0]) - (c.u[2] - c.u[0]) * (c.w[1] - c.w[0]);
  if (!(c.det != 0)) {
    ++counts.degenerate;
    return false;
  }
  c.depth_max = std::ldexp(1.0, params_.depth_bits) - 1.0;
  if (needs_adjacency(needed)) {
    c.adjacency = &adjacency();
    c.mesh = &scene_.mesh;
  }
  c.counts = &counts;

  // Only what the program uses, each from its registry entry, in enum order.
  out.values.expressions.reserve(needed.count());
  for (const ExpressionEntry& e : expression_registry()) {
    const int k = static_cast<int>(e.id);
    if (!needed.test(k)) continue;
    if (!e.compute(c, out.values.expressions[static_cast<std::size_t>(k)])) {
      ++counts.overflow;
      return false;
    }
  }
  return true;
}

const MeshAdjacency& GeometryEngine::adjacency() const {
  std::call_once(adjacency_once_, [this] { adjacency_ = build_mesh_adjacency(scene_.mesh); });
  return adjacency_;
}

void GeometryEngine::bin(const SetupResult& r, std::vector<int>& regions) const {
  const int rx0 = r.x_min / params_.region_width;
  const int rx1 = r.x_max / params_.region_width;
  const int ry0 = r.y_min / params_.region_height;
  const int ry1 = r.y_max / params_.region_height;
  const int across = (params_.screen_width + params_.region_width - 1) / params_.region_width;
  for (int ry = ry0; ry <= ry1; ++ry) {
    for (int rx = rx0; rx <= rx1; ++rx) regions.push_back(ry * across + rx);
  }
}

std::array<std::int64_t, static_cast<int>(Parameter::count)> GeometryEngine::frame_parameters(
    int light) const {
  if (light < 0 || light >= lights()) {
    throw std::out_of_range(fmt::format("light {} of a scene with {}", light, lights()));
  }
  std::array<std::int64_t, static_cast<int>(Parameter::count)> p{};
  auto at = [&](Parameter k) -> std::int64_t& { return p[static_cast<int>(k)]; };
  const glm::dvec3& to_light = light_eye_[static_cast<std::size_t>(light)];
  const glm::dvec3& half = half_eye_[static_cast<std::size_t>(light)];
  at(Parameter::light_x) = std::llround(127.0 * to_light.x);
  at(Parameter::light_y) = std::llround(127.0 * to_light.y);
  at(Parameter::light_z) = std::llround(127.0 * to_light.z);
  at(Parameter::half_x) = std::llround(127.0 * half.x);
  at(Parameter::half_y) = std::llround(127.0 * half.y);
  at(Parameter::half_z) = std::llround(127.0 * half.z);
  const Light& l = scene_.lights[static_cast<std::size_t>(light)];
  auto unit = [](double v) { return std::llround(std::clamp(v, 0.0, 1.0) * 255.0); };
  at(Parameter::ambient) = unit(scene_.ambient);
  at(Parameter::diffuse) = unit(l.diffuse);
  at(Parameter::specular) = unit(l.specular);
  at(Parameter::background_red) = unit(scene_.background.r);
  at(Parameter::background_green) = unit(scene_.background.g);
  at(Parameter::background_blue) = unit(scene_.background.b);
  // Settable ones: the declared default, then the scene's overrides, then the configuration's
  // (each checked against the declared range, which names the key).
  for (int k = 0; k < static_cast<int>(Parameter::count); ++k) {
    const auto id = static_cast<Parameter>(k);
    if (!frame_parameter_computed(id)) p[k] = frame_parameter_default(id, params_.depth_bits);
  }
  for (const auto& [name, value] : scene_.parameters) {
    const int k = parameter_index(name);
    if (k < 0) {
      throw std::invalid_argument(
          fmt::format("scene '{}': unknown frame parameter '{}'", scene_.name, name));
    }
    check_frame_parameter(static_cast<Parameter>(k), value, params_.depth_bits,
                          fmt::format("scene '{}'", scene_.name));
    p[k] = value;
  }
  for (int k = 0; k < static_cast<int>(Parameter::count); ++k) {
    if (const auto& v = params_.frame[static_cast<std::size_t>(k)]) {
      check_frame_parameter(static_cast<Parameter>(k), *v, params_.depth_bits, "configuration");
      p[k] = *v;
    }
  }
  at(Parameter::surface_keep) = 256 - at(Parameter::surface_opacity);
  at(Parameter::highlight_keep) = 256 - at(Parameter::highlight_opacity);
  // dz^2 < (delta/16)^2 * (slope * 2^kSlopeShift)^2  <=>  dz^2 < epsilon_scale * slope^2.
  at(Parameter::epsilon_scale) = std::llround(static_cast<double>(at(Parameter::delta)) *
                                              static_cast<double>(at(Parameter::delta)) *
                                              std::ldexp(1.0, 2 * kSlopeShift - 8));
  // Weak perspective at the target: d(depth)/dx_screen = S * (eye-space slope dz/dx), with
  // S = (d depth / d z_eye) / (d x_screen / d x_eye) = depth_max |P32| / (D W P00).
  const double distance = glm::length(glm::dvec3(scene_.camera.target - scene_.camera.eye));
  const double depth_max = std::ldexp(1.0, params_.depth_bits) - 1.0;
  const double s = depth_max * std::fabs(projection_[3][2]) /
                   (distance * params_.screen_width * projection_[0][0]);
  const double d = static_cast<double>(at(Parameter::delta)) / 16.0;
  at(Parameter::normal_epsilon_scale) =
      std::min<std::int64_t>(std::llround(d * d * s * s / 256.0), (std::int64_t{1} << 30) - 1);
  return p;
}

const ParameterValues& GeometryEngine::setup_parameters() const {
  std::call_once(setup_parameters_once_, [this] {
    if (lights() > 0) setup_parameters_ = frame_parameters(0);
  });
  return setup_parameters_;
}

FrameValues GeometryEngine::frame_values() const {
  FrameValues v;
  v.frame.parameters = frame_parameters(0);
  for (int k = 0; k < lights(); ++k) {
    v.lights.emplace_back();
    v.lights.back().parameters = frame_parameters(k);
  }
  return v;
}

}  // namespace pp5
