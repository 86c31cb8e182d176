#include "sim/animation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "common/strict_json.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/machine_plan.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

using json = nlohmann::json;
constexpr double kAnimPi = 3.14159265358979323846;

// A key of the "animation" object and its path, for messages as the scene loader words them.
struct AnimNode {
  const json& value;
  std::string path;
  const std::string& origin;

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(fmt::format("{}: key '{}' {}", origin, path, what));
  }
  bool has(const char* key) const { return value.is_object() && value.contains(key); }
  AnimNode at(const std::string& key) const { return {value.at(key), path + "." + key, origin}; }
  AnimNode at(std::size_t i) const { return {value.at(i), fmt::format("{}[{}]", path, i), origin}; }
  void check_keys(std::initializer_list<const char*> allowed) const {
    if (!value.is_object()) fail(fmt::format("must be an object (got {})", value.type_name()));
    for (const auto& item : value.items()) {
      if (std::none_of(allowed.begin(), allowed.end(),
                       [&](const char* k) { return item.key() == k; })) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        throw SceneError(fmt::format("{}: unknown key '{}.{}' (expected one of: {})", origin, path,
                                     item.key(), list));
      }
    }
  }
  double number(double lo, double hi) const {
    if (!value.is_number()) fail(fmt::format("must be a number (got {})", value.type_name()));
    const double v = value.get<double>();
    if (!(v >= lo && v <= hi)) fail(fmt::format("must be in [{}, {}] (got {})", lo, hi, v));
    return v;
  }
  int integer(int lo, int hi) const {
    if (!value.is_number_integer()) {
      fail(fmt::format("must be an integer (got {})", value.dump()));
    }
    const auto v = value.get<long long>();
    if (v < lo || v > hi) fail(fmt::format("must be in [{}, {}] (got {})", lo, hi, v));
    return static_cast<int>(v);
  }
  glm::dvec3 vec3(double bound = 1e12) const {
    if (!value.is_array() || value.size() != 3 ||
        !std::all_of(value.begin(), value.end(), [](const json& e) { return e.is_number(); })) {
      fail(fmt::format("must be an array of 3 numbers (got {})", value.dump()));
    }
    glm::dvec3 v;
    for (int i = 0; i < 3; ++i) {
      v[i] = value[static_cast<std::size_t>(i)].get<double>();
      if (!(std::abs(v[i]) <= bound)) {
        fail(fmt::format("must hold numbers in [-{0}, {0}] (got {1})", bound, value.dump()));
      }
    }
    return v;
  }
  const json& array() const {
    if (!value.is_array()) fail(fmt::format("must be an array (got {})", value.type_name()));
    return value;
  }
};

constexpr int kMaxKeyFrame = 1000000;

// Where `frame` falls among keys sorted by frame: the two keys around it and the weight of
// the second (0 before the first key, held after the last).
template <typename Key>
void bracket(const std::vector<Key>& keys, int frame, const Key*& a, const Key*& b, double& u) {
  a = &keys.front();
  b = &keys.front();
  u = 0;
  if (frame <= keys.front().frame) return;
  if (frame >= keys.back().frame) {
    a = b = &keys.back();
    return;
  }
  for (std::size_t i = 1; i < keys.size(); ++i) {
    if (frame < keys[i].frame) {
      a = &keys[i - 1];
      b = &keys[i];
      u = static_cast<double>(frame - a->frame) / static_cast<double>(b->frame - a->frame);
      return;
    }
  }
}

glm::dvec3 mix3(const glm::dvec3& a, const glm::dvec3& b, double u) {
  return u == 0 ? a : a + (b - a) * u;
}

// Checks that keys[i].frame increase strictly.
template <typename Key>
void check_order(const std::vector<Key>& keys, const AnimNode& list) {
  for (std::size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].frame <= keys[i - 1].frame) {
      list.at(i).at("frame").fail(fmt::format(
          "must be greater than the previous key's frame {} (keys in increasing frame order; "
          "got {})",
          keys[i - 1].frame, keys[i].frame));
    }
  }
}

glm::dmat4 rotation_xyz(const glm::dvec3& degrees) {
  glm::dmat4 r(1.0);
  r = glm::rotate(r, glm::radians(degrees.z), glm::dvec3(0, 0, 1));
  r = glm::rotate(r, glm::radians(degrees.y), glm::dvec3(0, 1, 0));
  r = glm::rotate(r, glm::radians(degrees.x), glm::dvec3(1, 0, 0));
  return r;
}

