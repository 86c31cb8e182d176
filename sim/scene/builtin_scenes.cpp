#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/scene/builtin_folded_slab.hpp"
#include "sim/scene/mesh_loader.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/sphere_scenes.hpp"

namespace pp5 {
namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr float kFrameMargin = 1.05f;

constexpr int kMaxSegments = 2048;

int segments(int requested, int default_value, int min_value, const char* scene, const char* what) {
  if (requested == 0) return default_value;
  if (requested < min_value || requested > kMaxSegments) {
    throw std::invalid_argument(
        fmt::format("scene '{}': {} must be 0 (default) or in [{}, {}], got {}", scene, what,
                    min_value, kMaxSegments, requested));
  }
  return requested;
}

// A tessellation of nu x nv quads, two triangles each, within the scene bound
// (kMaxSceneTriangles), checked before any vertex is made.
void check_tessellation(int nu, int nv, const char* scene) {
  const auto triangles = 2ull * static_cast<unsigned long long>(nu) * static_cast<unsigned>(nv);
  if (triangles > kMaxSceneTriangles) {
    throw std::invalid_argument(fmt::format(
        "scene '{}': a tessellation of {} x {} makes {} triangles; a scene holds at most {} "
        "(docs/inputs-and-outputs.md)",
        scene, nu, nv, triangles, kMaxSceneTriangles));
  }
}

// A smooth, periodic hue ramp (period 1) with every channel in [0.15, 0.95], so the colour
// wraps around a closed parameter without a seam.
glm::vec3 hue_ramp(double s) {
  const double phase = kTwoPi * s;
  return glm::vec3(static_cast<float>(0.55 + 0.4 * std::cos(phase)),
                   static_cast<float>(0.55 + 0.4 * std::cos(phase - kTwoPi / 3.0)),
                   static_cast<float>(0.55 + 0.4 * std::cos(phase - 2.0 * kTwoPi / 3.0)));
}

Scene finish_scene(std::string name, std::string description, Mesh mesh, glm::vec3 view_dir) {
  Scene scene;
  scene.name = std::move(name);
  scene.description = std::move(description);
  scene.mesh = std::move(mesh);
  scene.camera = frame_mesh(scene.mesh, view_dir, kBuiltinFovYDegrees, kFrameMargin);
  scene.lights = {default_light(scene.camera)};
  scene.background = kBuiltinBackground;
  return scene;
}

// The surface point at knot parameter s and revolution angle t (both radians, period 2*pi).
//
// The knot is the trefoil (sin s + 2 sin 2s, cos s - 2 cos 2s, -sin 3s) with its over/under
// coordinate (-sin 3s) placed on the x axis, scaled by 0.4 and shifted by 0.8 so that the knot
// lies in 0.4 <= x <= 1.2; its planar diagram lies in y and z. Spinning (x, y, z) through the
// xw-plane gives the torus (x cos t, y, z, x sin t), embedded in 4-space because x > 0 keeps
// the circles apart. A perspective projection from the eye (0, 0, 0, kEyeW) onto w = 0 turns it
// into a knotted tube that passes through itself at the three crossings (kEyeW exceeds
// |w| <= 1.2, so every scale factor is positive and bounded). The final cyclic permutation of
// the axes, a rotation, puts the knot diagram in the xy-plane, facing a camera on +z.
//
// `turn` (radians) first rotates the 4-D surface in the zw-plane, which changes its projected
// shape (a rotation in the xw-plane would only slide t); `eye_w` is the projection's eye. The
// static scene is turn 0 with the eye at w = 3.
glm::dvec3 torus_point(double s, double t, double turn, double eye_w) {
  const double x = 0.8 - 0.4 * std::sin(3.0 * s);
  const double y = std::sin(s) + 2.0 * std::sin(2.0 * s);
  double z = std::cos(s) - 2.0 * std::cos(2.0 * s);
  double w = x * std::sin(t);
  if (turn != 0.0) {
    const double z0 = z;
    z = z0 * std::cos(turn) - w * std::sin(turn);
    w = z0 * std::sin(turn) + w * std::cos(turn);
  }
  const double scale = eye_w / (eye_w - w);
  const glm::dvec3 p(x * std::cos(t) * scale, y * scale, z * scale);
  return glm::dvec3(p.y, p.z, p.x);
}

constexpr double kTorusEyeW = 3.0;

}  // namespace

