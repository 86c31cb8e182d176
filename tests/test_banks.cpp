// Intersection-highlighting firmware (Banks): the exactMatch predicates on random streams,
// shared-edge hits, epsilon on parallel and near-parallel planes against an integer model,
// fixed versus varying curve width on the figure-eight surface, and the bit budget.
#include <algorithm>
#include <bitset>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <tuple>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/analysis/intersections.hpp"
#include "sim/scene/order.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

using namespace pp5;

namespace {

std::string program_path(const std::string& name) {
  return std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + name + ".pp5";
}

std::int64_t floor_value(const QuadraticCoefficients& q, int x, int y, int shift) {
  const __int128 v = static_cast<__int128>(q.D) * x + static_cast<__int128>(q.E) * y + q.F;
  const __int128 d = static_cast<__int128>(1) << shift;
  __int128 f = v / d;
  if (v % d != 0 && v < 0) --f;
  return static_cast<std::int64_t>(f);
}

// One 128 x 128 region: triangles given directly in screen space, set up by the GP code and
// executed by a Renderer board.
struct Bench {
  MachineConfig config = MachineConfig::defaults();
  Scene scene = make_builtin_scene("two-triangles");
  GeometryParams gp;
  Bench() {
    gp = geometry_params(config);
    gp.screen_width = 128;
    gp.screen_height = 128;
  }
  Program load(const std::string& name) const {
    return assemble_file(program_path(name), assembler_options(config));
  }
  static ScreenTriangle triangle(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c, double za, double zb,
                                 double zc, glm::dvec3 na = {0, 0, 1}, glm::dvec3 nb = {0, 0, 1},
                                 glm::dvec3 nc = {0, 0, 1}) {
    ScreenTriangle t;
    const glm::dvec2 p[3] = {a, b, c};
    const double z[3] = {za, zb, zc};
    const glm::dvec3 n[3] = {na, nb, nc};
    for (int k = 0; k < 3; ++k) {
      t.v[k].position = p[k];
      t.v[k].depth = z[k];
      t.v[k].base_color = glm::dvec3(0.5);
      t.v[k].lit_color = glm::dvec3(0.5);
      t.v[k].normal = glm::normalize(n[k]);
    }
    t.flat_color = glm::dvec3(0.5);
    return t;
  }
  // Packets for `program`, in order; triangles with no pixels are dropped.
  std::vector<Packet> packets(const Program& program,
                              const std::vector<ScreenTriangle>& tris) const {
    const GeometryEngine engine(gp, scene);
    std::vector<Packet> out;
    SetupCounts counts;
    for (const ScreenTriangle& t : tris) {
      SetupResult r;
      if (!engine.setup(t, program.procedure(Procedure::triangle).expressions, r, counts)) continue;
      Packet packet;
      packet.primitive = static_cast<int>(out.size());
      packet.values = r.values;
      out.push_back(packet);
    }
    return out;
  }
  // Runs the program's region stream over `stream` and returns its flag field for every pixel.
  std::vector<std::uint64_t> flags(const Program& program,
                                   const std::vector<Packet>& stream) const {
    RendererBoard board(board_params(config));
    const FrameValues values = GeometryEngine(gp, scene).frame_values();
    board.begin_region(0, 0);
    RegionStream(program, values).for_each(stream, [&](const RegionStep& step) {
      board.run_step(step);
    });
    const FieldDecl* f = program.find_field("iflag");
    REQUIRE(f != nullptr);
    std::vector<std::uint64_t> out(128 * 128);
    for (int p = 0; p < 128 * 128; ++p)
      out[p] = board.array().read(p, Field{f->lo, f->width, f->is_signed});
    return out;
  }
};

bool covers(const Packet& v, int x, int y) {
  for (int e = 0; e < 3; ++e) {
    if (floor_value(v.values.expressions[static_cast<int>(Expression::edge0) + e], x, y, 0) < 0)
      return false;
  }
  return true;
}

std::int64_t depth_at(const Packet& v, int x, int y, int frac) {
  return floor_value(v.values.expressions[static_cast<int>(Expression::depth)], x, y, frac) &
         0xFFFFFF;
}

}  // namespace