// The centre and radius of a sphere holding every vertex and sphere of `scene`.
void scene_bounds(const Scene& scene, glm::dvec3& centre, double& radius) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const Vertex& v : scene.mesh.vertices) {
    lo = glm::min(lo, glm::dvec3(v.position));
    hi = glm::max(hi, glm::dvec3(v.position));
  }
  for (const Sphere& s : scene.spheres) {
    lo = glm::min(lo, glm::dvec3(s.center) - glm::dvec3(s.radius));
    hi = glm::max(hi, glm::dvec3(s.center) + glm::dvec3(s.radius));
  }
  centre = (lo + hi) * 0.5;
  radius = 0;
  for (const Vertex& v : scene.mesh.vertices)
    radius = std::max(radius, glm::length(glm::dvec3(v.position) - centre));
  for (const Sphere& s : scene.spheres)
    radius = std::max(radius, glm::length(glm::dvec3(s.center) - centre) + s.radius);
}

// A camera looking along `back` (from the scene toward the eye) at `centre`, far enough that
// a sphere of `radius` about it stays in view at aspect 1 (and so at any wider one).
Camera camera_around(const glm::dvec3& centre, double radius, glm::dvec3 back, const Camera& base) {
  back = glm::normalize(back);
  const double half = glm::radians(static_cast<double>(base.fov_y_degrees)) * 0.5;
  const double distance = radius * 1.05 / std::sin(half);
  Camera c = base;
  c.eye = glm::vec3(centre + back * distance);
  c.target = glm::vec3(centre);
  c.near_plane = static_cast<float>(std::max(distance - radius * 1.1, distance * 1e-3));
  c.far_plane = static_cast<float>(distance + radius * 1.1);
  return c;
}

}  // namespace

Animation::Animation(std::string name, std::string motion, int frames, double fps,
                     std::function<Scene(int frame)> make)
    : name_(std::move(name)),
      motion_(std::move(motion)),
      frames_(frames),
      fps_(fps),
      make_(std::move(make)) {}

Camera camera_at(const std::vector<CameraKey>& keys, int frame, const Camera& base) {
  const CameraKey* a = nullptr;
  const CameraKey* b = nullptr;
  double u = 0;
  bracket(keys, frame, a, b, u);
  Camera c = base;
  c.eye = glm::vec3(mix3(a->eye, b->eye, u));
  c.target = glm::vec3(mix3(a->target, b->target, u));
  c.up = glm::vec3(mix3(a->up, b->up, u));
  c.fov_y_degrees = static_cast<float>(
      u == 0 ? a->fov_y_degrees : a->fov_y_degrees + (b->fov_y_degrees - a->fov_y_degrees) * u);
  return c;
}

void apply_track(const ObjectTrack& track, int frame, Scene& scene) {
  const ObjectKey* a = nullptr;
  const ObjectKey* b = nullptr;
  double u = 0;
  bracket(track.keys, frame, a, b, u);
  const glm::dvec3 translate = mix3(a->translate, b->translate, u);
  const glm::dvec3 degrees = mix3(a->rotate_degrees, b->rotate_degrees, u);
  const double scale = u == 0 ? a->scale : a->scale + (b->scale - a->scale) * u;
  const glm::dmat4 rotation = rotation_xyz(degrees);
  const glm::dmat3 r3(rotation);
  for (int i = track.first_vertex; i < track.last_vertex; ++i) {
    Vertex& v = scene.mesh.vertices[static_cast<std::size_t>(i)];
    const glm::dvec3 p = glm::dvec3(v.position) - track.pivot;
    v.position = glm::vec3(track.pivot + translate + r3 * (p * scale));
    v.normal = glm::vec3(glm::normalize(r3 * glm::dvec3(v.normal)));
  }
  for (int i = track.first_sphere; i < track.last_sphere; ++i) {
    Sphere& s = scene.spheres[static_cast<std::size_t>(i)];
    const glm::dvec3 p = glm::dvec3(s.center) - track.pivot;
    s.center = glm::vec3(track.pivot + translate + r3 * (p * scale));
    s.radius = static_cast<float>(s.radius * scale);
  }
}

Scene turned_scene(const Scene& base, double degrees) {
  glm::dvec3 centre;
  double radius = 0;
  scene_bounds(base, centre, radius);
  Scene scene = base;
  const glm::dvec3 back = glm::dvec3(base.camera.eye) - glm::dvec3(base.camera.target);
  scene.camera = camera_around(centre, radius, back, base.camera);
  if (degrees != 0) {
    ObjectTrack all;
    all.last_vertex = static_cast<int>(scene.mesh.vertices.size());
    all.last_sphere = static_cast<int>(scene.spheres.size());
    all.pivot = centre;
    ObjectKey key;
    key.rotate_degrees = glm::dvec3(0, degrees, 0);
    all.keys = {key};
    apply_track(all, 0, scene);
  }
  return scene;
}

