// The machine configuration: documented defaults, strict JSON loading whose errors name the
// origin and the key, --set overrides, and a lossless round trip through JSON.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "common/strict_json.hpp"
#include "models/config/machine_config.hpp"

using namespace pp5;
using nlohmann::json;

namespace {

std::string config_error(const json& doc, const std::string& origin = "test.json") {
  try {
    MachineConfig::from_json(doc, origin);
  } catch (const ConfigError& e) {
    return e.what();
  }
  FAIL("accepted: " << doc.dump());
  return "";
}

void check_rejected(const json& doc, const std::string& key_path) {
  const std::string message = config_error(doc);
  INFO("message: " << message);
  CHECK(message.rfind("test.json: ", 0) == 0);
  CHECK(message.find(key_path) != std::string::npos);
}

std::string set_error(MachineConfig& c, const std::string& assignment) {
  try {
    c.set(assignment);
  } catch (const ConfigError& e) {
    return e.what();
  }
  FAIL("accepted: " << assignment);
  return "";
}

// "a.b" for every leaf of a two-level document.
std::set<std::string> leaf_keys(const json& doc) {
  std::set<std::string> keys;
  for (const auto& [section, body] : doc.items()) {
    for (const auto& [name, value] : body.items()) {
      CHECK(value.is_primitive());
      keys.insert(section + "." + name);
    }
  }
  return keys;
}

// A file in the temporary directory, removed when the test ends.
struct TempFile {
  std::string path;
  explicit TempFile(const std::string& name, const std::string& contents)
      : path((std::filesystem::temp_directory_path() /
              ("pp5_test_config_" + std::to_string(::getpid()) + "_" + name))
                 .string()) {
    std::ofstream(path) << contents;
  }
  ~TempFile() { std::remove(path.c_str()); }
};

}  // namespace

TEST_CASE("defaults are the documented machine", "[config]") {
  const MachineConfig c = MachineConfig::defaults();
  CHECK(c.gp.count == 32);
  CHECK(c.renderer.count == 16);
  CHECK(c.renderer.memory_bits == 208);
  CHECK(c.screen.width == 1280);
  CHECK(c.screen.height == 1024);
  CHECK(c.ring.channels == 8);
  CHECK(c.ring.word_bits == 32);
  CHECK(c.ring.clock_hz == 20e6);
  CHECK(c.renderer.region_width == 128);
  CHECK(c.renderer.region_height == 128);
  CHECK(c.renderer.clock_hz == 40e6);
  CHECK(c.renderer.backing_store_bits == 4096);
  CHECK(c.renderer.block_bits == 32);
  CHECK(c.evaluator.fraction_bits == 12);
  CHECK(c.regions_x() == 10);
  CHECK(c.regions_y() == 8);
  CHECK(c.regions() == 80);
  // An empty document is the defaults.
  CHECK(MachineConfig::from_json(json::object(), "empty").to_json() == c.to_json());
}

TEST_CASE("from_json overrides exactly the keys it names", "[config]") {
  const json doc = json::parse(R"({"renderer": {"count": 8, "clock_hz": 5e7},
                                   "screen": {"width": 640}, "ring": {"clock_hz": 40000000}})");
  const MachineConfig c = MachineConfig::from_json(doc, "test.json");
  CHECK(c.renderer.count == 8);
  CHECK(c.renderer.clock_hz == 5e7);
  CHECK(c.screen.width == 640);
  CHECK(c.ring.clock_hz == 40e6);  // an integer is a number
  CHECK(c.screen.height == 1024);
  CHECK(c.gp.count == 32);
  CHECK(c.regions_x() == 5);
}

