// The statistics registry (common/statistics.hpp): names, kinds, the stats.json document it
// dumps, reading back by name, and that a real run's stats.json is exactly what
// `pp5sim stats --describe` describes.
#include <catch2/catch.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "common/statistics.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;

namespace {

// Every leaf of a JSON document as a statistic name with its indices written N.
void leaf_patterns(const nlohmann::json& v, const std::string& name, std::set<std::string>& out) {
  if (v.is_object()) {
    for (const auto& [key, child] : v.items())
      leaf_patterns(child, name.empty() ? key : name + "." + key, out);
  } else if (v.is_array()) {
    for (const auto& child : v) leaf_patterns(child, name + ".N", out);
  } else {
    out.insert(name);
  }
}

}  // namespace

TEST_CASE("statistics: typed values read by name, dumped as nested objects and arrays",
          "[statistics]") {
  Statistics s;
  std::int64_t messages = 3;
  s.add_integer("ring.messages", stat_unit::count, "Messages", [&] { return messages; });
  s.add_real("gp.0.utilisation", stat_unit::ratio, "Busy", [] { return 0.25; });
  s.add_real("gp.1.utilisation", stat_unit::ratio, "Busy", [] { return 0.5; });
  s.add_text("timing.bottleneck", stat_unit::name, "Bottleneck", [] { return "ring"; });
  s.add_integer("per_region.0", stat_unit::count, "Per region", [] { return 7; });
  s.add_integer("per_region.1", stat_unit::count, "Per region", [] { return 8; });

  CHECK(s.integer("ring.messages") == 3);
  CHECK(s.real("gp.1.utilisation") == 0.5);
  CHECK(s.text("timing.bottleneck") == "ring");
  CHECK(s.elements("gp") == 2);
  CHECK(s.elements("per_region") == 2);
  CHECK(s.info("gp.0.utilisation").unit == stat_unit::ratio);

  // Live until frozen, then fixed: the registered objects may go away.
  messages = 4;
  CHECK(s.integer("ring.messages") == 4);
  s.freeze();
  messages = 5;
  CHECK(s.integer("ring.messages") == 4);

  const nlohmann::json doc = s.to_json();
  CHECK(doc == nlohmann::json::parse(R"({"ring": {"messages": 4},
      "gp": [{"utilisation": 0.25}, {"utilisation": 0.5}],
      "timing": {"bottleneck": "ring"}, "per_region": [7, 8]})"));

  // A written document reads back with the same kinds and values.
  const Statistics back = Statistics::from_json(doc);
  CHECK(back.integer("per_region.1") == 8);
  CHECK(back.real("gp.0.utilisation") == 0.25);
  CHECK(back.text("timing.bottleneck") == "ring");
  CHECK(back.to_json() == doc);

  const auto described = s.describe();
  REQUIRE(described.size() == 4);
  CHECK(described[1].name == "gp.N.utilisation");
  CHECK(described[1].kind == StatKind::real);
  CHECK(described[3].name == "per_region.N");
}

TEST_CASE("statistics: an unknown name or the wrong kind is an error that names it",
          "[statistics]") {
  Statistics s;
  s.add_integer("setup.packets", stat_unit::count, "Packets", [] { return 2; });
  CHECK_THROWS_WITH(s.integer("setup.packet"), Catch::Contains("no statistic 'setup.packet'"));
  CHECK_THROWS_WITH(s.real("setup.packets"),
                    Catch::Contains("'setup.packets' is integer, not real"));
  CHECK_THROWS_WITH(s.text("setup.packets"), Catch::Contains("not text"));
  CHECK_THROWS_AS(s.elements("setup.packets"), std::out_of_range);
  CHECK_FALSE(s.contains("setup"));
}

