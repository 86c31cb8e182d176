// Scene files with several lights, materials and transparency, end to end: what the loader
// accepts and refuses, what the GP and the firmware make of it, and what it costs.
#include <catch2/catch.hpp>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {

const char* const kQuad =
    R"("vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "triangles": [[0, 1, 2], [0, 2, 3]])";

Scene parse(const std::string& body) {
  return parse_scene_json("{" + body + "}", "test.json", ".");
}

std::string error_of(const std::string& body) {
  try {
    parse(body);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string mesh(const std::string& extra = "") {
  return std::string(R"("meshes": [{)") + kQuad + (extra.empty() ? "" : ", " + extra) + "}]";
}

MachineConfig small_config() {
  MachineConfig c = MachineConfig::defaults();
  c.set({"screen.width=256", "screen.height=256", "gp.count=2", "renderer.count=2"});
  return c;
}

glm::ivec3 pixel(const RgbImage& image, int x, int y) {
  const std::size_t k = (static_cast<std::size_t>(y) * image.width + x) * 3;
  return {image.rgb[k], image.rgb[k + 1], image.rgb[k + 2]};
}

long brightness(const RgbImage& image) {
  long sum = 0;
  for (std::uint8_t v : image.rgb) sum += v;
  return sum;
}

}  // namespace

TEST_CASE("scene files give several lights, an ambient term and the one-light form", "[lights]") {
  const Scene two = parse(mesh() + R"(, "ambient": 0.3, "lights": [
      {"direction": [0, 0, 2], "diffuse": 0.5, "specular": 0.1, "shininess": 8},
      {"diffuse": 0.25}])");
  CHECK(two.ambient == Approx(0.3));
  REQUIRE(two.lights.size() == 2);
  CHECK(two.lights[0].direction == glm::vec3(0, 0, 1));
  CHECK(two.lights[0].diffuse == Approx(0.5));
  CHECK(two.lights[0].specular == Approx(0.1));
  CHECK(two.lights[0].shininess == Approx(8));
  // Absent keys take the key light's.
  const Light key = default_light(two.camera);
  CHECK(two.lights[1].direction == key.direction);
  CHECK(two.lights[1].diffuse == Approx(0.25));
  CHECK(two.lights[1].specular == Approx(key.specular));

  const Scene one = parse(mesh() + R"(, "light": {"ambient": 0.4, "diffuse": 0.6})");
  CHECK(one.ambient == Approx(0.4));
  REQUIRE(one.lights.size() == 1);
  CHECK(one.lights[0].diffuse == Approx(0.6));
  const Scene none = parse(mesh());
  CHECK(none.ambient == Approx(0.15));
  REQUIRE(none.lights.size() == 1);
  CHECK(none.lights[0].direction == default_light(none.camera).direction);
  CHECK(parse(mesh() + R"(, "lights": [{}, {}, {}, {}, {}, {}, {}, {}])").lights.size() == 8);
}

TEST_CASE("scene files give materials, opacity and a default firmware", "[materials]") {
  const Scene s = parse(R"("materials": {"glass": {"color": [0.1, 0.2, 0.3], "opacity": 0.25},
                                          "matte": {"opacity": 1}},
      "meshes": [{)" + std::string(kQuad) +
                        R"(, "material": "glass"},
                 {)" + kQuad +
                        R"(, "material": {"color": [1, 0, 0], "opacity": 0.5}},
                 {)" + kQuad +
                        R"(, "color": [0, 1, 0]},
                 {)" + kQuad +
                        R"(, "material": "matte"},
                 {"builtin": "two-triangles", "material": "matte"}],
      "firmware": "transparent")");
  REQUIRE(s.mesh.vertices.size() >= 16 + 6);
  CHECK(s.mesh.vertices[0].color == glm::vec3(0.1f, 0.2f, 0.3f));
  CHECK(s.mesh.vertices[0].opacity == 0.25f);
  CHECK(s.mesh.vertices[4].color == glm::vec3(1, 0, 0));
  CHECK(s.mesh.vertices[4].opacity == 0.5f);
  CHECK(s.mesh.vertices[8].color == glm::vec3(0, 1, 0));
  CHECK(s.mesh.vertices[8].opacity == 1.0f);
  CHECK(s.mesh.vertices[12].color == glm::vec3(0.8f));  // a material without a colour
  // A built-in mesh keeps its own colours under a material without one.
  const Mesh builtin = make_builtin_scene("two-triangles").mesh;
  CHECK(s.mesh.vertices[16].color == builtin.vertices[0].color);
  CHECK(s.firmware == "transparent");
  // A .pp5 path is relative to the scene file.
  const Scene p = parse_scene_json("{" + mesh() + R"(, "firmware": "mine.pp5"})", "x/s.json", "x");
  CHECK(p.firmware == "x/mine.pp5");
}

