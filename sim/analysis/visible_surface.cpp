// The machine side of visible_surface.hpp: the visibility runs, the depth sort's cost, the
// comparison table.
#include "sim/analysis/visible_surface.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <stdexcept>

#include "models/machine.hpp"
#include "sim/analysis/analysis_firmware.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

const char* const kVisibilityPainterFirmware =
    R"(; Visibility, painter's: no depth; the last triangle drawn over a pixel keeps it.
field red     8
field green   8
field blue    8
output red green blue

proc clear
  eall
  mov red, 0
  mov green, 0
  mov blue, 0
end

proc triangle
  eall
  qtest.ge edge0
  qtest.ge edge1
  qtest.ge edge2
  qload red, base_red
  qload green, base_green
  qload blue, base_blue
end
)";

namespace {

constexpr std::size_t kMaxVisibilityTriangles = (std::size_t{1} << 24) - 1;

std::uint64_t busy_cycles(const FrameResult& r) {
  return static_cast<std::uint64_t>(r.stats.integer("renderers_total.busy_cycles"));
}

std::string region_text(const Difference& d, const MachineConfig& config) {
  if (d.regions == 0) return "-";
  const int per_row =
      (config.screen.width + config.renderer.region_width - 1) / config.renderer.region_width;
  return fmt::format("{} (densest {},{}: {})", d.regions, d.densest_region % per_row,
                     d.densest_region / per_row, d.densest);
}

// The sort's cost on the machine's GPs under one set of choices. Whole screen: each GP
// prepares and sorts its contiguous share, sends its sorted run (a key and an index a
// polygon) to GP 0, which merges and sends the order back (an index a polygon), and every
// polygon's record goes to the GP that checks it; the checks follow. Per region bin: each
// region's polygons (those whose rectangle meets it) are sorted on their own by the GP the
// region goes to (r mod gp.count), which first receives their records; no merge. The ring
// time is the larger of all words over the ring's bandwidth and the longest single message.
// `whole`, if given, is the whole-screen sort already run on `polygons`; `insert`, if given,
// each GP's splitting and inserting after its checks.
SortCost painter_sort_cost(const MachineConfig& config, const std::vector<SortPolygon>& polygons,
                           bool per_region, bool factor, const DepthSortResult* whole,
                           Containment containment, const std::vector<OpCounts>* insert = nullptr) {
  I860Params params = i860_params(config);
  if (!factor) params.overhead_factor = 1;
  const I860Model i860(params);
  const double hz = config.gp.clock_hz;
  const double ring_hz = config.ring.clock_hz;
  const double bandwidth = ring_hz * config.ring.channels;
  SortCost c;
  c.per_region = per_region;
  c.overhead_factor = factor;
  c.polygons = polygons.size();
  const int gps = config.gp.count;
  if (!per_region) {
    const DepthSortResult own = whole ? DepthSortResult{} : depth_sort(polygons, gps, containment);
    const DepthSortResult& r = whole ? *whole : own;
    c.pairs_checked = r.pairs_checked;
    std::uint64_t prepare = 0, check = 0;
    for (int k = 0; k < gps; ++k) {
      prepare =
          std::max(prepare, i860.clocks(r.costs.prepare[static_cast<std::size_t>(k)], 0).count);
      std::uint64_t own = i860.clocks(r.costs.check[static_cast<std::size_t>(k)], 0).count;
      if (insert != nullptr) own += i860.clocks((*insert)[static_cast<std::size_t>(k)], 0).count;
      check = std::max(check, own);
    }
    c.prepare_seconds = static_cast<double>(prepare) / hz;
    c.check_seconds = static_cast<double>(check) / hz;
    c.merge_seconds = static_cast<double>(i860.clocks(r.costs.merge, 0).count) / hz;
    const auto n = static_cast<std::uint64_t>(polygons.size());
    const std::uint64_t share =
        (n + static_cast<std::uint64_t>(gps) - 1) / static_cast<std::uint64_t>(gps);
    const std::uint64_t words = 2 * (n - std::min(n, share)) + n + kSortRecordWords * n;
    c.transfer_seconds = std::max(static_cast<double>(words) / bandwidth,
                                  static_cast<double>(std::max(2 * share, n)) / ring_hz);
    return c;
  }
  std::vector<std::uint64_t> gp_clocks(static_cast<std::size_t>(gps), 0);
  std::uint64_t words = 0, longest = 0;
  const int rw = config.renderer.region_width, rh = config.renderer.region_height;
  for (int region = 0; region < config.regions(); ++region) {
    const double x0 = config.region_x0(region), y0 = config.region_y0(region);
    std::vector<SortPolygon> bin;
    for (const SortPolygon& p : polygons) {
      double lx = p.v[0].x, hx = lx, ly = p.v[0].y, hy = ly;
      for (const glm::dvec3& v : p.v) {
        lx = std::min(lx, v.x), hx = std::max(hx, v.x), ly = std::min(ly, v.y),
        hy = std::max(hy, v.y);
      }
      if (hx >= x0 && lx < x0 + rw && hy >= y0 && ly < y0 + rh) bin.push_back(p);
    }
    if (bin.empty()) continue;
    const DepthSortResult r = depth_sort(bin, 1, containment);
    c.pairs_checked += r.pairs_checked;
    gp_clocks[static_cast<std::size_t>(region % gps)] += i860.clocks(r.costs.prepare[0], 0).count +
                                                         i860.clocks(r.costs.check[0], 0).count +
                                                         i860.clocks(r.costs.merge, 0).count;
    words += kSortRecordWords * bin.size();
    longest = std::max<std::uint64_t>(longest, kSortRecordWords * bin.size());
  }
  c.check_seconds = static_cast<double>(*std::max_element(gp_clocks.begin(), gp_clocks.end())) / hz;
  c.transfer_seconds =
      std::max(static_cast<double>(words) / bandwidth, static_cast<double>(longest) / ring_hz);
  return c;
}

// When the GPs' depth sort ended in a frame that ran it (the latest GP's), 0 if none did.
double simulated_sort_seconds(const FrameResult& r, int gps) {
  double t = 0;
  for (int k = 0; k < gps; ++k) {
    const std::string name = fmt::format("gp.{}.depth_sort.done_seconds", k);
    if (r.stats.contains(name)) t = std::max(t, r.stats.real(name));
  }
  return t;
}

// Painter's with splitting: the painted triangles as world-space pieces, each with its screen
// polygon, the clip w of its vertices and the scene triangle it came from.
struct PaintVertex {
  Vertex world;
  glm::dvec3 screen;
  double w = 1;
};
struct PaintPiece {
  std::array<PaintVertex, 3> v;
  int source = 0;
  // A clipped triangle (more than three screen vertices) is not split: it is drawn as its
  // scene triangle, and sorted by its clipped polygon.
  std::vector<glm::dvec3> clipped = {};
};

// The point where the edge a -> b crosses the plane whose side values x w are ga and gb:
// the world point, and its screen position and w, are affine in the crossing's parameter
// once the screen position is weighted by w.
PaintVertex crossing(const PaintVertex& a, const PaintVertex& b, double ga, double gb) {
  const double t = ga / (ga - gb);
  const auto ft = static_cast<float>(t);
  PaintVertex c;
  c.world.position = a.world.position + ft * (b.world.position - a.world.position);
  c.world.normal = glm::normalize(a.world.normal + ft * (b.world.normal - a.world.normal));
  c.world.color = a.world.color + ft * (b.world.color - a.world.color);
  c.world.opacity = a.world.opacity + ft * (b.world.opacity - a.world.opacity);
  c.w = a.w + t * (b.w - a.w);
  c.screen = (a.screen * a.w + t * (b.screen * b.w - a.screen * a.w)) / c.w;
  return c;
}

// Splits `piece` by `plane` (screen space) into the triangles on each side, fanned from
// each side's polygon in the original winding; false if the plane does not cut it.
bool split_piece(const PaintPiece& piece, const PlaneEquation& plane,
                 std::vector<PaintPiece>& out) {
  if (!piece.clipped.empty()) return false;
  std::array<double, 3> g{};
  bool above = false, below = false;
  const double eps = 1e-9 * (1.0 + std::abs(plane.d));
  for (int k = 0; k < 3; ++k) {
    const double f = plane.at(piece.v[static_cast<std::size_t>(k)].screen);
    g[static_cast<std::size_t>(k)] =
        std::abs(f) <= eps ? 0.0 : f * piece.v[static_cast<std::size_t>(k)].w;
    above = above || g[static_cast<std::size_t>(k)] > 0;
    below = below || g[static_cast<std::size_t>(k)] < 0;
  }
  if (!above || !below) return false;
  for (const int side : {1, -1}) {
    std::vector<PaintVertex> poly;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t n = (k + 1) % 3;
      const double a = side * g[k], b = side * g[n];
      if (a >= 0) poly.push_back(piece.v[k]);
      if ((a > 0 && b < 0) || (a < 0 && b > 0))
        poly.push_back(crossing(piece.v[k], piece.v[n], g[k], g[n]));
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      out.push_back({{poly[0], poly[k], poly[k + 1]}, piece.source});
  }
  return true;
}

// Each painted polygon as a piece: an unclipped triangle with its world vertices (it can be
// split), a clipped one as its screen polygon.
std::vector<PaintPiece> paint_pieces(const Scene& scene,
                                     const std::vector<ScreenPolygon>& painted) {
  std::vector<PaintPiece> pieces;
  for (const ScreenPolygon& poly : painted) {
    PaintPiece piece;
    piece.source = poly.source;
    if (poly.v.size() == 3 && poly.w.size() == 3) {
      const glm::uvec3& tri = scene.mesh.triangles[static_cast<std::size_t>(poly.source)];
      for (std::size_t k = 0; k < 3; ++k) {
        piece.v[k].world = scene.mesh.vertices[tri[static_cast<glm::length_t>(k)]];
        piece.v[k].screen = poly.v[k];
        piece.v[k].w = poly.w[k];
      }
    } else {
      piece.clipped = poly.v;
    }
    pieces.push_back(std::move(piece));
  }
  return pieces;
}

SortPolygon sort_polygon(const PaintPiece& p) {
  if (!p.clipped.empty()) return {p.clipped};
  return {{p.v[0].screen, p.v[1].screen, p.v[2].screen}};
}

// Splitting leaves T-junctions: a round cuts a piece along a plane that crosses an edge it
// shares with a sibling piece (of the same scene triangle) the round left whole, so the new
// vertex lies on the sibling's edge without being a vertex of it, and after the GP snaps
// vertices to the subpixel grid a sliver between the two can hold a pixel centre that
// neither covers. Every such sibling is split at the vertex into two triangles (fanned from
// the opposite vertex) until no vertex of a piece lies inside an edge of a sibling. The
// halves are parts of one polygon in one plane, so they keep its place in the order: any
// order that may draw a polygon before or after another may draw a part of it so, and no
// pair is checked again. Charged per test of a sibling's vertex against an edge (a cross
// product and the extents along the edge) and per split (the two triangles written) to the
// GP `gp_of` names. Returns the splits made.
std::uint64_t remove_t_junctions(std::vector<PaintPiece>& pieces, std::vector<char>& alive,
                                 std::vector<int>& order, std::vector<int>& gp_of,
                                 std::vector<OpCounts>& ops) {
  constexpr OpCounts kVertexOnEdge{5, 2, 4, 0, 0, 1, 0};
  constexpr OpCounts kHalve{0, 0, 3, 6, 4, 1, 0};
  constexpr OpCounts kEdgeLookup{0, 0, 4, 0, 2, 2, 0};  // hash the edge, load the sibling
  std::uint64_t splits = 0;
  // The pieces of each scene triangle that was split (more than one piece).
  std::map<int, std::vector<int>> siblings;
  for (const int k : order) {
    if (pieces[static_cast<std::size_t>(k)].clipped.empty())
      siblings[pieces[static_cast<std::size_t>(k)].source].push_back(k);
  }
  for (auto& [source, family] : siblings) {
    if (family.size() < 2) continue;
    // Each split adds no vertex (v is a sibling's), so the family's edges only subdivide; a
    // bound keeps near-degenerate slivers from halving without end.
    std::size_t budget = 8 * family.size();
    // What a GP that keeps each piece's edges does: for every vertex of a piece, look up the
    // sibling across the edge the vertex was cut on, and test the vertex against that edge
    // (the host searches every sibling instead, and starts over after each split).
    for (const int t : family) {
      for (int k = 0; k < 3; ++k)
        ops[static_cast<std::size_t>(gp_of[static_cast<std::size_t>(t)])] +=
            kEdgeLookup + kVertexOnEdge;
    }
    // After a split at family[a], the scan goes on from a: the pieces before it were checked
    // against every sibling's vertices, and a split adds no vertex, so none of them can have
    // gained a T-junction (the same splits, in the same order, as starting over).
    std::size_t resume = 0;
    bool changed = true;
    while (changed && budget > 0) {
      changed = false;
      for (std::size_t a = resume; a < family.size() && !changed; ++a) {
        const int t = family[a];
        for (std::size_t b = 0; b < family.size() && !changed; ++b) {
          if (a == b) continue;
          const PaintPiece& other = pieces[static_cast<std::size_t>(family[b])];
          for (const PaintVertex& v : other.v) {
            const PaintPiece& piece = pieces[static_cast<std::size_t>(t)];
            int edge = -1;
            for (int e = 0; e < 3 && edge < 0; ++e) {
              const glm::dvec2 p0(piece.v[static_cast<std::size_t>(e)].screen);
              const glm::dvec2 p1(piece.v[static_cast<std::size_t>((e + 1) % 3)].screen);
              const glm::dvec2 d = p1 - p0, q = glm::dvec2(v.screen) - p0;
              const double len2 = glm::dot(d, d);
              if (len2 <= 0) continue;
              const double along = glm::dot(q, d) / len2;
              const double across = std::abs(d.x * q.y - d.y * q.x) / len2;
              if (along > 1e-6 && along < 1 - 1e-6 && across < 1e-7) edge = e;
            }
            if (edge < 0) continue;
            // Not a sliver with no area to halve.
            {
              const glm::dvec2 a0(piece.v[0].screen), a1(piece.v[1].screen), a2(piece.v[2].screen);
              const glm::dvec2 u = a1 - a0, w = a2 - a0;
              if (std::abs(u.x * w.y - u.y * w.x) <= 1e-9 * (glm::dot(u, u) + glm::dot(w, w)))
                continue;
            }
            --budget;
            // Halve T at v: (A, v, C) and (v, B, C) for its edge A-B, in its winding.
            const auto e = static_cast<std::size_t>(edge);
            const PaintVertex pa = piece.v[e], pb = piece.v[(e + 1) % 3], pc = piece.v[(e + 2) % 3];
            const int source_of = piece.source;
            ops[static_cast<std::size_t>(gp_of[static_cast<std::size_t>(t)])] += kHalve;
            for (int k = 0; k < 6; ++k)
              ops[static_cast<std::size_t>(gp_of[static_cast<std::size_t>(t)])] +=
                  kEdgeLookup + kVertexOnEdge;
            const auto first = static_cast<int>(pieces.size());
            pieces.push_back({{pa, v, pc}, source_of});
            pieces.push_back({{v, pb, pc}, source_of});
            alive.push_back(1);
            alive.push_back(1);
            gp_of.push_back(gp_of[static_cast<std::size_t>(t)]);
            gp_of.push_back(gp_of[static_cast<std::size_t>(t)]);
            alive[static_cast<std::size_t>(t)] = 0;
            const auto at = std::find(order.begin(), order.end(), t);
            const auto pos = order.erase(at);
            order.insert(pos, {first, first + 1});
            family[a] = first;
            family.push_back(first + 1);
            ++splits;
            changed = true;
            resume = a;
            break;
          }
        }
      }
    }
  }
  return splits;
}

// Sorts the pieces once; then, for up to `rounds` rounds, splits one polygon of every pair no
// test orders by the other's plane (the farther one, P, by Q's plane if it cuts P, else Q by
// P's) and inserts the pieces into the order in its place (depth_sort_insert: only the pairs
// a piece touches are checked). `pieces` ends as the polygons of the returned order. The
// returned work is the first sort's, with the splitting and inserting charged (insert) to
// the GP that checked the split polygon (its pieces' too).
struct SplitSort {
  DepthSortResult sort;  // the last sort's counts and costs (with the pieces inserted into it);
                         // the final order and unresolved pairs
  // Each sort run, in order (one, or one per round when re-sorting): its polygons, its
  // result and the GPs' work (the last's insert holds the splitting and inserting).
  std::vector<std::vector<SortPolygon>> polygons;
  std::vector<DepthSortResult> sorts;
  std::vector<DepthSortWork> work;
  std::uint64_t pairs_rechecked = 0;
  // The work as the GPs run it: each sort after the one before (DepthSortWork::next).
  std::shared_ptr<const DepthSortWork> chained() const {
    std::shared_ptr<DepthSortWork> next;
    for (auto it = work.rbegin(); it != work.rend(); ++it) {
      auto w = std::make_shared<DepthSortWork>(*it);
      w->next = next;
      next = w;
    }
    return next;
  }
};
SplitSort sort_with_splitting(std::vector<PaintPiece>& pieces, int gps, int rounds,
                              VisibleSceneReport& rep, Containment containment, bool factor,
                              bool insert) {
  SplitSort out;
  std::vector<SortPolygon> polys;
  polys.reserve(pieces.size());
  for (const PaintPiece& p : pieces) polys.push_back(sort_polygon(p));
  DepthSortResult r = depth_sort(polys, gps, containment);
  out.polygons.push_back(polys);
  out.sorts.push_back(r);
  out.work.push_back(depth_sort_work(r, polys.size(), gps, factor));
  rep.unresolved_before_split = r.unresolved.size();
  std::vector<int> gp_of = r.checker;  // who splits and inserts a polygon's pieces
  std::vector<char> alive(pieces.size(), 1);
  std::vector<int> order = r.order;
  std::vector<std::pair<int, int>> unresolved = r.unresolved;
  for (int round = 0; round < rounds && !unresolved.empty(); ++round) {
    std::vector<char> cut(pieces.size(), 0);
    std::vector<std::pair<int, int>> carry;
    // Per cut polygon (in the order found), its pieces' indices.
    std::vector<std::pair<int, std::vector<int>>> made;
    for (const auto& [pi, qi] : unresolved) {
      const auto p = static_cast<std::size_t>(pi), q = static_cast<std::size_t>(qi);
      if (!alive[p] || !alive[q]) continue;  // split before: its pieces were checked
      if (cut[p] || cut[q]) continue;        // split this round: its pieces are checked below
      const SortPolygon& sp = polys[p];
      const SortPolygon& sq = polys[q];
      const PlaneEquation plane_q = plane_of(sq.v[0], sq.v[1], sq.v[2]);
      const PlaneEquation plane_p = plane_of(sp.v[0], sp.v[1], sp.v[2]);
      std::vector<PaintPiece> added;
      std::size_t parent = p;
      if (!(plane_q.c == 0 && plane_q.a == 0 && plane_q.b == 0) &&
          split_piece(pieces[p], plane_q, added)) {
        parent = p;
      } else if (split_piece(pieces[q], plane_p, added)) {
        parent = q;
      } else {
        carry.emplace_back(pi, qi);  // neither plane cuts the other polygon
        continue;
      }
      cut[parent] = 1;
      std::vector<int> indices;
      for (PaintPiece& piece : added) {
        indices.push_back(static_cast<int>(pieces.size()));
        polys.push_back(sort_polygon(piece));
        pieces.push_back(std::move(piece));
        alive.push_back(1);
        cut.push_back(0);
        gp_of.push_back(gp_of[parent]);
      }
      if (insert)
        out.work.back().insert[static_cast<std::size_t>(gp_of[parent])] +=
            split_triangle_ops(static_cast<int>(indices.size()));
      made.emplace_back(static_cast<int>(parent), std::move(indices));
    }
    if (made.empty()) break;
    for (const auto& made_by : made) {
      alive[static_cast<std::size_t>(made_by.first)] = 0;
      ++rep.split_triangles;
    }
    if (!insert) {
      // Re-sorting: every polygon left, sorted again from the start (the former behaviour).
      std::vector<PaintPiece> kept;
      for (std::size_t k = 0; k < pieces.size(); ++k)
        if (alive[k]) kept.push_back(std::move(pieces[k]));
      pieces = std::move(kept);
      polys.clear();
      for (const PaintPiece& p : pieces) polys.push_back(sort_polygon(p));
      r = depth_sort(polys, gps, containment);
      out.polygons.push_back(polys);
      out.sorts.push_back(r);
      out.work.push_back(depth_sort_work(r, polys.size(), gps, factor));
      gp_of = r.checker;
      alive.assign(pieces.size(), 1);
      order = r.order;
      unresolved = r.unresolved;
      ++rep.split_rounds;
      continue;
    }
    // The pieces take their polygon's place in the order, then are checked where they stand.
    std::vector<int> inserted;
    for (const auto& [parent, indices] : made) {
      const auto at = std::find(order.begin(), order.end(), parent);
      const auto pos = order.erase(at);
      order.insert(pos, indices.begin(), indices.end());
      inserted.insert(inserted.end(), indices.begin(), indices.end());
    }
    const InsertResult ins = depth_sort_insert(polys, order, inserted, gp_of, gps, containment);
    for (int k = 0; k < gps; ++k)
      out.work.back().insert[static_cast<std::size_t>(k)] += ins.ops[static_cast<std::size_t>(k)];
    out.pairs_rechecked += ins.pairs_checked;
    for (int t = 0; t < kOverlapTests; ++t) {
      r.tests_run[t] += ins.tests_run[t];
      r.decided[t] += ins.decided[t];
    }
    r.reorders += ins.moves;
    unresolved = carry;
    unresolved.insert(unresolved.end(), ins.unresolved.begin(), ins.unresolved.end());
    ++rep.split_rounds;
  }
  if (rep.split_triangles > 0)
    rep.t_junctions = remove_t_junctions(pieces, alive, order, gp_of, out.work.back().insert);
  // The polygons still in the order, renumbered in it.
  std::vector<int> index(pieces.size(), -1);
  std::vector<PaintPiece> kept;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if (!alive[k]) continue;
    index[k] = static_cast<int>(kept.size());
    kept.push_back(std::move(pieces[k]));
  }
  pieces = std::move(kept);
  r.order.clear();
  for (const int k : order) r.order.push_back(index[static_cast<std::size_t>(k)]);
  r.unresolved.clear();
  for (const auto& [p, q] : unresolved) {
    if (alive[static_cast<std::size_t>(p)] && alive[static_cast<std::size_t>(q)])
      r.unresolved.emplace_back(index[static_cast<std::size_t>(p)],
                                index[static_cast<std::size_t>(q)]);
  }
  out.sort = std::move(r);
  return out;
}