TEST_CASE("statistics: names are checked when registered", "[statistics]") {
  Statistics s;
  auto one = [] { return std::int64_t{1}; };
  s.add_integer("ring.words", stat_unit::ring_words, "Words", one);
  s.add_integer("gp.0.packets", stat_unit::count, "Packets", one);
  CHECK_THROWS_WITH(s.add_integer("ring.words", stat_unit::ring_words, "Words", one),
                    Catch::Contains("registered twice"));
  CHECK_THROWS_WITH(s.add_integer("ring", stat_unit::count, "Ring", one),
                    Catch::Contains("already a group"));
  CHECK_THROWS_WITH(s.add_integer("ring.words.high", stat_unit::count, "High", one),
                    Catch::Contains("'ring.words' is a value"));
  CHECK_THROWS_WITH(s.add_integer("gp.2.packets", stat_unit::count, "Packets", one),
                    Catch::Contains("without gaps"));
  CHECK_THROWS_WITH(s.add_integer("gp.1.packets", stat_unit::ring_words, "Packets", one),
                    Catch::Contains("differs from 'gp.0.packets'"));
  CHECK_THROWS_WITH(s.add_integer("Ring.Words", stat_unit::count, "Words", one),
                    Catch::Contains("[a-z0-9_]"));
  CHECK_THROWS_WITH(s.add_integer("ring..x", stat_unit::count, "X", one),
                    Catch::Contains("non-empty"));
  CHECK_THROWS_WITH(s.add_integer("0.x", stat_unit::count, "X", one),
                    Catch::Contains("not an array"));
  CHECK_THROWS_WITH(s.add_integer("gp.name", stat_unit::count, "X", one),
                    Catch::Contains("'gp' is an array"));
  CHECK_THROWS_WITH(s.add_integer("ring.0", stat_unit::count, "X", one),
                    Catch::Contains("'ring' is a group of names"));
  // "gp.00" is not index 0 but a name, and gp is an array.
  CHECK_THROWS_WITH(s.add_integer("gp.00.packets", stat_unit::count, "Packets", one),
                    Catch::Contains("'gp' is an array"));
  // A refused name leaves nothing behind.
  CHECK(s.elements("gp") == 1);
  CHECK_FALSE(s.contains("ring.words.high"));
  s.add_integer("gp.1.packets", stat_unit::count, "Packets", one);
  CHECK(s.elements("gp") == 2);
}

TEST_CASE(
    "statistics: every key of a real stats.json is described, and every description "
    "is a key",
    "[statistics]") {
  // The paper's machine on the torus: 32 GPs, 16 Renderers, 8 channels, 80 regions.
  const MachineConfig config = MachineConfig::defaults();
  const Scene scene = make_builtin_scene("torus", {64, 16});
  const FrameResult r = simulate_frame(config, scene, test::load_program("threshold", config), 2);
  std::set<std::string> keys;
  leaf_patterns(r.stats_json, "", keys);

  std::set<std::string> described;
  for (const StatisticInfo& i :
       describe_statistics(std::string(PP5_SOURCE_DIR) + "/firmware/programs/phong.pp5")) {
    INFO(i.name);
    CHECK(described.insert(i.name).second);
    CHECK_FALSE(i.unit.empty());
    CHECK_FALSE(i.description.empty());
  }
  CHECK(keys == described);
  // Every registered statistic is one leaf of the document, under its own name.
  std::set<std::string> registered, written;
  for (const auto& i : r.stats.infos()) registered.insert(i.name);
  for (const auto& i : Statistics::from_json(r.stats_json).infos()) written.insert(i.name);
  CHECK(registered == written);
  CHECK(registered.size() == r.stats.infos().size());
  CHECK(r.stats.elements("gp") == 32);
  CHECK(r.stats.elements("renderer") == 16);
  CHECK(r.stats.elements("ring.channels") == 8);
  CHECK(r.stats.elements("primitives_per_region") == static_cast<std::size_t>(config.regions()));
  // stats.json is the registry's dump.
  CHECK(r.stats.to_json() == r.stats_json);
}