TEST_CASE("scene-file errors name the light, material or key", "[materials]") {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {mesh() + R"(, "lights": {"diffuse": 1})", "key 'lights' must be an array (got object)"},
      {mesh() + R"(, "lights": [])", "key 'lights' holds 0 lights; a scene has 1 to 8"},
      {mesh() + R"(, "lights": [{}, {}, {}, {}, {}, {}, {}, {}, {}])",
       "key 'lights' holds 9 lights; a scene has 1 to 8"},
      {mesh() + R"(, "light": {}, "lights": [{}])", "key 'lights' cannot be given with 'light'"},
      {mesh() + R"(, "lights": [{}, {"diffuse": "bright"}])",
       "key 'lights[1].diffuse' must be a number (got string)"},
      {mesh() + R"(, "lights": [{"ambient": 0.2}])", "unknown key 'lights[0].ambient'"},
      {mesh() + R"(, "lights": [{"direction": [0, 0, 0]}])",
       "key 'lights[0].direction' must not be the zero vector"},
      {mesh() + R"(, "ambient": 0.2, "light": {"ambient": 0.3})",
       "key 'ambient' cannot be given with 'light.ambient'"},
      {mesh() + R"(, "ambient": 1.5)", "key 'ambient' must be in [0, 1] (got 1.5)"},
      {mesh(R"("material": "stone")"),
       "key 'meshes[0].material' names an unknown material 'stone'"},
      {mesh(R"("material": 3)"), "key 'meshes[0].material' must be a string (got number)"},
      {mesh(R"("material": {"opacity": 1.5})"),
       "key 'meshes[0].material.opacity' must be in [0, 1] (got 1.5)"},
      {mesh(R"("material": {"opacity": -0.1})"),
       "key 'meshes[0].material.opacity' must be in [0, 1]"},
      {mesh(R"("material": {"shine": 2})"), "unknown key 'meshes[0].material.shine'"},
      {mesh(R"("material": "a", "color": [1, 0, 0])") + R"(, "materials": {"a": {}})",
       "key 'meshes[0].color' cannot be given with 'material'"},
      {mesh() + R"(, "materials": [])", "key 'materials' must be an object of named materials"},
      {mesh() + R"(, "materials": {"glass": {"color": [2, 0, 0]}})",
       "key 'materials.glass.color[0]' must be in [0, 1] (got 2)"},
      {mesh() + R"(, "firmware": 7)", "key 'firmware' must be a string (got number)"},
      {mesh() + R"(, "firmware": "")", "key 'firmware' must name a program"},
  };
  for (const auto& [body, message] : cases) {
    INFO(body);
    const std::string what = error_of(body);
    CHECK_THAT(what, Catch::StartsWith("test.json: "));
    CHECK_THAT(what, Catch::Contains(message));
  }
  // The unknown-material message lists the file's materials.
  CHECK_THAT(error_of(mesh(R"("material": "stone")") + R"(, "materials": {"glass": {}})"),
             Catch::Contains("(the file's 'materials': glass)"));
}

