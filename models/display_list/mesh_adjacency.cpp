#include "models/display_list/mesh_adjacency.hpp"

#include <algorithm>
#include <utility>

namespace pp5 {

MeshAdjacency build_mesh_adjacency(const Mesh& mesh) {
  MeshAdjacency a;
  const std::size_t n = mesh.triangles.size();
  a.neighbour.assign(
      n, {MeshAdjacency::kBoundary, MeshAdjacency::kBoundary, MeshAdjacency::kBoundary});
  // Every (triangle, edge) keyed by its unordered vertex pair; sorting groups the users of
  // each edge together (a sort rather than a hash map: deterministic and cache-friendly).
  struct HalfEdge {
    std::uint64_t key;
    std::uint32_t slot;  // 3 * triangle + edge
  };
  std::vector<HalfEdge> half(3 * n);
  for (std::size_t t = 0; t < n; ++t) {
    const glm::uvec3& tri = mesh.triangles[t];
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t p = tri[e];
      const std::uint32_t q = tri[(e + 1) % 3];
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(p, q)) << 32) | std::max(p, q);
      half[3 * t + static_cast<std::size_t>(e)] = {key, static_cast<std::uint32_t>(3 * t + e)};
    }
  }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.slot < y.slot;
  });
  auto set = [&](std::uint32_t slot, int value) { a.neighbour[slot / 3][slot % 3] = value; };
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i + 1;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    ++a.edges;
    if (j - i == 1) {
      ++a.boundary_edges;
    } else if (j - i == 2) {
      set(half[i].slot, static_cast<int>(half[i + 1].slot / 3));
      set(half[i + 1].slot, static_cast<int>(half[i].slot / 3));
    } else {
      ++a.non_manifold_edges;
      for (std::size_t k = i; k < j; ++k) set(half[k].slot, MeshAdjacency::kNonManifold);
    }
    i = j;
  }
  return a;
}

}  // namespace pp5