// The closed form of every sort `split` ran (whole screen), summed: the rounds' sorts follow
// each other; the last's checks include the pieces inserted.
SortCost split_sort_cost(const MachineConfig& config, const SplitSort& split, bool factor,
                         Containment containment) {
  SortCost c;
  for (std::size_t k = 0; k < split.sorts.size(); ++k) {
    const bool last = k + 1 == split.sorts.size();
    const SortCost e = painter_sort_cost(config, split.polygons[k], false, factor, &split.sorts[k],
                                         containment, last ? &split.work[k].insert : nullptr);
    c.prepare_seconds += e.prepare_seconds;
    c.merge_seconds += e.merge_seconds;
    c.transfer_seconds += e.transfer_seconds;
    c.check_seconds += e.check_seconds;
    c.pairs_checked += e.pairs_checked;
  }
  c.pairs_checked += split.pairs_rechecked;
  return c;
}

// A scene of the pieces in `order` (indices into `pieces`) after the scene triangles in
// `first`, every triangle on its own vertices; with `ids`, each coloured by its source
// triangle's index + 1 as visibility_scene colours them, on a black background.
Scene pieces_scene(const Scene& scene, const std::vector<int>& first,
                   const std::vector<PaintPiece>& pieces, const std::vector<int>& order, bool ids) {
  Scene s = scene;
  s.mesh.vertices.clear();
  s.mesh.triangles.clear();
  auto colour_of = [](int t) {
    const unsigned id = static_cast<unsigned>(t) + 1;
    return glm::vec3((static_cast<float>(id & 0xFF) + 0.5f) / 255.0f,
                     (static_cast<float>((id >> 8) & 0xFF) + 0.5f) / 255.0f,
                     (static_cast<float>((id >> 16) & 0xFF) + 0.5f) / 255.0f);
  };
  auto add = [&](const std::array<Vertex, 3>& v, int source) {
    const auto base = static_cast<unsigned>(s.mesh.vertices.size());
    for (Vertex x : v) {
      if (ids) x.color = colour_of(source);
      s.mesh.vertices.push_back(x);
    }
    s.mesh.triangles.emplace_back(base, base + 1, base + 2);
  };
  for (int t : first) {
    const glm::uvec3& tri = scene.mesh.triangles[static_cast<std::size_t>(t)];
    add({scene.mesh.vertices[tri[0]], scene.mesh.vertices[tri[1]], scene.mesh.vertices[tri[2]]}, t);
  }
  for (int k : order) {
    const PaintPiece& p = pieces[static_cast<std::size_t>(k)];
    add({p.v[0].world, p.v[1].world, p.v[2].world}, p.source);
  }
  if (ids) s.background = glm::vec3(0.0f);
  return s;
}

}  // namespace