TEST_CASE("exactMatch flags exactly the pixels where two polygons share the minimum depth",
          "[banks]") {
  Bench b;
  const Program program = b.load("exactmatch");
  const int frac = b.config.evaluator.fraction_bits;
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> pos(-20.0, 148.0);
  std::uniform_int_distribution<int> level(1, 4);
  std::uniform_real_distribution<double> slope(-0.002, 0.002);
  // Depths on a few levels, so that ties of the frontmost depth are common: screen-parallel
  // triangles (exact constant depth) and a few sloped ones crossing them.
  std::vector<ScreenTriangle> tris;
  for (int i = 0; i < 24; ++i) {
    const glm::dvec2 a(pos(rng), pos(rng)), c(pos(rng), pos(rng)), d(pos(rng), pos(rng));
    const double z = level(rng) * 0.125;
    if (i % 4 == 3) {
      tris.push_back(
          Bench::triangle(a, c, d, z + 64 * slope(rng), z + 64 * slope(rng), z + 64 * slope(rng)));
    } else {
      tris.push_back(Bench::triangle(a, c, d, z, z, z));
    }
  }
  std::vector<Packet> stream = b.packets(program, tris);
  REQUIRE(stream.size() > 16);
  std::size_t flagged_total = 0;
  for (int order = 0; order < 6; ++order) {
    if (order > 0) std::shuffle(stream.begin(), stream.end(), rng);
    const auto flags = b.flags(program, stream);
    for (int y = 0; y < 128; ++y) {
      for (int x = 0; x < 128; ++x) {
        // P4: two different polygons attain the minimum depth over those covering the pixel.
        std::int64_t best = 0xFFFFFF;
        int at_best = 0;
        for (const Packet& v : stream) {
          if (!covers(v, x, y)) continue;
          const std::int64_t z = depth_at(v, x, y, frac);
          if (z < best) {
            best = z;
            at_best = 1;
          } else if (z == best) {
            ++at_best;
          }
        }
        INFO("pixel " << x << "," << y << " order " << order);
        REQUIRE((flags[y * 128 + x] == 1) == (at_best >= 2));
        flagged_total += flags[y * 128 + x];
      }
    }
  }
  CHECK(flagged_total > 100);  // the stream really does produce ties
}

TEST_CASE("Shared-edge false hits appear with exactMatch and not with exactMatch'", "[banks]") {
  Bench b;
  // A fold: two triangles share the vertical edge x = 10.5 (through pixel centres), both lie
  // to its right, so the top-left rule gives the edge's pixels to both; the vertex normals on
  // the shared edge are the same for both (a smooth mesh), the third vertices' differ.
  const glm::dvec3 edge_normal(-0.3, 0.1, 1.0);
  const ScreenTriangle t1 = Bench::triangle({10.5, 10.5}, {10.5, 70.5}, {70.5, 40.5}, 0.3, 0.3,
                                            0.31, edge_normal, edge_normal, {0.4, 0.0, 1.0});
  const ScreenTriangle t2 = Bench::triangle({10.5, 10.5}, {10.5, 70.5}, {50.5, 50.5}, 0.3, 0.3,
                                            0.36, edge_normal, edge_normal, {-0.5, 0.3, 1.0});
  std::size_t em = 0, emn = 0;
  int off_edge = 0;
  for (const char* name : {"exactmatch", "exactmatch_n"}) {
    const Program program = b.load(name);
    for (int order = 0; order < 2; ++order) {
      const auto stream = b.packets(program, order ? std::vector{t2, t1} : std::vector{t1, t2});
      REQUIRE(stream.size() == 2);
      const auto flags = b.flags(program, stream);
      for (int y = 0; y < 128; ++y) {
        for (int x = 0; x < 128; ++x) {
          if (!flags[y * 128 + x]) continue;
          (std::string(name) == "exactmatch" ? em : emn) += 1;
          off_edge += x != 10;
        }
      }
    }
  }
  CHECK(em >= 2 * 50);  // the edge's pixels, in both orders
  CHECK(off_edge == 0);
  CHECK(emn == 0);
}

