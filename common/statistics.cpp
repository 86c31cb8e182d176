#include "common/statistics.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "common/escape.hpp"

namespace pp5 {

namespace {

// An array index, written without leading zeros ("gp.01" would be a second name for gp.1).
bool is_index(std::string_view component) {
  if (component.empty() || (component.size() > 1 && component[0] == '0')) return false;
  for (char c : component) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// A name's components, as views into it, into `out` (this runs for every statistic of every
// frame).
void components_into(std::string_view name, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = name.find('.', start);
    out.push_back(
        name.substr(start, dot == std::string_view::npos ? std::string_view::npos : dot - start));
    if (dot == std::string_view::npos) return;
    start = dot + 1;
  }
}

std::vector<std::string_view> components(std::string_view name) {
  std::vector<std::string_view> out;
  out.reserve(8);
  components_into(name, out);
  return out;
}

// An index component's value (is_index holds); SIZE_MAX when it does not fit.
std::size_t index_value(std::string_view component) {
  std::size_t v = 0;
  const auto [end, error] =
      std::from_chars(component.data(), component.data() + component.size(), v);
  return error == std::errc() && end == component.data() + component.size() ? v : SIZE_MAX;
}

void check_name(const std::string& name, const std::vector<std::string_view>& parts) {
  for (std::string_view c : parts) {
    bool ok = !c.empty();
    for (char ch : c)
      ok = ok && ((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_');
    if (!ok) {
      throw std::invalid_argument("statistic '" + escape_for_message(name) +
                                  "': components must be non-empty and of [a-z0-9_]");
    }
  }
  if (is_index(parts.front())) {
    throw std::invalid_argument("statistic '" + name + "': the document itself is not an array");
  }
}

StatKind kind_of(const StatValue& v) { return static_cast<StatKind>(v.index()); }

nlohmann::json json_of(const StatValue& v) {
  switch (kind_of(v)) {
    case StatKind::integer:
      return std::get<std::int64_t>(v);
    case StatKind::real:
      return std::get<double>(v);
    case StatKind::text:
      break;
  }
  return std::get<std::string>(v);
}

}  // namespace

const char* stat_kind_name(StatKind kind) {
  switch (kind) {
    case StatKind::integer:
      return "integer";
    case StatKind::real:
      return "real";
    case StatKind::text:
      break;
  }
  return "text";
}

namespace {

void pattern_into(const std::vector<std::string_view>& parts, std::string& out) {
  out.clear();
  for (std::string_view c : parts) {
    if (!out.empty()) out += '.';
    if (is_index(c)) {
      out += 'N';
    } else {
      out += c;
    }
  }
}

std::string pattern_of(const std::vector<std::string_view>& parts) {
  std::string out;
  pattern_into(parts, out);
  return out;
}

}  // namespace

std::string stat_pattern(const std::string& name) { return pattern_of(components(name)); }

struct Statistics::Layout {
  std::vector<StatisticInfo> infos;  // in registration order
  std::unordered_map<std::string, std::size_t> index;
  // Every proper prefix of a registered name (its parents): an array (its children are
  // indices, `elements` of them) or a group of names, to refuse a value that is also a parent
  // or a parent that would be both, and to answer elements().
  struct Group {
    bool array = false;
    std::size_t elements = 0;
  };
  std::map<std::string, Group, std::less<>> parents;  // looked up by prefix (string_view)
  // The first statistic of each pattern.
  std::unordered_map<std::string, std::size_t> patterns;
};

std::shared_ptr<const Statistics::Layout> Statistics::layout() const {
  settle();
  return layout_;
}

void Statistics::follow(std::shared_ptr<const Layout> layout) {
  if (!values_.empty()) throw std::logic_error("statistics: follow() on a registry with values");
  // Shared, never changed through this registry: own_layout() copies it first.
  layout_ = std::const_pointer_cast<Layout>(std::move(layout));
}

void Statistics::settle() const {
  if (!layout_ || layout_->infos.size() == values_.size()) return;
  // Followed part of the way: that part again, as a registry that never followed makes it.
  Statistics part;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    const StatisticInfo& i = layout_->infos[k];
    part.add(i.name, i.kind, i.unit.c_str(), i.description.c_str(), std::monostate{});
  }
  layout_ = std::move(part.layout_);
}

void Statistics::own_layout() {
  settle();
  if (!layout_) {
    layout_ = std::make_shared<Layout>();
  } else if (layout_.use_count() > 1) {
    layout_ = std::make_shared<Layout>(*layout_);
  }
}

void Statistics::add_integer(const std::string& name, const char* unit, const char* description,
                             std::function<std::int64_t()> get) {
  add(name, StatKind::integer, unit, description, std::move(get));
}

void Statistics::add_real(const std::string& name, const char* unit, const char* description,
                          std::function<double()> get) {
  add(name, StatKind::real, unit, description, std::move(get));
}

void Statistics::add_text(const std::string& name, const char* unit, const char* description,
                          std::function<std::string()> get) {
  add(name, StatKind::text, unit, description, std::move(get));
}

StatValue Statistics::call(const Getter& get) {
  switch (get.index()) {
    case 1:
      return std::get<1>(get)();
    case 2:
      return std::get<2>(get)();
    case 3:
      return std::get<3>(get)();
    default:
      break;
  }
  throw std::logic_error("statistic read without a getter");
}

void Statistics::add(const std::string& name, StatKind kind, const char* unit,
                     const char* description, Getter get) {
  // Following a layout: the statistic it has next, as registered there (the same name after
  // the same ones: the same checks passed), takes its getter only.
  const std::size_t n = values_.size();
  if (layout_ && n < layout_->infos.size()) {
    const StatisticInfo& next = layout_->infos[n];
    if (next.name == name && next.kind == kind && next.unit == unit &&
        next.description == description) {
      values_.push_back({std::move(get), {}, false});
      return;
    }
  }
  own_layout();
  Layout& layout = *layout_;
  auto& index_ = layout.index;
  auto& parents_ = layout.parents;
  auto& patterns_ = layout.patterns;
  using Group = Layout::Group;
  // A frame registers about a thousand statistics: the name's components and pattern go in
  // scratch kept by the thread rather than new allocations each time.
  thread_local std::vector<std::string_view> parts_scratch;
  thread_local std::string pattern_scratch;
  std::vector<std::string_view>& parts = parts_scratch;
  components_into(name, parts);
  check_name(name, parts);
  if (index_.count(name)) throw std::invalid_argument("statistic '" + name + "' registered twice");
  if (parents_.count(name)) {
    throw std::invalid_argument("statistic '" + name + "' is already a group of statistics");
  }
  // Check everything before changing anything, so that a refused name leaves no trace. A
  // parent is a prefix of the name; one already known as a group is not a value (add keeps
  // the two apart), so only a new one is looked up among the values.
  const std::string_view whole(name);
  std::size_t end = 0;  // the parent's length
  for (std::size_t k = 0; k + 1 < parts.size(); ++k) {
    end += (k ? 1 : 0) + parts[k].size();
    const std::string_view parent = whole.substr(0, end);
    const auto it = parents_.find(parent);
    if (it == parents_.end() && index_.count(std::string(parent))) {
      throw std::invalid_argument("statistic '" + name + "': '" + std::string(parent) +
                                  "' is a value");
    }
    const bool index = is_index(parts[k + 1]);
    if (it != parents_.end() && it->second.array != index) {
      throw std::invalid_argument("statistic '" + name + "': '" + std::string(parent) + "' is " +
                                  (it->second.array ? "an array" : "a group of names"));
    }
    const std::size_t have = it == parents_.end() ? 0 : it->second.elements;
    if (index && index_value(parts[k + 1]) > have) {
      throw std::invalid_argument("statistic '" + name + "': indices of '" + std::string(parent) +
                                  "' must be registered from 0 without gaps");
    }
  }
  std::string& pattern = pattern_scratch;
  pattern_into(parts, pattern);
  const auto first = patterns_.find(pattern);
  if (first != patterns_.end()) {
    const StatisticInfo& e = layout.infos[first->second];
    if (e.kind != kind || e.unit != unit || e.description != description) {
      throw std::invalid_argument("statistic '" + name + "' differs from '" + e.name +
                                  "' in kind, unit or description");
    }
  } else {
    patterns_.emplace(pattern, layout.infos.size());
  }
  end = 0;
  for (std::size_t k = 0; k + 1 < parts.size(); ++k) {
    end += (k ? 1 : 0) + parts[k].size();
    const std::string_view parent = whole.substr(0, end);
    auto it = parents_.find(parent);
    if (it == parents_.end()) it = parents_.emplace(std::string(parent), Group{}).first;
    Group& group = it->second;
    group.array = is_index(parts[k + 1]);
    if (group.array) group.elements = std::max(group.elements, index_value(parts[k + 1]) + 1);
  }
  index_.emplace(name, layout.infos.size());
  layout.infos.push_back({name, kind, unit, description});
  values_.push_back({std::move(get), {}, false});
}

std::size_t Statistics::at(const std::string& name) const {
  settle();
  if (layout_) {
    const auto it = layout_->index.find(name);
    if (it != layout_->index.end()) return it->second;
  }
  throw std::out_of_range("no statistic '" + name + "' (pp5sim stats --describe lists them)");
}

bool Statistics::contains(const std::string& name) const {
  settle();
  return layout_ && layout_->index.count(name) != 0;
}

StatValue Statistics::value(const std::string& name) const { return read(values_[at(name)]); }

const StatisticInfo& Statistics::info(const std::string& name) const {
  return layout_->infos[at(name)];
}

namespace {

template <class T>
T typed(const StatValue& v, const std::string& name, StatKind want) {
  if (kind_of(v) != want) {
    throw std::out_of_range("statistic '" + name + "' is " + stat_kind_name(kind_of(v)) + ", not " +
                            stat_kind_name(want));
  }
  return std::get<T>(v);
}

}  // namespace

std::int64_t Statistics::integer(const std::string& name) const {
  return typed<std::int64_t>(value(name), name, StatKind::integer);
}

double Statistics::real(const std::string& name) const {
  return typed<double>(value(name), name, StatKind::real);
}

std::string Statistics::text(const std::string& name) const {
  return typed<std::string>(value(name), name, StatKind::text);
}

std::size_t Statistics::elements(const std::string& name) const {
  settle();
  if (layout_) {
    const auto it = layout_->parents.find(name);
    if (it != layout_->parents.end()) return it->second.elements;
  }
  throw std::out_of_range("no group of statistics '" + name + "'");
}

void Statistics::freeze() {
  settle();
  for (Value& e : values_) {
    if (e.frozen) continue;
    e.value = call(e.get);
    e.frozen = true;
    e.get = std::monostate{};
  }
}

nlohmann::json Statistics::to_json() const {
  settle();
  nlohmann::json doc = nlohmann::json::object();
  std::vector<std::string_view> parts;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    nlohmann::json* at = &doc;
    components_into(layout_->infos[k].name, parts);
    for (std::string_view c : parts) {
      // Dense registration (checked by add) means an index is at most the array's size.
      at = is_index(c) ? &(*at)[index_value(c)] : &(*at)[c];
    }
    *at = json_of(read(values_[k]));
  }
  return doc;
}

Statistics Statistics::from_json(const nlohmann::json& document) {
  Statistics s;
  std::function<void(const nlohmann::json&, const std::string&)> walk =
      [&](const nlohmann::json& v, const std::string& name) {
        if (v.is_object() || v.is_array()) {
          if (v.is_array()) {
            for (std::size_t k = 0; k < v.size(); ++k) walk(v[k], name + "." + std::to_string(k));
          } else {
            for (const auto& [key, child] : v.items())
              walk(child, name.empty() ? key : name + "." + key);
          }
          return;
        }
        StatValue value;
        if (v.is_number_unsigned()) {
          // A count past 2^63 - 1 (no run makes one) would read as a negative number.
          if (v.get<std::uint64_t>() > static_cast<std::uint64_t>(INT64_MAX)) {
            throw std::invalid_argument("statistic '" + escape_for_message(name) + "' = " +
                                        v.dump() + ": out of range (integers up to 2^63 - 1)");
          }
          value = static_cast<std::int64_t>(v.get<std::uint64_t>());
        } else if (v.is_number_integer()) {
          value = v.get<std::int64_t>();
        } else if (v.is_number_float()) {
          value = v.get<double>();
        } else if (v.is_string()) {
          value = v.get<std::string>();
        } else {
          throw std::invalid_argument("statistic '" + escape_for_message(name) +
                                      "': not a number or text");
        }
        s.add(name, kind_of(value), "", "", std::monostate{});
        Value& e = s.values_.back();
        e.value = std::move(value);
        e.frozen = true;
      };
  if (!document.is_object()) throw std::invalid_argument("statistics: not a JSON object");
  walk(document, "");
  return s;
}

std::vector<StatisticInfo> Statistics::describe() const {
  settle();
  std::vector<StatisticInfo> out;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    std::string pattern = stat_pattern(layout_->infos[k].name);
    if (layout_->patterns.at(pattern) != k) continue;  // not the pattern's first statistic
    StatisticInfo i = layout_->infos[k];
    i.name = std::move(pattern);
    out.push_back(std::move(i));
  }
  return out;
}

std::vector<StatisticInfo> Statistics::infos() const {
  settle();
  if (!layout_) return {};
  return layout_->infos;
}

}  // namespace pp5