PainterTiming painter_against_zbuffer(const MachineConfig& config_in, const Scene& scene,
                                      const Program& zbuffer, const Program& painter,
                                      const PainterOptions& options, bool per_region) {
  MachineConfig config = config_in;
  config.fidelity.pixels = MachineConfig::Fidelity::Pixels::none;
  MachineConfig painter_config = config;
  painter_config.gp.cull_back_faces = options.remove_back_faces ? 1 : 0;
  PainterTiming t;
  t.zbuffer_seconds = project_frame(config, scene, zbuffer).frame_seconds;
  const std::vector<ScreenPolygon> painted = project_scene(painter_config, scene);
  std::vector<PaintPiece> pieces = paint_pieces(scene, painted);
  VisibleSceneReport scratch;
  const SplitSort split =
      sort_with_splitting(pieces, config.gp.count, options.split_rounds, scratch,
                          options.containment, options.overhead_factor, options.insert_pieces);
  SortCost c;
  if (per_region) {
    // Per region bin (a cost only): the drawn pieces sorted per bin, after the rounds' sorts
    // before the last, whole screen, that split them.
    std::vector<SortPolygon> drawn;
    for (const PaintPiece& piece : pieces) drawn.push_back(sort_polygon(piece));
    c = painter_sort_cost(config, drawn, true, options.overhead_factor, nullptr,
                          options.containment);
    for (std::size_t k = 0; k + 1 < split.sorts.size(); ++k)
      c.prepare_seconds +=
          painter_sort_cost(config, split.polygons[k], false, options.overhead_factor,
                            &split.sorts[k], options.containment)
              .seconds();
  } else {
    c = split_sort_cost(config, split, options.overhead_factor, options.containment);
  }
  t.closed_form_sort_seconds = c.seconds();
  std::vector<int> first;
  std::vector<char> placed(scene.mesh.triangles.size(), 0);
  for (const ScreenPolygon& p : painted) placed[static_cast<std::size_t>(p.source)] = 1;
  for (int k = 0; k < static_cast<int>(placed.size()); ++k)
    if (!placed[static_cast<std::size_t>(k)]) first.push_back(k);
  Scene sorted = pieces_scene(scene, first, pieces, split.sort.order, false);
  // Whole screen, the GPs run the sort in the frame (simulated at fidelity.timing=event);
  // per region bin it is a cost only, added to the frame.
  if (!per_region) sorted.depth_sort = split.chained();
  const FrameResult pr = project_frame(painter_config, sorted, painter);
  t.simulated_sort_seconds = simulated_sort_seconds(pr, config.gp.count);
  t.painter_frame_seconds = pr.frame_seconds;
  // The sort not simulated (per region bin, or a level that does not run the GPs' phases):
  // its closed form is added.
  t.sort_seconds = t.simulated_sort_seconds > 0 ? 0 : c.seconds();
  return t;
}
VisibleSceneReport analyse_visible_surfaces(const MachineConfig& config_in, const Scene& scene,
                                            const Program& zbuffer, const Program& painter,
                                            int threads, const PainterOptions& painter_options) {
  if (scene.mesh.triangles.size() > kMaxVisibilityTriangles) {
    throw std::invalid_argument(fmt::format(
        "scene '{}': {} triangles; the visibility runs encode a triangle in 24 bits (at most {})",
        scene.name, scene.mesh.triangles.size(), kMaxVisibilityTriangles));
  }
  // Every algorithm sees every triangle; back-face removal is its own run below.
  MachineConfig config = config_in;
  config.gp.cull_back_faces = 0;
  MachineConfig culling = config_in;
  culling.gp.cull_back_faces = 1;
  const int width = config.screen.width, height = config.screen.height;
  const int rw = config.renderer.region_width, rh = config.renderer.region_height;

  VisibleSceneReport rep;
  rep.scene = scene.name;
  rep.triangles = scene.mesh.triangles.size();
  const std::vector<ScreenPolygon> polygons = project_scene(config, scene);
  rep.polygons = polygons.size();
  const ReferenceImage reference =
      exact_reference(polygons, width, height, config.gp.subpixel_bits, config.gp.depth_bits);

  // Painter's: the GPs' depth sort, then the scene in that order. As the slides run it, back
  // faces are removed first (painter_options.remove_back_faces); the painter's runs then cull
  // them on the GPs as well.
  rep.painter_options = painter_options;
  const MachineConfig& painter_config = painter_options.remove_back_faces ? culling : config;
  const std::vector<ScreenPolygon> front =
      painter_options.remove_back_faces ? project_scene(culling, scene) : polygons;
  const std::vector<ScreenPolygon>& painted = painter_options.remove_back_faces ? front : polygons;
  std::vector<PaintPiece> pieces = paint_pieces(scene, painted);
  SplitSort split = sort_with_splitting(
      pieces, config.gp.count, painter_options.split_rounds, rep, painter_options.containment,
      painter_options.overhead_factor, painter_options.insert_pieces);
  rep.sort = split.sort;
  rep.pairs_rechecked = split.pairs_rechecked;
  rep.pieces = pieces.size();
  I860Params sort_params = i860_params(config);
  if (!painter_options.overhead_factor) sort_params.overhead_factor = 1;
  const I860Model i860(sort_params);
  std::uint64_t sort_total = 0;
  rep.sort_clocks.assign(static_cast<std::size_t>(config.gp.count), GpClocks{});
  for (const DepthSortWork& w : split.work) {
    for (int k = 0; k < config.gp.count; ++k) {
      const auto g = static_cast<std::size_t>(k);
      const std::uint64_t clocks = i860.clocks(w.prepare[g], 0).count +
                                   i860.clocks(w.check[g], 0).count +
                                   i860.clocks(w.insert[g], 0).count;
      rep.sort_clocks[g] = GpClocks(rep.sort_clocks[g].count + clocks);
      sort_total += clocks;
    }
    rep.merge_clocks = GpClocks(rep.merge_clocks.count + i860.clocks(w.merge, 0).count);
    sort_total += i860.clocks(w.merge, 0).count;
  }
  // Every combination of the choices, the one painter's ran with among them.
  {
    std::vector<SortPolygon> fronts, every;
    for (const ScreenPolygon& p :
         painter_options.remove_back_faces ? front : project_scene(culling, scene))
      fronts.push_back({p.v});
    for (const ScreenPolygon& p : polygons) every.push_back({p.v});
    for (const bool removed : {true, false}) {
      for (const bool per_region : {false, true}) {
        for (const bool factor : {false, true}) {
          const bool ran = removed == painter_options.remove_back_faces && !per_region;
          SortCost c = ran ? split_sort_cost(config, split, factor, painter_options.containment)
                           : painter_sort_cost(config, removed ? fronts : every, per_region, factor,
                                               nullptr, painter_options.containment);
          c.back_faces_removed = removed;
          c.label = fmt::format("{}, {}, {}", removed ? "back faces removed" : "every face",
                                per_region ? "per region bin" : "whole screen",
                                factor ? "x gp.overhead_factor" : "own counts");
          if (ran) {
            c.polygons = pieces.size();
            if (rep.split_rounds > 0)
              c.label +=
                  fmt::format(", with {} rounds of splitting ({})", rep.split_rounds,
                              painter_options.insert_pieces ? "pieces inserted" : "each re-sorted");
          }
          if (ran && factor == painter_options.overhead_factor) rep.sort_seconds = c.seconds();
          rep.sort_costs.push_back(std::move(c));
        }
      }
    }
  }
  // Triangles the transform (or back-face removal) dropped make no pixels: they go first, in
  // scene order; then the pieces, back to front.
  std::vector<int> first;
  std::vector<char> placed(scene.mesh.triangles.size(), 0);
  for (const ScreenPolygon& p : painted) placed[static_cast<std::size_t>(p.source)] = 1;
  for (int t = 0; t < static_cast<int>(placed.size()); ++t)
    if (!placed[static_cast<std::size_t>(t)]) first.push_back(t);
  Scene sorted = pieces_scene(scene, first, pieces, rep.sort.order, false);
  // The GPs run the sort in the painter's frame, before their geometry (whole screen).
  sorted.depth_sort = split.chained();

  // The shaded runs: cycles, bits, frame time, and the frames.
  const FrameResult zr = simulate_frame(config, scene, zbuffer, threads);
  const FrameResult pr = simulate_frame(painter_config, sorted, painter, threads);
  const FrameResult cr = simulate_frame(culling, scene, zbuffer, threads);
  rep.sort_simulated_seconds = simulated_sort_seconds(pr, config.gp.count);
  for (const FrameResult* f : {&zr, &pr}) {
    (f == &zr ? rep.zbuffer_ring_words : rep.painter_ring_words) =
        static_cast<std::uint64_t>(f->stats.integer("ring.words"));
  }
  rep.zbuffer_frame = zr.image.flat();
  rep.painter_frame = pr.image.flat();

  // The visibility runs.
  const AssemblerOptions options = assembler_options(config);
  // z as wide as the depth expressions (gp.depth_bits), cleared to the far end.
  const int bits = config.gp.depth_bits;
  const Program vz = assemble(
      zbuffer_colour_firmware(
          "Visibility, z-buffered on screen depth: each pixel keeps the nearest triangle's index.",
          bits, "depth", "base"),
      "visibility-zbuffer", options);
  const Program ve = assemble(zbuffer_colour_firmware("Visibility, z-buffered on eye depth "
                                                      "interpolated linearly in screen space "
                                                      "(the bad one).",
                                                      bits, "eye_depth", "base"),
                              "visibility-eye-depth", options);
  const Program vp = assemble(kVisibilityPainterFirmware, "visibility-painter", options);
  const Scene ids = visibility_scene(scene, {});
  const IdImage zid = decode_visibility(simulate_frame(config, ids, vz, threads).image.flat());
  const IdImage eid = decode_visibility(simulate_frame(config, ids, ve, threads).image.flat());
  const IdImage pid = decode_visibility(
      simulate_frame(painter_config, pieces_scene(scene, first, pieces, rep.sort.order, true), vp,
                     threads)
          .image.flat());
  const IdImage cid = decode_visibility(simulate_frame(culling, ids, vz, threads).image.flat());

  const double triangles = static_cast<double>(rep.triangles);
  AlgorithmRow z;
  z.name = "z-buffer";
  z.difference = compare_visibility(zid, reference, rw, rh);
  z.bits = std::to_string(zr.stats.integer("pixel_memory.used"));
  z.gp_clocks_per_primitive = zr.stats.real("frame.gp_clocks_per_triangle");
  z.renderer_cycles = busy_cycles(zr);
  z.primitives_per_second = zr.triangles_per_second;
  z.work = "a depth compare per pixel per triangle";
  z.image = difference_image(zid, reference);

  AlgorithmRow p;
  p.name = "painter's";
  p.difference = compare_visibility(pid, reference, rw, rh);
  p.bits = std::to_string(pr.stats.integer("pixel_memory.used"));
  p.gp_clocks_per_primitive = pr.stats.real("frame.gp_clocks_per_triangle") +
                              (triangles > 0 ? static_cast<double>(sort_total) / triangles : 0);
  p.renderer_cycles = busy_cycles(pr);
  // The frame includes the sort, which the GPs ran in it (rep.sort_simulated_seconds); a
  // level that does not run it (fidelity.timing=analytic) gets the closed form added.
  const double painter_seconds =
      pr.frame_seconds + (rep.sort_simulated_seconds > 0 ? 0.0 : rep.sort_seconds);
  rep.painter_frame_seconds = pr.frame_seconds;
  p.primitives_per_second = painter_seconds > 0 ? triangles / painter_seconds : 0;
  p.work = fmt::format("{} pair checks, {} reorders, {} unresolved", rep.sort.pairs_checked,
                       rep.sort.reorders, rep.sort.unresolved.size());
  p.image = difference_image(pid, reference);

  ScanlineWork sw;
  const IdImage sid = scanline_visible(polygons, width, height, sw);
  AlgorithmRow s;
  s.name = "scan-line (CPU)";
  s.difference = compare_visibility(sid, reference, rw, rh);
  s.bits = "-";
  s.work = fmt::format("{} edges, {} spans, {} depth compares, {} span splits", sw.edges, sw.spans,
                       sw.depth_comparisons, sw.splits);
  s.image = difference_image(sid, reference);

  WarnockWork ww;
  const IdImage wid = warnock_visible(polygons, width, height, ww);
  AlgorithmRow w;
  w.name = "Warnock (CPU)";
  w.difference = compare_visibility(wid, reference, rw, rh);
  w.bits = "-";
  w.work = fmt::format(
      "{} areas (empty {}, one polygon {}, surrounding {}, surrounding in front {}, pixel {}), "
      "{} levels",
      ww.areas, ww.empty, ww.single, ww.surrounding, ww.front_surrounding, ww.pixels, ww.max_level);
  w.image = difference_image(wid, reference);
  rep.rows = {z, p, s, w};

  rep.bad_depth = compare_visibility(eid, reference, rw, rh);
  ReferenceImage correct = reference;
  correct.id = zid.id;
  for (std::size_t k = 0; k < correct.id.size(); ++k) {
    if (eid.id[k] != zid.id[k] && !reference.uncertain[k]) ++rep.flips;
  }
  rep.flip_image = difference_image(eid, correct);

  rep.culled = static_cast<std::uint64_t>(cr.stats.integer("setup.culled"));
  rep.renderer_cycles_culled = busy_cycles(cr);
  rep.culled_difference = compare_visibility(cid, reference, rw, rh);
  return rep;
}

