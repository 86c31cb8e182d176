// Face/face adjacency (models/display_list/mesh_adjacency.hpp) on a closed mesh, an open one
// and a non-manifold one, plus the display list's (kind, index) enumeration.
#include <catch2/catch.hpp>
#include <vector>

#include "models/display_list/display_list.hpp"
#include "models/display_list/mesh_adjacency.hpp"
#include "sim/scene/scene.hpp"

using pp5::build_mesh_adjacency;
using pp5::Mesh;
using pp5::MeshAdjacency;

namespace {

Mesh mesh_of(int vertices, std::vector<glm::uvec3> triangles) {
  Mesh m;
  m.vertices.resize(static_cast<std::size_t>(vertices));
  m.triangles = std::move(triangles);
  return m;
}

// Every neighbour relation is mutual and names the shared edge from both sides.
void check_symmetric(const Mesh& mesh, const MeshAdjacency& a) {
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    for (int e = 0; e < 3; ++e) {
      const int u = a.across(t, e);
      if (u < 0) continue;
      const glm::uvec3 tt = mesh.triangles[static_cast<std::size_t>(t)];
      const unsigned p = tt[e];
      const unsigned q = tt[(e + 1) % 3];
      int back = 0;
      for (int f = 0; f < 3; ++f) {
        const glm::uvec3 uu = mesh.triangles[static_cast<std::size_t>(u)];
        const unsigned r = uu[f];
        const unsigned s = uu[(f + 1) % 3];
        if ((r == p && s == q) || (r == q && s == p)) {
          CHECK(a.across(u, f) == t);
          ++back;
        }
      }
      CHECK(back == 1);
    }
  }
}

}  // namespace

TEST_CASE("mesh adjacency: a closed tetrahedron has a neighbour across every edge", "[adjacency]") {
  const Mesh m = mesh_of(4, {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}});
  const MeshAdjacency a = build_mesh_adjacency(m);
  CHECK(a.edges == 6);
  CHECK(a.boundary_edges == 0);
  CHECK(a.non_manifold_edges == 0);
  CHECK(a.closed());
  // Triangle 0 = (0, 2, 1): edge 0 is {0, 2} (shared with 3), edge 1 {2, 1} (with 2), edge 2
  // {1, 0} (with 1).
  CHECK(a.across(0, 0) == 3);
  CHECK(a.across(0, 1) == 2);
  CHECK(a.across(0, 2) == 1);
  check_symmetric(m, a);
}

TEST_CASE("mesh adjacency: the built-in torus is closed and every edge has one neighbour",
          "[adjacency]") {
  const pp5::Scene s = pp5::make_builtin_scene("torus", {16, 8});
  const MeshAdjacency a = build_mesh_adjacency(s.mesh);
  REQUIRE(a.neighbour.size() == s.mesh.triangles.size());
  CHECK(a.closed());
  // A closed triangle mesh: every edge is used twice, so 2 E = 3 F.
  CHECK(2 * a.edges == 3 * s.mesh.triangles.size());
  for (const auto& n : a.neighbour) {
    for (int x : n) CHECK(x >= 0);
  }
  check_symmetric(s.mesh, a);
}

TEST_CASE("mesh adjacency: an open quad has four boundary edges and one shared diagonal",
          "[adjacency]") {
  const Mesh m = mesh_of(4, {{0, 1, 2}, {0, 2, 3}});
  const MeshAdjacency a = build_mesh_adjacency(m);
  CHECK(a.edges == 5);
  CHECK(a.boundary_edges == 4);
  CHECK(a.non_manifold_edges == 0);
  CHECK_FALSE(a.closed());
  CHECK(a.across(0, 0) == MeshAdjacency::kBoundary);  // {0, 1}
  CHECK(a.across(0, 1) == MeshAdjacency::kBoundary);  // {1, 2}
  CHECK(a.across(0, 2) == 1);                         // {2, 0}
  CHECK(a.across(1, 0) == 0);                         // {0, 2}
  CHECK(a.across(1, 1) == MeshAdjacency::kBoundary);
  CHECK(a.across(1, 2) == MeshAdjacency::kBoundary);
  check_symmetric(m, a);
}

TEST_CASE("mesh adjacency: three triangles on one edge make it non-manifold", "[adjacency]") {
  // A book of three pages bound along {0, 1}, and a fourth triangle sharing a page's outer
  // edge {1, 2} normally.
  const Mesh m = mesh_of(6, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 1, 5}});
  const MeshAdjacency a = build_mesh_adjacency(m);
  CHECK(a.non_manifold_edges == 1);
  CHECK(a.edges == 9);
  // {0,2} {0,3} {1,3} {0,4} {1,4} {1,5} {2,5}: boundaries; {1,2} is shared by 0 and 3.
  CHECK(a.boundary_edges == 7);
  CHECK(a.across(0, 0) == MeshAdjacency::kNonManifold);
  CHECK(a.across(1, 0) == MeshAdjacency::kNonManifold);
  CHECK(a.across(2, 0) == MeshAdjacency::kNonManifold);
  CHECK(a.across(0, 1) == 3);
  CHECK(a.across(3, 0) == 0);
  CHECK(a.across(0, 2) == MeshAdjacency::kBoundary);
  check_symmetric(m, a);
}

TEST_CASE("mesh adjacency: an empty mesh has no edges", "[adjacency]") {
  const MeshAdjacency a = build_mesh_adjacency(Mesh{});
  CHECK(a.neighbour.empty());
  CHECK(a.edges == 0);
  CHECK(a.closed());
}

TEST_CASE("display list: kinds in order, each kind's primitives in storage order",
          "[adjacency][display_list]") {
  const pp5::DisplayList list({3, 0, 2});
  REQUIRE(list.size() == 5);
  const int kinds[] = {0, 0, 0, 2, 2};
  const int indices[] = {0, 1, 2, 0, 1};
  for (int i = 0; i < 5; ++i) {
    CHECK(list.at(i).kind == kinds[i]);
    CHECK(list.at(i).index == indices[i]);
  }
  CHECK(pp5::DisplayList().size() == 0);
  CHECK(pp5::DisplayList({0, 0}).size() == 0);
}
