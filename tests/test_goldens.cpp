// Whole-frame goldens: every built-in scene with every shipped program on a small machine,
// and the torus at 1280 x 1024 with phong and threshold on the paper's machine. Each golden
// holds the frame's image hash and its stats.json without the host section, so a change that
// moves any pixel or any statistic fails here. A deliberate change is its own commit that
// says why and regenerates the goldens:
//
//   PP5_UPDATE_GOLDENS=1 build/pp5_tests "[golden]"
//
// (tests/golden/README.md says the same, and what each file holds.)
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/animation.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

namespace fs = std::filesystem;
using namespace pp5;

namespace {

const char* const kGoldenPrograms[] = {"accurate",
                                       "epsilon",
                                       "epsilon_folded",
                                       "epsilon_folded_squares",
                                       "epsilon_normal",
                                       "exactmatch",
                                       "exactmatch_n",
                                       "flat",
                                       "gouraud",
                                       "painter",
                                       "phong",
                                       "threshold",
                                       "threshold_eyez",
                                       "threshold_keep",
                                       "transparent",
                                       "transparent_exactmatch",
                                       "transparent_interval",
                                       "transparent_threshold"};

// FNV-1a, 64 bits, over the image's size and its RGB bytes.
std::string image_hash(const RgbImage& image) {
  std::uint64_t h = 14695981039346656037ull;
  auto mix = [&](std::uint8_t b) {
    h ^= b;
    h *= 1099511628211ull;
  };
  for (int v : {image.width, image.height}) {
    for (int k = 0; k < 4; ++k) mix(static_cast<std::uint8_t>(static_cast<unsigned>(v) >> (8 * k)));
  }
  for (std::uint8_t b : image.rgb) mix(b);
  return fmt::format("{:016x}", h);
}

fs::path golden_path(const std::string& name) {
  return fs::path(PP5_SOURCE_DIR) / "tests" / "golden" / (name + ".json");
}

// Numbers compare exactly when integral and to 1e-12 relative otherwise (ratios such as
// utilisations are computed in double precision with fp-contraction off, so they repeat
// bit for bit; the tolerance only keeps the golden independent of the JSON round trip).
void compare(const nlohmann::json& want, const nlohmann::json& got, const std::string& path) {
  INFO("at " << path);
  if (want.is_number_float() || got.is_number_float()) {
    REQUIRE(got.is_number());
    const double a = want.get<double>();
    const double b = got.get<double>();
    REQUIRE(std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b)));
    return;
  }
  if (want.is_number_integer() && got.is_number_integer()) {
    // Signed and unsigned are one kind here: a value read back from the file is signed.
    const bool neg_want =
        want.is_number_integer() && !want.is_number_unsigned() && want.get<std::int64_t>() < 0;
    const bool neg_got =
        got.is_number_integer() && !got.is_number_unsigned() && got.get<std::int64_t>() < 0;
    REQUIRE(neg_want == neg_got);
    if (neg_want) {
      REQUIRE(want.get<std::int64_t>() == got.get<std::int64_t>());
    } else {
      REQUIRE(want.get<std::uint64_t>() == got.get<std::uint64_t>());
    }
    return;
  }
  REQUIRE(want.type() == got.type());
  if (want.is_object()) {
    for (const auto& [k, v] : want.items()) {
      INFO("missing key " << path << "/" << k);
      REQUIRE(got.contains(k));
      compare(v, got[k], path + "/" + k);
    }
    for (const auto& [k, v] : got.items()) {
      INFO("new key " << path << "/" << k);
      REQUIRE(want.contains(k));
    }
  } else if (want.is_array()) {
    REQUIRE(want.size() == got.size());
    for (std::size_t i = 0; i < want.size(); ++i)
      compare(want[i], got[i], path + "/" + std::to_string(i));
  } else {
    REQUIRE(want == got);
  }
}