TEST_CASE("epsilon is zero for parallel planes and near-parallel planes do not overflow",
          "[banks]") {
  Bench b;
  const int frac = b.config.evaluator.fraction_bits;
  const GeometryEngine engine(b.gp, b.scene);
  const auto k = engine.frame_parameters();
  const std::int64_t scale = k[static_cast<int>(Parameter::epsilon_scale)];
  // Two triangles covering the region, plane depths z = base + gx x + gy y (depth in [0,1]).
  auto plane = [](double base, double gx, double gy) {
    return Bench::triangle({-8, -8}, {300, -8}, {-8, 300}, base - 8 * gx - 8 * gy,
                           base + 300 * gx - 8 * gy, base - 8 * gx + 300 * gy);
  };
  struct Case {
    const char* what;
    ScreenTriangle a, b;
  };
  const double px = 1.0 / 16777215.0;  // one depth unit
  const std::vector<Case> cases = {
      {"parallel, 3 units apart", plane(0.4, 500 * px, 200 * px),
       plane(0.4 + 3 * px, 500 * px, 200 * px)},
      {"near-parallel, slopes 64 units/pixel apart", plane(0.4, 500 * px, 200 * px),
       plane(0.4, 564 * px, 200 * px)},
      {"near-parallel and steep (clamped slopes)", plane(0.5, 0.004, 0.0005),
       plane(0.5, 0.004 + 64 * px, 0.0005)},
      {"crossing steeply", plane(0.5, 0.003, -0.001), plane(0.5, -0.002, 0.0004)},
  };
  const std::int64_t delta = k[static_cast<int>(Parameter::delta)];
  for (const char* name : {"epsilon", "epsilon_folded_squares", "epsilon_folded"}) {
    const Program program = b.load(name);
    // epsilon_folded takes the slope difference's length as max + 3/8 min of its components.
    const bool alpha_max_beta_min = std::string(name) == "epsilon_folded";
    for (const Case& c : cases) {
      const auto stream = b.packets(program, {c.a, c.b});
      REQUIRE(stream.size() == 2);
      const auto flags = b.flags(program, stream);
      // The integer model of the test: dz^2 < epsilon_scale * ((a2-a1)^2 + (b2-b1)^2), or
      // for max + 3/8 min, with h = delta * (8 max + 3 min) / 2 (floored), -h <= dz < h for
      // dz = depth - z: |dz| < 4 delta (max + 3/8 min), as epsilon_scale = 16 delta^2.
      auto slope = [&](const Packet& v, Expression e) {
        return v.values.expressions[static_cast<int>(e)].F >> frac;
      };
      const __int128 da =
          slope(stream[1], Expression::slope_x) - slope(stream[0], Expression::slope_x);
      const __int128 db =
          slope(stream[1], Expression::slope_y) - slope(stream[0], Expression::slope_y);
      const __int128 m2 = da * da + db * db;
      const __int128 big = std::max(da < 0 ? -da : da, db < 0 ? -db : db);
      const __int128 small = std::min(da < 0 ? -da : da, db < 0 ? -db : db);
      const __int128 h = (static_cast<__int128>(delta) * (8 * big + 3 * small)) >> 1;
      std::size_t expected_count = 0;
      for (int y = 0; y < 128; ++y) {
        for (int x = 0; x < 128; ++x) {
          const __int128 dz = depth_at(stream[0], x, y, frac) - depth_at(stream[1], x, y, frac);
          const bool expected = alpha_max_beta_min ? (-dz < h && dz - 1 < h)
                                                   : dz * dz < static_cast<__int128>(scale) * m2;
          expected_count += expected;
          INFO(name << ": " << c.what << " at " << x << "," << y);
          REQUIRE((flags[y * 128 + x] == 1) == expected);
        }
      }
      if (std::string(c.what).rfind("parallel", 0) == 0) CHECK(expected_count == 0);
      if (std::string(c.what).rfind("crossing", 0) == 0) CHECK(expected_count > 100);
    }
  }
  // The threshold program, by contrast, flags the parallel near-miss everywhere.
  const Program threshold = b.load("threshold");
  const auto flags = b.flags(threshold, b.packets(threshold, {cases[0].a, cases[0].b}));
  CHECK(std::count(flags.begin(), flags.end(), 1u) == 128 * 128);
}

TEST_CASE("On the figure-eight surface epsilon's curve width varies less than threshold's",
          "[banks]") {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  Scene scene = make_builtin_scene("figure-eight");
  scene.parameters["threshold"] = 131072;  // about the same mean width at this screen size
  const IntersectionTruth truth = intersection_truth(scene, 256, 256, 1.5);
  REQUIRE(truth.visible.size() > 200);
  Accuracy acc[2];
  int i = 0;
  for (const char* name : {"threshold", "epsilon"}) {
    const Program program = assemble_file(program_path(name), assembler_options(config));
    const FieldFrame frame = render_field(config, scene, program, "iflag", 2);
    std::vector<std::uint8_t> flagged(frame.values.begin(), frame.values.end());
    acc[i++] = measure_accuracy(truth, flagged);
  }
  INFO("threshold width " << acc[0].width_mean << " +- " << acc[0].width_sd << ", epsilon "
                          << acc[1].width_mean << " +- " << acc[1].width_sd);
  CHECK(acc[1].recall > 0.8);
  CHECK(acc[0].width_samples > 100);
  CHECK(acc[1].width_sd / acc[1].width_mean < 0.5 * (acc[0].width_sd / acc[0].width_mean));
}

