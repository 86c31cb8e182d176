#pragma once
// The statistics registry: every figure a run reports (stats.json) is registered here by the
// module that owns it, with its name, kind, unit and description, and read back by name as a
// typed value. stats.json is the registry dumped generically (to_json); `pp5sim stats
// --describe` lists what is registered.
//
// Contract:
//  - A name is a dotted path of components made of [a-z0-9_]. A component of digits only (no
//    leading zero) is an array index: "renderer.3.busy_cycles" is stats.json's
//    renderer[3].busy_cycles. The indices of one array are registered densely from 0;
//    everything else is an object key, and one parent is either an array or an object.
//  - A name is registered once; a name that is both a value and the parent of another
//    ("ring" and "ring.words") is refused. Registering checks the name and throws
//    std::invalid_argument, and a refused name changes nothing.
//  - Each statistic has one kind: integer (std::int64_t), real (double) or text. Reading it as
//    another kind, or reading a name nobody registered, throws std::out_of_range with the name.
//  - Getters are called when a value is read, and by freeze(), which calls each exactly once
//    and keeps the values; after freeze() the registered objects may be destroyed. A frozen
//    registry is what a run hands back (FrameResult::stats).
//  - The pattern of a name replaces each index by "N" ("renderer.N.busy_cycles"); every
//    statistic of one pattern has the same kind, unit and description (add_* checks).
//  - What was registered (names, kinds, units, descriptions, in order) is a Layout, shared
//    between registries rather than copied. follow(layout) on an empty registry makes add_*
//    take, while each statistic matches the layout's next one, only its getter; at the first
//    that differs the registry goes on as one that never followed (the same checks, the same
//    result). A run of frames registers each frame's statistics following the frame before's.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_map>
#include <variant>
#include <vector>

namespace pp5 {

enum class StatKind { integer, real, text };
const char* stat_kind_name(StatKind kind);

using StatValue = std::variant<std::int64_t, double, std::string>;

// Units, so that the same thing is always spelled the same way.
namespace stat_unit {
inline constexpr const char* count = "count";
inline constexpr const char* seconds = "simulated seconds";
inline constexpr const char* host_seconds = "host seconds";
inline constexpr const char* gp_clocks = "i860 clocks";
inline constexpr const char* array_cycles = "array cycles";
inline constexpr const char* ring_cycles = "ring cycles";
inline constexpr const char* ring_words = "ring words";
inline constexpr const char* bits = "bits";
inline constexpr const char* bits_per_second = "bits/s";
inline constexpr const char* ratio = "ratio";
inline constexpr const char* per_second = "per simulated second";
inline constexpr const char* index = "index";
inline constexpr const char* name = "name";
}  // namespace stat_unit

struct StatisticInfo {
  std::string name;  // the full name, or the pattern in describe()
  StatKind kind = StatKind::integer;
  std::string unit;
  std::string description;
};

// A hardware counter (an unsigned count) as an integer statistic's value.
inline std::int64_t stat_count(std::uint64_t v) { return static_cast<std::int64_t>(v); }

class Statistics {
 public:
  struct Layout;  // what was registered (see the contract)

  void add_integer(const std::string& name, const char* unit, const char* description,
                   std::function<std::int64_t()> get);
  void add_real(const std::string& name, const char* unit, const char* description,
                std::function<double()> get);
  void add_text(const std::string& name, const char* unit, const char* description,
                std::function<std::string()> get);

  // This registry's layout (shared, not copied) and following one (see the contract): on an
  // empty registry.
  std::shared_ptr<const Layout> layout() const;
  void follow(std::shared_ptr<const Layout> layout);

  bool contains(const std::string& name) const;
  std::int64_t integer(const std::string& name) const;
  double real(const std::string& name) const;
  std::string text(const std::string& name) const;
  StatValue value(const std::string& name) const;
  const StatisticInfo& info(const std::string& name) const;
  // Elements of the array `name` ("gp": one per GP): the number of indices registered under it.
  std::size_t elements(const std::string& name) const;

  // Reads every value once and keeps it (see the contract).
  void freeze();
  // The registry as stats.json's document: nested objects and arrays (see the contract).
  nlohmann::json to_json() const;
  // A frozen registry of a stats.json document's values (integers, reals and text), for
  // reading written runs by name; units and descriptions are not in the file and stay empty.
  static Statistics from_json(const nlohmann::json& document);

  // One entry per pattern, in registration order.
  std::vector<StatisticInfo> describe() const;
  // The statistics in registration order.
  std::vector<StatisticInfo> infos() const;

 private:
  // The getter as registered, of the statistic's kind (none once frozen, or for a statistic
  // read from a file).
  using Getter = std::variant<std::monostate, std::function<std::int64_t()>,
                              std::function<double()>, std::function<std::string()>>;
  struct Value {
    Getter get;
    StatValue value;
    bool frozen = false;
  };
  void add(const std::string& name, StatKind kind, const char* unit, const char* description,
           Getter get);
  std::size_t at(const std::string& name) const;  // the statistic's index
  static StatValue call(const Getter& get);
  StatValue read(const Value& v) const { return v.frozen ? v.value : call(v.get); }
  // Before a read: a layout followed part of the way is cut to that part (a new layout).
  void settle() const;
  // Before a change: settle(), and the layout made this registry's own (copied if shared).
  void own_layout();

  // Shared with other registries (copy on write); while following, it may hold more
  // statistics than values_ (the part registered so far is values_.size()).
  mutable std::shared_ptr<Layout> layout_;
  std::vector<Value> values_;
};

// "renderer.3.busy_cycles" -> "renderer.N.busy_cycles".
std::string stat_pattern(const std::string& name);

}  // namespace pp5