TEST_CASE("from_json rejects what the table does not allow", "[config]") {
  SECTION("unknown top-level key") {
    const std::string m = config_error(json::parse(R"({"rendrer": {"count": 8}})"));
    CHECK(m.rfind("test.json: unknown key 'rendrer'", 0) == 0);
    CHECK(m.find("'renderer'") != std::string::npos);  // the known sections are listed
    check_rejected(json::parse(R"({"count": 8})"), "'count'");
  }
  SECTION("unknown nested key") {
    const std::string m = config_error(json::parse(R"({"renderer": {"cont": 8}})"));
    CHECK(m.rfind("test.json: unknown key 'renderer.cont'", 0) == 0);
    CHECK(m.find("'count'") != std::string::npos);
    CHECK(m.find("'memory_bits'") != std::string::npos);
  }
  SECTION("wrong type") {
    check_rejected(json::parse(R"({"renderer": {"count": "8"}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": 8.5}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": 8.0}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": true}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": null}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": [8]}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": {"value": 8}}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"gp": {"clock_hz": "fast"}})"), "'gp.clock_hz'");
    const std::string m = config_error(json::parse(R"({"renderer": {"count": "8"}})"));
    CHECK(m.find("must be an integer") != std::string::npos);
  }
  SECTION("out of range") {
    check_rejected(json::parse(R"({"renderer": {"count": 0}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": 33}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"count": -1}})"), "'renderer.count'");
    check_rejected(json::parse(R"({"renderer": {"memory_bits": 1000000000000}})"),
                   "'renderer.memory_bits'");
    check_rejected(json::parse(R"({"ring": {"clock_hz": 1e12}})"), "'ring.clock_hz'");
    const std::string m = config_error(json::parse(R"({"renderer": {"count": 33}})"));
    CHECK(m.find("out of range [1, 32]") != std::string::npos);
    // The ends of the range are in it.
    CHECK(MachineConfig::from_json(json::parse(R"({"renderer": {"count": 32}})"), "t")
              .renderer.count == 32);
    CHECK(MachineConfig::from_json(json::parse(R"({"renderer": {"count": 1}})"), "t")
              .renderer.count == 1);
  }
  SECTION("non-object section") {
    check_rejected(json::parse(R"({"renderer": 8})"), "'renderer' must be an object");
    check_rejected(json::parse(R"({"renderer": [1, 2]})"), "'renderer' must be an object");
    check_rejected(json::parse(R"({"gp": null})"), "'gp' must be an object");
    check_rejected(json::parse("[1, 2]"), "<top level>");
    check_rejected(json::parse("42"), "<top level>");
  }
  SECTION("cross-checks") {
    check_rejected(json::parse(R"({"renderer": {"region_width": 96}})"), "renderer.region_width");
    CHECK(MachineConfig::from_json(json::parse(R"({"renderer": {"region_width": 192}})"), "t")
              .renderer.region_width == 192);
    check_rejected(json::parse(R"({"evaluator": {"result_bits": 32}})"), "evaluator.result_bits");
    check_rejected(json::parse(R"({"evaluator": {"coefficient_bits": 48}})"),
                   "evaluator.coefficient_bits");
    CHECK_NOTHROW(MachineConfig::from_json(
        json::parse(R"({"evaluator": {"coefficient_bits": 48, "result_bits": 48}})"), "t"));
    check_rejected(json::parse(R"({"gp": {"depth_bits": 32}})"), "gp.depth_bits");
    check_rejected(json::parse(R"({"renderer": {"block_bits": 48}})"),
                   "renderer.backing_store_bits");
  }
  SECTION("the origin names the document") {
    const std::string m =
        config_error(json::parse(R"({"renderer": {"cont": 8}})"), "configs/what-if.json");
    CHECK(m.rfind("configs/what-if.json: ", 0) == 0);
  }
}