Scene make_turned_torus(const SceneOptions& options, double turn, double eye_w) {
  const int nu = segments(options.tessellation_u, 128, 3, "torus", "tessellation_u");
  const int nv = segments(options.tessellation_v, 32, 3, "torus", "tessellation_v");
  check_tessellation(nu, nv, "torus");
  Mesh mesh;
  mesh.vertices.reserve(static_cast<std::size_t>(nu) * nv);
  mesh.triangles.reserve(2 * static_cast<std::size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i) {
    const double u = static_cast<double>(i) / nu;
    const glm::vec3 color = hue_ramp(u);
    for (int j = 0; j < nv; ++j) {
      const double v = static_cast<double>(j) / nv;
      mesh.vertices.push_back(
          {glm::vec3(torus_point(kTwoPi * u, kTwoPi * v, turn, eye_w)), glm::vec3(0.0f), color});
    }
  }
  // Vertex (i, j) has index i * nv + j; both directions wrap, so the seams share vertices and
  // the surface is closed. Both triangles of every quad are wound so that their normals point
  // along dP/dv x dP/du, which is away from the tube's core curve: outward.
  auto index = [nu, nv](int i, int j) { return static_cast<unsigned>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const unsigned a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1),
                     d = index(i, j + 1);
      mesh.triangles.emplace_back(a, d, c);
      mesh.triangles.emplace_back(a, c, b);
    }
  }
  compute_smooth_normals(mesh);
  return finish_scene("torus",
                      "Banks' self-intersecting torus: a trefoil knot spun through the xw-plane of "
                      "4-space and projected to 3-D in perspective",
                      std::move(mesh), glm::vec3(0.3f, 0.5f, 1.0f));
}

