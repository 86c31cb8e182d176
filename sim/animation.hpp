#pragma once
// Scenes that change from frame to frame: the scene of each frame of an animation, for a
// Session (sim/simulation.hpp, Session::set_scene) to draw one after the other.
//
// Three kinds of motion, chosen by the scene argument:
//  - "torus": Banks' torus turning in 4-space. Frame k turns the 4-D surface by
//    360 * k / frames degrees in the zw-plane before the perspective projection to 3-D
//    (make_turned_torus), from an eye at w = kAnimatedTorusEyeW, so the projected surface
//    changes shape (and its normals with it) from frame to frame. The camera is one for all
//    frames: framed to the surfaces of 16 turns at once.
//  - any other built-in scene (the molecule among them) and a scene file without
//    "animation": a turn about the vertical axis through the centre of the scene's bounding
//    sphere, 360 * k / frames degrees at frame k; the camera looks along the scene's own view
//    direction at that centre from far enough to keep the bounding sphere in view; the lights
//    stay where they are in the world.
//  - a scene file with "animation" (docs/reference/scene-files.md): a camera path and
//    per-object transforms given by keyframes, interpolated linearly between keys and held
//    before the first and after the last.
//
// Contract:
//  - scene(k) is a function of the animation and k alone (any k >= 0; deterministic, the
//    same bits on any host thread); every frame's scene has the primitives of frame 0, in the
//    same order (only positions, normals, the camera and lights change), as Session::set_scene
//    requires.
//  - Bad "animation" input throws SceneError naming the file and the key's path
//    ("animation.camera[1].frame") and what was expected.
#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "models/config/machine_config.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"

namespace pp5 {

inline constexpr double kAnimatedTorusEyeW = 5.0;
inline constexpr int kDefaultAnimationFrames = 24;
inline constexpr double kDefaultAnimationFps = 12.0;

// A camera keyframe: at frame `frame`, the camera at eye looking at target.
struct CameraKey {
  int frame = 0;
  glm::dvec3 eye{0, 0, 1}, target{0}, up{0, 1, 0};
  double fov_y_degrees = 40;
};

// An object keyframe: the object's extra transform at frame `frame`, about its pivot (the
// centre of its bounding box in the file's scene): scaled, rotated about x then y then z,
// then moved by translate.
struct ObjectKey {
  int frame = 0;
  glm::dvec3 translate{0}, rotate_degrees{0};
  double scale = 1;
};

// One animated entry of the scene file: vertices [first, last) of the mesh and spheres
// [first_sphere, last_sphere).
struct ObjectTrack {
  std::string what;  // "meshes[1]", "spheres[0]"
  int first_vertex = 0, last_vertex = 0;
  int first_sphere = 0, last_sphere = 0;
  glm::dvec3 pivot{0};
  std::vector<ObjectKey> keys;  // in increasing frame order, at least one
};

struct AnimationOptions {
  SceneOptions scene;  // tessellation of the built-in torus or sphere
  int frames = 0;      // 0: the scene file's "animation.frames", else kDefaultAnimationFrames
  double fps = 0;      // 0: the scene file's "animation.fps", else kDefaultAnimationFps
};

class Animation {
 public:
  Animation(std::string name, std::string motion, int frames, double fps,
            std::function<Scene(int frame)> make);
  const std::string& name() const { return name_; }
  // What moves, for people ("turning in the zw-plane of 4-space", ...).
  const std::string& motion() const { return motion_; }
  int frames() const { return frames_; }
  double fps() const { return fps_; }
  Scene scene(int frame) const { return make_(frame); }

 private:
  std::string name_, motion_;
  int frames_;
  double fps_;
  std::function<Scene(int frame)> make_;
};

// A built-in scene name or a scene file (.json); a mesh file turns as a built-in does.
Animation load_animation(const std::string& name_or_path, const AnimationOptions& options = {});

// The scene file's "animation" over its scene (`base`, as the loader read it, with `parts`
// saying where each entry landed); `origin` names the file in messages.
Animation parse_animation_json(const std::string& text, const std::string& origin, Scene base,
                               const SceneParts& parts, const AnimationOptions& options);

// Every frame's scene of `animation`, made and checked (each frame's parameters computed for
// `config`'s Graphics Processors) before anything runs: a bad frame throws before any frame is
// simulated. `pp5sim animate` and the Python module's animated sessions draw these.
std::vector<std::shared_ptr<const Scene>> animation_scenes(const Animation& animation,
                                                           const MachineConfig& config);

// The same checks, keeping no scene: each frame's scene is made, checked and dropped, so that
// a long animation (pp5sim animate) holds one scene at a time and makes each again as its
// frame runs (animation_scene). Returns frame 0's.
std::shared_ptr<const Scene> check_animation_scenes(const Animation& animation,
                                                    const MachineConfig& config);
// Frame `frame`'s scene, as animation_scenes makes it (not checked again).
std::shared_ptr<const Scene> animation_scene(const Animation& animation, int frame);

// The camera of `keys` at `frame`, near and far planes from `base`.
Camera camera_at(const std::vector<CameraKey>& keys, int frame, const Camera& base);
// `track`'s transform at `frame` applied to `scene` (which holds the track's frame-0 geometry).
void apply_track(const ObjectTrack& track, int frame, Scene& scene);
// The turn about the vertical axis (see above) of `base` by `degrees`.
Scene turned_scene(const Scene& base, double degrees);

}  // namespace pp5
