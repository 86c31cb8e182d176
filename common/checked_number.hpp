#pragma once
// Numbers from untrusted text (command-line arguments) and from untrusted JSON (file headers),
// parsed into a checked width: a value that does not fit is refused, never narrowed or wrapped.
//
// Contract:
//  - parse_integer<T>(text, what, min, max) accepts the whole of `text` as a decimal integer
//    (an optional leading '-', then digits; no spaces, no '+', no hex, no fraction) with
//    min <= value <= max, and returns it as T. Anything else throws std::invalid_argument
//    "WHAT 'TEXT': expected an integer from MIN to MAX", TEXT escaped and cut short
//    (common/escape.hpp); a value out of range says "is out of range" instead of wrapping.
//  - json_integer<T>(value, what, min, max): the same for a JSON value, which must be an
//    integer number (not a float, string or bool) within [min, max].
#include <charconv>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/escape.hpp"

namespace pp5 {

template <class T>
std::string integer_range_text(T min, T max) {
  return "an integer from " + std::to_string(min) + " to " + std::to_string(max);
}

template <class T>
T parse_integer(std::string_view text, std::string_view what, T min = std::numeric_limits<T>::min(),
                T max = std::numeric_limits<T>::max()) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>);
  auto fail = [&](std::string_view why) {
    return std::invalid_argument(std::string(what) + " '" + escape_for_message(text) + "': " +
                                 std::string(why) + "expected " + integer_range_text(min, max));
  };
  // Parsed as the widest type of the same signedness, so that range errors are told apart.
  using Wide = std::conditional_t<std::is_signed_v<T>, long long, unsigned long long>;
  Wide v{};
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (text.empty()) throw fail("");
  if constexpr (!std::is_signed_v<T>) {
    if (text[0] == '-') {
      // A negative number for an unsigned quantity: out of range, not "not a number".
      long long s{};
      const auto [p, ec] = std::from_chars(first, last, s);
      if (p == last && (ec == std::errc() || ec == std::errc::result_out_of_range))
        throw fail("is out of range, ");
      throw fail("");
    }
  }
  const auto [p, ec] = std::from_chars(first, last, v);
  if (p != last || (ec != std::errc() && ec != std::errc::result_out_of_range)) throw fail("");
  if (ec == std::errc::result_out_of_range || v < static_cast<Wide>(min) ||
      v > static_cast<Wide>(max)) {
    throw fail("is out of range, ");
  }
  return static_cast<T>(v);
}

template <class T>
T json_integer(const nlohmann::json& value, std::string_view what,
               T min = std::numeric_limits<T>::min(), T max = std::numeric_limits<T>::max()) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>);
  auto fail = [&](std::string_view why) {
    return std::invalid_argument(
        std::string(what) + " = " +
        escape_for_message(value.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace)) +
        ": " + std::string(why) + "expected " + integer_range_text(min, max));
  };
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    if (v > static_cast<std::uint64_t>(max) || (min > 0 && v < static_cast<std::uint64_t>(min)))
      throw fail("is out of range, ");
    return static_cast<T>(v);
  }
  if (value.is_number_integer()) {
    const auto v = value.get<std::int64_t>();
    if constexpr (std::is_signed_v<T>) {
      if (v < static_cast<std::int64_t>(min) || v > static_cast<std::int64_t>(max))
        throw fail("is out of range, ");
    } else {
      if (v < 0 || static_cast<std::uint64_t>(v) < static_cast<std::uint64_t>(min) ||
          static_cast<std::uint64_t>(v) > static_cast<std::uint64_t>(max))
        throw fail("is out of range, ");
    }
    return static_cast<T>(v);
  }
  throw fail("");
}

}  // namespace pp5