TEST_CASE("the GP sums every light into the vertex colours", "[lights]") {
  Scene scene = make_builtin_scene("sphere");
  for (Vertex& v : scene.mesh.vertices) v.color = glm::vec3(0.5f, 0.4f, 0.3f);
  scene.ambient = 0.1f;
  const Light a{glm::normalize(glm::vec3(-1, 1, 1)), 0.3f, 0.1f, 16.0f};
  const Light b{glm::normalize(glm::vec3(1, -0.5f, 1)), 0.2f, 0.15f, 8.0f};
  const GeometryParams params = geometry_params(MachineConfig::defaults());
  auto lit = [&](std::vector<Light> lights) {
    scene.lights = std::move(lights);
    const GeometryEngine engine(params, scene);
    std::vector<ScreenTriangle> out;
    SetupCounts counts;
    for (int i = 0; i < 200; ++i) engine.transform(i, out, counts);
    return out;
  };
  const auto ta = lit({a}), tb = lit({b}), tab = lit({a, b});
  REQUIRE(ta.size() == tab.size());
  int compared = 0;
  for (std::size_t i = 0; i < ta.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      // Dim enough that nothing clamps: the sum of both, with the ambient term once.
      const glm::dvec3 ambient = ta[i].v[k].base_color * 0.1;
      const glm::dvec3 sum = ta[i].v[k].lit_color + tb[i].v[k].lit_color - ambient;
      CHECK(glm::length(tab[i].v[k].lit_color - sum) < 1e-7);
      ++compared;
    }
    const glm::dvec3 flat =
        ta[i].flat_color + tb[i].flat_color -
        (ta[i].v[0].base_color + ta[i].v[1].base_color + ta[i].v[2].base_color) / 3.0 * 0.1;
    CHECK(glm::length(tab[i].flat_color - flat) < 1e-7);
  }
  CHECK(compared > 100);
  // One parameter set per light, the same but for the light's own.
  const GeometryEngine engine(params, scene);
  const FrameValues values = engine.frame_values();
  REQUIRE(values.lights.size() == 2);
  CHECK(values.lights[0].parameters == values.frame.parameters);
  for (int p = 0; p < static_cast<int>(Parameter::count); ++p) {
    const bool own = p <= static_cast<int>(Parameter::half_z) ||
                     p == static_cast<int>(Parameter::diffuse) ||
                     p == static_cast<int>(Parameter::specular);
    INFO(kParameters[p].name);
    if (!own) CHECK(values.lights[1].parameters[p] == values.frame.parameters[p]);
  }
  CHECK(values.lights[1].parameters[static_cast<int>(Parameter::diffuse)] == 51);
}

TEST_CASE("a second light brightens the Phong image", "[lights]") {
  const MachineConfig config = small_config();
  const Program phong = load_program("phong", config);
  Scene scene = make_builtin_scene("sphere");
  const FrameResult one = simulate_frame(config, scene, phong, 2);
  scene.lights.push_back({glm::normalize(glm::vec3(1, -0.3f, 0.5f)), 0.6f, 0.4f, 16.0f});
  const FrameResult two = simulate_frame(config, scene, phong, 2);
  CHECK(two.image.flat().rgb != one.image.flat().rgb);
  CHECK(brightness(two.image.flat()) > brightness(one.image.flat()) + 256 * 256);
  // No pixel gets darker: light only adds.
  for (std::size_t k = 0; k < one.image.flat().rgb.size(); ++k) {
    if (two.image.flat().rgb[k] < one.image.flat().rgb[k])
      FAIL("pixel byte " << k << " got darker");
  }
}

