// The statistics registry (common/statistics.hpp): names, kinds, the stats.json document it
// dumps, reading back by name, and that a real run's stats.json is exactly what
// `pp5sim stats --describe` describes.
#include <catch2/catch.hpp>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

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

// A run's frames register their statistics following the frame before's
// (Statistics::follow): the registry, its stats.json and its descriptions are those of a
// registry that registered afresh, whether a frame registers what the one before did, more,
// less or something else.
namespace {

struct FrameShape {
  int gps = 3;
  const char* busy = "Busy time over the frame time";
  bool extra = false;
};

void register_shaped(Statistics& s, const FrameShape& shape, int frame) {
  s.add_integer("frame.index", stat_unit::index, "The frame's place",
                [frame] { return std::int64_t{frame}; });
  for (int k = 0; k < shape.gps; ++k) {
    s.add_real("gp." + std::to_string(k) + ".busy", stat_unit::ratio, shape.busy,
               [k, frame] { return 0.25 * k + frame; });
  }
  if (shape.extra) s.add_text("run.note", stat_unit::name, "A note", [] { return "x"; });
  s.add_integer("ring.words", stat_unit::ring_words, "Words of the frame",
                [frame] { return std::int64_t{100 + frame}; });
}

void check_same(const Statistics& followed, const Statistics& fresh) {
  CHECK(followed.to_json().dump() == fresh.to_json().dump());
  const auto a = followed.infos(), b = fresh.infos();
  REQUIRE(a.size() == b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    CHECK(a[k].name == b[k].name);
    CHECK(a[k].kind == b[k].kind);
    CHECK(a[k].unit == b[k].unit);
    CHECK(a[k].description == b[k].description);
  }
  const auto da = followed.describe(), db = fresh.describe();
  REQUIRE(da.size() == db.size());
  for (std::size_t k = 0; k < da.size(); ++k) CHECK(da[k].name == db[k].name);
  CHECK(followed.elements("gp") == fresh.elements("gp"));
  for (const char* name : {"gp.2.busy", "gp.3.busy", "run.note", "ring.words"})
    CHECK(followed.contains(name) == fresh.contains(name));
}

}  // namespace

TEST_CASE("statistics: a frame registered following the frame before is as if registered afresh",
          "[statistics]") {
  const std::vector<FrameShape> run = {
      {},
      {},                                      // the same: only getters taken
      {},                                      //
      {5},                                     // more GPs
      {2},                                     // fewer: a layout followed part of the way is cut
      {2, "Busy time, described anew"},        // a different description
      {2, "Busy time, described anew", true},  // a statistic more in the middle
      {3},
      {3},
  };
  std::shared_ptr<const Statistics::Layout> before;
  for (std::size_t f = 0; f < run.size(); ++f) {
    INFO("frame " << f);
    Statistics fresh, followed;
    followed.follow(before);
    register_shaped(fresh, run[f], static_cast<int>(f));
    register_shaped(followed, run[f], static_cast<int>(f));
    followed.freeze();
    fresh.freeze();
    check_same(followed, fresh);
    // Registered as the frame before: its layout is that frame's, shared, not a copy.
    const bool same_shape = f > 0 && run[f].gps == run[f - 1].gps &&
                            std::string(run[f].busy) == run[f - 1].busy &&
                            run[f].extra == run[f - 1].extra;
    CHECK((followed.layout() == before) == same_shape);
    before = followed.layout();
  }
  // The checks of a registry that never followed still hold.
  Statistics twice;
  twice.follow(before);
  twice.add_integer("frame.index", stat_unit::index, "The frame's place", [] { return 0; });
  CHECK_THROWS_AS(
      twice.add_integer("frame.index", stat_unit::index, "The frame's place", [] { return 0; }),
      std::invalid_argument);
  Statistics unlike;
  unlike.follow(before);
  unlike.add_integer("frame.index", stat_unit::index, "The frame's place", [] { return 0; });
  unlike.add_real("gp.0.busy", stat_unit::ratio, "Busy time over the frame time", [] { return 0; });
  CHECK_THROWS_AS(unlike.add_real("gp.1.busy", stat_unit::ratio, "Another", [] { return 0; }),
                  std::invalid_argument);
  // A followed layout is not changed by the registries that left it: one registering the
  // last frame's statistics again still shares it.
  Statistics again;
  again.follow(before);
  register_shaped(again, run.back(), 0);
  CHECK(again.layout() == before);
  CHECK(again.infos().size() == 5);
}

TEST_CASE("statistics: a run's frames' stats.json are those of registries made afresh",
          "[statistics]") {
  // A run of frames (Session::run_frames) registers each frame following the one before; its
  // statistics' documents, names and descriptions are those of single frames of the same
  // scenes (simulate_frame registers afresh). Timing only, a small screen.
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 256;
  c.screen.height = 256;
  c.set(std::vector<std::string>{"fidelity.pixels=none"});
  const auto program = std::make_shared<const Program>(pp5::test::load_program("phong", c));
  const auto scene = std::make_shared<const Scene>(make_builtin_scene("torus", {24, 12}));
  Session session(c, scene, program, 1);
  std::vector<FrameResult> frames;
  session.run_frames(
      3, [&](int, FrameResult& r) { frames.push_back(std::move(r)); }, false);
  REQUIRE(frames.size() == 3);
  for (std::size_t f = 1; f < frames.size(); ++f) {
    INFO("frame " << f);
    CHECK(frames[f].stats.layout() == frames[0].stats.layout());
    CHECK(frames[f].stats.infos().size() == frames[0].stats.infos().size());
  }
}