TEST_CASE("from_file names the path in its errors", "[config]") {
  const TempFile good("good.json", R"({"renderer": {"memory_bits": 256}})");
  CHECK(MachineConfig::from_file(good.path).renderer.memory_bits == 256);

  const std::string missing =
      (std::filesystem::temp_directory_path() / "pp5_test_config_no_such_file.json").string();
  try {
    MachineConfig::from_file(missing);
    FAIL("a missing file loaded");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).rfind(missing + ": cannot open", 0) == 0);
  }

  const TempFile broken("broken.json", R"({"renderer": {"count": 8,}})");
  try {
    MachineConfig::from_file(broken.path);
    FAIL("invalid JSON loaded");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).rfind(broken.path + ": not valid JSON", 0) == 0);
  }

  const TempFile unknown("unknown.json", R"({"renderer": {"cont": 8}})");
  try {
    MachineConfig::from_file(unknown.path);
    FAIL("an unknown key loaded");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).rfind(unknown.path + ": unknown key 'renderer.cont'", 0) == 0);
  }
}

TEST_CASE("set applies one key=value override", "[config]") {
  MachineConfig c = MachineConfig::defaults();
  c.set("renderer.count=8");
  CHECK(c.renderer.count == 8);
  c.set("gp.clock_hz=5e7");
  CHECK(c.gp.clock_hz == 5e7);
  c.set("ring.clock_hz=40000000");
  CHECK(c.ring.clock_hz == 40e6);

  const MachineConfig before = c;
  CHECK(set_error(c, "renderer.count").find("expected KEY=VALUE") != std::string::npos);
  CHECK(set_error(c, "=8").find("expected KEY=VALUE") != std::string::npos);
  CHECK(set_error(c, "renderer.cont=8").find("unknown key 'renderer.cont'") != std::string::npos);
  CHECK(set_error(c, "renderer=8").find("unknown key 'renderer'") != std::string::npos);
  CHECK(set_error(c, "renderer.count=").find("is not a number") != std::string::npos);
  CHECK(set_error(c, "renderer.count=eight").find("is not a number") != std::string::npos);
  CHECK(set_error(c, "renderer.count=8.5").find("must be an integer") != std::string::npos);
  CHECK(set_error(c, "renderer.count=\"8\"").find("must be an integer") != std::string::npos);
  const std::string range = set_error(c, "renderer.count=99");
  CHECK(range.rfind("--set renderer.count=99: ", 0) == 0);
  CHECK(range.find("'renderer.count'") != std::string::npos);
  // A whole number past 64 bits reaches the table as a float: out of range, not a fraction.
  CHECK(set_error(c, "renderer.count=99999999999999999999").find("is out of range [1,") !=
        std::string::npos);
  CHECK(c.to_json() == before.to_json());
}

TEST_CASE("a rejected set leaves the configuration unchanged", "[config]") {
  // The value passes its own range check, so it is assigned; the cross-check then throws.
  MachineConfig c = MachineConfig::defaults();
  const std::string message = set_error(c, "renderer.region_width=96");
  CHECK(message.find("renderer.region_width") != std::string::npos);
  CHECK(c.renderer.region_width == 128);
}

TEST_CASE("to_json round-trips and every key is described", "[config]") {
  MachineConfig c = MachineConfig::defaults();
  c.set("renderer.memory_bits=256");
  c.set("gp.clock_hz=33.3e6");
  c.set("screen.height=1000");
  const json doc = c.to_json();
  CHECK(MachineConfig::from_json(doc, "round trip").to_json() == doc);
  CHECK(MachineConfig::from_json(json::parse(doc.dump()), "text").to_json() == doc);
  CHECK(doc["renderer"]["memory_bits"] == 256);
  CHECK(doc["gp"]["clock_hz"] == 33.3e6);

  const std::set<std::string> keys = leaf_keys(doc);
  CHECK(keys.size() >= 25);
  std::set<std::string> described;
  const json defaults = MachineConfig::defaults().to_json();
  for (const ParameterInfo& p : describe_parameters()) {
    INFO(p.key);
    CHECK(described.insert(p.key).second);
    CHECK_FALSE(p.unit.empty());
    CHECK_FALSE(p.description.empty());
    CHECK_FALSE(p.default_value.empty());
    CHECK((p.confidence == "P" || p.confidence == "S" || p.confidence == "A"));
    if (p.key.rfind("frame.", 0) == 0) {
      // Frame parameters: to_json shows only those set; computed ones say from what.
      described.erase(p.key);
      if (p.computed) CHECK(p.range.rfind("from ", 0) == 0);
      if (!p.computed) CHECK(json::parse(p.default_value).is_number_integer());
      continue;
    }
    // The described default is the one defaults() has.
    const auto dot = p.key.find('.');
    const json& value = defaults[p.key.substr(0, dot)][p.key.substr(dot + 1)];
    if (value.is_string()) {  // a choice: the range lists the allowed values
      CHECK(value.get<std::string>() == p.default_value);
      CHECK(p.range.find(p.default_value) != std::string::npos);
      continue;
    }
    CHECK(p.range.find(" .. ") != std::string::npos);
    CHECK(json::parse(p.default_value).get<double>() == value.get<double>());
  }
  CHECK(described == keys);
}