Statistics visible_statistics(const std::vector<VisibleSceneReport>& reports) {
  namespace u = stat_unit;
  Statistics stats;
  auto count = [](std::uint64_t v) { return [v] { return static_cast<std::int64_t>(v); }; };
  const char* const keys[] = {"zbuffer", "painter", "scanline", "warnock"};
  for (std::size_t k = 0; k < reports.size(); ++k) {
    const VisibleSceneReport& r = reports[k];
    const std::string p = fmt::format("scene.{}.", k);
    const std::string name = r.scene;
    stats.add_text(p + "name", u::name, "The scene", [name] { return name; });
    stats.add_integer(p + "triangles", u::count, "Triangles in the scene", count(r.triangles));
    register_depth_sort_statistics(stats, p + "depth_sort", r.sort, r.sort_clocks, r.merge_clocks,
                                   r.sort_seconds);
    for (std::size_t a = 0; a < r.rows.size() && a < 4; ++a) {
      const AlgorithmRow& row = r.rows[a];
      const std::string q = p + "algorithm." + keys[a] + ".";
      stats.add_integer(q + "differing_pixels", u::count,
                        "Certain pixels whose visible triangle differs from the reference",
                        count(row.difference.differing));
      stats.add_integer(q + "uncertain_pixels", u::count,
                        "Uncertain pixels that differ (not counted as differing)",
                        count(row.difference.uncertain));
      stats.add_integer(q + "regions", u::count, "Regions with a differing pixel",
                        count(row.difference.regions));
      stats.add_integer(q + "renderer_cycles", u::array_cycles,
                        "Renderer busy cycles of the shaded run (0: a CPU reference)",
                        count(row.renderer_cycles));
      const double clocks = row.gp_clocks_per_primitive, rate = row.primitives_per_second;
      stats.add_real(q + "gp_clocks_per_primitive", u::gp_clocks,
                     "GP clocks per triangle, depth sort included (0: a CPU reference)",
                     [clocks] { return clocks; });
      stats.add_real(q + "primitives_per_second", u::per_second,
                     "Projected triangles per second (0: a CPU reference)",
                     [rate] { return rate; });
    }
    stats.add_integer(p + "painter.unresolved_before_split", u::count,
                      "Pairs the first depth sort could not order",
                      count(r.unresolved_before_split));
    stats.add_integer(p + "painter.split_triangles", u::count,
                      "Triangles (or pieces) split by another polygon's plane",
                      count(r.split_triangles));
    stats.add_integer(p + "painter.polygons", u::count,
                      "Polygons the last sort ordered and painter's drew", count(r.pieces));
    stats.add_integer(p + "perspective.flips", u::count,
                      "Certain pixels whose visible triangle differs between eye depth "
                      "interpolated in screen space and screen depth",
                      count(r.flips));
    stats.add_integer(p + "perspective.bad_differing_pixels", u::count,
                      "Certain pixels where the eye-depth z-buffer differs from the reference",
                      count(r.bad_depth.differing));
    stats.add_integer(p + "back_faces.culled", u::count, "Back-facing triangles culled",
                      count(r.culled));
    stats.add_integer(p + "back_faces.renderer_cycles", u::array_cycles,
                      "Renderer busy cycles of the z-buffer with back faces culled",
                      count(r.renderer_cycles_culled));
    stats.add_integer(p + "back_faces.differing_pixels", u::count,
                      "Certain pixels where the culled z-buffer differs from the reference",
                      count(r.culled_difference.differing));
  }
  stats.freeze();
  return stats;
}

