// Frames from the simulated machine against a plain CPU z-buffer that uses the same
// fixed-point plane equations (GeometryEngine's packets), evaluated directly in C++.
// The simulator's pixels come from the firmware executing on the bit-sliced array; the
// reference shares nothing with that path but the GP's coefficients.
#include <catch2/catch.hpp>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/machine.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {

MachineConfig small_machine() {
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 320;  // not a multiple of the region size: edge regions are partial
  c.screen.height = 256;
  c.gp.count = 3;
  c.renderer.count = 2;
  return c;
}

// floor(value / 2^shift) of A X + B Y + C, exactly.
std::int64_t floor_value(const QuadraticCoefficients& q, int x, int y, int shift) {
  const __int128 v = static_cast<__int128>(q.D) * x + static_cast<__int128>(q.E) * y + q.F;
  __int128 d = static_cast<__int128>(1) << shift;
  __int128 f = v / d;
  if (v % d != 0 && v < 0) --f;
  return static_cast<std::int64_t>(f);
}

struct RefPixel {
  std::uint32_t z = 0xFFFFFF;
  int rgb[3] = {0, 0, 0};
  int n[3] = {0, 0, 0};
  bool covered = false;
};

std::int64_t wrap_signed(std::int64_t v, int bits) {
  const std::uint64_t m = (std::uint64_t{1} << bits) - 1;
  std::uint64_t u = static_cast<std::uint64_t>(v) & m;
  const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
  return static_cast<std::int64_t>((u ^ sign) - sign);
}

// The phong.pp5 light and shade procedures, written out in integer C++: each light adds its
// diffuse and specular terms to the accumulators (clamped after each), then the material is
// multiplied by the level and the specular added.
void shade_phong(RefPixel& p, const FrameValues& values) {
  auto P = [&](const PacketValues& v, Parameter q) { return v.parameters[static_cast<int>(q)]; };
  std::int64_t level = P(values.frame, Parameter::ambient);
  std::int64_t spec = 0;
  for (const OwnedValues& light : values.lights) {
    auto dot = [&](Parameter a, Parameter b, Parameter c) {
      std::int64_t d =
          wrap_signed(p.n[0] * P(light, a) + p.n[1] * P(light, b) + p.n[2] * P(light, c), 16);
      return d < 0 ? 0 : d;
    };
    const std::int64_t nl = dot(Parameter::light_x, Parameter::light_y, Parameter::light_z);
    std::int64_t term = (((nl >> 6) & 0xFF) * P(light, Parameter::diffuse)) & 0xFFFF;
    level = (level + (term >> 8)) & 0x1FF;
    if (level > 255) level = 255;
    const std::int64_t nh = dot(Parameter::half_x, Parameter::half_y, Parameter::half_z);
    std::int64_t shine = (((nh >> 6) & 0xFF) * ((nh >> 6) & 0xFF)) & 0xFFFF;
    for (int i = 0; i < 3; ++i) shine = ((shine >> 8) * (shine >> 8)) & 0xFFFF;
    term = ((shine >> 8) * P(light, Parameter::specular)) & 0xFFFF;
    spec = (spec + (term >> 8)) & 0x1FF;
    if (spec > 255) spec = 255;
  }
  for (int c = 0; c < 3; ++c) {
    std::int64_t v = ((p.rgb[c] * level) & 0xFFFF) >> 8;
    v += spec;
    p.rgb[c] = static_cast<int>(v > 255 ? 255 : v);
  }
}

