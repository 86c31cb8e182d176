#pragma once
// Face/face adjacency of an indexed triangle mesh: the triangle across each edge, found from
// shared vertex-index pairs. Built once per scene (GeometryEngine builds it on first use) for
// GP-side values computed from a triangle's neighbours (models/gp/expressions.hpp).
//
// Contract:
//  - Edge e of triangle t joins its corners e and (e + 1) % 3 (the same numbering as the
//    GP's edge expressions edge0..edge2). Two triangles are neighbours across an edge when
//    they use the same two vertex indices, in either order; positions are not compared, so
//    a seam of duplicated vertices is a boundary.
//  - across(t, e) is the neighbour's index, kBoundary when no other triangle uses the edge,
//    kNonManifold when more than two triangles do (every one of them gets kNonManifold).
//  - Counts are of distinct undirected edges (vertex-index pairs). An edge whose two ends are
//    the same index (a triangle with a repeated vertex) is an edge like any other.
//  - Deterministic: depends only on mesh.triangles.
#include <array>
#include <cstdint>
#include <vector>

#include "models/display_list/scene.hpp"

namespace pp5 {

struct MeshAdjacency {
  static constexpr int kBoundary = -1;
  static constexpr int kNonManifold = -2;

  // neighbour[t][e]: the triangle across edge e of triangle t, or kBoundary / kNonManifold.
  std::vector<std::array<int, 3>> neighbour;
  std::uint64_t edges = 0;               // distinct undirected edges
  std::uint64_t boundary_edges = 0;      // used by one triangle only
  std::uint64_t non_manifold_edges = 0;  // used by more than two triangles

  int across(int triangle, int edge) const {
    return neighbour[static_cast<std::size_t>(triangle)][static_cast<std::size_t>(edge)];
  }
  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
};

MeshAdjacency build_mesh_adjacency(const Mesh& mesh);

}  // namespace pp5