namespace {

Scene make_torus(const SceneOptions& options) {
  return make_turned_torus(options, 0.0, kTorusEyeW);
}

Scene make_two_triangles() {
  // Both triangles contain the segment of the y axis between y = -0.8 and 0.8, so each pierces
  // the other along it. The red one points up, the blue one down, in vertical planes turned -30
  // and +30 degrees about y from facing +z: 60 degrees apart and both lit from the front.
  const glm::vec3 view_dir(0.15f, 0.3f, 1.0f);
  auto across = [](float degrees) {
    const float a = glm::radians(degrees);
    return glm::vec3(std::cos(a), 0.0f, -std::sin(a));
  };
  const glm::vec3 red_across = across(-30.0f), blue_across = across(30.0f);
  const glm::vec3 red(0.9f, 0.2f, 0.15f), blue(0.2f, 0.35f, 0.95f);
  const glm::vec3 low(0.0f, -0.8f, 0.0f), high(0.0f, 0.8f, 0.0f);
  const glm::vec3 red_corners[3] = {low - red_across, low + red_across, {0.0f, 0.9f, 0.0f}};
  const glm::vec3 blue_corners[3] = {high - blue_across, high + blue_across, {0.0f, -0.9f, 0.0f}};
  Mesh mesh;
  auto add = [&mesh, view_dir](const glm::vec3(&p)[3], glm::vec3 color) {
    glm::vec3 normal = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    const auto base = static_cast<unsigned>(mesh.vertices.size());
    // Wind each triangle counter-clockwise as seen from the camera, so its front faces the eye.
    const bool flip = glm::dot(normal, view_dir) < 0.0f;
    if (flip) normal = -normal;
    for (const glm::vec3& corner : p) mesh.vertices.push_back({corner, normal, color});
    mesh.triangles.push_back(flip ? glm::uvec3(base, base + 2, base + 1)
                                  : glm::uvec3(base, base + 1, base + 2));
  };
  add(red_corners, red);
  add(blue_corners, blue);
  return finish_scene("two-triangles",
                      "Two interpenetrating triangles, red and blue, crossing at 60 degrees",
                      std::move(mesh), view_dir);
}

Scene make_sphere(const SceneOptions& options) {
  const int nu = segments(options.tessellation_u, 64, 3, "sphere", "tessellation_u");
  const int nv = segments(options.tessellation_v, 32, 2, "sphere", "tessellation_v");
  check_tessellation(nu, nv, "sphere");
  const glm::vec3 color(0.9f, 0.55f, 0.25f);
  // Vertex 0 is the north pole (+y), then nv - 1 rings of nu vertices from north to south, then
  // the south pole. Position and outward normal coincide on the unit sphere; the surface point
  // at polar angle theta and azimuth phi is (sin theta sin phi, cos theta, sin theta cos phi),
  // for which d/dtheta x d/dphi points outward.
  Mesh mesh;
  mesh.vertices.push_back({{0.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, color});
  for (int k = 1; k < nv; ++k) {
    const double theta = 0.5 * kTwoPi * k / nv;
    for (int i = 0; i < nu; ++i) {
      const double phi = kTwoPi * i / nu;
      const glm::vec3 p(glm::dvec3(std::sin(theta) * std::sin(phi), std::cos(theta),
                                   std::sin(theta) * std::cos(phi)));
      mesh.vertices.push_back({p, glm::normalize(p), color});
    }
  }
  const auto south = static_cast<unsigned>(mesh.vertices.size());
  mesh.vertices.push_back({{0.0f, -1.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, color});
  auto ring = [nu](int k, int i) { return static_cast<unsigned>(1 + (k - 1) * nu + i % nu); };
  for (int i = 0; i < nu; ++i) mesh.triangles.emplace_back(0u, ring(1, i), ring(1, i + 1));
  for (int k = 1; k + 1 < nv; ++k) {
    for (int i = 0; i < nu; ++i) {
      const unsigned a = ring(k, i), b = ring(k + 1, i), c = ring(k + 1, i + 1), d = ring(k, i + 1);
      mesh.triangles.emplace_back(a, b, c);
      mesh.triangles.emplace_back(a, c, d);
    }
  }
  for (int i = 0; i < nu; ++i)
    mesh.triangles.emplace_back(ring(nv - 1, i), south, ring(nv - 1, i + 1));
  return finish_scene("sphere", "A UV sphere of one colour", std::move(mesh),
                      glm::vec3(0.3f, 0.4f, 1.0f));
}

Scene make_figure_eight(const SceneOptions& options) {
  // Cross-sections y = const are figure-eights x = sin u, z = b(y) sin u cos u, which cross
  // themselves at x = z = 0 with slopes dz/dx = +-b(y): steeply near the ends (|y| = 1),
  // shallowly in the middle. The crossing line, x = z = 0, is the self-intersection. The
  // samples of u are offset by half a step so the line runs through triangle interiors.
  const int nu = segments(options.tessellation_u, 96, 8, "figure-eight", "tessellation_u");
  const int nv = segments(options.tessellation_v, 48, 2, "figure-eight", "tessellation_v");
  check_tessellation(nu, nv, "figure-eight");
  Mesh mesh;
  for (int j = 0; j <= nv; ++j) {
    const double y = -1.0 + 2.0 * j / nv;
    const double b = 0.2 + 2.2 * y * y;
    for (int i = 0; i < nu; ++i) {
      const double u = kTwoPi * (i + 0.5) / nu;
      const glm::vec3 color = hue_ramp(0.5 * (y + 1.0) * 0.6);
      mesh.vertices.push_back({glm::vec3(static_cast<float>(std::sin(u)), static_cast<float>(y),
                                         static_cast<float>(b * std::sin(u) * std::cos(u))),
                               glm::vec3(0.0f), color});
    }
  }
  auto index = [nu](int i, int j) { return static_cast<unsigned>(j * nu + (i % nu)); };
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      mesh.triangles.emplace_back(index(i, j), index(i + 1, j), index(i + 1, j + 1));
      mesh.triangles.emplace_back(index(i, j), index(i + 1, j + 1), index(i, j + 1));
    }
  }
  compute_smooth_normals(mesh);
  return finish_scene("figure-eight",
                      "A surface whose cross-sections are figure-eights, self-intersecting "
                      "steeply at its ends and shallowly in the middle (Banks, figure 7)",
                      std::move(mesh), glm::vec3(0.25f, 0.2f, 1.0f));
}

Scene make_crossing_quads() {
  // Two unit squares through the y axis, 50 degrees apart, each two triangles: the scene for
  // transparency, where blending hides the line where they cross.
  Mesh mesh;
  auto add = [&mesh](double degrees, glm::vec3 color) {
    const double a = degrees * kTwoPi / 360.0;
    const glm::vec3 across(static_cast<float>(std::cos(a)), 0.0f, static_cast<float>(-std::sin(a)));
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    const glm::vec3 normal = glm::normalize(glm::cross(across, up));
    const auto base = static_cast<unsigned>(mesh.vertices.size());
    for (const glm::vec3 corner : {-across - up, across - up, across + up, -across + up})
      mesh.vertices.push_back({corner, normal, color});
    mesh.triangles.emplace_back(base, base + 1, base + 2);
    mesh.triangles.emplace_back(base, base + 2, base + 3);
  };
  add(-25.0, glm::vec3(0.95f, 0.55f, 0.2f));
  add(25.0, glm::vec3(0.25f, 0.6f, 0.95f));
  return finish_scene("crossing-quads",
                      "Two intersecting square polygons, 50 degrees apart (for transparency)",
                      std::move(mesh), glm::vec3(0.2f, 0.35f, 1.0f));
}

Scene make_receding_pairs() {
  // Five identical pairs of interpenetrating triangles (as in two-triangles: vertical planes
  // 60 degrees apart, crossing along a vertical segment 1.2 long) at eye distances 5, 7.5,
  // 11.25, 16.9 and 25.3, each turned to face the eye, spread left to right so that none
  // hides another. The same geometry at growing distance: the scene for comparing depth
  // quantities under perspective (the crossing line of pair k lies at distance 5 * 1.5^k).
  constexpr int kPairs = 5;
  constexpr double kHalfWidth = 0.5;
  constexpr double kHalfHeight = 0.6;
  constexpr double kGap = 0.04;  // radians between neighbouring pairs
  // Directions of the pairs' centres: each pair's angular half-width beside the next, the
  // row centred on the view axis.
  double distance[kPairs], angle[kPairs];
  for (int k = 0; k < kPairs; ++k) {
    distance[k] = 5.0 * std::pow(1.5, k);
    const double half = std::atan(kHalfWidth / distance[k]);
    angle[k] = k == 0 ? 0.0 : angle[k - 1] + std::atan(kHalfWidth / distance[k - 1]) + half + kGap;
  }
  const double shift = 0.5 * (angle[0] - std::atan(kHalfWidth / distance[0]) + angle[kPairs - 1] +
                              std::atan(kHalfWidth / distance[kPairs - 1]));
  Mesh mesh;
  for (int k = 0; k < kPairs; ++k) {
    const double direction = angle[k] - shift;
    const glm::dvec3 centre(distance[k] * std::sin(direction), 0.0,
                            -distance[k] * std::cos(direction));
    const glm::dvec3 toward_eye = -glm::normalize(centre);
    const glm::dvec3 up(0.0, 1.0, 0.0);
    const glm::dvec3 side = glm::normalize(glm::cross(up, toward_eye));
    const glm::vec3 colors[2] = {{0.9f, 0.2f, 0.15f}, {0.2f, 0.35f, 0.95f}};
    for (int t = 0; t < 2; ++t) {
      // Turned -30 (red, pointing up) and +30 degrees (blue, pointing down) about the vertical.
      const double a = glm::radians(t == 0 ? -30.0 : 30.0);
      const glm::dvec3 across = std::cos(a) * side + std::sin(a) * toward_eye;
      const double s = t == 0 ? 1.0 : -1.0;
      const glm::dvec3 p[3] = {centre - s * up * kHalfHeight - across * kHalfWidth,
                               centre - s * up * kHalfHeight + across * kHalfWidth,
                               centre + s * up * (kHalfHeight + 0.1)};
      glm::dvec3 normal = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
      const auto base = static_cast<unsigned>(mesh.vertices.size());
      const bool flip = glm::dot(normal, toward_eye) < 0.0;
      if (flip) normal = -normal;
      for (const glm::dvec3& corner : p)
        mesh.vertices.push_back({glm::vec3(corner), glm::vec3(normal), colors[t]});
      mesh.triangles.push_back(flip ? glm::uvec3(base, base + 2, base + 1)
                                    : glm::uvec3(base, base + 1, base + 2));
    }
  }
  Scene scene;
  scene.name = "receding-pairs";
  scene.description =
      "Five identical pairs of interpenetrating triangles receding from the eye (5 to 25 "
      "units), for depth quantities under perspective";
  scene.mesh = std::move(mesh);
  // The target is the middle pair's distance: epsilon_normal scales its slopes there.
  scene.camera = {{0.0f, 0.0f, 0.0f},
                  {0.0f, 0.0f, -11.25f},
                  {0.0f, 1.0f, 0.0f},
                  kBuiltinFovYDegrees,
                  2.0f,
                  40.0f};
  scene.lights = {default_light(scene.camera)};
  scene.background = kBuiltinBackground;
  return scene;
}

// Appends the planar convex polygon `corners` (3 or 4, in order) in one colour, wound
// counter-clockwise as seen from the side `toward_eye` points to, as a fan of triangles.
void add_facing_polygon(Mesh& mesh, const std::vector<glm::dvec3>& corners, glm::vec3 color,
                        const glm::dvec3& toward_eye) {
  glm::dvec3 normal = glm::normalize(glm::cross(corners[1] - corners[0], corners[2] - corners[0]));
  const bool flip = glm::dot(normal, toward_eye) < 0.0;
  if (flip) normal = -normal;
  const auto base = static_cast<unsigned>(mesh.vertices.size());
  for (const glm::dvec3& c : corners)
    mesh.vertices.push_back({glm::vec3(c), glm::vec3(normal), color});
  for (unsigned k = 1; k + 1 < corners.size(); ++k) {
    mesh.triangles.push_back(flip ? glm::uvec3(base, base + k + 1, base + k)
                                  : glm::uvec3(base, base + k, base + k + 1));
  }
}

Scene make_cyclic_overlap() {
  // Three sticks along the sides of an equilateral triangle (lines at 120 degrees tangent to
  // a circle of radius 0.3), each tilted in depth along its length (z = 0.25 s at position s
  // along it). Stick k crosses stick k + 1 at s = +0.3 sqrt(3) on itself and s = -0.3 sqrt(3)
  // on the other, so at every crossing k lies in front of k + 1: 0 over 1, 1 over 2, 2 over
  // 0, a cyclic overlap with 0.26 of depth between the sticks at each crossing (no two
  // intersect). No order of the six triangles paints it right.
  const glm::dvec3 toward_eye(0.0, 0.0, 1.0);
  const glm::vec3 colors[3] = {{0.9f, 0.25f, 0.2f}, {0.25f, 0.8f, 0.3f}, {0.25f, 0.4f, 0.95f}};
  constexpr double kRadius = 0.3, kTilt = 0.25, kHalfWidth = 0.08, kHalfLength = 1.0;
  Mesh mesh;
  for (int k = 0; k < 3; ++k) {
    const double a = kTwoPi * k / 3.0;
    const glm::dvec2 d(std::cos(a), std::sin(a)), n(-std::sin(a), std::cos(a));
    auto at = [&](double s, double t) {
      const glm::dvec2 p = (kRadius + t) * n + s * d;
      return glm::dvec3(p.x, p.y, kTilt * s);
    };
    add_facing_polygon(mesh,
                       {at(-kHalfLength, -kHalfWidth), at(kHalfLength, -kHalfWidth),
                        at(kHalfLength, kHalfWidth), at(-kHalfLength, kHalfWidth)},
                       colors[k], toward_eye);
  }
  return finish_scene("cyclic-overlap",
                      "Three sticks overlapping cyclically, each in front of the next: no "
                      "back-to-front order exists (painter's hard case)",
                      std::move(mesh), glm::vec3(toward_eye));
}

Scene make_pierced_quad() {
  // A square in the plane z = 0 and a long thin triangle through it, from z = -0.8 at the
  // left to z = +0.8 at the right: they interpenetrate along x = 0, so neither is wholly in
  // front of the other.
  const glm::dvec3 toward_eye(0.0, 0.0, 1.0);
  Mesh mesh;
  add_facing_polygon(mesh, {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}},
                     glm::vec3(0.3f, 0.5f, 0.9f), toward_eye);
  add_facing_polygon(mesh, {{-1.2, -0.15, -0.8}, {1.2, 0.0, 0.8}, {-1.2, 0.15, -0.8}},
                     glm::vec3(0.95f, 0.6f, 0.15f), toward_eye);
  return finish_scene("pierced-quad",
                      "A long thin triangle piercing a square: interpenetration (painter's "
                      "hard case)",
                      std::move(mesh), glm::vec3(0.3, 0.2, 1.0));
}

