#pragma once
// The display list as the GPs walk it: every primitive of the scene as a reference (kind,
// index), where `kind` is an index into the GP's primitive-kind registry
// (models/gp/primitive_kind.hpp) and `index` a position in that kind's storage in the Scene
// (the triangle kind's storage is Scene::mesh.triangles).
//
// Contract:
//  - Order: the kinds in registry order, each kind's primitives in its storage order. The
//    host splits this order over the GPs in contiguous blocks, so the concatenation of the
//    GPs' bins is in display-list order.
//  - at(i) for 0 <= i < size(); a kind with no primitives takes no room.
#include <algorithm>
#include <vector>

namespace pp5 {

struct PrimitiveRef {
  int kind = 0;
  int index = 0;
};

class DisplayList {
 public:
  DisplayList() = default;
  // counts[k]: the primitives of kind k in the scene.
  explicit DisplayList(const std::vector<int>& counts) {
    int total = 0;
    for (int c : counts) {
      total += c;
      ends_.push_back(total);
    }
  }
  int size() const { return ends_.empty() ? 0 : ends_.back(); }
  PrimitiveRef at(int i) const {
    // The first kind whose block ends after i; few kinds, so a linear scan would do as well.
    const auto it = std::upper_bound(ends_.begin(), ends_.end(), i);
    const int kind = static_cast<int>(it - ends_.begin());
    return {kind, i - (kind == 0 ? 0 : ends_[static_cast<std::size_t>(kind) - 1])};
  }

 private:
  std::vector<int> ends_;  // ends_[k]: one past kind k's last display-list position
};

}  // namespace pp5
