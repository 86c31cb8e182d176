#pragma once
// Strict JSON parsing for every file pp5sim reads (machine configurations, scene files and
// their materials, sweep results): nlohmann::json keeps the last of two equal keys in an
// object without a word, so a typo'd copy of a key silently wins. This parser refuses it.
//
// Contract: parse_strict_json(text, origin) returns the document, or throws
// std::runtime_error whose message starts with "ORIGIN: " and, for a duplicate key, names
// the key and its object's path ("duplicate key 'count' in 'renderer'"); a syntax error keeps
// nlohmann's description (which gives the byte offset) without its "[json.exception...]"
// tag. Containers nested deeper than kMaxJsonDepth are refused as they are met, before the
// parser's memory grows with them (no file pp5sim reads nests more than a few levels). Keys
// in messages are escaped and cut short (common/escape.hpp). The document is identical to
// what nlohmann::json::parse gives for input without duplicates.
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/escape.hpp"

namespace pp5 {

inline constexpr int kMaxJsonDepth = 256;

// nlohmann's exception text without its "[json.exception.parse_error.101] " tag.
inline std::string json_error_text(const std::exception& e) {
  std::string text = e.what();
  if (text.rfind("[json.exception.", 0) == 0) {
    const std::size_t end = text.find("] ");
    if (end != std::string::npos) text.erase(0, end + 2);
  }
  return text;
}

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
  // A path is kept to its first 200 bytes, so that long keys at every level cannot make
  // the frames' memory grow as depth x key length.
  auto child_path = [&]() -> std::string {
    if (open.empty()) return "";
    const Frame& parent = open.back();
    std::string path = !parent.is_object     ? parent.path + "[]"
                       : parent.path.empty() ? last_key
                                             : parent.path + "." + last_key;
    if (path.size() > 200) path.resize(200);
    return path;
  };
  json::parser_callback_t check = [&](int depth, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (depth >= kMaxJsonDepth) {
          throw std::runtime_error(fmt::format(
              "{}: containers nested more than {} deep (at '{}'); no pp5sim input nests "
              "that deep",
              origin, kMaxJsonDepth, escape_for_message(open.empty() ? "" : open.back().path)));
        }
        open.push_back({{}, child_path(), event == json::parse_event_t::object_start});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!open.empty()) open.pop_back();
        break;
      case json::parse_event_t::key: {
        last_key = parsed.get<std::string>();
        Frame& object = open.back();
        if (!object.keys.insert(last_key).second) {
          throw DuplicateKeyError(
              fmt::format("{}: duplicate key '{}' in {}: JSON would silently keep the last value",
                          origin, escape_for_message(last_key),
                          object.path.empty() ? "the top-level object"
                                              : "'" + escape_for_message(object.path) + "'"));
        }
        break;
      }
      case json::parse_event_t::value:
        break;
    }
    return true;
  };
  // nlohmann's reader ends the document at a NUL byte and ignores what follows it, so a
  // file with a NUL (not text, or two files run together) would be read in part.
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    throw std::runtime_error(fmt::format(
        "{}: a NUL byte at byte {}: not JSON text (JSON cannot hold one unescaped)", origin, nul));
  }
  try {
    return json::parse(text, check);
  } catch (const json::exception& e) {
    // The library's "last read: '...'" quotes the file's bytes: escaped.
    throw std::runtime_error(
        fmt::format("{}: not valid JSON: {}", origin, escape_for_message(json_error_text(e), 300)));
  }
}

}  // namespace pp5