Scene make_long_thin() {
  // Two layers of six long thin triangles (slivers 2.4 long, 0.1 wide at the base) on
  // parallel tilted planes z = 0.4 y and z = 0.4 y + 0.08: horizontal ones behind,
  // vertical ones in front. Every sliver spans most of the depth range, so the depth extents
  // of crossing slivers overlap and the minimax tests cannot order them; the plane tests
  // can. Painter's is right here when the tests run, wrong when sorting by depth alone.
  const glm::dvec3 toward_eye(0.0, 0.0, 1.0);
  constexpr int kSlivers = 6;
  constexpr double kHalfBase = 0.05, kHalfLength = 1.2, kTilt = 0.4, kGap = 0.08;
  Mesh mesh;
  for (int i = 0; i < kSlivers; ++i) {
    const double c = -1.0 + 2.0 * (i + 0.5) / kSlivers;
    auto back = [&](double x, double y) { return glm::dvec3(x, y, kTilt * y); };
    add_facing_polygon(mesh,
                       {back(-kHalfLength, c - kHalfBase), back(kHalfLength, c),
                        back(-kHalfLength, c + kHalfBase)},
                       hue_ramp(0.1 + 0.05 * i), toward_eye);
  }
  for (int i = 0; i < kSlivers; ++i) {
    const double c = -1.0 + 2.0 * (i + 0.5) / kSlivers;
    auto front = [&](double x, double y) { return glm::dvec3(x, y, kTilt * y + kGap); };
    add_facing_polygon(mesh,
                       {front(c - kHalfBase, -kHalfLength), front(c + kHalfBase, -kHalfLength),
                        front(c, kHalfLength)},
                       hue_ramp(0.55 + 0.05 * i), toward_eye);
  }
  return finish_scene("long-thin",
                      "Two crossing layers of long thin triangles on parallel tilted planes: "
                      "overlapping depth extents that only the plane tests order",
                      std::move(mesh), glm::vec3(0.0, 0.1, 1.0));
}

}  // namespace