TEST_CASE("choice keys are enums, checked at load, written back by name", "[config]") {
  MachineConfig c = MachineConfig::defaults();
  CHECK(c.gp.code == MachineConfig::Gp::Code::assembly);
  CHECK(c.renderer.balancing == MachineConfig::Renderer::Balancing::static_);
  c.set(std::vector<std::string>{"gp.code=compiled", "renderer.balancing=dynamic"});
  CHECK(c.gp.code == MachineConfig::Gp::Code::compiled);
  CHECK(c.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic);
  CHECK(name_of(c.gp.code) == "compiled");
  CHECK(name_of(c.renderer.balancing) == "dynamic");
  const json doc = c.to_json();
  CHECK(doc["gp"]["code"] == "compiled");
  CHECK(doc["renderer"]["balancing"] == "dynamic");
  CHECK(MachineConfig::from_json(doc, "t").renderer.balancing ==
        MachineConfig::Renderer::Balancing::dynamic);
  const std::string m = config_error(json::parse(R"({"renderer": {"balancing": "round-robin"}})"));
  CHECK(m.find("'renderer.balancing' must be one of \"static\", \"dynamic\"") != std::string::npos);
  CHECK(set_error(c, "gp.code=fast").find("'gp.code' must be one of \"assembly\", \"compiled\"") !=
        std::string::npos);
}

