#pragma once
// The display-list order in which a scene's triangles reach the GPs, for experiments on
// order-sensitive firmware (Banks' single-pass epsilon): the order the scene was built in,
// its reverse, or a seeded shuffle. Deterministic: the same text gives the same order on
// every host and for any thread count (the shuffle uses std::mt19937_64 and its own
// Fisher-Yates draw, not the library's implementation-defined distributions).
#include <cstdint>
#include <string>

#include "sim/scene/scene.hpp"

namespace pp5 {

struct DisplayOrder {
  enum class Kind { given, reversed, shuffled };
  Kind kind = Kind::given;
  std::uint64_t seed = 1;    // shuffled only
  std::string text() const;  // "given", "reversed" or "shuffled:SEED"
};

// Parses "given", "reversed", "shuffled" (seed 1) or "shuffled:SEED" (a non-negative
// integer). Throws std::invalid_argument naming `option` and what was expected.
DisplayOrder parse_display_order(const std::string& text, const std::string& option);

// Permutes mesh.triangles into `order` (vertices and every triangle's winding unchanged).
void apply_display_order(Mesh& mesh, const DisplayOrder& order);

}  // namespace pp5