RgbImage reference_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                         const std::string& mode) {
  const GeometryEngine engine(geometry_params(config), scene);
  const FrameValues values = engine.frame_values();
  const auto& params = values.frame.parameters;
  const int frac = config.evaluator.fraction_bits;
  const int w = config.screen.width;
  const int h = config.screen.height;
  std::vector<RefPixel> px(static_cast<std::size_t>(w) * h);
  for (auto& p : px) {
    for (int c = 0; c < 3; ++c) {
      p.rgb[c] = static_cast<int>(params[static_cast<int>(Parameter::background_red) + c]);
    }
  }
  const auto& needed = program.procedure(Procedure::triangle).expressions;
  SetupCounts counts;
  std::vector<ScreenTriangle> screen;
  auto E = [](Expression e) { return static_cast<int>(e); };
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    screen.clear();
    engine.transform(i, screen, counts);
    for (const auto& t : screen) {
      SetupResult r;
      if (!engine.setup(t, needed, r, counts)) continue;
      const auto& ex = r.values.expressions;
      for (int y = r.y_min; y <= r.y_max; ++y) {
        for (int x = r.x_min; x <= r.x_max; ++x) {
          bool inside = true;
          for (int e = 0; e < 3; ++e)
            inside = inside && floor_value(ex[E(Expression::edge0) + e], x, y, 0) >= 0;
          if (!inside) continue;
          RefPixel& p = px[static_cast<std::size_t>(y) * w + x];
          const auto z = static_cast<std::uint32_t>(
              floor_value(ex[E(Expression::depth)], x, y, frac) & 0xFFFFFF);
          if (!(z < p.z)) continue;
          p.z = z;
          p.covered = true;
          for (int c = 0; c < 3; ++c) {
            const Expression colour = mode == "flat"      ? Expression::flat_red
                                      : mode == "gouraud" ? Expression::red
                                                          : Expression::base_red;
            p.rgb[c] = static_cast<int>(floor_value(ex[E(colour) + c], x, y, frac) & 0xFF);
            if (mode == "phong") {
              p.n[c] = static_cast<int>(
                  wrap_signed(floor_value(ex[E(Expression::nx) + c], x, y, frac), 8));
            }
          }
        }
      }
    }
  }
  RgbImage img;
  img.width = w;
  img.height = h;
  img.rgb.resize(px.size() * 3);
  for (std::size_t k = 0; k < px.size(); ++k) {
    if (mode == "phong" && px[k].covered) shade_phong(px[k], values);
    for (int c = 0; c < 3; ++c) img.rgb[k * 3 + c] = static_cast<std::uint8_t>(px[k].rgb[c]);
  }
  return img;
}

std::size_t differing_pixels(const RgbImage& a, const RgbImage& b) {
  std::size_t n = 0;
  for (std::size_t k = 0; k + 2 < a.rgb.size(); k += 3) {
    if (a.rgb[k] != b.rgb[k] || a.rgb[k + 1] != b.rgb[k + 1] || a.rgb[k + 2] != b.rgb[k + 2]) ++n;
  }
  return n;
}

// With `lights` > 1, the scene gets lights from other sides besides its key light.
void check_scene(const std::string& scene_name, const std::string& firmware, int lights = 1) {
  const MachineConfig config = small_machine();
  SceneOptions options;
  if (scene_name == "torus") options = {48, 16};
  Scene scene = make_builtin_scene(scene_name, options);
  const Light others[] = {{glm::normalize(glm::vec3(1.0f, -0.3f, 0.6f)), 0.5f, 0.6f, 32.0f},
                          {glm::vec3(0.0f, 0.0f, 1.0f), 0.3f, 0.9f, 8.0f},
                          {glm::normalize(glm::vec3(0.2f, 1.0f, -0.4f)), 0.7f, 0.4f, 16.0f}};
  for (int k = 1; k < lights; ++k) scene.lights.push_back(others[(k - 1) % 3]);
  const Program program = load_program(firmware, config);
  const FrameResult result = simulate_frame(config, scene, program, 2);
  const RgbImage expected = reference_frame(config, scene, program, firmware);
  REQUIRE(result.image.width() == expected.width);
  REQUIRE(result.image.height() == expected.height);
  INFO(scene_name << " with " << firmware << ", " << lights << " lights");
  CHECK(differing_pixels(result.image.flat(), expected) == 0);
  // The scene must actually draw something, or the comparison proves nothing.
  std::size_t background = 0;
  for (std::size_t k = 0; k < expected.rgb.size(); k += 3) {
    background += expected.rgb[k] == expected.rgb[0] && expected.rgb[k + 1] == expected.rgb[1] &&
                  expected.rgb[k + 2] == expected.rgb[2];
  }
  CHECK(background < expected.rgb.size() / 3 * 9 / 10);
}

}  // namespace

TEST_CASE("flat firmware equals the reference z-buffer", "[reference]") {
  for (const char* scene : {"two-triangles", "sphere", "torus"}) check_scene(scene, "flat");
}

TEST_CASE("Gouraud firmware equals the reference z-buffer", "[reference]") {
  for (const char* scene : {"two-triangles", "sphere", "torus"}) check_scene(scene, "gouraud");
}

TEST_CASE("deferred Phong firmware equals the reference shading", "[reference]") {
  for (const char* scene : {"two-triangles", "sphere", "torus"}) check_scene(scene, "phong");
}

TEST_CASE("deferred Phong with several lights equals the reference shading", "[reference]") {
  // The light procedure runs once per light; two, three and eight lights (the accumulators
  // saturate with many).
  for (const char* scene : {"sphere", "torus"}) {
    for (int lights : {2, 3, 8}) check_scene(scene, "phong", lights);
  }
}
