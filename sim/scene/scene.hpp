#pragma once
// Scenes as the host builds them: the built-in scenes, framing a mesh with a camera, the
// default light and smooth normals. The display list itself (what the GPs read) is
// models/display_list/scene.hpp.

#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "models/display_list/scene.hpp"

namespace pp5 {

// Tessellation overrides; 0 keeps the scene's default. For the torus, u runs along the knot and v
// around the revolution; for the sphere, u runs around the equator and v from pole to pole. The
// scenes of fixed geometry (two-triangles, crossing-quads, receding-pairs, cyclic-overlap,
// pierced-quad, long-thin) and files refuse them.
struct SceneOptions {
  int tessellation_u = 0;
  int tessellation_v = 0;
};

// The names make_builtin_scene accepts: {"torus", "two-triangles", "sphere", "figure-eight",
// "crossing-quads", "receding-pairs", "cyclic-overlap", "pierced-quad", "long-thin",
// "folded-slab"}.
std::vector<std::string> builtin_scene_names();
// The built-in scenes made of triangles only (no spheres): what the analyses that compare
// triangle algorithms (visible, scanconvert) run by default.
std::vector<std::string> builtin_triangle_scene_names();

// Builds a scene deterministically from its arguments alone. Throws std::invalid_argument for an
// unknown name (the message lists the valid names) or a tessellation outside the scene's range.
//   torus:  2*u*v triangles, default u=128, v=32 (8,192); u and v in [3, 2048].
//   sphere: 2*u*(v-1) triangles, default u=64, v=32 (3,968); u in [3, 2048], v in [2, 2048].
//   two-triangles: 2 triangles, 6 vertices.
//   figure-eight: 2*u*v triangles, default u=96, v=48; u in [8, 2048], v in [2, 2048].
//   crossing-quads: 4 triangles, 8 vertices.
//   receding-pairs: 10 triangles, 30 vertices; a fixed camera at the origin looking down -z.
//   cyclic-overlap: 6 triangles (three sticks, each in front of the next: painter's cannot
//   order them); pierced-quad: 3 triangles (a sliver through a square); long-thin: 12
//   slivers on two parallel tilted planes (only the plane tests order them).
//   folded-slab: 1,696 triangles, 850 vertices (sim/scene/builtin_folded_slab.hpp).
Scene make_builtin_scene(const std::string& name, const SceneOptions& options = {});

// The torus turned by `turn` radians in the zw-plane of 4-space before its perspective
// projection from the eye (0, 0, 0, eye_w) (eye_w must exceed the surface's |w|, 3.3 at any
// turn); make_builtin_scene("torus") is turn 0 with eye_w 3. Its camera is framed to this
// turn's mesh.
Scene make_turned_torus(const SceneOptions& options, double turn, double eye_w);

struct BoundingSphere {
  glm::vec3 center;
  float radius;
};

// A sphere containing every vertex: centred on the bounding box, radius to the farthest vertex.
BoundingSphere bounding_sphere(const Mesh& mesh);

// A camera looking along -view_direction (view_direction points from the object toward the eye
// and need not be unit) with world +y as up, fitted to the mesh: the view is shifted sideways to
// centre the mesh's image and moved as close as possible while every vertex stays inside the
// central 1/margin of the frame at aspect ratio 1 (and so at any wider aspect). The near and far
// planes bracket the mesh's depth range with 10% slack to keep depth precision. view_direction
// must not be parallel to +y.
Camera frame_mesh(const Mesh& mesh, glm::vec3 view_direction, float fov_y_degrees,
                  float margin = 1.05f);

// The built-in scenes' vertical field of view and background.
inline constexpr float kBuiltinFovYDegrees = 40.0f;
inline const glm::vec3 kBuiltinBackground{0.05f, 0.05f, 0.08f};

// The project's standard key light, from the upper left in front of `camera`: diffuse 0.8,
// specular 0.3, shininess 16 (with the scene's default ambient 0.15).
Light default_light(const Camera& camera);

// Sets every vertex normal to the normalised area-weighted sum of the normals of the triangles
// that use it. A vertex whose sum vanishes (or that no triangle uses) gets the normal of its
// largest adjacent triangle, or +z if it has none, so every normal stays unit length.
void compute_smooth_normals(Mesh& mesh);

}  // namespace pp5