void check_golden(const std::string& name, const MachineConfig& config, const Scene& scene,
                  const std::string& program_name) {
  const Program program = test::load_program(program_name, config);
  const FrameResult r = simulate_frame(config, scene, program, 2);
  nlohmann::json got = {{"scene", scene.name},
                        {"firmware", program_name},
                        {"screen", {config.screen.width, config.screen.height}},
                        {"image_fnv1a64", image_hash(r.image.flat())},
                        {"stats", test::without_host(r.stats_json)}};
  // The program's name in the statistics is the path it was assembled from: keep the
  // golden independent of where the checkout lies.
  got["stats"]["frame"]["firmware"] = program_name;
  const fs::path path = golden_path(name);
  const char* update = std::getenv("PP5_UPDATE_GOLDENS");
  if (update && std::string(update) == "1") {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << got.dump(1) << "\n";
    return;
  }
  std::ifstream in(path);
  INFO("golden " << path.string() << " (PP5_UPDATE_GOLDENS=1 writes it)");
  REQUIRE(in.good());
  const nlohmann::json want = nlohmann::json::parse(in);
  CHECK(want["image_fnv1a64"] == got["image_fnv1a64"]);
  compare(want["stats"], got["stats"], name);
}

// The small machine: 256 x 256 (four regions), 4 GPs and 2 Renderers, so that every
// program's every procedure, the bins of several GPs and a Renderer with two regions are
// all exercised in a fraction of a second.
MachineConfig small_machine() {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=4", "renderer.count=2"});
  return config;
}

}  // namespace

TEST_CASE("golden frames: every built-in scene with every program, 256 x 256", "[golden]") {
  const MachineConfig config = small_machine();
  for (const std::string& scene_name : builtin_scene_names()) {
    const Scene scene = make_builtin_scene(scene_name);
    for (const char* program : kGoldenPrograms) {
      // Scenes of spheres (sim/scene/sphere_scenes.cpp) only with the programs that draw
      // spheres (a `sphere` procedure): the others refuse them.
      if (!scene.spheres.empty() &&
          !test::load_program(program, config).procedure(Procedure::sphere).defined) {
        continue;
      }
      SECTION(scene_name + " " + program) {
        check_golden("small-" + scene_name + "-" + program, config, scene, program);
      }
    }
  }
}

TEST_CASE("golden frames: the torus at 1280 x 1024 with phong and threshold", "[golden]") {
  const MachineConfig config = MachineConfig::defaults();
  const Scene scene = make_builtin_scene("torus");
  for (const char* program : {"phong", "threshold"}) {
    SECTION(program) { check_golden(std::string("torus-1280-") + program, config, scene, program); }
  }
}

// Three frames of the torus turning in 4-space (sim/animation.hpp) in one session, at
// 128 x 128, overlapped: each frame's image hash and statistics, as pp5sim animate draws them.
TEST_CASE("golden animation: three frames of the turning torus, 128 x 128", "[golden]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "gp.count=2", "renderer.count=1"});
  AnimationOptions options;
  options.scene.tessellation_u = 48;
  options.scene.tessellation_v = 12;
  options.frames = 3;
  const Animation animation = load_animation("torus", options);
  auto program = std::make_shared<const Program>(test::load_program("phong", config));
  Session session(config, std::make_shared<const Scene>(animation.scene(0)), program, 2);
  nlohmann::json got = {
      {"scene", "torus"},         {"motion", animation.motion()},
      {"firmware", "phong"},      {"screen", {config.screen.width, config.screen.height}},
      {"tessellation", {48, 12}}, {"frames", nlohmann::json::array()}};
  // Overlapped, as pp5sim animate runs them: frame k's own scene on the GPs while the
  // Renderers draw frame k - 1.
  session.run_frames(
      3,
      [&got](int, FrameResult& r) {
        nlohmann::json stats = test::without_host(r.stats_json);
        stats["frame"]["firmware"] = "phong";
        got["frames"].push_back({{"image_fnv1a64", image_hash(r.image.flat())}, {"stats", stats}});
      },
      true, [&animation](int k) { return std::make_shared<const Scene>(animation.scene(k)); });
  const std::string name = "animation-torus-3-phong";
  const fs::path path = golden_path(name);
  const char* update = std::getenv("PP5_UPDATE_GOLDENS");
  if (update && std::string(update) == "1") {
    std::ofstream(path) << got.dump(1) << "\n";
    return;
  }
  std::ifstream in(path);
  INFO("golden " << path.string() << " (PP5_UPDATE_GOLDENS=1 writes it)");
  REQUIRE(in.good());
  const nlohmann::json want = nlohmann::json::parse(in);
  REQUIRE(want["frames"].size() == 3);
  for (int k = 0; k < 3; ++k) {
    INFO("frame " << k);
    CHECK(want["frames"][k]["image_fnv1a64"] == got["frames"][k]["image_fnv1a64"]);
    compare(want["frames"][k]["stats"], got["frames"][k]["stats"], name);
  }
}
