#pragma once
// Strict JSON parsing for every file pp5sim reads (machine configurations, scene files and
// their materials, sweep results): nlohmann::json keeps the last of two equal keys in an
// object without a word, so a typo'd copy of a key silently wins. This parser refuses it.
//
// Contract: parse_strict_json(text, origin) returns the document, or throws
// std::runtime_error whose message starts with "ORIGIN: " and, for a duplicate key, names
// the key and its object's path ("duplicate key 'count' in 'renderer'"); a syntax error keeps
// nlohmann's description (which gives the byte offset). The document is identical to what
// nlohmann::json::parse gives for input without duplicates.
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace pp5 {

struct DuplicateKeyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline nlohmann::json parse_strict_json(const std::string& text, const std::string& origin) {
  using json = nlohmann::json;
  // One frame per open container: the keys seen so far (objects) and the container's name,
  // for the path in the message. Arrays push a frame too, so that object_end pops the right one.
  struct Frame {
    std::set<std::string> keys;
    std::string path;
    bool is_object;
  };
  std::vector<Frame> open;
  std::string last_key;
  auto child_path = [&]() -> std::string {
    if (open.empty()) return "";
    const Frame& parent = open.back();
    if (!parent.is_object) return parent.path + "[]";
    return parent.path.empty() ? last_key : parent.path + "." + last_key;
  };
  json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        open.push_back({{}, child_path(), true});
        break;
      case json::parse_event_t::array_start:
        open.push_back({{}, child_path(), false});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!open.empty()) open.pop_back();
        break;
      case json::parse_event_t::key: {
        last_key = parsed.get<std::string>();
        Frame& object = open.back();
        if (!object.keys.insert(last_key).second) {
          throw DuplicateKeyError(fmt::format(
              "{}: duplicate key '{}' in {}: JSON would silently keep the last value", origin,
              last_key, object.path.empty() ? "the top-level object" : "'" + object.path + "'"));
        }
        break;
      }
      case json::parse_event_t::value:
        break;
    }
    return true;
  };
  try {
    return json::parse(text, check);
  } catch (const json::exception& e) {
    throw std::runtime_error(fmt::format("{}: not valid JSON: {}", origin, e.what()));
  }
}

}  // namespace pp5
