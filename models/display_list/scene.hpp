#pragma once
// The host's display list: meshes with their materials, the camera, the lights and the frame's
// parameter overrides. The GPs read it (models/gp); sim/scene builds and loads it.
#include <cstdint>
#include <glm/glm.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pp5 {

struct DepthSortWork;  // models/gp/depth_sort.hpp

// One mesh vertex in world space. `normal` is unit length; `color` is RGB in [0,1]; `opacity`
// is the material's, in [0,1] (1 = opaque; only programs with the `opacity` expression use it).
struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec3 color;
  float opacity = 1.0f;
};

// An indexed triangle mesh. Every index in `triangles` is < vertices.size(). Triangles are wound
// counter-clockwise around their front side, consistently across each connected surface.
struct Mesh {
  std::vector<Vertex> vertices;
  std::vector<glm::uvec3> triangles;
};

// A sphere in world space (the `sphere` primitive kind, models/gp/sphere.hpp): radius > 0,
// `color` RGB in [0,1], opaque.
struct Sphere {
  glm::vec3 center;
  float radius = 1.0f;
  glm::vec3 color{0.8f};
};

struct Camera {
  glm::vec3 eye, target, up;
  float fov_y_degrees;
  float near_plane, far_plane;
};

// A directional light. Its diffuse and specular terms add to those of the scene's other lights.
struct Light {
  // Unit vector from the surface toward the light, in world space.
  glm::vec3 direction;
  float diffuse;
  float specular;
  float shininess;  // the GP's exponent (Gouraud, flat); phong.pp5 uses a fixed 16
};

// Lights per scene: the Renderer runs the firmware's `light` procedure once for each.
inline constexpr int kMaxLights = 8;

// A named closed solid of the scene: triangles [first, last) of the mesh and spheres
// [first_sphere, last_sphere) of Scene::spheres (a quadric solid; the GP sends such a sphere
// as two packets, its near hemisphere as a front face and its far one as a back face). Point
// in solid and CSG classify against solids (the pass plan, models/gp/pass_plan.hpp); a
// primitive in no solid is in group -1.
struct Solid {
  std::string name;
  int first = 0;
  int last = 0;
  int first_sphere = 0;
  int last_sphere = 0;
};

// A literal of a CSG product: solid `solid`, or its complement.
struct CsgLiteral {
  int solid = 0;
  bool negated = false;
  bool operator==(const CsgLiteral& o) const { return solid == o.solid && negated == o.negated; }
};
// A CSG expression as a sum (union) of products (intersections) of literals, each product
// with at least one positive literal (sim/scene/csg_expression.hpp normalises to it).
using CsgProducts = std::vector<std::vector<CsgLiteral>>;

struct Scene {
  std::string name;
  std::string description;
  Mesh mesh;
  std::vector<Sphere> spheres;  // drawn after the mesh's triangles (display-list order)
  Camera camera;
  float ambient = 0.15f;      // ambient reflection, in [0,1], once for the whole scene
  std::vector<Light> lights;  // 1..kMaxLights
  glm::vec3 background;       // RGB in [0,1]
  // The firmware the scene asks for (a program name or .pp5 path), or empty for the
  // command's default; `pp5sim render --firmware` overrides it.
  std::string firmware;
  // Frame-parameter overrides by name (firmware/isa/interface.hpp), from a scene file's
  // "parameters"; the configuration's frame.NAME (--param) wins over them. Unknown or computed
  // names and out-of-range values are rejected by the GP, naming the key.
  std::map<std::string, std::int64_t> parameters;
  // Closed solids over the mesh's triangles (and spheres), disjoint ranges in increasing
  // order; empty for most scenes.
  std::vector<Solid> solids;
  // The scene file's "csg" over its solids, normalised; empty for none.
  CsgProducts csg;
  // Whether the GP prunes the expression by the solids' bounding boxes before planning its
  // passes (Goldfeather's geometric pruning, models/gp/pass_plan.hpp); off only to measure it.
  bool prune_csg = true;
  // Painter's: the GPs' depth sort that put the display list in its order, which the GPs run
  // (spend and send) before their geometry (GraphicsProcessor); null for none. The order
  // itself is the display list's: the host computed it (depth_sort) and only the sort's time
  // and messages are simulated.
  std::shared_ptr<const DepthSortWork> depth_sort;

  // The solid triangle t belongs to, -1 for none.
  int solid_of_triangle(int t) const {
    for (std::size_t s = 0; s < solids.size(); ++s) {
      if (t >= solids[s].first && t < solids[s].last) return static_cast<int>(s);
    }
    return -1;
  }
  // The solid sphere i belongs to, -1 for none.
  int solid_of_sphere(int i) const {
    for (std::size_t s = 0; s < solids.size(); ++s) {
      if (i >= solids[s].first_sphere && i < solids[s].last_sphere) return static_cast<int>(s);
    }
    return -1;
  }
};

// Right-handed view and OpenGL-convention projection (clip z in [-w,w]), as glm::lookAt and
// glm::perspective build them.
glm::mat4 view_matrix(const Camera& camera);
glm::mat4 projection_matrix(const Camera& camera, float aspect);

}  // namespace pp5
