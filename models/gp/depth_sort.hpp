#pragma once
// Depth sort for the painter's algorithm (Newell, Newell and Sancha), as the GPs run it: the
// primitives after projection are sorted back to front by their farthest depth, then every
// pair whose depth extents overlap is checked with the overlap tests of the
// visible-surface slides, cheapest first, and reordered where a test says so. What the tests
// cannot order (cyclic overlap, interpenetration) is reported, not split.
//
// Space: screen space after the perspective divide, x and y in pixels (y down) and z the
// screen depth (0 near, 1 far, NDC z mapped to [0, 1]). The projection maps planes to planes
// and makes the view direction +z everywhere, so "behind" is a plane-side test there.
//
// The tests, in the order they run for a pair (P farther by its far end, Q overlapping P in
// depth); the first that succeeds says P cannot hide Q, so P may be drawn before Q:
//   x_extent, y_extent   minimax test on the containing rectangles (disjoint in x or y)
//   p_behind_q           every vertex of P on Q's far side (the slides' plane-side test)
//   q_in_front_of_p      every vertex of Q on P's near side
//   projection           the projections do not overlap: no two edges cross (the slides'
//                        three-step line test) and neither contains the other's centroid
//                        (Containment::edges: the centroid against every edge, the slides'
//                        inside test) or centre (Containment::rectangle: the slides' "check
//                        for containment", a minimax test of one polygon's centre against
//                        the other's containing rectangle, which says "overlap" more often)
// If all fail, the reversed plane tests (q_behind_p, p_in_front_of_q) are tried: if one
// succeeds, Q must be drawn first and is moved ahead of P. A Q that was moved once and must
// move again closes a cycle; a pair no test orders either way interpenetrates, or overlaps
// cyclically with planes that cut each other (three long sticks do). Both are counted as
// unresolved and left in the order they have (P first).
//
// Contract:
//  - Deterministic: the order depends only on the polygons and the GP count, never on the
//    host (the sort is a stable merge sort; every tie keeps display-list order).
//  - Each polygon moves ahead at most once, so the sort ends after O(n^2) pair checks.
//  - The returned order is a permutation of the input indices, back to front.
//  - OpCounts follow docs/timing.md's style: every compare is an adder operation, every
//    multiply a multiplier operation, loads and stores of the polygons' records are counted,
//    and each test's dependent arithmetic is one chain.
//  - How the work splits over `gps` GPs (DepthSortCosts): each GP prepares (extents, plane)
//    and sorts its contiguous share of the display list; GP 0 merges the sorted runs (a
//    tournament of ceil(log2 gps) compares per polygon); the pair checks of polygon P are
//    charged to the GP that holds P's slice of the merged order. The three phases follow
//    each other, so the sort takes max(prepare) + merge + max(check).
#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "models/gp/i860.hpp"