TEST_CASE("frame parameters are keys of the table", "[config]") {
  // Every Parameter the firmware can name has exactly one row, frame.NAME.
  std::set<std::string> rows;
  for (const ParameterInfo& p : describe_parameters()) {
    if (p.key.rfind("frame.", 0) == 0) rows.insert(p.key.substr(6));
  }
  std::set<std::string> names;
  for (const auto& p : kParameters) names.insert(p.name);
  CHECK(rows == names);
  MachineConfig c = MachineConfig::defaults();
  // Unset, each takes its declared default; today's values at the default depth.
  CHECK(resolved_frame_parameter(c, Parameter::threshold) == 32768);
  CHECK(resolved_frame_parameter(c, Parameter::delta) == 24);
  CHECK(resolved_frame_parameter(c, Parameter::highlight_green) == 230);
  CHECK(resolved_frame_parameter(c, Parameter::surface_opacity) == 128);
  CHECK_FALSE(c.to_json().contains("frame"));

  c.set("frame.threshold=8192");
  CHECK(resolved_frame_parameter(c, Parameter::threshold) == 8192);
  CHECK(c.to_json()["frame"]["threshold"] == 8192);
  CHECK(MachineConfig::from_json(c.to_json(), "t")
            .frame.set[static_cast<int>(Parameter::threshold)] == 8192);
  const MachineConfig loaded =
      MachineConfig::from_json(json::parse(R"({"frame": {"delta": 32}})"), "t");
  CHECK(resolved_frame_parameter(loaded, Parameter::delta) == 32);

  SECTION("ranges name the key") {
    const std::string m = set_error(c, "frame.highlight_opacity=300");
    CHECK(m.find("'frame.highlight_opacity' = 300 is out of range [0, 256]") != std::string::npos);
    check_rejected(json::parse(R"({"frame": {"delta": -1}})"), "'frame.delta'");
    check_rejected(json::parse(R"({"frame": {"silhouette": 128}})"), "'frame.silhouette'");
    check_rejected(json::parse(R"({"frame": {"threshold": 1.5}})"), "'frame.threshold'");
    check_rejected(json::parse(R"({"frame": {"no_such": 1}})"), "'frame.no_such'");
  }
  SECTION("computed ones are refused, saying why") {
    // Issue 18: ambient=-1, ambient=99999999 and specular=-100000 were accepted.
    for (const char* a : {"frame.ambient=-1", "frame.ambient=99999999", "frame.specular=-100000",
                          "frame.light_x=1", "frame.background_red=3"}) {
      const std::string m = set_error(c, a);
      INFO(m);
      CHECK(m.find("cannot be set: the GP computes it from the scene's") != std::string::npos);
    }
    const std::string m = set_error(c, "frame.epsilon_scale=1");
    CHECK(m.find("'frame.epsilon_scale' cannot be set") != std::string::npos);
    CHECK(m.find("frame.delta (derived)") != std::string::npos);
    check_rejected(json::parse(R"({"frame": {"ambient": 10}})"), "'frame.ambient'");
  }
  SECTION("threshold follows gp.depth_bits") {
    // Issue 18: --set gp.depth_bits=8 was refused because the default threshold (32768) no
    // longer fitted. The default is 1/512 of the depth range at any depth.
    MachineConfig d = MachineConfig::defaults();
    REQUIRE_NOTHROW(d.set("gp.depth_bits=8"));
    CHECK(resolved_frame_parameter(d, Parameter::threshold) == 1);
    d.set("gp.depth_bits=16");
    CHECK(resolved_frame_parameter(d, Parameter::threshold) == 128);
    // An explicit value is checked against the depth it is used with, whichever comes first.
    CHECK(set_error(d, "frame.threshold=70000")
              .find("'frame.threshold' = 70000 is out of range "
                    "[0, 65535] depth units (at gp.depth_bits = "
                    "16)") != std::string::npos);
    MachineConfig e = MachineConfig::defaults();
    e.set("frame.threshold=32768");
    CHECK(set_error(e, "gp.depth_bits=8").find("'frame.threshold'") != std::string::npos);
    check_rejected(json::parse(R"({"frame": {"threshold": 300}, "gp": {"depth_bits": 8}})"),
                   "'frame.threshold'");
  }
}

TEST_CASE("duplicate JSON keys are refused with the file and the key", "[config]") {
  const TempFile dup("dup.json", R"({"renderer": {"count": 8, "memory_bits": 256, "count": 4}})");
  try {
    MachineConfig::from_file(dup.path);
    FAIL("a duplicate key loaded");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK(m.rfind(dup.path + ": duplicate key 'count' in 'renderer'", 0) == 0);
  }
  const TempFile top("top.json", R"({"gp": {"count": 2}, "gp": {"count": 4}})");
  try {
    MachineConfig::from_file(top.path);
    FAIL("a duplicate section loaded");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).find("duplicate key 'gp' in the top-level object") !=
          std::string::npos);
  }
  // Equal keys in different objects are not duplicates.
  const TempFile ok("ok.json", R"({"gp": {"count": 2}, "renderer": {"count": 4}})");
  CHECK(MachineConfig::from_file(ok.path).renderer.count == 4);
  // The helper itself: nested objects inside arrays, and the path it reports.
  CHECK_THROWS_WITH(parse_strict_json(R"({"a": [{"b": 1, "b": 2}]})", "x.json"),
                    Catch::StartsWith("x.json: duplicate key 'b' in 'a[]'"));
  CHECK(parse_strict_json(R"({"a": [{"b": 1}, {"b": 2}]})", "x.json") ==
        json::parse(R"({"a": [{"b": 1}, {"b": 2}]})"));
}