Animation parse_animation_json(const std::string& text, const std::string& origin, Scene base,
                               const SceneParts& parts, const AnimationOptions& options) {
  json doc;
  try {
    doc = parse_strict_json(text, origin);
  } catch (const std::runtime_error& e) {
    throw SceneError(e.what());
  }
  const std::string name = base.name;
  if (!doc.is_object() || !doc.contains("animation")) {
    // No keyframes: the scene turns about the vertical axis.
    auto shared = std::make_shared<const Scene>(std::move(base));
    const int frames = options.frames > 0 ? options.frames : kDefaultAnimationFrames;
    return Animation(name, "turning about the vertical axis", frames,
                     options.fps > 0 ? options.fps : kDefaultAnimationFps,
                     [shared, frames](int k) { return turned_scene(*shared, 360.0 * k / frames); });
  }
  const AnimNode root{doc.at("animation"), "animation", origin};
  root.check_keys({"frames", "fps", "camera", "objects"});
  int frames = root.has("frames") ? root.at("frames").integer(1, 100000) : kDefaultAnimationFrames;
  double fps = root.has("fps") ? root.at("fps").number(0.1, 100) : kDefaultAnimationFps;
  if (options.frames > 0) frames = options.frames;
  if (options.fps > 0) fps = options.fps;

  std::vector<CameraKey> camera_keys;
  if (root.has("camera")) {
    const AnimNode list = root.at("camera");
    if (list.array().empty()) list.fail("must hold at least one camera key");
    for (std::size_t i = 0; i < list.value.size(); ++i) {
      const AnimNode k = list.at(i);
      k.check_keys({"frame", "eye", "target", "up", "fov_y_degrees"});
      if (!k.has("frame")) k.fail("needs 'frame' (the frame number of the key)");
      if (!k.has("eye") || !k.has("target")) k.fail("needs 'eye' and 'target'");
      CameraKey key;
      key.frame = k.at("frame").integer(0, kMaxKeyFrame);
      key.eye = k.at("eye").vec3();
      key.target = k.at("target").vec3();
      key.up = k.has("up") ? k.at("up").vec3() : glm::dvec3(0, 1, 0);
      key.fov_y_degrees =
          k.has("fov_y_degrees") ? k.at("fov_y_degrees").number(1, 179) : base.camera.fov_y_degrees;
      const glm::dvec3 back = key.eye - key.target;
      if (glm::length(back) == 0.0) k.at("target").fail("must differ from 'eye'");
      if (glm::length(glm::cross(key.up, back)) == 0.0) {
        k.at("up").fail("must not be zero or parallel to the view direction");
      }
      camera_keys.push_back(key);
    }
    check_order(camera_keys, list);
  }

  std::vector<ObjectTrack> tracks;
  if (root.has("objects")) {
    const AnimNode list = root.at("objects");
    if (list.array().empty()) list.fail("must hold at least one object");
    for (std::size_t i = 0; i < list.value.size(); ++i) {
      const AnimNode o = list.at(i);
      o.check_keys({"mesh", "sphere", "keys"});
      if (o.has("mesh") == o.has("sphere")) {
        o.fail(
            "needs exactly one of 'mesh' or 'sphere' (an index into the scene's 'meshes' or "
            "'spheres')");
      }
      ObjectTrack track;
      if (o.has("mesh")) {
        const int n = static_cast<int>(parts.mesh_vertices.size());
        if (n == 0) o.at("mesh").fail("names a mesh, but the scene has no 'meshes'");
        const int m = o.at("mesh").integer(0, n - 1);
        track.what = fmt::format("meshes[{}]", m);
        std::tie(track.first_vertex, track.last_vertex) =
            parts.mesh_vertices[static_cast<std::size_t>(m)];
      } else {
        const int n = static_cast<int>(parts.spheres.size());
        if (n == 0) o.at("sphere").fail("names a sphere entry, but the scene has no 'spheres'");
        const int m = o.at("sphere").integer(0, n - 1);
        track.what = fmt::format("spheres[{}]", m);
        std::tie(track.first_sphere, track.last_sphere) =
            parts.spheres[static_cast<std::size_t>(m)];
      }
      if (!o.has("keys")) o.fail("needs 'keys' (keyframes of the object's transform)");
      const AnimNode keys = o.at("keys");
      if (keys.array().empty()) keys.fail("must hold at least one key");
      for (std::size_t j = 0; j < keys.value.size(); ++j) {
        const AnimNode k = keys.at(j);
        k.check_keys({"frame", "translate", "rotate_degrees", "scale"});
        if (!k.has("frame")) k.fail("needs 'frame' (the frame number of the key)");
        ObjectKey key;
        key.frame = k.at("frame").integer(0, kMaxKeyFrame);
        if (k.has("translate")) key.translate = k.at("translate").vec3();
        if (k.has("rotate_degrees")) key.rotate_degrees = k.at("rotate_degrees").vec3(1e6);
        if (k.has("scale")) key.scale = k.at("scale").number(1e-6, 1e6);
        track.keys.push_back(key);
      }
      check_order(track.keys, keys);
      // The pivot: the centre of the entry's bounding box.
      glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
      for (int v = track.first_vertex; v < track.last_vertex; ++v) {
        const glm::dvec3 p(base.mesh.vertices[static_cast<std::size_t>(v)].position);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
      for (int s = track.first_sphere; s < track.last_sphere; ++s) {
        const glm::dvec3 p(base.spheres[static_cast<std::size_t>(s)].center);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
      track.pivot = (lo + hi) * 0.5;
      tracks.push_back(std::move(track));
    }
  }
  std::string motion;
  if (!camera_keys.empty()) motion = fmt::format("a camera path of {} keys", camera_keys.size());
  if (!tracks.empty()) {
    motion += fmt::format("{}{} object{} moved by keyframes", motion.empty() ? "" : " and ",
                          tracks.size(), tracks.size() == 1 ? "" : "s");
  }
  if (motion.empty()) motion = "no motion (an 'animation' without 'camera' or 'objects')";
  auto shared = std::make_shared<const Scene>(std::move(base));
  return Animation(name, motion, frames, fps, [shared, camera_keys, tracks](int k) {
    Scene scene = *shared;
    for (const ObjectTrack& t : tracks) apply_track(t, k, scene);
    if (!camera_keys.empty()) scene.camera = camera_at(camera_keys, k, shared->camera);
    return scene;
  });
}

Animation load_animation(const std::string& name_or_path, const AnimationOptions& options) {
  const int frames = options.frames > 0 ? options.frames : kDefaultAnimationFrames;
  const double fps = options.fps > 0 ? options.fps : kDefaultAnimationFps;
  std::string ext = fs::path(name_or_path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".json") {
    if (options.scene.tessellation_u != 0 || options.scene.tessellation_v != 0) {
      throw std::invalid_argument(
          fmt::format("--tessellation: {} is a file, whose geometry is its own", name_or_path));
    }
    SceneParts parts;
    std::string text;
    Scene base = load_scene_file(name_or_path, {}, &parts, &text);
    return parse_animation_json(text, name_or_path, std::move(base), parts, options);
  }
  if (name_or_path == "torus") {
    // One camera for every turn: framed to the surfaces of 16 turns at once.
    const SceneOptions so = options.scene;
    Mesh all;
    for (int i = 0; i < 16; ++i) {
      const Scene s = make_turned_torus(so, 2.0 * kAnimPi * i / 16, kAnimatedTorusEyeW);
      all.vertices.insert(all.vertices.end(), s.mesh.vertices.begin(), s.mesh.vertices.end());
    }
    const Camera camera = frame_mesh(all, glm::vec3(0.3f, 0.5f, 1.0f), kBuiltinFovYDegrees, 1.05f);
    const std::vector<Light> lights = {default_light(camera)};
    return Animation("torus", "turning in the zw-plane of 4-space", frames, fps,
                     [so, camera, lights, frames](int k) {
                       Scene s =
                           make_turned_torus(so, 2.0 * kAnimPi * k / frames, kAnimatedTorusEyeW);
                       s.camera = camera;
                       s.lights = lights;
                       s.description =
                           "Banks' torus turning in the zw-plane of 4-space, projected to 3-D "
                           "in perspective";
                       return s;
                     });
  }
  auto shared = std::make_shared<const Scene>(load_scene(name_or_path, options.scene));
  return Animation(shared->name, "turning about the vertical axis", frames, fps,
                   [shared, frames](int k) { return turned_scene(*shared, 360.0 * k / frames); });
}

std::vector<std::shared_ptr<const Scene>> animation_scenes(const Animation& animation,
                                                           const MachineConfig& config) {
  std::vector<std::shared_ptr<const Scene>> scenes;
  for (int k = 0; k < animation.frames(); ++k) {
    scenes.push_back(std::make_shared<const Scene>(animation.scene(k)));
    GeometryEngine(geometry_params(config), *scenes.back()).frame_parameters();
  }
  return scenes;
}

std::shared_ptr<const Scene> check_animation_scenes(const Animation& animation,
                                                    const MachineConfig& config) {
  std::shared_ptr<const Scene> first;
  for (int k = 0; k < animation.frames(); ++k) {
    auto scene = animation_scene(animation, k);
    GeometryEngine(geometry_params(config), *scene).frame_parameters();
    if (k == 0) first = std::move(scene);
  }
  return first;
}

std::shared_ptr<const Scene> animation_scene(const Animation& animation, int frame) {
  return std::make_shared<const Scene>(animation.scene(frame));
}

}  // namespace pp5