namespace pp5 {

// A convex, planar polygon in screen space (x, y pixels; z depth 0 near .. 1 far).
struct SortPolygon {
  std::vector<glm::dvec3> v;
};

// Ax + By + Cz - D: zero on the plane, positive on the side (A, B, C) points to.
struct PlaneEquation {
  double a = 0, b = 0, c = 0, d = 0;
  double at(const glm::dvec3& p) const { return a * p.x + b * p.y + c * p.z - d; }
};
// The plane through (a, b, c) with normal (A, B, C): D = Aa + Bb + Cc (the slides' form).
PlaneEquation plane_through(const glm::dvec3& normal, const glm::dvec3& point);
// The plane through three points by the slides' determinants; (A, B, C) points to the side
// from which p1, p2, p3 appear counter-clockwise in a right-handed frame.
PlaneEquation plane_of(const glm::dvec3& p1, const glm::dvec3& p2, const glm::dvec3& p3);

// The slides' 2-D helpers (x and y of the points).
// f(x, y) = (x - x1)(y2 - y1) - (x2 - x1)(y - y1) for the line through l1, l2.
double line_side(const glm::dvec2& p, const glm::dvec2& l1, const glm::dvec2& l2);
bool same_side(const glm::dvec2& p1, const glm::dvec2& p2, const glm::dvec2& l1,
               const glm::dvec2& l2);
bool inside_triangle(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b,
                     const glm::dvec2& c);
// Segments (x1,y1)-(x2,y2) and (x3,y3)-(x4,y4): the minimax line test, the parallel check
// (|D| < eps) and the intersection with 0 < s, t < 1 (touching at an end is not crossing).
enum class SegmentResult { disjoint_extents, parallel, crossing, not_crossing };
SegmentResult segments_cross(const glm::dvec2& p1, const glm::dvec2& p2, const glm::dvec2& p3,
                             const glm::dvec2& p4);

// The projection test's last step: is one polygon's centre inside the other?
enum class Containment {
  edges,      // the centroid against every edge (same-side tests): exact for convex polygons
  rectangle,  // the slides': the centre against the containing rectangle (minimax)
};

enum class OverlapTest {
  z_extent,  // the depth extents do not overlap (the sort's own criterion)
  x_extent,
  y_extent,
  p_behind_q,
  q_in_front_of_p,
  projection,
  q_behind_p,       // reversed: Q must be drawn first
  p_in_front_of_q,  // reversed
  count
};
inline constexpr int kOverlapTests = static_cast<int>(OverlapTest::count);
const char* overlap_test_name(OverlapTest t);

// What one pair check found: the test that decided (count when none did).
struct PairVerdict {
  OverlapTest decided_by = OverlapTest::count;
  bool q_first = false;  // a reversed test succeeded: Q must be drawn before P
};
// Checks P (farther by its far end) against Q with the tests in order; adds the tests run to
// `runs` and their operations to `ops`.
PairVerdict check_pair(const SortPolygon& p, const SortPolygon& q,
                       std::array<std::uint64_t, kOverlapTests>& runs, OpCounts& ops,
                       Containment containment = Containment::edges);

struct DepthSortCosts {
  std::vector<OpCounts> prepare;  // per GP: extents, planes, its share's merge sort
  OpCounts merge;                 // GP 0: merging the GPs' sorted runs
  std::vector<OpCounts> check;    // per GP: pair checks of its slice of the merged order
};

struct DepthSortResult {
  std::vector<int> order;             // input indices, back to front
  std::uint64_t key_comparisons = 0;  // comparisons of far depths (sorts and merge)
  std::uint64_t pairs_checked = 0;    // pairs whose depth extents overlap
  std::array<std::uint64_t, kOverlapTests> tests_run{};
  std::array<std::uint64_t, kOverlapTests> decided{};  // pairs each test settled
  std::uint64_t reorders = 0;                          // polygons moved ahead
  std::uint64_t cycles = 0;                     // a moved polygon that would have to move again
  std::uint64_t unorderable = 0;                // pairs no test orders either way
  std::vector<std::pair<int, int>> unresolved;  // (P, Q) input indices, in the order found
  std::vector<int> checker;  // per input polygon, the GP holding its slice of the merged order
  DepthSortCosts costs;
};

DepthSortResult depth_sort(const std::vector<SortPolygon>& polygons, int gps,
                           Containment containment = Containment::edges);

// Splitting by insertion (Newell, Newell and Sancha split what the tests cannot order): the
// pieces of a split polygon take its place in the order a sort made, and only the pairs that
// touch a piece, or a polygon moved since, are checked again; the pairs of two other
// polygons keep their relative order, which the sort checked. The check phase runs again
// over the order as the sort's does (each head P against the polygons after it that overlap
// it in depth; a Q that must go first moves ahead of P and is checked in its turn; a Q moved
// once that must move again closes a cycle), but a head that is neither a piece nor moved
// is checked only against the pieces and moved polygons. The candidates of a head come from
// a far-depth index by two binary searches (its near end, and its far end plus the deepest
// polygon's depth extent): of every polygon for a piece or a moved head, of the pieces and
// moved polygons for the others. Pairs no test orders, and cycles, are unresolved (the next
// round splits them). `order` holds the polygons drawn (the split ones are not in it); each
// head's operations go to the GP `owner` names for it.
struct InsertResult {
  std::uint64_t pairs_checked = 0;  // pairs checked again
  std::uint64_t moves = 0;          // polygons moved ahead
  std::array<std::uint64_t, kOverlapTests> tests_run{};
  std::array<std::uint64_t, kOverlapTests> decided{};
  std::vector<std::pair<int, int>> unresolved;  // (P, Q): P earlier in the order
  std::vector<OpCounts> ops;                    // per GP
};
InsertResult depth_sort_insert(const std::vector<SortPolygon>& polygons, std::vector<int>& order,
                               const std::vector<int>& pieces, const std::vector<int>& owner,
                               int gps, Containment containment = Containment::edges);
// The i860 operations of splitting a triangle by a plane into triangles: the plane's side of
// each vertex (weighted by its clip w), the two edge crossings (the parameter by a reciprocal,
// the world position, normal, colour, opacity and screen position interpolated, the normal
// renormalised), each piece's record (extents, plane) prepared.
OpCounts split_triangle_ops(int pieces);

// A polygon's record as the sort keeps it and the ring moves it, in 32-bit words: three
// vertices (9), its plane (4) and its extents in x, y and z (6).
inline constexpr std::uint64_t kSortRecordWords = 19;
// A sorted run's entry (a far-depth key and an index) and the merged order's (an index).
inline constexpr std::uint64_t kSortRunWords = 2;
inline constexpr std::uint64_t kSortOrderWords = 1;

// What each GP computes and sends in one whole-screen sort, for the GP module to spend and
// send in simulated time (GraphicsProcessor runs it before its geometry when the frame's
// scene carries one: Scene::depth_sort). Function only: the order is the DepthSortResult's;
// this says what the phases cost and which words cross the ring:
//  1. every GP k prepares and sorts its share (prepare[k]), then sends its sorted run to
//     GP 0 (run_words[k]; GP 0's own stays);
//  2. GP 0 merges the runs (merge) and sends the merged order around the ring to every GP
//     (order_words, one message past every GP);
//  3. every GP j sends each GP k the records of the polygons of j's share that k checks
//     (record_words[j][k]; none to itself);
//  4. every GP checks its slice (check[k]), then re-checks the pieces splitting inserted
//     into it (insert[k]: empty without splitting).
struct DepthSortWork {
  std::vector<OpCounts> prepare;
  OpCounts merge;
  std::vector<OpCounts> check;
  std::vector<OpCounts> insert;
  std::vector<std::uint64_t> run_words;
  std::uint64_t order_words = 0;
  std::vector<std::vector<std::uint64_t>> record_words;
  // The clocks: the sort's own counts (false), or x gp.overhead_factor as the geometry's.
  bool overhead_factor = false;
  // A sort run after this one (splitting by sorting again), null for none.
  std::shared_ptr<const DepthSortWork> next;
  int gps() const { return static_cast<int>(prepare.size()); }
};
// The work of `sort` (depth_sort of `polygons` polygons on `gps` GPs).
DepthSortWork depth_sort_work(const DepthSortResult& sort, std::size_t polygons, int gps,
                              bool overhead_factor);

class Statistics;
// Registers PREFIX.key_comparisons, .pairs_checked, .tests_run.TEST, .decided.TEST,
// .reorders, .cycles, .unorderable, .gp.N.clocks (prepare and checks, per GP),
// .merge_clocks and .seconds (the sort's time on the GPs). The values are copied: `result`
// need not outlive the registry.
void register_depth_sort_statistics(Statistics& stats, const std::string& prefix,
                                    const DepthSortResult& result,
                                    const std::vector<GpClocks>& gp_clocks, GpClocks merge_clocks,
                                    double seconds);

}  // namespace pp5
