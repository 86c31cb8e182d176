#pragma once
// The GP side of Rossignac's accurate scan conversion (Rossignac, "Accurate scan conversion
// of triangulated surfaces", sections 9.3 and 9.4): per triangle, the face's own depth plane
// (through the unsnapped vertices), the snapped edges moved outward by the vertex round-off
// (the enlarged area the Renderer visits), and for each edge i the signed depth difference
// K_i (Z - Z_i) to the plane of the neighbour across that edge. The firmware
// (firmware/programs/accurate.pp5) admits a pixel only where all three are >= 0: the point of
// this face's plane under the pixel centre lies in the volume V bounded by the neighbours'
// planes, whose intersection with the plane is exactly the unsnapped triangle.
//
// Contract:
//  - side_plane(c, e) is a pure function of the scene, the camera, the machine parameters and
//    the mesh edge; it does not depend on which of the edge's two triangles asks, except that
//    the neighbour gets exactly the negated D coefficients. For an edge classified `plane`
//    both triangles use it; at every pixel exactly one of them admits the centre (a shared
//    interior edge) or both or neither (a silhouette edge, where the two faces overlap on the
//    screen), so parity across a closed mesh is kept along each edge.
//  - K_i = sign of (Z - Z_i) at this face's third vertex: the face must lie inside the
//    half-space it is classified against (9.4.2). That sign is the product of the edge's
//    convexity and the neighbour's orientation to the viewer; it is computed this way because
//    the product needs no consistent winding of the mesh.
//  - An edge without a usable neighbour is classified by its own unsnapped line instead, in
//    the same fixed point and with the same tie-break, and says why: a boundary edge, a
//    non-manifold edge, a neighbour degenerate on the screen, or planes so nearly coplanar
//    that the rounded difference could not place the crossing within kLineTolerance pixels
//    (9.4 relies on the two planes crossing at a definite line). Both triangles of an edge
//    form the same line function, so parity holds along these edges too. Only a piece of a
//    triangle clipped by the view volume (or an edge whose neighbour is clipped) uses the
//    snapped edge function with the top-left rule, what the standard program uses.
//  - D (or the line) is sent with as many fraction bits as fit (at most 48, possibly negative)
//    so that its value never wraps anywhere on the screen: only its sign is tested.
#include <cstdint>

#include "models/gp/expressions.hpp"

namespace pp5 {

enum class SideKind { plane, boundary, non_manifold, clipped, degenerate, coplanar, count };
const char* side_kind_name(SideKind kind);

// How far (pixels) rounding may move a crossing line before the edge's own line is used.
inline constexpr double kLineTolerance = 1.0 / 256;

struct SidePlane {
  SideKind kind = SideKind::boundary;  // plane, or why the edge's line is used instead
  bool snapped = false;  // the expression is the snapped edge function (clipped pieces)
  // Unless snapped: the test K (D - t) in the evaluator's integers (D, or the line, scaled by
  // 2^fraction_bits), t the tie-break (0 or 1) that gives a centre exactly on the crossing
  // line to one triangle of an interior edge.
  QuadraticCoefficients coefficients;
  int fraction_bits = 0;
  int sign = 0;  // K, +1 or -1
  bool silhouette = false;
};

// The classification of edge e of the set-up triangle against its neighbour's plane (or the
// edge's own line). Needs c.adjacency and c.mesh.
SidePlane side_plane(const SetupContext& c, int e);

// The expressions' compute functions (registered in models/gp/expressions.cpp).
bool plane_depth_expression(const SetupContext& c, QuadraticCoefficients& out);
bool wide_edge_expression(const SetupContext& c, int e, QuadraticCoefficients& out);
bool side_expression(const SetupContext& c, int e, QuadraticCoefficients& out);
template <int e>
bool wide_edge(const SetupContext& c, QuadraticCoefficients& out) {
  return wide_edge_expression(c, e, out);
}
template <int e>
bool side(const SetupContext& c, QuadraticCoefficients& out) {
  return side_expression(c, e, out);
}

// i860 operations of one set-up (docs/timing.md):
// plane_depth: an attribute plane (the unsnapped positions are already in registers).
inline constexpr OpCounts kPlaneDepthCost{2 + 1 + 1 + 2 + 3 + 3, 3 + 3 + 2 + 3, 3, 0, 2, 1, 1};
// wide edge: an edge (A, B, C, no top-left rule) and the offset (|dx| + |dy| + 1) / 2: two
// absolute values, an add and a shift.
inline constexpr OpCounts kWideEdgeCost{1 + 1, 2, 0, 0, 2 + 4, 0, 1};
// side: load the neighbour's index and its third vertex (2 + 4 loads); transform and project
// that vertex (16 multiplies, 12 adds, a reciprocal of 4 multiplies and 1 add); the
// neighbour's plane (12 adds, 11 multiplies); D = the difference (3 adds); D at the two third
// vertices (4 multiplies, 4 adds) for K, the silhouette test and the coplanar test (2
// compares); the shift that fits (4 integer, 3 branches); scale and convert (3 multiplies, 3
// converts); K and the tie-break applied (3 integer).
inline constexpr OpCounts kSideCost{
    12 + 1 + 12 + 3 + 4 + 2 + 3, 16 + 4 + 11 + 4 + 3, 2 + 4, 0, 4 + 3, 3 + 2, 4};

}  // namespace pp5