TEST_CASE(
    "Shared scratch is invisible in the pixels: each program computes the same bits with "
    "every scratch field in bits of its own",
    "[banks]") {
  // The rewritten programs (issue 17) fit in 208 bits because their scratch fields share bits
  // with each other and with fields dead in shade. Declared as ordinary fields, the same text
  // needs more than 208 bits and no field shares a bit: flags and image must not change.
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  MachineConfig big = config;
  big.set(std::vector<std::string>{"renderer.memory_bits=640"});
  for (const char* name :
       {"threshold", "epsilon", "epsilon_normal", "epsilon_folded", "transparent_threshold"}) {
    INFO("program " << name);
    std::ifstream in(program_path(name));
    std::stringstream text;
    text << in.rdbuf();
    const std::string separate =
        std::regex_replace(text.str(), std::regex("\nscratch "), "\nfield ");
    REQUIRE(separate != text.str());
    const Program shared = assemble(text.str(), name, assembler_options(config));
    CHECK(shared.bits_used() <= 208);
    CHECK(shared.staging_bits == 0);
    const Program own = assemble(separate, name, assembler_options(big));
    CHECK(own.bits_used() > shared.bits_used());
    // Without sharing, the epsilon programs do not fit in 208 bits (the paper's problem).
    if (std::string(name).rfind("epsilon", 0) == 0) {
      CHECK(own.bits_used() > 208);
      CHECK_THROWS_WITH(assemble(separate, name, assembler_options(config)),
                        Catch::Contains("pixel memory has 208"));
    }
    for (const char* scene_name : {"two-triangles", "figure-eight"}) {
      INFO("scene " << scene_name);
      const Scene scene = make_builtin_scene(scene_name);
      const FieldFrame a = render_field(config, scene, shared, "iflag", 2);
      const FieldFrame r = render_field(big, scene, own, "iflag", 1);
      CHECK(std::count(a.values.begin(), a.values.end(), 1u) > 50);
      CHECK(a.values == r.values);
      CHECK(a.image.rgb == r.image.rgb);
    }
  }
}

