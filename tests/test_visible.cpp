// Visible-surface algorithms: the depth sort's overlap tests against the slides' worked
// examples, and every algorithm against the exact reference (models/gp/depth_sort.hpp,
// sim/analysis/visible_surface.hpp).
#include <algorithm>
#include <catch2/catch.hpp>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/depth_sort.hpp"
#include "models/machine.hpp"
#include "sim/analysis/visible_surface.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

using namespace pp5;

TEST_CASE("depth sort: the slides' plane-side examples", "[visible]") {
  // Example 1: (A, B, C) = (5, -3, 1) through (0, 2, 4): D = -2, so 5x - 3y + z + 2 = 0.
  const PlaneEquation e = plane_through({5, -3, 1}, {0, 2, 4});
  CHECK(e.d == -2);
  CHECK(e.at({3, 5, -6}) == -4);  // not on the positive side
  // Example 2: the origin is on the positive side.
  CHECK(e.at({0, 0, 0}) == 2);
  // Example 3: (A, B, C) + (a, b, c) = (5, -1, 4) is on the positive side.
  CHECK(e.at({5, -1, 4}) == 34);
}

TEST_CASE("depth sort: the plane through three points by the slides' determinants", "[visible]") {
  const glm::dvec3 p1(1, 0, 2), p2(0, 3, 1), p3(-2, 1, 5);
  const PlaneEquation e = plane_of(p1, p2, p3);
  CHECK(e.at(p1) == Approx(0).margin(1e-12));
  CHECK(e.at(p2) == Approx(0).margin(1e-12));
  CHECK(e.at(p3) == Approx(0).margin(1e-12));
  // The same cyclic order gives the same plane; the reverse order flips its side.
  const PlaneEquation f = plane_of(p2, p3, p1);
  CHECK(f.a == Approx(e.a));
  CHECK(f.d == Approx(e.d));
  CHECK(plane_of(p1, p3, p2).a == Approx(-e.a));
  // Counter-clockwise in the xy-plane seen from +z: the normal points to +z.
  const PlaneEquation g = plane_of({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  CHECK(g.c > 0);
  CHECK(g.at({0.2, 0.2, 1}) > 0);
}

TEST_CASE("depth sort: the slides' inside and line tests", "[visible]") {
  const glm::dvec2 a(0, 0), b(4, 0), c(0, 4);
  CHECK(inside_triangle({1, 1}, a, b, c));
  CHECK_FALSE(inside_triangle({3, 3}, a, b, c));
  CHECK(same_side({1, 1}, {0.5, 0.1}, b, c));
  CHECK(line_side({2, 2}, b, c) == 0);  // on the line
  // Minimax line test: far apart.
  CHECK(segments_cross({0, 0}, {1, 1}, {3, 0}, {4, 1}) == SegmentResult::disjoint_extents);
  // Parallel slopes, overlapping extents.
  CHECK(segments_cross({0, 0}, {2, 2}, {1, 0}, {3, 2}) == SegmentResult::parallel);
  // The diagonals of a square cross at s = t = 1/2.
  CHECK(segments_cross({0, 0}, {2, 2}, {0, 2}, {2, 0}) == SegmentResult::crossing);
  // Touching at an end is not crossing.
  CHECK(segments_cross({0, 0}, {2, 2}, {2, 2}, {3, 0}) == SegmentResult::not_crossing);
}

TEST_CASE("depth sort: each overlap test decides the case it is for", "[visible]") {
  std::array<std::uint64_t, kOverlapTests> runs{};
  OpCounts ops;
  auto tri = [](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return SortPolygon{{a, b, c}}; };
  // Depth extents apart.
  const SortPolygon far = tri({0, 0, 0.9}, {10, 0, 0.9}, {0, 10, 0.8});
  CHECK(check_pair(far, tri({0, 0, 0.2}, {10, 0, 0.2}, {0, 10, 0.1}), runs, ops).decided_by ==
        OverlapTest::z_extent);
  // Depths overlap, x extents apart; then y extents apart.
  const SortPolygon p = tri({0, 0, 0.9}, {10, 0, 0.5}, {0, 10, 0.7});
  CHECK(check_pair(p, tri({20, 0, 0.8}, {30, 0, 0.6}, {20, 10, 0.6}), runs, ops).decided_by ==
        OverlapTest::x_extent);
  CHECK(check_pair(p, tri({0, 20, 0.8}, {10, 20, 0.6}, {0, 30, 0.6}), runs, ops).decided_by ==
        OverlapTest::y_extent);
  // Overlapping in x, y and z, P wholly behind Q's plane (Q is the plane z = 0.6 + 0.01 x).
  const SortPolygon back = tri({0, 0, 0.9}, {10, 0, 0.75}, {0, 10, 0.9});
  const SortPolygon front = tri({-5, -5, 0.55}, {20, -5, 0.8}, {-5, 20, 0.55});
  CHECK(check_pair(back, front, runs, ops).decided_by == OverlapTest::p_behind_q);
  // Projections that overlap only in their rectangles: the edge and containment tests.
  const SortPolygon left = tri({0, 0, 0.9}, {10, 0, 0.5}, {0, 10, 0.5});
  const SortPolygon right = tri({10, 10, 0.5}, {10, 4, 0.9}, {4, 10, 0.9});
  const PairVerdict v = check_pair(left, right, runs, ops);
  CHECK((v.decided_by == OverlapTest::projection || v.decided_by == OverlapTest::p_behind_q ||
         v.decided_by == OverlapTest::q_in_front_of_p));
  // Q behind P's plane while P is farther by its far end: Q must go first.
  const SortPolygon steep = tri({0, 0, 0.95}, {10, 0, 0.3}, {0, 10, 0.3});
  const SortPolygon flat_behind = tri({2, 2, 0.9}, {3, 2, 0.9}, {2, 3, 0.9});
  CHECK(check_pair(steep, flat_behind, runs, ops).q_first);
  // Two triangles that pierce each other: no test orders them either way.
  const SortPolygon a = tri({0, 0, 0.2}, {10, 0, 0.8}, {5, 10, 0.5});
  const SortPolygon b = tri({0, 5, 0.8}, {10, 5, 0.2}, {5, -5, 0.5});
  CHECK(check_pair(a, b, runs, ops).decided_by == OverlapTest::count);
  CHECK(runs[static_cast<int>(OverlapTest::projection)] > 0);
  CHECK(ops.fadd > 0);
}

// The slides' containment ("minimax test with center of one triangle and containing rectangle
// of the other") against the centroid-in-every-edge test: Q's centre lies in P's rectangle
// but outside P, no edges cross, and the planes cut each other. The edge test finds the
// projections apart; the slides' rectangle says they overlap, and then no test orders them.
TEST_CASE("depth sort: the slides' containment test says overlap where the edges do not",
          "[visible]") {
  auto tri = [](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return SortPolygon{{a, b, c}}; };
  const SortPolygon p = tri({0, 0, 0.4}, {10, 0, 0.8}, {0, 10, 0.4});  // z = 0.4 + 0.04 x
  const SortPolygon q = tri({8, 8, 0.5}, {9, 8, 0.5}, {8, 9, 0.75});   // z = 0.5 + 0.25 (y - 8)
  std::array<std::uint64_t, kOverlapTests> runs{};
  OpCounts ops;
  const PairVerdict edges = check_pair(p, q, runs, ops, Containment::edges);
  const PairVerdict rectangle = check_pair(p, q, runs, ops, Containment::rectangle);
  CHECK(edges.decided_by == OverlapTest::projection);
  CHECK(rectangle.decided_by == OverlapTest::count);
}

namespace {

// 256 x 256 (four regions), 4 GPs, 2 Renderers: the goldens' small machine.
MachineConfig small_machine() {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=4", "renderer.count=2"});
  return config;
}

VisibleSceneReport analyse(const std::string& name) {
  const MachineConfig config = small_machine();
  const Program gouraud = test::load_program("gouraud", config);
  const Program painter = test::load_program("painter", config);
  return analyse_visible_surfaces(config, make_builtin_scene(name), gouraud, painter, 2);
}

}  // namespace

TEST_CASE("visible surfaces: every algorithm agrees with the reference without hard cases",
          "[visible]") {
  for (const char* name : {"sphere", "long-thin"}) {
    SECTION(name) {
      const VisibleSceneReport r = analyse(name);
      REQUIRE(r.rows.size() == 4);
      INFO(format_visible_report({r}, small_machine()));
      for (const AlgorithmRow& a : r.rows) {
        INFO(a.name);
        CHECK(a.difference.differing == 0);
      }
    }
  }
}

// Cyclic overlap and interpenetration are the failure cases of Newell, Newell and Sancha's
// depth sort, which splits a polygon by the other's plane there; the slides do not discuss
// them. Without splitting (split_rounds 0) painter's fails on them; with it (the default)
// it draws them with no differing certain pixel.
TEST_CASE("visible surfaces: painter's splits the pairs its tests cannot order", "[visible]") {
  const MachineConfig config = small_machine();
  const Program gouraud = test::load_program("gouraud", config);
  const Program painter = test::load_program("painter", config);
  PainterOptions unsplit;
  unsplit.split_rounds = 0;
  for (const char* name : {"cyclic-overlap", "pierced-quad", "two-triangles", "receding-pairs"}) {
    SECTION(name) {
      const Scene scene = make_builtin_scene(name);
      const VisibleSceneReport r =
          analyse_visible_surfaces(config, scene, gouraud, painter, 2, unsplit);
      const std::string text = format_visible_report({r}, config);
      INFO(text);
      CHECK_FALSE(r.sort.unresolved.empty());
      CHECK(r.rows[1].difference.differing > 0);
      CHECK(r.split_triangles == 0);
      CHECK(text.find("failure cases of Newell, Newell and Sancha's depth sort") !=
            std::string::npos);
      CHECK(text.find("as the slides say") == std::string::npos);
      // The z-buffer, scan-line and Warnock resolve interpenetration and cycles per pixel.
      CHECK(r.rows[0].difference.differing == 0);
      CHECK(r.rows[2].difference.differing == 0);
      CHECK(r.rows[3].difference.differing == 0);
      // Split, painter's draws them too.
      const VisibleSceneReport split = analyse_visible_surfaces(config, scene, gouraud, painter, 2);
      INFO(format_visible_report({split}, config));
      CHECK(split.unresolved_before_split == r.sort.unresolved.size());
      CHECK(split.split_triangles > 0);
      CHECK(split.pieces > split.polygons - split.culled);
      CHECK(split.sort.unresolved.empty());
      CHECK(split.rows[1].difference.differing == 0);
    }
  }
  SECTION("the torus's self-intersections") {
    // On the default machine (1280 x 1024, 32 GPs), as `pp5sim visible` reports it: 296 pairs
    // no test orders, and no certain pixel differs once they are split, whether the pieces
    // are inserted into the order (the default) or every polygon is sorted again each round;
    // inserting costs less. At 256 x 256 on 4 GPs splitting leaves T-junctions between pieces
    // of one triangle (pixel (181, 153) showed the background through one); the siblings are
    // halved at the new vertices, and no certain pixel differs there either.
    const MachineConfig full = MachineConfig::defaults();
    const Program gouraud_full = test::load_program("gouraud", full);
    const Program painter_full = test::load_program("painter", full);
    const Scene torus = make_builtin_scene("torus");
    const VisibleSceneReport r =
        analyse_visible_surfaces(full, torus, gouraud_full, painter_full, 2);
    CHECK(r.unresolved_before_split > 0);
    CHECK(r.split_triangles > 0);
    CHECK(r.sort.unresolved.empty());
    CHECK(r.rows[1].difference.differing == 0);
    CHECK(r.pairs_rechecked > 0);
    PainterOptions resort;
    resort.insert_pieces = false;
    const VisibleSceneReport o =
        analyse_visible_surfaces(full, torus, gouraud_full, painter_full, 2, resort);
    CHECK(o.sort.unresolved.empty());
    CHECK(o.rows[1].difference.differing == 0);
    CHECK(o.pairs_rechecked == 0);
    CHECK(r.sort_seconds < 0.6 * o.sort_seconds);
    // The simulated sort follows the closed form within the messages' latencies.
    CHECK(r.sort_simulated_seconds == Approx(r.sort_seconds).epsilon(0.02));
    CHECK(o.sort_simulated_seconds == Approx(o.sort_seconds).epsilon(0.02));
    const VisibleSceneReport s = analyse_visible_surfaces(config, torus, gouraud, painter, 2);
    CHECK(s.t_junctions > 0);
    CHECK(s.rows[1].difference.differing == 0);
  }
  SECTION("the registered statistics say so too") {
    const Statistics stats = visible_statistics({analyse_visible_surfaces(
        config, make_builtin_scene("pierced-quad"), gouraud, painter, 2, unsplit)});
    CHECK(stats.text("scene.0.name") == "pierced-quad");
    CHECK(stats.integer("scene.0.depth_sort.unorderable") > 0);
    CHECK(stats.integer("scene.0.depth_sort.tests_run.projection") > 0);
    CHECK(stats.integer("scene.0.algorithm.painter.differing_pixels") > 0);
    CHECK(stats.integer("scene.0.algorithm.zbuffer.differing_pixels") == 0);
    CHECK(stats.elements("scene.0.depth_sort.gp") == 4);
  }
  SECTION("the sticks' and the sliver's planes cut the others: no test orders them") {
    CHECK(analyse("cyclic-overlap").unresolved_before_split > 0);
    CHECK(analyse("pierced-quad").unresolved_before_split > 0);
  }
}

TEST_CASE("visible surfaces: long thin slivers need the plane tests", "[visible]") {
  const VisibleSceneReport r = analyse("long-thin");
  // Sorting by far depth alone leaves pairs the minimax tests cannot settle ...
  const int plane_tests[] = {
      static_cast<int>(OverlapTest::p_behind_q), static_cast<int>(OverlapTest::q_in_front_of_p),
      static_cast<int>(OverlapTest::q_behind_p), static_cast<int>(OverlapTest::p_in_front_of_q)};
  std::uint64_t by_planes = 0;
  for (int t : plane_tests) by_planes += r.sort.decided[t];
  CHECK(by_planes > 0);
  CHECK(r.sort.unresolved.empty());
  CHECK(r.sort.reorders > 0);
  // ... and with them painter's is right (checked above), at 24 bits where the z-buffer
  // needs 48.
  CHECK(r.rows[1].bits == "24");
  CHECK(r.rows[0].bits == "48");
}

TEST_CASE("visible surfaces: perspective depth and back faces", "[visible]") {
  // Eye depth interpolated linearly across large triangles that pierce each other at an
  // angle picks the wrong one near the crossing line; screen depth does not.
  const VisibleSceneReport pairs = analyse("two-triangles");
  CHECK(pairs.rows[0].difference.differing == 0);
  CHECK(pairs.flips > 0);
  CHECK(pairs.bad_depth.differing > 0);
  // The sphere is closed: culling its back faces changes no pixel and saves Renderer cycles.
  const VisibleSceneReport sphere = analyse("sphere");
  CHECK(sphere.culled > 0);
  CHECK(sphere.culled_difference.differing == 0);
  CHECK(sphere.renderer_cycles_culled < sphere.rows[0].renderer_cycles);
}

TEST_CASE(
    "depth sort: the order does not depend on the host's threads, and the GP split "
    "only moves costs",
    "[visible]") {
  const MachineConfig config = small_machine();
  const auto polygons = project_scene(config, make_builtin_scene("long-thin"));
  std::vector<SortPolygon> s;
  for (const auto& p : polygons) s.push_back({p.v});
  const DepthSortResult one = depth_sort(s, 1);
  const DepthSortResult four = depth_sort(s, 4);
  CHECK(one.costs.prepare.size() == 1);
  CHECK(four.costs.prepare.size() == 4);
  CHECK(one.order.size() == s.size());
  std::vector<int> sorted = one.order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 0; k < sorted.size(); ++k) CHECK(sorted[k] == static_cast<int>(k));
  CHECK(four.unresolved.empty());
}

TEST_CASE("visible surfaces: scan-line and Warnock resolve the torus's self-intersections",
          "[visible]") {
  const MachineConfig config = small_machine();
  const auto polygons = project_scene(config, make_builtin_scene("torus"));
  const ReferenceImage reference =
      exact_reference(polygons, 256, 256, config.gp.subpixel_bits, config.gp.depth_bits);
  ScanlineWork sw;
  WarnockWork ww;
  const Difference s =
      compare_visibility(scanline_visible(polygons, 256, 256, sw), reference, 128, 128);
  const Difference w =
      compare_visibility(warnock_visible(polygons, 256, 256, ww), reference, 128, 128);
  INFO("spans " << sw.spans << " splits " << sw.splits << " areas " << ww.areas << " single "
                << ww.single << " pixels " << ww.pixels << " levels " << ww.max_level);
  const auto covered =
      std::count_if(reference.id.begin(), reference.id.end(), [](int id) { return id >= 0; });
  CHECK(covered > 256 * 256 / 4);
  CHECK(s.differing == 0);
  CHECK(w.differing == 0);
  // Both did the work their method implies: many spans, each resolved by depth compares;
  // areas subdivided to at most log2(256) = 8 levels, where a pixel-sized area holds only
  // surrounding polygons, settled by the surrounding cases.
  CHECK(sw.spans > 256);
  CHECK(sw.depth_comparisons > sw.spans);
  CHECK(ww.empty > 0);
  CHECK(ww.front_surrounding > 0);
  CHECK(ww.max_level <= 8);
}

// The sort's cost under each choice: back faces removed first (the slides' order, the default)
// or every face; the whole screen or each region's bin; its own operation counts or
// multiplied by gp.overhead_factor. The run's own sort is one of the eight, and the choices
// move the cost the way their work says.
TEST_CASE("visible surfaces: the depth sort's cost over the painter's choices", "[visible]") {
  const MachineConfig config = small_machine();
  const Program gouraud = test::load_program("gouraud", config);
  const Program painter = test::load_program("painter", config);
  const Scene sphere = make_builtin_scene("sphere");
  const VisibleSceneReport r = analyse_visible_surfaces(config, sphere, gouraud, painter, 2);
  REQUIRE(r.sort_costs.size() == 8);
  CHECK(r.painter_options.remove_back_faces);
  // The run's sort: back faces removed, whole screen, own counts.
  CHECK(r.sort_costs[0].back_faces_removed);
  CHECK_FALSE(r.sort_costs[0].per_region);
  CHECK_FALSE(r.sort_costs[0].overhead_factor);
  CHECK(r.sort_seconds == r.sort_costs[0].seconds());
  CHECK(r.sort_costs[0].polygons == r.polygons - r.culled);
  CHECK(r.sort_costs[4].polygons == r.polygons);
  for (std::size_t k = 0; k < 8; k += 2) {
    const SortCost& own = r.sort_costs[k];
    const SortCost& fitted = r.sort_costs[k + 1];
    INFO(own.label);
    // The factor multiplies the GP's clocks, not the ring's transfers.
    CHECK(fitted.check_seconds ==
          Approx(own.check_seconds * config.gp.overhead_factor).epsilon(0.01));
    CHECK(fitted.transfer_seconds == own.transfer_seconds);
    CHECK(own.transfer_seconds > 0);
  }
  // Whole screen: a merge on GP 0; per region bin: none.
  CHECK(r.sort_costs[0].merge_seconds > 0);
  CHECK(r.sort_costs[2].merge_seconds == 0);
  // Half the sphere's faces sort in less time than all of them.
  CHECK(r.sort_costs[0].seconds() < r.sort_costs[4].seconds());
  // The present behaviour stays a choice: every face sorted and drawn, the factor applied.
  PainterOptions old;
  old.remove_back_faces = false;
  old.overhead_factor = true;
  const VisibleSceneReport o = analyse_visible_surfaces(config, sphere, gouraud, painter, 2, old);
  CHECK(o.sort_seconds == o.sort_costs[5].seconds());
  CHECK(o.sort.order.size() == o.pieces);
  CHECK(o.pieces >= r.polygons);
  CHECK(o.rows[1].difference.differing == 0);
  CHECK(r.rows[1].difference.differing == 0);
  CHECK_THAT(format_visible_report({r}, config),
             Catch::Contains("depth sort's cost over the choices"));
}

// Painter's depth sort runs inside the GPs (Scene::depth_sort): each GP spends its phases'
// clocks and the runs, the order and the records cross the ring as messages, before the
// geometry. Fails if the GP skips the sort's time or its messages.
TEST_CASE("depth sort: the GPs run it in the frame, its transfers on the ring", "[visible]") {
  MachineConfig config = small_machine();
  config.fidelity.pixels = MachineConfig::Fidelity::Pixels::none;
  const Program painter = test::load_program("painter", config);
  const Scene scene = make_builtin_scene("torus");
  std::vector<SortPolygon> polygons;
  for (const ScreenPolygon& p : project_scene(config, scene)) polygons.push_back({p.v});
  const int gps = config.gp.count;
  const DepthSortResult sort = depth_sort(polygons, gps);
  const DepthSortWork work = depth_sort_work(sort, polygons.size(), gps, false);
  std::uint64_t words = work.order_words, messages = work.order_words > 0 ? 1 : 0;
  for (int j = 0; j < gps; ++j) {
    const auto a = static_cast<std::size_t>(j);
    words += work.run_words[a];
    messages += work.run_words[a] > 0 ? 1 : 0;
    for (int k = 0; k < gps; ++k) {
      words += work.record_words[a][static_cast<std::size_t>(k)];
      messages += work.record_words[a][static_cast<std::size_t>(k)] > 0 ? 1 : 0;
    }
  }
  REQUIRE(words > 0);
  const FrameResult plain = project_frame(config, scene, painter);
  Scene sorting = scene;
  sorting.depth_sort = std::make_shared<DepthSortWork>(work);
  nlohmann::json timeline;
  const FrameResult sorted = simulate_frame(config, sorting, painter, 1, {}, &timeline);
  // The transfers are ring messages, beside the frame's own.
  CHECK(sorted.stats.integer("ring.words") - plain.stats.integer("ring.words") ==
        static_cast<std::int64_t>(words));
  CHECK(sorted.stats.integer("ring.messages") - plain.stats.integer("ring.messages") ==
        static_cast<std::int64_t>(messages));
  // Its time is the GPs': the last GP's sort ends no earlier than the slowest prepare, the
  // merge and the slowest checks one after another, and the frame includes it.
  I860Params params = i860_params(config);
  params.overhead_factor = 1;
  const I860Model i860(params);
  std::uint64_t prepare = 0, check = 0, sort_clocks = i860.clocks(work.merge, 0).count;
  for (int k = 0; k < gps; ++k) {
    const auto a = static_cast<std::size_t>(k);
    prepare = std::max(prepare, i860.clocks(work.prepare[a], 0).count);
    check = std::max(check, i860.clocks(work.check[a], 0).count);
    sort_clocks += i860.clocks(work.prepare[a], 0).count + i860.clocks(work.check[a], 0).count;
  }
  const double least =
      static_cast<double>(prepare + i860.clocks(work.merge, 0).count + check) / config.gp.clock_hz;
  double done = 0;
  std::int64_t clocks = 0;
  for (int k = 0; k < gps; ++k) {
    done =
        std::max(done, sorted.stats.real("gp." + std::to_string(k) + ".depth_sort.done_seconds"));
    clocks += sorted.stats.integer("gp." + std::to_string(k) + ".depth_sort.clocks");
  }
  CHECK(clocks == static_cast<std::int64_t>(sort_clocks));
  CHECK(done >= least);
  CHECK(sorted.frame_seconds > done);
  CHECK(sorted.frame_seconds > plain.frame_seconds);
  CHECK_FALSE(plain.stats.contains("gp.0.depth_sort.done_seconds"));
  // The timeline shows the phases.
  const std::string trace = timeline.dump();
  for (const char* phase :
       {"depth sort: prepare", "depth sort: merge", "depth sort: check", "depth sort: send run"})
    CHECK(trace.find(phase) != std::string::npos);
}