TEST_CASE("each light's procedure is charged on every region", "[lights]") {
  const MachineConfig config = small_config();
  Scene scene = make_builtin_scene("sphere");
  auto busy = [&](const Program& program) {
    return test::count(simulate_frame(config, scene, program, 2).stats,
                       "renderers_total.busy_cycles");
  };
  for (const char* name : {"phong", "gouraud"}) {
    INFO(name);
    const Program program = load_program(name, config);
    scene.lights.resize(1);
    const std::uint64_t with_one = busy(program);
    scene.lights.push_back({glm::normalize(glm::vec3(1, -0.3f, 0.5f)), 0.6f, 0.4f, 16.0f});
    scene.lights.push_back({glm::vec3(0, 0, 1), 0.2f, 0.9f, 16.0f});
    const std::uint64_t with_three = busy(program);
    // The extra lights' procedure cycles (their mac costs follow their parameters) plus the
    // packet overhead, on every region.
    const FrameValues values = GeometryEngine(geometry_params(config), scene).frame_values();
    const ProcedureCode& light = program.procedure(Procedure::light);
    std::uint64_t per_region = 0;
    for (int k = 1; k < 3; ++k) {
      if (!light.defined) continue;
      per_region += procedure_cost(light, timing_params(config), values.lights[k]).count +
                    static_cast<std::uint64_t>(config.renderer.packet_overhead_cycles);
    }
    CHECK(light.defined == (std::string(name) == "phong"));
    CHECK(with_three - with_one == per_region * static_cast<std::uint64_t>(config.regions()));
    if (light.defined) CHECK(per_region > 0);
  }
}

TEST_CASE("a half-transparent quad blends with the opaque one behind it", "[materials]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "renderer.count=1", "gp.count=1"});
  const Scene scene =
      load_scene(std::string(PP5_SOURCE_DIR) + "/tests/data/scenes/glass_quads.json");
  REQUIRE(scene.firmware == "transparent");
  const Program program = load_program("transparent", config);
  const FrameResult r = simulate_frame(config, scene, program, 1);
  // Lit by ambient 1 alone, each surface's colour is its material's: floor(c * 255).
  const glm::ivec3 glass(102, 204, 51), wall(255, 51, 153);
  // The firmware's rules, front to back from T = 256: w = floor(T * opacity / 256),
  // acc += colour * w, T = floor(T * (256 - opacity) / 256); output floor(acc / 256).
  auto composite = [](std::vector<std::pair<glm::ivec3, int>> layers) {
    int t = 256;
    glm::ivec3 acc(0);
    for (const auto& [colour, opacity] : layers) {
      const int w = t * opacity >> 8;
      acc += colour * w;
      t = t * (256 - opacity) >> 8;
    }
    return acc / 256;  // non-negative: division is floor
  };
  const glm::ivec3 blended = composite({{glass, 128}, {wall, 256}});
  CHECK(blended == glm::ivec3(178, 127, 102));
  CHECK(pixel(r.image.flat(), 64, 64) == blended);      // both quads
  CHECK(pixel(r.image.flat(), 96, 64) == wall);         // only the opaque one
  CHECK(pixel(r.image.flat(), 2, 2) == glm::ivec3(0));  // the background
  // Opacity ignored (gouraud): the glass hides the wall.
  const FrameResult opaque = simulate_frame(config, scene, load_program("gouraud", config), 1);
  CHECK(pixel(opaque.image.flat(), 64, 64) == glass);
}

TEST_CASE("opaque surfaces through the transparency program equal Gouraud", "[materials]") {
  const MachineConfig config = small_config();
  for (const char* name : {"sphere", "torus", "two-triangles"}) {
    INFO(name);
    SceneOptions options;
    if (std::string(name) == "torus") options = {48, 16};
    Scene scene = make_builtin_scene(name, options);
    scene.lights.push_back({glm::normalize(glm::vec3(1, -0.3f, 0.5f)), 0.4f, 0.3f, 16.0f});
    const FrameResult gouraud = simulate_frame(config, scene, load_program("gouraud", config), 2);
    // Front to back and back to front (depth-interval buffer): with as many layers as the
    // scene has (4, the default), the frontmost opaque surface takes all.
    for (const char* program : {"transparent", "transparent_interval"}) {
      INFO(program);
      const FrameResult peeled = simulate_frame(config, scene, load_program(program, config), 2);
      CHECK(peeled.image.flat().rgb == gouraud.image.flat().rgb);
    }
  }
}