TEST_CASE("The truth finds the two triangles' crossing and the highlight command's parts agree",
          "[banks]") {
  const Scene scene = make_builtin_scene("two-triangles");
  const auto segments = intersection_segments(scene.mesh);
  REQUIRE(segments.size() == 1);
  // Both triangles contain the y axis between -0.8 and 0.8.
  const double lo = std::min(segments[0].a.y, segments[0].b.y);
  const double hi = std::max(segments[0].a.y, segments[0].b.y);
  CHECK(lo == Approx(-0.8).margin(1e-5));
  CHECK(hi == Approx(0.8).margin(1e-5));
  CHECK(std::abs(segments[0].a.x) < 1e-5);
  CHECK(std::abs(segments[0].a.z) < 1e-5);
  // Parallel and disjoint triangles do not intersect.
  const glm::dvec3 p[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const glm::dvec3 q[3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  glm::dvec3 a, b2;
  CHECK_FALSE(triangle_intersection(p, q, a, b2));
}

TEST_CASE(
    "The highlight truth's recall ceiling is what a flag on every doubly covered pixel "
    "reaches",
    "[banks]") {
  // The crossing ends where the triangles do: its band of half-width delta spills past them,
  // onto pixels one surface (or none) reaches, which no depth test can flag. threshold_keep
  // with a threshold spanning the whole depth range and no silhouette cut flags every pixel
  // two triangles reach, so its recall is the ceiling (to the pixels whose centre lies on an
  // edge, where the machine's edge test and the truth's barycentric test may differ).
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  Scene scene = make_builtin_scene("two-triangles");
  scene.parameters["threshold"] = 0xFFFFFF;
  scene.parameters["silhouette"] = 0;
  const IntersectionTruth truth = intersection_truth(scene, 256, 256, 1.5);
  REQUIRE(truth.pixels > 200);
  CHECK(truth.reachable < truth.pixels);
  CHECK(truth.reachable > truth.pixels / 2);
  // The per-pixel mask the report draws holds those pixels, each a truth pixel.
  std::size_t reached = 0, outside = 0;
  for (std::size_t p = 0; p < truth.reached.size(); ++p) {
    outside += truth.reached[p] && !truth.mask[p];
    reached += truth.reached[p];
  }
  CHECK(outside == 0);
  CHECK(reached == truth.reachable);
  const Program program = assemble_file(program_path("threshold_keep"), assembler_options(config));
  const FieldFrame frame = render_field(config, scene, program, "iflag", 2);
  const std::vector<std::uint8_t> flagged(frame.values.begin(), frame.values.end());
  const Accuracy a = measure_accuracy(truth, flagged);
  INFO("truth " << truth.pixels << ", reachable " << truth.reachable << ", hits " << a.hits);
  CHECK(a.ceiling == Approx(static_cast<double>(truth.reachable) / truth.pixels));
  CHECK(a.recall <= a.ceiling + 4.0 / truth.pixels);
  CHECK(std::abs(static_cast<long>(a.hits) - static_cast<long>(truth.reachable)) <= 4);
}

TEST_CASE("Unknown or derived frame parameters are rejected by name", "[banks]") {
  Scene scene = make_builtin_scene("two-triangles");
  const MachineConfig config = MachineConfig::defaults();
  scene.parameters["no_such"] = 1;
  CHECK_THROWS_WITH(GeometryEngine(geometry_params(config), scene).frame_parameters(),
                    Catch::Contains("no_such"));
  scene.parameters.clear();
  scene.parameters["epsilon_scale"] = 1;
  CHECK_THROWS_WITH(GeometryEngine(geometry_params(config), scene).frame_parameters(),
                    Catch::Contains("derived"));
  scene.parameters.clear();
  scene.parameters["highlight_opacity"] = 300;
  CHECK_THROWS_WITH(GeometryEngine(geometry_params(config), scene).frame_parameters(),
                    Catch::Contains("highlight_opacity"));
}

TEST_CASE("Multipass transparency finds intersections behind the frontmost layer", "[banks]") {
  Bench b;
  // A front layer over everything; behind it two screen-parallel triangles at one depth
  // overlap in the square x, y in [40, 80): a tie in the second layer only.
  const ScreenTriangle front = Bench::triangle({-8, -8}, {300, -8}, {-8, 300}, 0.2, 0.2, 0.2);
  const ScreenTriangle left = Bench::triangle({0, 0}, {80, 0}, {0, 160}, 0.5, 0.5, 0.5);
  const ScreenTriangle right = Bench::triangle({40, 40}, {128, 40}, {40, 128}, 0.5, 0.5, 0.5);
  auto count = [&](const char* name) {
    const Program program = b.load(name);
    const auto flags = b.flags(program, b.packets(program, {front, left, right}));
    return std::count(flags.begin(), flags.end(), 1u);
  };
  CHECK(count("exactmatch") == 0);
  const Program opaque = b.load("exactmatch");
  const auto packets = b.packets(opaque, {front, left, right});
  long overlap = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) overlap += covers(packets[1], x, y) && covers(packets[2], x, y);
  const auto behind = count("transparent_exactmatch");
  CHECK(overlap > 300);
  CHECK(behind == overlap);  // exactly the overlap of the two hidden triangles
  CHECK(count("transparent_threshold") >= behind);
}

TEST_CASE("epsilon folded into the rendering pass is order-sensitive - two-pass epsilon is not",
          "[banks]") {
  Bench b;
  // The paper's case: P faces the screen in front, M parallel to it behind, and B, far
  // behind, is nearly edge-on (a sliver whose depth rises steeply across a few pixels).
  const ScreenTriangle p = Bench::triangle({-8, -8}, {300, -8}, {-8, 300}, 0.55, 0.55, 0.55);
  const ScreenTriangle m = Bench::triangle({-8, -8}, {300, -8}, {-8, 300}, 0.56, 0.56, 0.56);
  const ScreenTriangle s = Bench::triangle({60, -8}, {66, -8}, {60, 300}, 0.57, 0.99, 0.57);
  auto count = [&](const char* name, std::vector<ScreenTriangle> order) {
    const Program program = b.load(name);
    const auto flags = b.flags(program, b.packets(program, order));
    return std::count(flags.begin(), flags.end(), 1u);
  };
  const auto folded_late = count("epsilon_folded", {p, m, s});   // B compared with P
  const auto folded_early = count("epsilon_folded", {s, m, p});  // P arrives last
  INFO("folded: " << folded_late << " flagged with B last, " << folded_early << " with B first");
  CHECK(folded_late > 0);
  CHECK(folded_early == 0);
  CHECK(count("epsilon", {p, m, s}) == 0);
  CHECK(count("epsilon", {s, m, p}) == 0);
}

TEST_CASE("On the torus, reversing the display list changes epsilon_folded's flags, not epsilon's",
          "[banks]") {
  // At the default 1280 x 1024: since the folded epsilon ignores depth gaps of 2^20 and more
  // (issue 17), the far, steep sheets that reorder its flags at 128 x 128 no longer count,
  // and the effect shows at the README's resolution (11 pixels of about 4,800).
  MachineConfig config = MachineConfig::defaults();
  const Scene given = make_builtin_scene("torus");
  Scene reversed = given;
  apply_display_order(reversed.mesh, parse_display_order("reversed", "--order"));
  REQUIRE(reversed.mesh.triangles.front() == given.mesh.triangles.back());
  auto changed = [&](const char* name) {
    const Program program = assemble_file(program_path(name), assembler_options(config));
    const FieldFrame a = render_field(config, given, program, "iflag", 2);
    const FieldFrame b = render_field(config, reversed, program, "iflag", 1);
    long flagged = 0, differ = 0;
    for (std::size_t p = 0; p < a.values.size(); ++p) {
      flagged += a.values[p] != 0;
      differ += (a.values[p] != 0) != (b.values[p] != 0);
    }
    REQUIRE(flagged > 100);
    return differ;
  };
  const long two_pass = changed("epsilon");
  const long folded = changed("epsilon_folded");
  INFO("pixels changed by reversing: epsilon " << two_pass << ", epsilon_folded " << folded);
  CHECK(two_pass == 0);
  CHECK(folded > 0);
}

TEST_CASE("Display orders are deterministic permutations and bad ones are named", "[banks]") {
  const Scene given = make_builtin_scene("figure-eight");
  Scene a = given, b = given, c = given;
  apply_display_order(a.mesh, parse_display_order("shuffled:7", "--order"));
  apply_display_order(b.mesh, parse_display_order("shuffled:7", "--order"));
  apply_display_order(c.mesh, parse_display_order("shuffled:8", "--order"));
  CHECK(a.mesh.triangles == b.mesh.triangles);
  CHECK(a.mesh.triangles != c.mesh.triangles);
  CHECK(a.mesh.triangles != given.mesh.triangles);
  auto key = [](const glm::uvec3& t) { return std::make_tuple(t.x, t.y, t.z); };
  auto sorted = [&](std::vector<glm::uvec3> v) {
    std::sort(v.begin(), v.end(), [&](auto& p, auto& q) { return key(p) < key(q); });
    return v;
  };
  CHECK(sorted(a.mesh.triangles) == sorted(given.mesh.triangles));
  CHECK(parse_display_order("shuffled", "--order").text() == "shuffled:1");
  for (const char* bad : {"backwards", "shuffled:", "shuffled:-1", "shuffled:x", "shuffledx"}) {
    CHECK_THROWS_WITH(parse_display_order(bad, "--order"),
                      Catch::Contains("--order") && Catch::Contains("expected given, reversed"));
  }
}

TEST_CASE("Under perspective a fixed threshold widens with distance on screen z, narrows on eye z",
          "[banks]") {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=640", "screen.height=512"});
  Scene scene = make_builtin_scene("receding-pairs");
  scene.parameters["threshold"] = 16384;
  const IntersectionTruth truth = intersection_truth(scene, 640, 512, 1.5);
  REQUIRE(truth.curves.size() == 5);
  // The pairs are identical and recede: each curve's midpoint is farther than the last.
  const auto distance = [&](std::size_t i) {
    return -0.5 * (truth.curves[i].a.z + truth.curves[i].b.z);
  };
  for (std::size_t i = 1; i < truth.curves.size(); ++i) CHECK(distance(i) > distance(i - 1));
  std::vector<double> width[2];
  int k = 0;
  // threshold_keep and threshold_eyez share their flag rule (a new frontmost sample within
  // the threshold keeps the flag), so only the depth quantity differs. The paper's threshold
  // flags only one side of each crossing, in display-list order (measured in the README).
  for (const char* name : {"threshold_keep", "threshold_eyez"}) {
    const Program program = assemble_file(program_path(name), assembler_options(config));
    const FieldFrame frame = render_field(config, scene, program, "iflag", 2);
    std::vector<std::uint8_t> flagged(frame.values.begin(), frame.values.end());
    for (const Accuracy& a : measure_width_by_segment(truth, flagged)) {
      CHECK(a.coverage > 0.5);
      width[k].push_back(a.width_mean);
    }
    ++k;
  }
  INFO("screen z: " << width[0][0] << " ... " << width[0][4] << " px; eye z: " << width[1][0]
                    << " ... " << width[1][4] << " px");
  CHECK(width[0][4] > 1.5 * width[0][0]);  // nearest to farthest pair: wider
  CHECK(width[1][0] > 1.5 * width[1][4]);  // narrower
}

TEST_CASE("eye_depth is exact at the vertices and affine in screen space", "[banks]") {
  Bench b;
  ScreenTriangle t = Bench::triangle({10, 10}, {100, 20}, {30, 110}, 0.3, 0.6, 0.9);
  // Eye depths (camera units) at the vertices; the plane through them is not the
  // perspective-correct eye depth, and the GP says so in the expression's meaning.
  const Camera& cam = b.scene.camera;
  const double fraction[3] = {0.1, 0.4, 0.8};
  double eye[3];
  for (int k = 0; k < 3; ++k) {
    eye[k] = cam.near_plane + fraction[k] * (cam.far_plane - cam.near_plane);
    t.v[k].eye_depth = eye[k];
  }
  std::bitset<static_cast<int>(Expression::count)> need;
  need.set(static_cast<int>(Expression::eye_depth));
  SetupResult r;
  SetupCounts counts;
  REQUIRE(GeometryEngine(b.gp, b.scene).setup(t, need, r, counts));
  const auto& q = r.values.expressions[static_cast<int>(Expression::eye_depth)];
  const double depth_max = std::ldexp(1.0, b.gp.depth_bits) - 1.0;
  for (int k = 0; k < 3; ++k) {
    const double expect = (eye[k] - cam.near_plane) / (cam.far_plane - cam.near_plane) * depth_max;
    const double x = t.v[k].position.x - 0.5, y = t.v[k].position.y - 0.5;
    const double got =
        (q.D * x + q.E * y + static_cast<double>(q.F)) / std::ldexp(1.0, b.gp.fraction_bits);
    INFO("vertex " << k);
    CHECK(got == Approx(expect).margin(64));
    CHECK(got == Approx(fraction[k] * depth_max).margin(64));
  }
  CHECK(q.A == 0);
  CHECK(q.B == 0);
  CHECK(q.C == 0);
  CHECK(std::string(kExpressions[static_cast<int>(Expression::eye_depth)].meaning)
            .find("not perspective-correct") != std::string::npos);
}

TEST_CASE("The GP cost model counts the highlighting expressions like any other expression",
          "[banks]") {
  MachineConfig config = MachineConfig::defaults();
  auto workload = [&](const char* name) {
    const Program p = assemble_file(program_path(name), assembler_options(config));
    GpWorkload w;
    w.expressions = p.procedure(Procedure::triangle).expressions;
    w.packet_words = 1 + w.expressions.count() * 3 * 2;  // 40-bit coefficients, 32-bit words
    return w;
  };
  GpWorkload threshold = workload("threshold");
  // threshold's depth_minus_threshold (depth's plane, offset by one integer add) set aside:
  // the rest is what epsilon adds its slopes to.
  REQUIRE(threshold.expressions.test(static_cast<int>(Expression::depth_minus_threshold)));
  const OpCounts offset = I860Work::expression_setup(Expression::depth_minus_threshold);
  CHECK(offset.floating() == 0);
  CHECK(offset.core() > 0);
  threshold.expressions.reset(static_cast<int>(Expression::depth_minus_threshold));
  threshold.packet_words -= 3 * 2;
  const GpWorkload eyez = workload("threshold_eyez");
  const GpWorkload epsilon = workload("epsilon");
  REQUIRE(epsilon.expressions.test(static_cast<int>(Expression::slope_x)));
  REQUIRE(epsilon.expressions.test(static_cast<int>(Expression::slope_y)));
  REQUIRE(eyez.expressions.test(static_cast<int>(Expression::eye_depth)));
  REQUIRE_FALSE(eyez.expressions.test(static_cast<int>(Expression::depth)));
  // epsilon = threshold + the two slopes: each costs an expression's set-up and its words.
  REQUIRE((epsilon.expressions ^ threshold.expressions).count() == 2);
  const OpCounts t = I860Work::triangle(threshold, 1, 1, 1);
  const OpCounts e = I860Work::triangle(epsilon, 1, 1, 1);
  const OpCounts slopes = I860Work::expression_setup(Expression::slope_x) +
                          I860Work::expression_setup(Expression::slope_y);
  CHECK(slopes.floating() > 0);
  CHECK(e.fadd == t.fadd + slopes.fadd);
  CHECK(e.fmul == t.fmul + slopes.fmul);
  CHECK(e.store == t.store + slopes.store + (epsilon.packet_words - threshold.packet_words));
  // eye_depth replaces depth: the same work (the vertices' eye depth is the clip w).
  const OpCounts z = I860Work::triangle(eyez, 1, 1, 1);
  CHECK(z.floating() == t.floating());
  CHECK(z.core() == t.core());
  // Under both code profiles the slopes cost clocks; compiled C much more than assembly.
  for (const char* code : {"assembly", "compiled"}) {
    MachineConfig c = config;
    c.set(std::vector<std::string>{std::string("gp.code=") + code});
    const I860Model model(i860_params(c));
    INFO(code);
    CHECK(model.reference_triangle(epsilon).count > model.reference_triangle(threshold).count);
  }
  MachineConfig c = config;
  c.set(std::vector<std::string>{"gp.code=compiled"});
  const I860Model compiled(i860_params(c));
  const I860Model assembly(i860_params(config));
  CHECK(compiled.reference_triangle(epsilon).count >
        5 * assembly.reference_triangle(epsilon).count);
}

TEST_CASE("threshold is the paper's figure 1 with line (4''), threshold_keep keeps the flag",
          "[banks]") {
  Bench b;
  // Two screen-parallel triangles, the second 0.0005 of the depth range behind the first
  // (about 8,400 units: within the default threshold of 32,768), overlapping on a square.
  const ScreenTriangle near = Bench::triangle({0, 0}, {200, 0}, {0, 200}, 0.5, 0.5, 0.5);
  const ScreenTriangle far =
      Bench::triangle({20, 20}, {220, 20}, {20, 220}, 0.5005, 0.5005, 0.5005);
  auto count = [&](const char* name, std::vector<ScreenTriangle> order) {
    const Program program = b.load(name);
    const auto flags = b.flags(program, b.packets(program, order));
    return std::count(flags.begin(), flags.end(), 1u);
  };
  const Program probe = b.load("threshold");
  const auto packets = b.packets(probe, {near, far});
  long overlap = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) overlap += covers(packets[0], x, y) && covers(packets[1], x, y);
  REQUIRE(overlap > 1000);
  // Near first: the far one arrives behind within the threshold, line (4''): flagged.
  CHECK(count("threshold", {near, far}) == overlap);
  CHECK(count("threshold_keep", {near, far}) == overlap);
  // Far first: the near one is a new frontmost sample; line (3) lowers the flag, while
  // threshold_keep keeps it because the old sample lies within the threshold.
  CHECK(count("threshold", {far, near}) == 0);
  CHECK(count("threshold_keep", {far, near}) == overlap);
  // Beyond the threshold neither flags, in either order.
  const ScreenTriangle distant = Bench::triangle({20, 20}, {220, 20}, {20, 220}, 0.51, 0.51, 0.51);
  for (const char* name : {"threshold", "threshold_keep"}) {
    CHECK(count(name, {near, distant}) == 0);
    CHECK(count(name, {distant, near}) == 0);
  }
}

