#pragma once
// Scene description files (JSON) and the one entry point the command line uses to turn a
// --scene argument (a built-in name, a mesh file or a scene file) into a Scene.
//
// A scene file:
//   {
//     "meshes": [                                  at least one, if given
//       {"file": "bunny.obj",                      a mesh file, relative to the scene file,
//        "translate": [0, 0, 0],                   or "builtin": "sphere", or inline
//        "rotate_degrees": [0, 30, 0],             "vertices": [[x,y,z], ...] and
//        "scale": 1.0,                             "triangles": [[i,j,k], ...];
//        "material": "glass"}                      a name from "materials", or an inline
//                                                  {"color": .., "opacity": ..}, or
//                                                  "color": [r,g,b] (an opaque material);
//                                                  none: the mesh file's colours or 0.8 grey
//     ],
//     "spheres": [                                 sphere primitives (models/gp/sphere.hpp);
//       {"center": [x,y,z], "radius": 1,           "meshes" or "spheres" or both, each with
//        "color": [r,g,b]} (or an opaque           at least one entry
//        "material"),
//       {"molecule": "crambin.pdb",                a PDB or mmCIF file's atoms (Bondi radii,
//        "translate": [..], "rotate_degrees": [..],  CPK colours), relative to the scene
//        "scale": 0.1}                             file; a uniform scale, radii too
//     ],
//     "materials": {"glass": {"color": [0.6, 0.8, 1.0],   RGB in 0..1 (absent: as above)
//                             "opacity": 0.4}},           0..1, default 1 (opaque); reaches
//                                                         the pixels through the `opacity`
//                                                         expression (transparent.pp5)
//     "camera": {"eye": [..], "target": [..], "up": [0,1,0],
//                "fov_y_degrees": 40, "near": 0.1, "far": 100},
//        or {"view_direction": [x,y,z], "fov_y_degrees": 40} to frame the meshes;
//        absent: framed from the front and a little above
//     "ambient": 0.15,                             the scene's ambient reflection, 0..1
//     "lights": [                                  1 to 8 directional lights, each adding
//       {"direction": [x,y,z], "diffuse": 0.8,     its diffuse and specular terms; absent
//        "specular": 0.3, "shininess": 16}, ...]   keys take the standard key light's
//        or "light": {...} for one light (which may also hold "ambient"; not with "lights");
//        neither: the standard key light
//     "background": [r, g, b],
//     "firmware": "transparent",                   the program `pp5sim render` uses unless
//                                                  --firmware says otherwise (a name in
//                                                  firmware/programs or a .pp5 path relative
//                                                  to the scene file)
//     "name": "...", "description": "..."
//   }
// Rotation applies about x, then y, then z, after scaling and before translation.
//
// Contract: unknown keys, wrong types, out-of-range values and keys that exclude each other
// ("light" with "lights", "ambient" with "light.ambient", "color" with "material") and
// unknown material names are SceneError whose message names
// the file and the key's path (e.g. "meshes[1].scale", "lights[2].diffuse"); mesh-file errors
// keep the mesh file's own line numbers.
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/scene/mesh_loader.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Where each entry of a scene file landed in the Scene: per "meshes" entry its vertices
// [first, second), per "spheres" entry its spheres [first, second). An animation's
// per-object keyframes move them (sim/animation.hpp).
struct SceneParts {
  std::vector<std::pair<int, int>> mesh_vertices;
  std::vector<std::pair<int, int>> spheres;
};

// Parses a scene description; `origin` names it in messages and `base_dir` resolves
// relative mesh paths. Its "animation" is read by sim/animation.hpp, not here.
Scene parse_scene_json(const std::string& text, const std::string& origin,
                       const std::string& base_dir, const LoadLimits& limits = {},
                       SceneParts* parts = nullptr);
// `text_out`, if given, receives the file's text.
Scene load_scene_file(const std::string& path, const LoadLimits& limits = {},
                      SceneParts* parts = nullptr, std::string* text_out = nullptr);

// A built-in scene name, a mesh file (.obj .ply .stl .off) or a scene file (.json).
Scene load_scene(const std::string& name_or_path, const SceneOptions& options = {});

}  // namespace pp5