report::Table visible_table(const std::vector<VisibleSceneReport>& reports,
                            const MachineConfig& config) {
  using namespace report;
  Table t;
  t.id = "visible";
  t.columns = {
      text_column("scene"),
      text_column("algorithm"),
      left_aligned(integer_column("pixels differing", "pixels",
                                  "Certain pixels that differ from the reference (in brackets: "
                                  "uncertain pixels that differ, not counted)"),
                   "pixels differing (uncertain)"),
      text_column("regions with differences",
                  "Regions with a differing pixel, and how they cluster"),
      left_aligned(integer_column("bits", "bits", "Pixel-memory bits the program uses"), "bits"),
      left_aligned(
          real_column("GP clocks / primitive", "i860 clocks", 0,
                      "GP clocks per triangle, depth sort included ('-': a CPU reference)"),
          "GP clocks / primitive"),
      left_aligned(integer_column("Renderer cycles", "array cycles",
                                  "Renderer busy cycles of the shaded run ('-': a CPU reference)"),
                   "Renderer cycles"),
      left_aligned(real_column("primitives / s", "triangles/s", -1,
                               "Projected triangles per second ('-': a CPU reference)"),
                   "primitives / s"),
  };
  for (const VisibleSceneReport& r : reports) {
    for (const AlgorithmRow& a : r.rows) {
      const bool machine = a.renderer_cycles > 0;
      t.add_row(
          {r.scene, a.name,
           Cell::shown_as(static_cast<std::int64_t>(a.difference.differing),
                          fmt::format("{} ({})", a.difference.differing, a.difference.uncertain)),
           region_text(a.difference, config), a.bits,
           machine ? Cell(a.gp_clocks_per_primitive) : Cell::missing(),
           machine ? Cell(static_cast<std::int64_t>(a.renderer_cycles)) : Cell::missing(),
           machine ? Cell::shown_as(a.primitives_per_second,
                                    fmt::format("{:.3g}", a.primitives_per_second))
                   : Cell::missing()});
    }
  }
  return t;
}

