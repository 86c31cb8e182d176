#include "sim/scene/order.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <random>
#include <stdexcept>

namespace pp5 {

std::string DisplayOrder::text() const {
  switch (kind) {
    case Kind::given:
      return "given";
    case Kind::reversed:
      return "reversed";
    case Kind::shuffled:
      return fmt::format("shuffled:{}", seed);
  }
  return "given";
}

DisplayOrder parse_display_order(const std::string& text, const std::string& option) {
  DisplayOrder o;
  if (text == "given") return o;
  if (text == "reversed") {
    o.kind = DisplayOrder::Kind::reversed;
    return o;
  }
  const std::string prefix = "shuffled";
  if (text.compare(0, prefix.size(), prefix) == 0) {
    o.kind = DisplayOrder::Kind::shuffled;
    if (text.size() == prefix.size()) return o;
    const std::string seed = text.substr(prefix.size() + 1);
    const bool digits =
        text[prefix.size()] == ':' && !seed.empty() && seed.size() <= 19 &&
        std::all_of(seed.begin(), seed.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (digits) {
      o.seed = std::stoull(seed);
      return o;
    }
  }
  throw std::invalid_argument(fmt::format(
      "{} '{}': expected given, reversed, shuffled or shuffled:SEED (SEED a non-negative integer)",
      option, text));
}

void apply_display_order(Mesh& mesh, const DisplayOrder& order) {
  auto& t = mesh.triangles;
  if (order.kind == DisplayOrder::Kind::reversed) {
    std::reverse(t.begin(), t.end());
  } else if (order.kind == DisplayOrder::Kind::shuffled) {
    std::mt19937_64 rng(order.seed);
    for (std::size_t i = t.size(); i > 1; --i) {
      // An unbiased draw in [0, i) by rejection, independent of the standard library.
      const std::uint64_t n = i;
      const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
      std::uint64_t r = rng();
      while (r >= limit) r = rng();
      std::swap(t[i - 1], t[static_cast<std::size_t>(r % n)]);
    }
  }
}

}  // namespace pp5