TEST_CASE("threshold's line (3): a new frontmost sample lowers a flag raised behind it",
          "[banks]") {
  // The near/far pair flags its overlap (line (4'')); then a third triangle arrives well in
  // front of both (beyond the threshold) over part of it. Where it covers, the pixel now
  // shows a surface that crosses nothing: line (3) must lower the flag there, and only
  // there. Without line (3) the flag raised behind would survive under the new front.
  Bench b;
  const ScreenTriangle near = Bench::triangle({0, 0}, {200, 0}, {0, 200}, 0.5, 0.5, 0.5);
  const ScreenTriangle far =
      Bench::triangle({20, 20}, {220, 20}, {20, 220}, 0.5005, 0.5005, 0.5005);
  const ScreenTriangle front = Bench::triangle({0, 0}, {60, 0}, {0, 128}, 0.3, 0.3, 0.3);
  for (const char* name : {"threshold", "threshold_keep"}) {
    INFO(name);
    const Program program = b.load(name);
    const auto packets = b.packets(program, {near, far, front});
    REQUIRE(packets.size() == 3);
    const auto flags = b.flags(program, packets);
    long pair = 0, lowered = 0, wrong = 0;
    for (int y = 0; y < 128; ++y) {
      for (int x = 0; x < 128; ++x) {
        const bool both = covers(packets[0], x, y) && covers(packets[1], x, y);
        const bool under = covers(packets[2], x, y);
        const bool expect = both && !under;
        pair += both;
        lowered += both && under;
        wrong += (flags[static_cast<std::size_t>(y) * 128 + x] == 1) != expect;
      }
    }
    REQUIRE(pair > 1000);
    REQUIRE(lowered > 500);
    CHECK(wrong == 0);
  }
}

TEST_CASE("The transparency programs peel as many layers as frame.layers says", "[banks]") {
  // crossing-quads is two surfaces deep: one layer shows only the front one; two and more
  // show both, and passes beyond the depth complexity change no pixel.
  const Scene scene = make_builtin_scene("crossing-quads");
  auto image = [&](int layers) {
    MachineConfig config = MachineConfig::defaults();
    config.set(std::vector<std::string>{"screen.width=256", "screen.height=256",
                                        "frame.layers=" + std::to_string(layers)});
    // Every surface at surface_opacity (128): the second layer shows through the first.
    const Program program =
        assemble_file(program_path("transparent_threshold"), assembler_options(config));
    const FrameResult r = simulate_frame(config, scene, program, 2);
    return r.image.flat().rgb;
  };
  const auto one = image(1);
  const auto two = image(2);
  CHECK(one != two);
  CHECK(two == image(4));
  CHECK(two == image(7));
}
