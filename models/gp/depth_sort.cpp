#include "models/gp/depth_sort.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/statistics.hpp"

namespace pp5 {

namespace {

// i860 operations of each step (docs/timing.md, "Depth sort"). Every compare is an adder
// operation and a branch; operands come from the polygon records in the data cache.
// Comparing two far depths and moving one record pointer (merge sort, tournament).
constexpr OpCounts kKeyCompare{1, 0, 2, 1, 1, 1, 0};
// The depth-extent check of a pair: one compare.
constexpr OpCounts kZExtent{1, 0, 2, 0, 0, 1, 0};
// An x or y minimax test: two compares on the stored extents.
constexpr OpCounts kExtent{2, 0, 4, 0, 0, 2, 0};
// One vertex against a plane: A x + B y + C z - D (3 multiplies, 3 adds) and its sign.
constexpr OpCounts kPlaneVertex{3 + 1, 3, 3, 0, 0, 1, 0};
// One pair of edges, the minimax line test (4 compares of the edges' stored extents).
constexpr OpCounts kLineMinimax{4, 0, 8, 0, 0, 1, 0};
// The slope check: D (2 multiplies, 3 subtracts) and |D| < eps.
constexpr OpCounts kLineParallel{3 + 1, 2, 0, 0, 0, 1, 1};
// The crossing: s and t numerators (4 multiplies, 6 subtracts), 1/D (a reciprocal: seed
// and two Newton steps), s and t, four compares against 0 and 1.
constexpr OpCounts kLineCross{6 + 2 + 4, 4 + 5 + 2, 0, 0, 0, 2, 2};
// The slides' same-side test of a centroid against one edge: f(x, y) (2 multiplies, 3
// subtracts) and the sign compare with the third vertex's (stored) sign.
constexpr OpCounts kSameSide{3 + 1, 2, 2, 0, 0, 1, 0};
// The slides' containment: a centre against a containing rectangle, four compares (and
// their branches) on the centre (2 loads) and the stored extents (4 loads).
constexpr OpCounts kCentreMinimax{4, 0, 6, 0, 0, 4, 0};

// A polygon's record, made once (the prepare phase): extents, plane, centroid.
struct Record {
  double x0, x1, y0, y1, z0, z1;
  PlaneEquation plane;  // oriented toward the viewer (C < 0); valid = false when edge-on
  bool valid = false;
  glm::dvec2 centroid;
};

// Prepare: extents (2 compares per coordinate and vertex after the first), the plane (edge
// vectors, cross product, normalise by a reciprocal square root, D), its orientation and
// the centroid.
OpCounts prepare_ops(std::size_t n) {
  const auto m = static_cast<std::uint64_t>(n);
  OpCounts c{6 * (m - 1), 0, 3 * m, 10, 0, 1, 0};
  c += OpCounts{6 + 3 + 2 + 2 + 1, 6 + 3 + 5 + 4 + 3, 0, 0, 0, 1, 3};
  c += OpCounts{2 * (m - 1), 2, 0, 2, 0, 0, 1};
  return c;
}

Record make_record(const SortPolygon& p) {
  if (p.v.size() < 3) throw std::invalid_argument("depth_sort: a polygon needs 3 vertices");
  Record r{};
  r.x0 = r.x1 = p.v[0].x;
  r.y0 = r.y1 = p.v[0].y;
  r.z0 = r.z1 = p.v[0].z;
  glm::dvec2 sum(0);
  for (const glm::dvec3& v : p.v) {
    r.x0 = std::min(r.x0, v.x);
    r.x1 = std::max(r.x1, v.x);
    r.y0 = std::min(r.y0, v.y);
    r.y1 = std::max(r.y1, v.y);
    r.z0 = std::min(r.z0, v.z);
    r.z1 = std::max(r.z1, v.z);
    sum += glm::dvec2(v);
  }
  r.centroid = sum / static_cast<double>(p.v.size());
  // The plane through the first three vertices (the polygon is planar and convex).
  const glm::dvec3 n = glm::cross(p.v[1] - p.v[0], p.v[2] - p.v[0]);
  const double len = glm::length(n);
  if (len > 0 && std::abs(n.z) > 1e-12 * len) {
    const glm::dvec3 u = (n.z < 0 ? n : -n) / len;
    r.plane = plane_through(u, p.v[0]);
    r.valid = true;
  }
  return r;
}

// Relative tolerance of the plane-side tests: a vertex within it of the plane lies on it.
double plane_tolerance(const PlaneEquation& e) { return 1e-9 * (1.0 + std::abs(e.d)); }

// Every vertex of `poly` on the viewer's side of `e` (front) or on its far side (back).
bool all_on_side(const SortPolygon& poly, const Record& plane_owner, bool front, OpCounts& ops) {
  if (!plane_owner.valid) {
    ops += OpCounts{0, 0, 0, 0, 0, 1, 0};
    return false;
  }
  const double eps = plane_tolerance(plane_owner.plane);
  ops.chains += 1;
  for (const glm::dvec3& v : poly.v) {
    ops += kPlaneVertex;
    const double s = plane_owner.plane.at(v);
    if (front ? s < -eps : s > eps) return false;
  }
  return true;
}

// Whether the centroid `c` lies strictly inside convex polygon `poly` (the slides' inside
// test, one same-side check per edge against a vertex not on it).
bool contains(const SortPolygon& poly, const glm::dvec2& c, OpCounts& ops) {
  const std::size_t n = poly.v.size();
  for (std::size_t i = 0; i < n; ++i) {
    ops += kSameSide;
    const glm::dvec2 a(poly.v[i]), b(poly.v[(i + 1) % n]), other(poly.v[(i + 2) % n]);
    if (!same_side(c, other, a, b)) return false;
  }
  return true;
}

// The slides' containment: `c` inside the containing rectangle of `r` (minimax).
bool in_rectangle(const Record& r, const glm::dvec2& c, OpCounts& ops) {
  ops += kCentreMinimax;
  return c.x > r.x0 && c.x < r.x1 && c.y > r.y0 && c.y < r.y1;
}

// The projections overlap: an edge of P crosses an edge of Q, or one contains the other's
// centroid.
bool projections_overlap(const SortPolygon& p, const Record& rp, const SortPolygon& q,
                         const Record& rq, OpCounts& ops, Containment containment) {
  const std::size_t np = p.v.size(), nq = q.v.size();
  for (std::size_t i = 0; i < np; ++i) {
    for (std::size_t j = 0; j < nq; ++j) {
      const SegmentResult s = segments_cross(glm::dvec2(p.v[i]), glm::dvec2(p.v[(i + 1) % np]),
                                             glm::dvec2(q.v[j]), glm::dvec2(q.v[(j + 1) % nq]));
      ops += kLineMinimax;
      if (s == SegmentResult::disjoint_extents) continue;
      ops += kLineParallel;
      if (s == SegmentResult::parallel) continue;
      ops += kLineCross;
      if (s == SegmentResult::crossing) return true;
    }
  }
  if (containment == Containment::rectangle)
    return in_rectangle(rq, rp.centroid, ops) || in_rectangle(rp, rq.centroid, ops);
  return contains(q, rp.centroid, ops) || contains(p, rq.centroid, ops);
}

PairVerdict check_records(const SortPolygon& p, const Record& rp, const SortPolygon& q,
                          const Record& rq, std::array<std::uint64_t, kOverlapTests>& runs,
                          OpCounts& ops, Containment containment) {
  auto run = [&](OverlapTest t) { ++runs[static_cast<int>(t)]; };
  PairVerdict v;
  run(OverlapTest::x_extent);
  ops += kExtent;
  if (rp.x1 <= rq.x0 || rq.x1 <= rp.x0) {
    v.decided_by = OverlapTest::x_extent;
    return v;
  }
  run(OverlapTest::y_extent);
  ops += kExtent;
  if (rp.y1 <= rq.y0 || rq.y1 <= rp.y0) {
    v.decided_by = OverlapTest::y_extent;
    return v;
  }
  run(OverlapTest::p_behind_q);
  if (all_on_side(p, rq, false, ops)) {
    v.decided_by = OverlapTest::p_behind_q;
    return v;
  }
  run(OverlapTest::q_in_front_of_p);
  if (all_on_side(q, rp, true, ops)) {
    v.decided_by = OverlapTest::q_in_front_of_p;
    return v;
  }
  run(OverlapTest::projection);
  if (!projections_overlap(p, rp, q, rq, ops, containment)) {
    v.decided_by = OverlapTest::projection;
    return v;
  }
  run(OverlapTest::q_behind_p);
  if (all_on_side(q, rp, false, ops)) {
    v.decided_by = OverlapTest::q_behind_p;
    v.q_first = true;
    return v;
  }
  run(OverlapTest::p_in_front_of_q);
  if (all_on_side(p, rq, true, ops)) {
    v.decided_by = OverlapTest::p_in_front_of_q;
    v.q_first = true;
    return v;
  }
  return v;
}

// Stable bottom-up merge sort of `items` by far depth, farthest first; counts comparisons.
void sort_far_first(std::vector<int>& items, const std::vector<Record>& rec,
                    std::uint64_t& comparisons, OpCounts& ops) {
  std::vector<int> buffer(items.size());
  for (std::size_t width = 1; width < items.size(); width *= 2) {
    for (std::size_t lo = 0; lo < items.size(); lo += 2 * width) {
      const std::size_t mid = std::min(lo + width, items.size());
      const std::size_t hi = std::min(lo + 2 * width, items.size());
      std::size_t a = lo, b = mid, o = lo;
      while (a < mid && b < hi) {
        ++comparisons;
        ops += kKeyCompare;
        // Ties keep the earlier item first (stable).
        if (rec[items[b]].z1 > rec[items[a]].z1) {
          buffer[o++] = items[b++];
        } else {
          buffer[o++] = items[a++];
        }
      }
      while (a < mid) buffer[o++] = items[a++];
      while (b < hi) buffer[o++] = items[b++];
    }
    items.swap(buffer);
  }
}

int ceil_log2(int n) {
  int k = 0;
  while ((1 << k) < n) ++k;
  return k;
}

}  // namespace

PlaneEquation plane_through(const glm::dvec3& normal, const glm::dvec3& point) {
  return {normal.x, normal.y, normal.z, glm::dot(normal, point)};
}

PlaneEquation plane_of(const glm::dvec3& p1, const glm::dvec3& p2, const glm::dvec3& p3) {
  auto det = [](const glm::dvec3& r1, const glm::dvec3& r2, const glm::dvec3& r3) {
    return r1.x * (r2.y * r3.z - r2.z * r3.y) - r1.y * (r2.x * r3.z - r2.z * r3.x) +
           r1.z * (r2.x * r3.y - r2.y * r3.x);
  };
  PlaneEquation e;
  e.a = det({1, p1.y, p1.z}, {1, p2.y, p2.z}, {1, p3.y, p3.z});
  e.b = det({p1.x, 1, p1.z}, {p2.x, 1, p2.z}, {p3.x, 1, p3.z});
  e.c = det({p1.x, p1.y, 1}, {p2.x, p2.y, 1}, {p3.x, p3.y, 1});
  e.d = det(p1, p2, p3);
  return e;
}

double line_side(const glm::dvec2& p, const glm::dvec2& l1, const glm::dvec2& l2) {
  return (p.x - l1.x) * (l2.y - l1.y) - (l2.x - l1.x) * (p.y - l1.y);
}

bool same_side(const glm::dvec2& p1, const glm::dvec2& p2, const glm::dvec2& l1,
               const glm::dvec2& l2) {
  return line_side(p1, l1, l2) * line_side(p2, l1, l2) > 0;
}

bool inside_triangle(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b,
                     const glm::dvec2& c) {
  return same_side(p, a, b, c) && same_side(p, b, a, c) && same_side(p, c, a, b);
}

SegmentResult segments_cross(const glm::dvec2& p1, const glm::dvec2& p2, const glm::dvec2& p3,
                             const glm::dvec2& p4) {
  if (std::max(p1.x, p2.x) < std::min(p3.x, p4.x) || std::max(p3.x, p4.x) < std::min(p1.x, p2.x) ||
      std::max(p1.y, p2.y) < std::min(p3.y, p4.y) || std::max(p3.y, p4.y) < std::min(p1.y, p2.y)) {
    return SegmentResult::disjoint_extents;
  }
  const double d = (p3.x - p4.x) * (p1.y - p2.y) - (p1.x - p2.x) * (p3.y - p4.y);
  const double scale = (std::abs(p1.x - p2.x) + std::abs(p1.y - p2.y)) *
                       (std::abs(p3.x - p4.x) + std::abs(p3.y - p4.y));
  if (std::abs(d) <= 1e-12 * scale) return SegmentResult::parallel;
  const double s = ((p3.x - p4.x) * (p1.y - p3.y) - (p1.x - p3.x) * (p3.y - p4.y)) / d;
  const double t = ((p1.x - p2.x) * (p1.y - p3.y) - (p1.x - p3.x) * (p1.y - p2.y)) / d;
  // Strictly inside both segments: polygons that only touch (a shared edge or vertex) do not
  // overlap.
  constexpr double kEnd = 1e-9;
  return s > kEnd && s < 1 - kEnd && t > kEnd && t < 1 - kEnd ? SegmentResult::crossing
                                                              : SegmentResult::not_crossing;
}

const char* overlap_test_name(OverlapTest t) {
  switch (t) {
    case OverlapTest::z_extent:
      return "z_extent";
    case OverlapTest::x_extent:
      return "x_extent";
    case OverlapTest::y_extent:
      return "y_extent";
    case OverlapTest::p_behind_q:
      return "p_behind_q";
    case OverlapTest::q_in_front_of_p:
      return "q_in_front_of_p";
    case OverlapTest::projection:
      return "projection";
    case OverlapTest::q_behind_p:
      return "q_behind_p";
    case OverlapTest::p_in_front_of_q:
      return "p_in_front_of_q";
    case OverlapTest::count:
      break;
  }
  return "none";
}

PairVerdict check_pair(const SortPolygon& p, const SortPolygon& q,
                       std::array<std::uint64_t, kOverlapTests>& runs, OpCounts& ops,
                       Containment containment) {
  const Record rp = make_record(p), rq = make_record(q);
  ++runs[static_cast<int>(OverlapTest::z_extent)];
  ops += kZExtent;
  if (rq.z1 <= rp.z0) return {OverlapTest::z_extent, false};
  return check_records(p, rp, q, rq, runs, ops, containment);
}

DepthSortResult depth_sort(const std::vector<SortPolygon>& polygons, int gps,
                           Containment containment) {
  if (gps < 1) throw std::invalid_argument("depth_sort: gps must be at least 1");
  DepthSortResult r;
  const auto n = static_cast<long long>(polygons.size());
  r.costs.prepare.assign(static_cast<std::size_t>(gps), {});
  r.costs.check.assign(static_cast<std::size_t>(gps), {});
  std::vector<Record> rec;
  rec.reserve(polygons.size());
  for (const SortPolygon& p : polygons) rec.push_back(make_record(p));

  // Phase 1, every GP on its contiguous share (the split Machine makes): records and a sort.
  std::vector<std::vector<int>> runs(static_cast<std::size_t>(gps));
  for (int k = 0; k < gps; ++k) {
    const auto first = static_cast<int>(n * k / gps), last = static_cast<int>(n * (k + 1) / gps);
    for (int i = first; i < last; ++i) {
      runs[k].push_back(i);
      r.costs.prepare[k] += prepare_ops(polygons[i].v.size());
    }
    sort_far_first(runs[k], rec, r.key_comparisons, r.costs.prepare[k]);
  }

  // Phase 2, GP 0 merges the runs: a tournament tree of the runs' heads costs ceil(log2 gps)
  // compares per polygon; ties go to the lower GP, which holds the earlier display-list part.
  std::vector<int> merged;
  merged.reserve(polygons.size());
  std::vector<std::size_t> next(static_cast<std::size_t>(gps), 0);
  const auto per_output = static_cast<std::uint64_t>(ceil_log2(gps));
  for (long long out = 0; out < n; ++out) {
    int best = -1;
    for (int k = 0; k < gps; ++k) {
      if (next[k] == runs[k].size()) continue;
      if (best < 0 || rec[runs[k][next[k]]].z1 > rec[runs[best][next[best]]].z1) best = k;
    }
    merged.push_back(runs[best][next[best]++]);
    r.key_comparisons += per_output;
    r.costs.merge += kKeyCompare * per_output;
  }

  // Phase 3, the pair checks. Polygon i's checks are charged to the GP holding its slice
  // of the merged order.
  std::vector<int> owner(polygons.size(), 0);
  for (int k = 0; k < gps; ++k) {
    for (long long pos = n * k / gps; pos < n * (k + 1) / gps; ++pos) owner[merged[pos]] = k;
  }
  r.checker = owner;
  std::vector<int> list = merged;
  std::vector<char> moved(polygons.size(), 0);
  std::size_t head = 0;
  // list[sorted_from..] is still sorted by far depth; before it are polygons moved ahead and
  // the heads they were moved ahead of.
  std::size_t sorted_from = 0;
  auto zrun = [&](OpCounts& ops) {
    ++r.tests_run[static_cast<int>(OverlapTest::z_extent)];
    ops += kZExtent;
  };
  while (head < list.size()) {
    const int p = list[head];
    OpCounts& ops = r.costs.check[owner[p]];
    bool restarted = false;
    for (std::size_t j = head + 1; j < list.size(); ++j) {
      const int q = list[j];
      zrun(ops);
      // In the sorted part, the first Q wholly nearer than P's near end ends P's checks.
      if (rec[q].z1 <= rec[p].z0) {
        ++r.decided[static_cast<int>(OverlapTest::z_extent)];
        if (j >= sorted_from) break;
        continue;
      }
      ++r.pairs_checked;
      const PairVerdict v =
          check_records(polygons[p], rec[p], polygons[q], rec[q], r.tests_run, ops, containment);
      if (v.decided_by != OverlapTest::count) ++r.decided[static_cast<int>(v.decided_by)];
      if (v.decided_by == OverlapTest::count) {
        ++r.unorderable;
        r.unresolved.emplace_back(p, q);
        continue;
      }
      if (!v.q_first) continue;
      if (moved[q]) {
        ++r.cycles;
        r.unresolved.emplace_back(p, q);
        continue;
      }
      // Q goes ahead of P and is checked in its turn.
      moved[q] = 1;
      ++r.reorders;
      if (j >= sorted_from) ++sorted_from;
      list.erase(list.begin() + static_cast<std::ptrdiff_t>(j));
      list.insert(list.begin() + static_cast<std::ptrdiff_t>(head), q);
      ops += OpCounts{0, 0, 2, 2, 4, 1, 0};  // relinking Q in the list
      restarted = true;
      break;
    }
    if (!restarted) {
      r.order.push_back(p);
      ++head;
      sorted_from = std::max(sorted_from, head);
    }
  }
  return r;
}

OpCounts split_triangle_ops(int pieces) {
  // A vertex's side: the plane test (kPlaneVertex) and one multiply by w.
  constexpr OpCounts kSide{4, 4, 3, 0, 0, 1, 0};
  // One crossing: t = ga / (ga - gb) (a subtract, a reciprocal by seed and two Newton steps,
  // a multiply); ten world values (position 3, normal 3, colour 3, opacity) by a + t (b - a);
  // the normal renormalised (dot product, reciprocal square root by seed and two Newton
  // steps, three multiplies); w; the screen position (x, y, z times w, interpolated, over w by
  // a reciprocal). Loads both end vertices (14 values each), stores the new one.
  constexpr OpCounts kCrossing{
      1 + 2 + 20 + 2 + 2 + 1 + 6 + 2, 1 + 5 + 10 + 3 + 6 + 3 + 1 + 6 + 5 + 3, 28, 14, 0, 1, 4};
  OpCounts ops;
  for (int k = 0; k < 3; ++k) ops += kSide;
  ops += kCrossing;
  ops += kCrossing;
  for (int k = 0; k < pieces; ++k) ops += prepare_ops(3);
  return ops;
}

InsertResult depth_sort_insert(const std::vector<SortPolygon>& polygons, std::vector<int>& order,
                               const std::vector<int>& pieces, const std::vector<int>& owner,
                               int gps, Containment containment) {
  InsertResult r;
  r.ops.assign(static_cast<std::size_t>(gps), {});
  std::vector<Record> rec;
  rec.reserve(polygons.size());
  for (const SortPolygon& p : polygons) rec.push_back(make_record(p));
  // The deepest depth extent in the order: a polygon overlapping P in depth has its far end in
  // (P's near end, P's far end + deepest], a window of the far-depth index.
  double deepest = 0;
  for (const int i : order) deepest = std::max(deepest, rec[i].z1 - rec[i].z0);
  // Far-depth indices (far end descending): of every polygon in the order, and of the dirty
  // ones (the pieces, and the polygons moved since).
  const auto by_far = [&rec](int a, int b) { return rec[a].z1 > rec[b].z1; };
  std::vector<int> all = order;
  std::stable_sort(all.begin(), all.end(), by_far);
  std::vector<char> dirty(polygons.size(), 0), moved(polygons.size(), 0);
  std::vector<int> dirty_index;
  for (const int x : pieces) {
    dirty[x] = 1;
    dirty_index.push_back(x);
  }
  std::stable_sort(dirty_index.begin(), dirty_index.end(), by_far);
  std::vector<std::size_t> pos(polygons.size(), 0);
  const auto renumber = [&] {
    for (std::size_t k = 0; k < order.size(); ++k) pos[order[k]] = k;
  };
  renumber();
  constexpr OpCounts kMove{0, 0, 2, 2, 4, 1, 0};
  // A window's candidate also costs a load of its place in the order (after the head or not).
  constexpr OpCounts kPlace{0, 0, 1, 0, 0, 1, 0};
  std::vector<int> after;
  std::size_t head = 0;
  while (head < order.size()) {
    const int p = order[head];
    OpCounts& ops = r.ops[static_cast<std::size_t>(owner[p])];
    // A clean head's pairs with clean polygons were checked before and keep their order: only
    // the dirty polygons are candidates. A dirty head is checked against every polygon.
    const std::vector<int>& index = dirty[p] ? all : dirty_index;
    if (index.empty()) {
      ++head;
      continue;
    }
    for (int k = 0; k < 2 * ceil_log2(static_cast<int>(index.size()) + 1); ++k) ops += kKeyCompare;
    const auto lo = std::upper_bound(index.begin(), index.end(), rec[p].z1 + deepest,
                                     [&rec](double z, int v) { return z > rec[v].z1; });
    after.clear();
    for (auto it = lo; it != index.end() && rec[*it].z1 > rec[p].z0; ++it) {
      ops += kPlace;
      if (*it != p && pos[*it] > head) after.push_back(*it);
    }
    std::sort(after.begin(), after.end(), [&pos](int a, int b) { return pos[a] < pos[b]; });
    bool restarted = false;
    for (const int q : after) {
      ++r.tests_run[static_cast<int>(OverlapTest::z_extent)];
      ops += kZExtent;
      if (rec[q].z0 >= rec[p].z1) {
        ++r.decided[static_cast<int>(OverlapTest::z_extent)];
        continue;
      }
      ++r.pairs_checked;
      const PairVerdict v = check_records(polygons[static_cast<std::size_t>(p)], rec[p],
                                          polygons[static_cast<std::size_t>(q)], rec[q],
                                          r.tests_run, ops, containment);
      if (v.decided_by == OverlapTest::count) {
        r.unresolved.emplace_back(p, q);
        continue;
      }
      ++r.decided[static_cast<int>(v.decided_by)];
      if (!v.q_first) continue;
      if (moved[q]) {
        r.unresolved.emplace_back(p, q);  // it would have to move again: a cycle
        continue;
      }
      // Q goes ahead of P, as in the sort, and is checked in its turn against every polygon.
      moved[q] = 1;
      ++r.moves;
      ops += kMove;
      order.erase(order.begin() + static_cast<std::ptrdiff_t>(pos[q]));
      order.insert(order.begin() + static_cast<std::ptrdiff_t>(head), q);
      renumber();
      if (!dirty[q]) {
        dirty[q] = 1;
        dirty_index.insert(std::upper_bound(dirty_index.begin(), dirty_index.end(), q, by_far), q);
      }
      restarted = true;
      break;
    }
    if (!restarted) ++head;
  }
  return r;
}

DepthSortWork depth_sort_work(const DepthSortResult& sort, std::size_t polygons, int gps,
                              bool overhead_factor) {
  if (gps < 1 || sort.costs.prepare.size() != static_cast<std::size_t>(gps) ||
      sort.checker.size() != polygons) {
    throw std::invalid_argument("depth_sort_work: the sort was not made for these polygons");
  }
  DepthSortWork w;
  const auto g = static_cast<std::size_t>(gps);
  w.prepare = sort.costs.prepare;
  w.merge = sort.costs.merge;
  w.check = sort.costs.check;
  w.insert.assign(g, {});
  w.overhead_factor = overhead_factor;
  w.run_words.assign(g, 0);
  w.record_words.assign(g, std::vector<std::uint64_t>(g, 0));
  const auto n = static_cast<long long>(polygons);
  for (int k = 0; k < gps; ++k) {
    const long long first = n * k / gps, last = n * (k + 1) / gps;
    if (k != 0) w.run_words[static_cast<std::size_t>(k)] = kSortRunWords * (last - first);
    for (long long i = first; i < last; ++i) {
      const int to = sort.checker[static_cast<std::size_t>(i)];
      if (to != k)
        w.record_words[static_cast<std::size_t>(k)][static_cast<std::size_t>(to)] +=
            kSortRecordWords;
    }
  }
  w.order_words = gps > 1 ? kSortOrderWords * polygons : 0;
  return w;
}

void register_depth_sort_statistics(Statistics& stats, const std::string& prefix,
                                    const DepthSortResult& r,
                                    const std::vector<GpClocks>& gp_clocks, GpClocks merge_clocks,
                                    double seconds) {
  namespace u = stat_unit;
  auto count = [](std::uint64_t v) { return [v] { return static_cast<std::int64_t>(v); }; };
  const std::string p = prefix + ".";
  stats.add_integer(p + "key_comparisons", u::count,
                    "Far-depth comparisons of the depth sort (the GPs' sorts and the merge)",
                    count(r.key_comparisons));
  stats.add_integer(p + "pairs_checked", u::count,
                    "Pairs whose depth extents overlap, checked with the overlap tests",
                    count(r.pairs_checked));
  for (int t = 0; t < kOverlapTests; ++t) {
    const std::string name = overlap_test_name(static_cast<OverlapTest>(t));
    stats.add_integer(p + "tests_run." + name, u::count, "Times the overlap test ran",
                      count(r.tests_run[t]));
    stats.add_integer(p + "decided." + name, u::count, "Pairs the overlap test settled",
                      count(r.decided[t]));
  }
  stats.add_integer(p + "reorders", u::count, "Polygons moved ahead of a farther one",
                    count(r.reorders));
  stats.add_integer(p + "cycles", u::count,
                    "Pairs unresolved because a moved polygon would have to move again",
                    count(r.cycles));
  stats.add_integer(p + "unorderable", u::count,
                    "Pairs unresolved because no test orders them either way",
                    count(r.unorderable));
  for (std::size_t k = 0; k < gp_clocks.size(); ++k) {
    stats.add_integer(p + "gp." + std::to_string(k) + ".clocks", u::gp_clocks,
                      "The GP's depth-sort clocks: its share's prepare and sort, and its checks",
                      count(gp_clocks[k].count));
  }
  stats.add_integer(p + "merge_clocks", u::gp_clocks, "GP 0's clocks merging the sorted runs",
                    count(merge_clocks.count));
  stats.add_real(p + "seconds", u::seconds,
                 "The sort's time: the slowest prepare, the merge, the slowest checks",
                 [seconds] { return seconds; });
}

}  // namespace pp5