std::vector<std::string> builtin_scene_names() {
  std::vector<std::string> names = {
      "torus",          "two-triangles",  "sphere",       "figure-eight", "crossing-quads",
      "receding-pairs", "cyclic-overlap", "pierced-quad", "long-thin",    "folded-slab"};
  for (const std::string& n : sphere_scene_names()) names.push_back(n);
  return names;
}

std::vector<std::string> builtin_triangle_scene_names() {
  std::vector<std::string> names = builtin_scene_names();
  const std::vector<std::string> spheres = sphere_scene_names();
  names.erase(std::remove_if(names.begin(), names.end(),
                             [&](const std::string& n) {
                               return std::find(spheres.begin(), spheres.end(), n) != spheres.end();
                             }),
              names.end());
  return names;
}

Scene make_builtin_scene(const std::string& name, const SceneOptions& options) {
  if (name == "torus") return make_torus(options);
  if (name == "sphere") return make_sphere(options);
  if (name == "figure-eight") return make_figure_eight(options);
  const auto spheres = sphere_scene_names();
  const bool sphere_scene = std::find(spheres.begin(), spheres.end(), name) != spheres.end();
  const bool fixed = name == "two-triangles" || name == "crossing-quads" ||
                     name == "receding-pairs" || name == "cyclic-overlap" ||
                     name == "pierced-quad" || name == "long-thin" || name == "folded-slab" ||
                     sphere_scene;
  if (fixed && (options.tessellation_u != 0 || options.tessellation_v != 0)) {
    throw std::invalid_argument(fmt::format(
        "--tessellation: scene '{}' has fixed geometry; only torus, sphere and figure-eight "
        "take a tessellation",
        name));
  }
  if (sphere_scene) return make_sphere_scene(name);
  if (name == "two-triangles") return make_two_triangles();
  if (name == "crossing-quads") return make_crossing_quads();
  if (name == "receding-pairs") return make_receding_pairs();
  if (name == "cyclic-overlap") return make_cyclic_overlap();
  if (name == "pierced-quad") return make_pierced_quad();
  if (name == "long-thin") return make_long_thin();
  if (name == "folded-slab") return make_folded_slab();
  std::string valid;
  for (const std::string& n : builtin_scene_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument(fmt::format("unknown scene '{}'; valid scenes: {}", name, valid));
}

}  // namespace pp5