std::string format_visible_report(const std::vector<VisibleSceneReport>& reports,
                                  const MachineConfig& config) {
  return report::markdown(visible_table(reports, config)) + "\n" + visible_notes(reports);
}

std::string visible_notes(const std::vector<VisibleSceneReport>& reports) {
  std::string out;
  for (const VisibleSceneReport& r : reports) {
    const DepthSortResult& s = r.sort;
    out += fmt::format("- {}: {} triangles, {} after the transform.\n", r.scene, r.triangles,
                       r.polygons);
    std::string tests;
    for (int t = 0; t < kOverlapTests; ++t) {
      tests +=
          fmt::format("{}{} {}/{}", t ? ", " : "", overlap_test_name(static_cast<OverlapTest>(t)),
                      s.decided[t], s.tests_run[t]);
    }
    out += fmt::format(
        "  - depth sort ({}, {}): {} key comparisons, {} pairs checked; tests (settled/run): {}; "
        "{} moved ahead; {:.3f} ms on the GPs, ring transfers included.\n",
        r.painter_options.remove_back_faces ? "back faces removed first, as the slides do"
                                            : "every face sorted",
        r.painter_options.overhead_factor ? "clocks x gp.overhead_factor"
                                          : "clocks from its own counts",
        s.key_comparisons, s.pairs_checked, tests, s.reorders, 1e3 * r.sort_seconds);
    if (!r.sort_costs.empty()) {
      double lo = r.sort_costs[0].seconds(), hi = lo;
      std::string each;
      for (const SortCost& c : r.sort_costs) {
        lo = std::min(lo, c.seconds());
        hi = std::max(hi, c.seconds());
        each += fmt::format("{}{}: {:.2f}", each.empty() ? "" : "; ", c.label, 1e3 * c.seconds());
      }
      out += fmt::format(
          "  - depth sort's cost over the choices: {:.2f} .. {:.2f} ms against a z-buffer frame "
          "of {:.2f} ms ({}; ms).\n",
          1e3 * lo, 1e3 * hi,
          r.rows[0].primitives_per_second > 0
              ? 1e3 * static_cast<double>(r.triangles) / r.rows[0].primitives_per_second
              : 0.0,
          each);
    }
    if (r.sort_simulated_seconds > 0) {
      out += fmt::format(
          "  - depth sort simulated on the GPs (phases spent and messages sent in the painter's "
          "frame, before the geometry): the last GP's sort ends at {:.3f} ms against {:.3f} ms "
          "in closed form; the frame takes {:.3f} ms, sort included; its ring carries {} words "
          "against {} in the z-buffer frame.\n",
          1e3 * r.sort_simulated_seconds, 1e3 * r.sort_seconds, 1e3 * r.painter_frame_seconds,
          r.painter_ring_words, r.zbuffer_ring_words);
    }
    const Difference& painter = r.rows[1].difference;
    if (r.split_triangles > 0 && r.painter_options.insert_pieces) {
      out += fmt::format(
          "  - splitting by insertion: the pieces took their polygon's place and {} pairs they "
          "touch were checked again (no re-sort).\n",
          r.pairs_rechecked);
    }
    if (r.split_triangles > 0) {
      out += fmt::format(
          "  - painter's splits: {} pairs no test ordered (the failure cases of Newell, Newell "
          "and Sancha's depth sort, which splits there; the slides do not discuss them); {} "
          "triangles split by the other polygon's plane in {} rounds, {} polygons sorted and "
          "drawn, {} pairs still unordered.\n",
          r.unresolved_before_split, r.split_triangles, r.split_rounds, r.pieces,
          s.unresolved.size());
    }
    if (s.unresolved.empty()) {
      out += fmt::format(
          "  - painter's: every overlapping pair ordered; {} pixels differ from the reference.\n",
          painter.differing);
    } else if (painter.differing > 0) {
      out += fmt::format(
          "  - painter's: {} pairs the tests cannot order ({} closing a cycle, {} that no test "
          "orders either way: interpenetration, or a cyclic overlap whose planes cut each "
          "other), not split; these are the failure cases of Newell, Newell and Sancha's depth "
          "sort (1972), which splits such polygons, not cases the slides discuss; {} pixels "
          "differ from the reference.\n",
          s.unresolved.size(), s.cycles, s.unorderable, painter.differing);
    } else {
      out += fmt::format(
          "  - painter's: {} pairs the tests cannot order ({} closing a cycle, {} no test orders), "
          "left in far-depth order, and no pixel shows it: 0 differ from the reference.\n",
          s.unresolved.size(), s.cycles, s.unorderable);
    }
    out += fmt::format(
        "  - perspective depth: eye depth interpolated linearly in screen space (bad) against "
        "screen depth (correct): {} pixels flip; bad against the reference: {} differ.\n",
        r.flips, r.bad_depth.differing);
    const std::uint64_t full = r.rows[0].renderer_cycles;
    out += fmt::format(
        "  - back faces: {} of {} culled ({:.1f}%); Renderer cycles {} -> {} ({:.1f}% saved); {} "
        "pixels differ from the reference with culling.\n",
        r.culled, r.triangles, r.triangles ? 100.0 * r.culled / r.triangles : 0.0, full,
        r.renderer_cycles_culled,
        full ? 100.0 * (static_cast<double>(full) - static_cast<double>(r.renderer_cycles_culled)) /
                   static_cast<double>(full)
             : 0.0,
        r.culled_difference.differing);
  }
  return out;
}

}  // namespace pp5
