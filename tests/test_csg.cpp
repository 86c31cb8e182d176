// Parity and depth-interval applications (issue 15): the pass plan that draws one solid per
// pass, point in solid by parity against a double-precision ray caster.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/read_file.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/gp/pass_plan.hpp"
#include "models/machine.hpp"
#include "models/protocol/region_stream.hpp"
#include "sim/analysis/csg.hpp"
#include "sim/analysis/field_render.hpp"
#include "sim/analysis/transparency.hpp"
#include "sim/scene/csg_expression.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"

using namespace pp5;

namespace {

const char* kParitySource = R"(
field z 24
field par 1
field inside 1
field red 8
field green 8
field blue 8
output red green blue
proc clear
  eall
  mov z, 0xFFFFFF
  mov par, 0
  mov inside, 0
end
proc triangle
  eall
  qtest.ge edge0
  qcmp.lt z, depth
  qload z, depth
end
proc parity
  eall
  qtest.ge edge0
  qcmp.gt z, depth
  xor par, 1
end
proc pass
  eall
  or inside, par
  mov par, 0
end
)";

// The procedures a region runs, in order, each packet's with its primitive's number
// ("triangle0"); steps with no code (packets a pass does not draw) left out.
std::vector<std::string> procedures_run(const RegionStream& stream,
                                        const std::vector<Packet>& packets) {
  std::vector<std::string> ran;
  stream.for_each(packets, [&](const RegionStep& step) {
    if (!step.code.defined) return;
    std::string s = kProcedureNames[static_cast<int>(step.procedure)];
    if (step.packet) s += std::to_string(step.packet->primitive);
    ran.push_back(s);
  });
  return ran;
}

}  // namespace

TEST_CASE("a pass plan draws each solid in its own pass with the plan's procedure", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  const Program program = assemble(kParitySource, "plan", assembler_options(config));
  Scene scene;
  scene.solids = {{"a", 2, 4}, {"b", 4, 5}};
  CHECK(scene.solid_of_triangle(0) == -1);
  CHECK(scene.solid_of_triangle(3) == 0);
  CHECK(scene.solid_of_triangle(4) == 1);
  CHECK(scene.solid_of_triangle(5) == -1);
  FrameValues values;
  values.plan = make_pass_plan(program, scene);
  REQUIRE(values.plan.size() == 3);
  std::vector<Packet> packets(5);
  for (int i = 0; i < 5; ++i) {
    packets[static_cast<std::size_t>(i)].primitive = i;
    packets[static_cast<std::size_t>(i)].group = i < 2 ? -1 : i < 4 ? 0 : 1;
  }
  const RegionStream stream(program, values);
  CHECK(stream.passes() == 3);
  const std::vector<std::string> ran = procedures_run(stream, packets);
  const std::vector<std::string> expected = {"clear",   "triangle0", "triangle1", "pass",
                                             "parity2", "parity3",   "pass",      "parity4"};
  CHECK(ran == expected);

  // Without `parity`, no plan: the program's own passes, every packet its own procedure.
  const Program plain = assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/flat.pp5",
                                      assembler_options(config));
  CHECK(make_pass_plan(plain, scene).empty());
}

TEST_CASE("parity may use only what the triangle's packets carry", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  std::string source = kParitySource;
  source.replace(source.find("qtest.ge edge0\n  qcmp.gt"), 14, "qtest.ge edge1");
  const Program program = assemble(source, "bad-parity", assembler_options(config));
  CHECK_THROWS_WITH(check_pass_plan(program), Catch::Contains("'parity' uses expression 'edge1'") &&
                                                  Catch::Contains("bad-parity"));
}

namespace {

MachineConfig small_screen() {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  return config;
}

Program program_named(const std::string& name, const MachineConfig& config) {
  Program p = assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + name + ".pp5",
                            assembler_options(config));
  p.name = name;
  return p;
}

// Shipped program `name` with the text `find` (which it must hold) replaced by `replace`,
// assembled as `label`: a deliberately broken or bad variant for a test.
Program program_edited(const std::string& name, const std::string& find, const std::string& replace,
                       const std::string& label, const MachineConfig& config) {
  std::string source =
      read_regular_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + name + ".pp5",
                        1 << 20, "a firmware program");
  const std::size_t at = source.find(find);
  REQUIRE(at != std::string::npos);
  source.replace(at, find.size(), replace);
  return assemble(source, label, assembler_options(config));
}

}  // namespace

TEST_CASE("point in solid by parity agrees with the ray caster away from edges", "[csg]") {
  const MachineConfig config = small_screen();
  for (const std::string& scene_name : parity_scene_names()) {
    const Scene scene = make_parity_scene(scene_name);
    for (const char* name : {"parity", "parity_accurate"}) {
      INFO(scene_name << " " << name);
      const ParityMeasure m = measure_parity(config, scene, program_named(name, config), 2);
      // The scene is made so that most of the screen is compared and a good part is inside.
      CHECK(m.compared > 256 * 256 * 8 / 10);
      CHECK(m.points > 256 * 256 / 4);
      CHECK(m.inside > 256 * 256 / 20);
      CHECK(m.disagree == 0);
      CHECK(m.passes == 1 + static_cast<int>(scene.solids.size()));
      // Accurate scan conversion owns each centre once per sheet of a closed solid: even at
      // the centres near edges, it agrees with the ray through the centre (measured; the
      // standard program differs at a few there, see README "Point in solid by parity").
      if (std::string(name) == "parity_accurate") CHECK(m.edge_disagree == 0);
    }
  }
}

TEST_CASE("parity without the depth test is caught by the comparison", "[csg]") {
  // Every face of a closed solid toggles: the parity is always even, nothing is inside.
  const MachineConfig config = small_screen();
  const Program broken = program_edited("parity", "  qcmp.gt z, depth\n  xor par, 1",
                                        "  xor par, 1", "parity-without-depth", config);
  const ParityMeasure m = measure_parity(config, make_parity_scene("plane-sphere"), broken, 2);
  CHECK(m.disagree == m.inside);
  CHECK(m.disagree > 0);
}

namespace {

// A closed axis-aligned box as a scene-file mesh entry, named.
std::string box_json(const std::string& name, glm::dvec3 lo, glm::dvec3 hi) {
  std::string v;
  for (int i = 0; i < 8; ++i) {
    v += fmt::format("{}[{}, {}, {}]", i ? ", " : "", (i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y,
                     (i & 4) ? hi.z : lo.z);
  }
  return fmt::format(
      R"({{"name": "{}", "vertices": [{}], "triangles": [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6],
      [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]}})",
      name, v);
}

std::string csg_scene(const std::string& csg) {
  return "{\"meshes\": [" + box_json("cube", {-1, -1, -1}, {1, 1, 1}) + ", " +
         box_json("bite", {-0.5, -0.5, 0.5}, {0.5, 0.5, 1.5}) + ", " +
         box_json("far", {3, 3, 3}, {4, 4, 4}) + "], \"csg\": " + csg + "}";
}

Scene parse_csg_scene(const std::string& csg) {
  return parse_scene_json(csg_scene(csg), "csg.json", ".");
}

std::string products(const Scene& s) {
  std::vector<std::string> names;
  for (const Solid& solid : s.solids) names.push_back(solid.name);
  return format_csg(s.csg, names);
}

}  // namespace

TEST_CASE("CSG expressions normalise to a sum of products", "[csg]") {
  CHECK(products(parse_csg_scene(R"({"difference": ["cube", {"union": ["bite", "far"]}]})")) ==
        "cube & !bite & !far");
  CHECK(products(parse_csg_scene(R"({"intersection": [{"union": ["cube", "bite"]}, "far"]})")) ==
        "cube & far | bite & far");
  CHECK(
      products(parse_csg_scene(R"({"difference": ["cube", {"intersection": ["bite", "far"]}]})")) ==
      "cube & !bite | cube & !far");
  CHECK(products(parse_csg_scene(R"({"difference": ["cube", {"difference": ["bite", "far"]}]})")) ==
        "cube & !bite | cube & far");
  CHECK(products(parse_csg_scene(R"({"union": ["cube", "cube", "bite"]})")) == "cube | bite");
  const Scene s = parse_csg_scene(R"("cube")");
  REQUIRE(s.solids.size() == 3);
  CHECK(s.solids[1].first == 12);
  CHECK(s.solids[1].last == 24);
}

TEST_CASE("a CSG expression's expansion is bounded before the products are built", "[csg]") {
  // An intersection of a union of 200 solids with a union of 100,000: 2 x 10^7 products of
  // two literals were built before the count was checked (gigabytes).
  const int many = 100'000;
  std::vector<std::string> names(static_cast<std::size_t>(many));
  for (int k = 0; k < many; ++k) names[static_cast<std::size_t>(k)] = "s" + std::to_string(k);
  auto union_of = [](int first, int count) {
    CsgNode u;
    u.op = CsgNode::Op::union_;
    for (int k = 0; k < count; ++k) {
      CsgNode leaf;
      leaf.solid = first + k;
      u.operands.push_back(leaf);
    }
    return u;
  };
  CsgNode tree;
  tree.op = CsgNode::Op::intersection;
  tree.operands = {union_of(0, 200), union_of(0, many)};
  // (Before, the products were built and then counted: "more than 64 products".)
  CHECK_THROWS_WITH(normalise_csg(tree, names),
                    Catch::Contains("expands to more than 256 products (before duplicates"));
  // A union of many equal operands is as small as its distinct products.
  CsgNode copies;
  copies.op = CsgNode::Op::union_;
  for (int k = 0; k < 1000; ++k) copies.operands.push_back(union_of(0, 3));
  CHECK(normalise_csg(copies, names).size() == 3);
}

namespace {

// A random CSG tree over `solids` solids: operators with two to four operands, at most
// `depth` levels.
CsgNode random_csg_tree(std::mt19937& rng, int solids, int depth) {
  CsgNode n;
  if (depth == 0 || std::uniform_int_distribution<int>(0, 3)(rng) == 0) {
    n.solid = std::uniform_int_distribution<int>(0, solids - 1)(rng);
    return n;
  }
  static constexpr CsgNode::Op kOps[] = {CsgNode::Op::union_, CsgNode::Op::intersection,
                                         CsgNode::Op::difference};
  n.op = kOps[std::uniform_int_distribution<int>(0, 2)(rng)];
  const int count = std::uniform_int_distribution<int>(2, 4)(rng);
  for (int k = 0; k < count; ++k) n.operands.push_back(random_csg_tree(rng, solids, depth - 1));
  return n;
}

// The tree itself, evaluated on one classification of the point (no normalisation).
bool evaluate_csg_tree(const CsgNode& n, const std::vector<bool>& inside) {
  switch (n.op) {
    case CsgNode::Op::solid:
      return inside.at(static_cast<std::size_t>(n.solid));
    case CsgNode::Op::union_:
      for (const CsgNode& o : n.operands)
        if (evaluate_csg_tree(o, inside)) return true;
      return false;
    case CsgNode::Op::intersection:
      for (const CsgNode& o : n.operands)
        if (!evaluate_csg_tree(o, inside)) return false;
      return true;
    case CsgNode::Op::difference:
      if (!evaluate_csg_tree(n.operands.front(), inside)) return false;
      for (std::size_t k = 1; k < n.operands.size(); ++k)
        if (evaluate_csg_tree(n.operands[k], inside)) return false;
      return true;
  }
  return false;
}

}  // namespace

TEST_CASE("CSG normalisation equals the tree on random trees and point classifications", "[csg]") {
  // 5,000 seeded trees over 1..6 solids, up to 3 levels; each normalised sum of products is
  // evaluated on 64 random classifications of a point (each solid: inside or not) and
  // compared with the tree evaluated directly. A tree the normaliser refuses must be empty
  // (false everywhere: checked on every classification) or expand past kMaxCsgProducts.
  std::mt19937 rng(20261127);
  std::vector<std::string> names;
  for (int k = 0; k < 6; ++k) names.push_back(fmt::format("s{}", k));
  int normalised = 0, empty = 0, too_many = 0, classifications = 0;
  for (int t = 0; t < 5000; ++t) {
    const int solids = std::uniform_int_distribution<int>(1, 6)(rng);
    const CsgNode tree = random_csg_tree(rng, solids, 3);
    CsgProducts products;
    try {
      products = normalise_csg(tree, names);
    } catch (const CsgError& e) {
      const std::string what = e.what();
      if (what.find("expands") != std::string::npos) {
        ++too_many;
        continue;
      }
      INFO("tree " << t << ": " << what);
      REQUIRE(what.find("empty") != std::string::npos);
      for (unsigned bits = 0; bits < (1u << solids); ++bits) {
        std::vector<bool> inside(static_cast<std::size_t>(solids));
        for (int s = 0; s < solids; ++s) inside[s] = (bits >> s) & 1u;
        REQUIRE_FALSE(evaluate_csg_tree(tree, inside));
      }
      ++empty;
      continue;
    }
    ++normalised;
    INFO("tree " << t << " normalised to " << format_csg(products, names));
    REQUIRE(!products.empty());
    REQUIRE(products.size() <= kMaxCsgProducts);
    for (std::size_t p = 0; p < products.size(); ++p) {
      const auto& product = products[p];
      // The contract's form: a positive literal, no literal twice, no solid with its
      // complement, no product twice.
      REQUIRE(std::any_of(product.begin(), product.end(),
                          [](const CsgLiteral& l) { return !l.negated; }));
      for (std::size_t a = 0; a < product.size(); ++a)
        for (std::size_t b = a + 1; b < product.size(); ++b)
          REQUIRE(product[a].solid != product[b].solid);
      for (std::size_t q = 0; q < p; ++q) REQUIRE(products[q] != product);
    }
    std::bernoulli_distribution coin(0.5);
    for (int c = 0; c < 64; ++c) {
      std::vector<bool> inside(static_cast<std::size_t>(solids));
      for (int s = 0; s < solids; ++s) inside[s] = coin(rng);
      REQUIRE(csg_contains(products, inside) == evaluate_csg_tree(tree, inside));
      ++classifications;
    }
  }
  // The generator reaches every outcome, and mostly trees that normalise.
  CHECK(normalised > 3000);
  CHECK(empty > 0);
  CHECK(too_many > 0);
  CHECK(classifications == 64 * normalised);
}

TEST_CASE("bad CSG expressions in scene files are refused naming the file and key", "[csg]") {
  auto refused = [](const std::string& csg, const std::string& what) {
    INFO(csg);
    CHECK_THROWS_WITH(parse_csg_scene(csg), Catch::Contains("csg.json") && Catch::Contains(what));
  };
  refused(R"({"unoin": ["cube", "bite"]})",
          "unknown key 'csg.unoin' (expected one of: union, intersection, difference)");
  refused(R"({"difference": ["cube", "ball"]})",
          "key 'csg.difference[1]' names no mesh 'ball' (the named meshes: cube, bite, far)");
  refused(R"({"union": ["cube"]})", "key 'csg.union' must hold at least two operands (got 1)");
  refused(R"({"union": ["cube", "bite"], "intersection": ["cube", "far"]})",
          "key 'csg' must hold exactly one operator (got 2)");
  refused(R"({"union": ["cube", 3]})", "key 'csg.union[1]' must be a mesh name or an object");
  refused(R"({"difference": ["cube", "cube"]})", "key 'csg' the expression is empty");
  refused(R"({"union": "cube"})", "key 'csg.union' must be an array");
  std::string deep = "\"cube\"";
  for (int k = 0; k < 40; ++k) deep = "{\"union\": [" + deep + ", \"bite\"]}";
  refused(deep, "nests deeper than 32 operators");
  std::string text = csg_scene("\"cube\"");
  text.replace(text.find("\"bite\""), 6, "\"cube\"");
  CHECK_THROWS_WITH(
      parse_scene_json(text, "csg.json", "."),
      Catch::Contains("csg.json: key 'meshes[1].name' repeats the name 'cube' of mesh 0"));
}

TEST_CASE("the CSG ray caster finds the visible surface by interval merge", "[csg]") {
  // Rays off the faces' diagonals (a hit on a shared edge counts for both triangles).
  const glm::dvec3 down(0, 0, -1);
  const Scene minus = parse_csg_scene(R"({"difference": ["cube", "bite"]})");
  // Through the bite: its far face at z = 0.5 is the visible surface of cube - bite.
  CsgSurface h = csg_first_surface(minus, {0.1, 0.3, 5}, down);
  CHECK(h.solid == 1);
  CHECK(h.t == Approx(4.5));
  // Beside it: the cube's front face.
  h = csg_first_surface(minus, {0.8, 0.6, 5}, down);
  CHECK(h.solid == 0);
  CHECK(h.t == Approx(4.0));
  const Scene both = parse_csg_scene(R"({"intersection": ["cube", "bite"]})");
  h = csg_first_surface(both, {0.1, 0.3, 5}, down);
  CHECK(h.solid == 0);  // the cube's face at z = 1, inside the bite
  CHECK(h.t == Approx(4.0));
  CHECK(csg_first_surface(both, {0.8, 0.6, 5}, down).solid == -1);
  const Scene either = parse_csg_scene(R"({"union": ["cube", "bite"]})");
  h = csg_first_surface(either, {0.1, 0.3, 5}, down);
  CHECK(h.solid == 1);  // the bite's front face at z = 1.5
  CHECK(h.t == Approx(3.5));
  // From inside the bite (each solid's side at the origin comes from the parity of the hits
  // ahead): entering the cube at z = 1 is still in the bite; leaving the bite at z = 0.5 is.
  h = csg_first_surface(minus, {0.1, 0.3, 1.2}, down);
  CHECK(h.solid == 1);
  CHECK(h.t == Approx(0.7));
  // From inside the result, nothing is entered.
  CHECK(csg_first_surface(minus, {0.1, 0.3, 0}, {0, 0, 1}).solid == -1);
}

TEST_CASE("epsilon-regularised parity: a solid thinner than epsilon vanishes", "[csg]") {
  const MachineConfig config = small_screen();
  const Program plain = program_named("parity", config);
  const Program epsilon = program_named("parity_epsilon", config);
  const Scene slab = make_parity_scene("plane-slab");
  // Exact parity finds the slab's points (the ray caster too); with epsilon = the default
  // threshold, 1/512 of the depth range, none is inside: every point the ray caster finds
  // inside disagrees, and no other.
  const ParityMeasure exact = measure_parity(config, slab, plain, 2);
  CHECK(exact.inside > 50);
  CHECK(exact.disagree == 0);
  const ParityMeasure thin = measure_parity(config, slab, epsilon, 2);
  CHECK(thin.inside == exact.inside);
  CHECK(thin.disagree == thin.inside);
  // A thick solid stays, eroded by epsilon in depth only near its outline.
  const ParityMeasure ball = measure_parity(config, make_parity_scene("plane-sphere"), epsilon, 2);
  CHECK(ball.inside > 1000);
  CHECK(ball.disagree * 50 < ball.inside);
  // With epsilon 0 it is exact parity again (a face at exactly z + 0 is not behind).
  MachineConfig zero = config;
  zero.set(std::vector<std::string>{"frame.threshold=0"});
  CHECK(measure_parity(zero, slab, epsilon, 2).disagree == 0);
}

TEST_CASE("Goldfeather's pruning saves passes and draws the same pixels", "[csg]") {
  const MachineConfig config = small_screen();
  const Program program = program_named("csg", config);
  // The bar lies apart from the box and the ball: its literal goes from the first product
  // and the second product (bar & ball) goes whole: 13 passes become 4.
  const CsgPruning apart =
      measure_csg_pruning(config, make_parity_scene("box-minus-apart"), program, 2);
  CHECK(apart.pruned_expression == "box & !ball");
  CHECK(apart.passes_whole == 13);
  CHECK(apart.passes_pruned == 4);
  CHECK(apart.surface > 5000);
  CHECK(apart.differing == 0);
  CHECK(pruned_passes(program, make_parity_scene("box-minus-apart")) == 9);
  // Where every literal's box meets the others' (the ball and the bar both cut the box),
  // nothing is pruned and nothing changes.
  const CsgPruning two =
      measure_csg_pruning(config, make_parity_scene("box-minus-two"), program, 2);
  CHECK(two.passes_pruned == two.passes_whole);
  CHECK(two.differing == 0);
}

TEST_CASE("Rossignac's epsilon test at z + epsilon keeps what the erosion loses", "[csg]") {
  const MachineConfig config = small_screen();
  const Program plain = program_named("parity", config);
  const Program erosion = program_named("parity_epsilon", config);
  const Program behind = program_named("parity_behind", config);
  // Points inside a thick box, within epsilon below its top face: the ray caster and exact
  // parity find them inside; the erosion loses every one; the test at z + epsilon none.
  const Scene in = make_parity_scene("plane-in-box");
  const ParityMeasure exact_in = measure_parity(config, in, plain, 2);
  REQUIRE(exact_in.inside > 10000);
  CHECK(exact_in.disagree == 0);
  const ParityMeasure eroded_in = measure_parity(config, in, erosion, 2);
  CHECK(eroded_in.lost == exact_in.inside);
  const ParityMeasure behind_in = measure_parity(config, in, behind, 2);
  CHECK(behind_in.inside == exact_in.inside);
  CHECK(behind_in.disagree == 0);
  // Points within epsilon above the top face (nearly coincident faces, figure 9.4): outside
  // by the ray caster, exact parity and the erosion; inside by the test at z + epsilon, over
  // the whole face (as many points as the plane inside the box has, give or take the
  // outline's pixels).
  const Scene over = make_parity_scene("plane-over-box");
  CHECK(measure_parity(config, over, plain, 2).machine_inside == 0);
  CHECK(measure_parity(config, over, erosion, 2).machine_inside == 0);
  const ParityMeasure behind_over = measure_parity(config, over, behind, 2);
  CHECK(behind_over.gained == behind_over.machine_inside);
  CHECK(behind_over.gained > exact_in.inside * 99 / 100);
  CHECK(behind_over.gained < exact_in.inside * 103 / 100);
  // On a thick solid of the default table both stay within 1/1000 of the ray caster.
  const ParityMeasure ball = measure_parity(config, make_parity_scene("plane-sphere"), behind, 2);
  CHECK(ball.inside > 1000);
  CHECK(ball.disagree * 1000 < ball.inside);
  // With epsilon 0 it is exact parity again.
  MachineConfig zero = config;
  zero.set(std::vector<std::string>{"frame.threshold=0"});
  CHECK(measure_parity(zero, over, behind, 2).machine_inside == 0);
}

TEST_CASE("interference is found exactly when two solids overlap, and as epsilon says", "[csg]") {
  const MachineConfig config = small_screen();
  MachineConfig exact = config;
  exact.set(std::vector<std::string>{"frame.threshold=0"});
  for (const char* name : {"interference", "interference_accurate"}) {
    INFO(name);
    const Program program = program_named(name, config);
    const InterferenceMeasure overlap =
        measure_interference(config, make_parity_scene("boxes-overlap"), program, 2);
    CHECK(overlap.truth > 2000);
    CHECK(overlap.disagree == 0);
    // The table's counts are of one pixel set: with no disagreement they are equal.
    CHECK(overlap.flagged == overlap.truth);
    CHECK(overlap.flagged_uncertain > 0);
    CHECK(overlap.lo > 0);
    CHECK(overlap.lo < overlap.hi);
    for (const MachineConfig& c : {exact, config}) {
      const InterferenceMeasure apart =
          measure_interference(c, make_parity_scene("boxes-apart"), program, 2);
      CHECK(apart.flagged + apart.flagged_uncertain == 0);
    }
    // 0.0002 apart: no overlap (the ray caster finds none), but within the default epsilon.
    const InterferenceMeasure near =
        measure_interference(config, make_parity_scene("boxes-touching"), program, 2);
    CHECK(near.truth == 0);
    CHECK(near.flagged + near.flagged_uncertain > 100);
  }
  // With epsilon 0, the accurate program's unsnapped planes find no overlap in the
  // near-touching pair (at this screen the standard one's snapped steep faces flag 337
  // pixels: README).
  const InterferenceMeasure accurate =
      measure_interference(exact, make_parity_scene("boxes-touching"),
                           program_named("interference_accurate", config), 2);
  CHECK(accurate.flagged + accurate.flagged_uncertain == 0);
}

TEST_CASE("the CSG pass plan: a surface pass per literal, a parity pass per other literal",
          "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  const Program program = program_named("csg", config);
  check_pass_plan(program);
  // Triangle 0 in no solid; a: 1, 2; b: 3, 4; c: 5. (a & !b) | c.
  Scene scene;
  scene.solids = {{"a", 1, 3}, {"b", 3, 5}, {"c", 5, 6}};
  scene.mesh.triangles.resize(6);
  scene.csg = {{CsgLiteral{0, false}, CsgLiteral{1, true}}, {CsgLiteral{2, false}}};
  FrameValues values;
  set_pass_plan(program, scene, values);
  REQUIRE(values.plan.size() == 6);
  CHECK(values.closing == std::vector<Procedure>{Procedure::merge});
  // 1 and 3 turn their back to the eye, the others face it.
  std::vector<Packet> packets(6);
  for (int i = 0; i < 6; ++i) {
    Packet& p = packets[static_cast<std::size_t>(i)];
    p.primitive = i;
    p.group = scene.solid_of_triangle(i);
    p.back = i == 1 || i == 3;
  }
  const RegionStream stream(program, values);
  const std::vector<std::string> ran = procedures_run(stream, packets);
  const std::vector<std::string> expected = {
      "clear",        "triangle0", "candidate",                // the primitive in no solid
      "surface2",                                              // a's front faces
      "parity3",      "parity4",                               // classified against b
      "keep_outside", "merge",     "candidate",   "surface3",  // !b: b's back faces
      "parity1",      "parity2",   "keep_inside", "merge",     // classified against a
      "candidate",    "surface5",  "merge",                    // c alone
      "shade"};
  CHECK(ran == expected);

  // Without primitives in no solid, the first surface pass opens with clear.
  Scene solids_only = scene;
  solids_only.solids = {{"a", 0, 3}, {"b", 3, 5}, {"c", 5, 6}};
  const std::vector<PlannedPass> plan = make_pass_plan(program, solids_only);
  REQUIRE(plan.size() == 5);
  CHECK(plan[0].opening == std::vector<Procedure>{Procedure::clear, Procedure::candidate});
  CHECK(plan[0].faces == PlannedPass::Faces::front);
  CHECK(plan[2].faces == PlannedPass::Faces::back);
  CHECK(plan[1].faces == PlannedPass::Faces::all);

  // No CSG expression: no plan, every primitive drawn by its own procedure.
  Scene plain = scene;
  plain.csg.clear();
  CHECK(make_pass_plan(program, plain).empty());
}

TEST_CASE("surface may use only what the triangle's packets carry", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  const Program program =
      program_edited("csg", "  qload cnz, nz\n", "  qload cnz, nz\n  qload cz, eye_depth\n",
                     "bad-surface", config);
  CHECK_THROWS_WITH(
      check_pass_plan(program),
      Catch::Contains("'surface' uses expression 'eye_depth'") && Catch::Contains("bad-surface"));
}

TEST_CASE("CSG rendering agrees with the ray caster on convex solids", "[csg]") {
  // 256 x 256: every scene of convex solids agrees at every compared pixel (coverage, and
  // depth within the stated tolerance); the non-convex one shows the algorithm's limit.
  const MachineConfig config = small_screen();
  for (const char* program_name : {"csg", "csg_accurate"}) {
    const Program program = program_named(program_name, config);
    for (const std::string& name : csg_scene_names()) {
      INFO(name << " with " << program_name);
      const Scene scene = make_parity_scene(name);
      const CsgMeasure m = measure_csg(config, scene, program, 2);
      int passes = 0;
      for (const auto& product : scene.csg)
        passes += static_cast<int>(product.size() * product.size());
      CHECK(m.passes == passes);
      CHECK(m.bits <= 208);
      CHECK(m.compared > 256 * 256 * 9 / 10);
      CHECK(m.surface > 256 * 256 / 5);
      if (name == "pair-minus-bar") {
        // Through the hole in the upper slab the ray caster sees the lower one; the machine
        // keeps only each literal's nearest surface, both discarded there: background.
        CHECK(m.disagree == m.coverage);
        CHECK(m.disagree > 1000);
      } else {
        CHECK(m.disagree == 0);
        // Unsnapped planes: the depth shown is the exact one, to the integer depth, but where
        // two solids' surfaces cross within a pixel (either may show, within the tolerance).
        if (std::string(program_name) == "csg_accurate") CHECK(m.median_depth_error < 1.0);
      }
    }
  }
}

TEST_CASE("CSG rendering that peels layers agrees with the ray caster on every scene", "[csg]") {
  // csg_layers peels `layers` (4) surfaces of each literal of a product: the non-convex
  // slabs' lower top face, behind the discarded upper one, is the second round's candidate.
  MachineConfig config = small_screen();
  const Program program = program_named("csg_layers", config);
  for (const std::string& name : csg_scene_names()) {
    INFO(name);
    const Scene scene = make_parity_scene(name);
    const CsgMeasure m = measure_csg(config, scene, program, 2);
    int passes = 0;
    for (const auto& product : scene.csg) {
      const auto n = static_cast<int>(product.size());
      passes += n * n * (n > 1 ? 4 : 1);
    }
    CHECK(m.passes == passes);
    CHECK(m.compared > 256 * 256 * 9 / 10);
    CHECK(m.disagree == 0);
  }
  // One layer is csg.pp5's algorithm: the hole in the upper slab shows background again.
  config.set(std::vector<std::string>{"frame.layers=1"});
  const CsgMeasure one = measure_csg(config, make_parity_scene("pair-minus-bar"), program, 2);
  CHECK(one.passes == 4);
  CHECK(one.disagree == one.coverage);
  CHECK(one.disagree > 1000);
}

TEST_CASE("the peeling CSG plan repeats each literal's passes per layer", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  const Program program = program_named("csg_layers", config);
  Scene scene;
  scene.solids = {{"a", 0, 2}, {"b", 2, 4}, {"c", 4, 6}};
  scene.mesh.triangles.resize(6);
  scene.csg = {{CsgLiteral{0, false}, CsgLiteral{1, true}}, {CsgLiteral{2, false}}};
  FrameValues values;
  values.frame.parameters[static_cast<std::size_t>(Parameter::layers)] = 2;
  set_pass_plan(program, scene, values);
  // a & !b: a twice (surface, parity of b), !b twice (surface, parity of a); c once.
  REQUIRE(values.plan.size() == 9);
  using P = Procedure;
  CHECK(values.plan[0].opening == std::vector<P>{P::clear, P::candidate});
  CHECK(values.plan[2].opening == std::vector<P>{P::keep_outside, P::merge, P::next_layer});
  CHECK(values.plan[2].group == 0);
  CHECK(values.plan[4].opening == std::vector<P>{P::keep_outside, P::merge, P::candidate});
  CHECK(values.plan[4].faces == PlannedPass::Faces::back);
  CHECK(values.plan[6].opening == std::vector<P>{P::keep_inside, P::merge, P::next_layer});
  CHECK(values.plan[8].opening == std::vector<P>{P::keep_inside, P::merge, P::candidate});
  CHECK(values.plan[8].group == 2);
  CHECK(values.closing == std::vector<P>{P::merge});
  // Without frame parameters (make_pass_plan): one layer.
  CHECK(make_pass_plan(program, scene).size() == 5);
}

TEST_CASE("CSG rendering without classification is caught by the comparison", "[csg]") {
  // Folds that keep every candidate: the box's faces hide the bite the ball takes (depth
  // disagrees), and the inside of the ball shows where it sticks out of the box (coverage).
  const MachineConfig config = small_screen();
  std::string source = read_regular_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/csg.pp5",
                                         1 << 20, "a firmware program");
  for (const std::string fold : {"proc keep_inside\n", "proc keep_outside\n"}) {
    const std::size_t at = source.find(fold);
    REQUIRE(at != std::string::npos);
    source.replace(at, source.find("end\n", at) + 4 - at, "");
  }
  const Program broken = assemble(source, "csg-unclassified", assembler_options(config));
  const Program good = program_named("csg", config);
  const Scene scene = make_parity_scene("box-minus-ball");
  const CsgMeasure m = measure_csg(config, scene, broken, 2);
  CHECK(m.disagree > 2000);
  CHECK(m.coverage > 1000);
  CHECK(m.disagree - m.coverage > 1000);
  CHECK(measure_csg(config, scene, good, 2).disagree == 0);
}

TEST_CASE("CSG with quadric spheres as solids agrees with the ray caster to the depth bound",
          "[csg][quadric]") {
  // A sphere of a solid travels as two packets, its near hemisphere a front face and its far
  // one a back face, and runs sphere_surface and sphere_parity. The lens of two quadric
  // spheres agrees everywhere. Where the quadric ball leaves the box, the far hemisphere's
  // approximate depth (off by up to ScreenSphere::depth_bound, largest at the rim) decides
  // which of it lies inside the box there: a thin crescent disagrees, stated here as under 2%
  // of the surface.
  const MachineConfig config = small_screen();
  const Program program = program_named("csg", config);
  for (const std::string& name : csg_quadric_scene_names()) {
    INFO(name);
    const Scene scene = make_parity_scene(name);
    REQUIRE(scene.spheres.size() >= 1);
    const CsgMeasure m = measure_csg(config, scene, program, 2);
    CHECK(m.passes == 4);
    CHECK(m.compared > 256 * 256 * 9 / 10);
    CHECK(m.surface > 256 * 256 / 10);
    if (name == "quadric-lens") {
      CHECK(m.disagree == 0);
    } else {
      CHECK(m.disagree > 0);
      CHECK(m.disagree * 50 < m.surface);
    }
    // The machine's frame and the field readout walk the same plan.
    const FrameResult frame = simulate_frame(config, scene, program, 2);
    const FieldFrame field = render_field(config, scene, program, "z", 2);
    CHECK(frame.image.flat().rgb == field.image.rgb);
  }
  {
    // Each sphere of a solid is two packets per region it touches; out of its solid, one.
    Scene loose = make_parity_scene("quadric-lens");
    const Scene solid = loose;
    for (Solid& s : loose.solids) s.last_sphere = s.first_sphere;
    const Program phong = program_named("phong", config);
    CHECK(render_field(config, solid, phong, "z", 2).packets ==
          2 * render_field(config, loose, phong, "z", 2).packets);
  }
  // Without sphere_parity the spheres classify nothing: the box keeps the bite, the lens
  // shows each whole ball.
  const Program broken = program_edited("csg", "  qcmp.gt cz, sphere_depth\n  xor par, 1\n", "",
                                        "csg-no-sphere-parity", config);
  for (const std::string& name : csg_quadric_scene_names()) {
    INFO(name);
    CHECK(measure_csg(config, make_parity_scene(name), broken, 2).disagree > 2000);
  }
  // A program without the sphere procedures is refused for such a scene, naming what it lacks.
  CHECK_THROWS_WITH(
      measure_csg(config, make_parity_scene("quadric-lens"), program_named("csg_layers", config),
                  2),
      Catch::Contains("does not define 'sphere_surface'") && Catch::Contains("'left'"));
}

TEST_CASE("the sphere counterparts may use only what the sphere's packets carry", "[csg]") {
  const Program program = assemble(
      "field z 24\nfield r 8\nfield g 8\nfield b 8\nfield par 1\noutput r g b\nproc "
      "triangle\nend\nproc sphere\n  "
      "qtest.ge sphere_inside\nend\n"
      "proc surface\nend\nproc sphere_parity\n  qcmp.gt z, sphere_depth\n  xor par, 1\nend\n",
      "bad-sphere-parity", assembler_options(MachineConfig::defaults()));
  CHECK_THROWS_WITH(check_pass_plan(program),
                    Catch::Contains("'sphere_parity' uses expression 'sphere_depth'") &&
                        Catch::Contains("procedure 'sphere' does not"));
}

TEST_CASE("a CSG frame is the same image however the plan is walked", "[csg]") {
  // The machine's frame (event-driven timing, then execution, with empty-region reuse) and
  // the field readout walk the same plan: the same pixels.
  const MachineConfig config = small_screen();
  const Program program = program_named("csg", config);
  for (const char* name : {"box-minus-two", "box-or-ball"}) {
    INFO(name);
    const Scene scene = make_parity_scene(name);
    const FrameResult frame = simulate_frame(config, scene, program, 2);
    const FieldFrame field = render_field(config, scene, program, "z", 2);
    CHECK(frame.image.flat().rgb == field.image.rgb);
    CHECK(frame.stats.integer("renderers_total.busy_cycles") > 0);
  }
}

TEST_CASE("transparency front to back and back to front agree with every layer composited",
          "[csg][transparency]") {
  // An opaque torus in a glass sphere: up to six layers a pixel.
  const Scene scene = load_scene(std::string(PP5_SOURCE_DIR) + "/examples/scenes/glass.json");
  MachineConfig config = small_screen();
  config.set(std::vector<std::string>{"frame.layers=8"});
  for (const char* name : {"transparent", "transparent_interval"}) {
    INFO(name);
    const TransparencyMeasure m =
        measure_transparency(config, scene, program_named(name, config), 2);
    CHECK(m.layers == 8);
    CHECK(m.compared > 256 * 256 * 9 / 10);
    CHECK(m.covered > 256 * 256 / 3);
    CHECK(m.most >= 5);
    CHECK(m.too_many == 0);
    CHECK(m.differ == 0);
    CHECK(m.max_error <= kTransparencyTolerance);
  }
}

TEST_CASE("back to front with too few layers drops the front ones", "[csg][transparency]") {
  const Scene scene = load_scene(std::string(PP5_SOURCE_DIR) + "/examples/scenes/glass.json");
  MachineConfig config = small_screen();
  config.set(std::vector<std::string>{"frame.layers=4"});
  const TransparencyMeasure front =
      measure_transparency(config, scene, program_named("transparent", config), 2);
  const TransparencyMeasure back =
      measure_transparency(config, scene, program_named("transparent_interval", config), 2);
  // Where the glass and the torus give more than four layers, the front ones are the glass
  // and the opaque torus: front to back loses only what the torus hides; back to front loses
  // the torus's near side and shows its far inside.
  REQUIRE(front.too_many > 500);
  CHECK(front.differ == 0);
  CHECK(back.too_many == front.too_many);
  CHECK(back.differ > back.too_many * 9 / 10);
  CHECK(back.differ <= back.too_many);  // nowhere else
  CHECK(back.max_error_within <= kTransparencyTolerance);
  CHECK(back.max_error > 50);
}

TEST_CASE("a cross-section is capped exactly where the ray caster sees the cut", "[csg][section]") {
  const MachineConfig config = small_screen();
  for (const std::string& name : section_scene_names()) {
    for (const char* program : {"section", "section_accurate"}) {
      INFO(name << " with " << program);
      const Scene scene = make_parity_scene(name);
      const SectionMeasure m = measure_section(config, scene, program_named(program, config), 2);
      // Most of the screen is compared; the cap, and the solid behind the plane, both show.
      CHECK(m.surface.compared > 256 * 256 * 8 / 10);
      CHECK(m.cap > 256 * 256 / 40);
      CHECK(m.surface.surface > m.cap + 256 * 256 / 100);
      CHECK(m.cap_disagree == 0);
      CHECK(m.surface.disagree == 0);
      CHECK(m.surface.passes == 2);
      // Unsnapped planes: the shown depth is the exact one to the integer depth (floor) and
      // the GP's single-precision plane.
      if (std::string(program) == "section_accurate") CHECK(m.surface.max_depth_error < 1.5);
    }
  }
}

TEST_CASE("a cross-section without the parity is caught by the comparison", "[csg][section]") {
  // No parity toggles: nothing is inside, the cap is missing and the solid's far inside shows.
  const MachineConfig config = small_screen();
  const Program broken =
      program_edited("section", "  xor par, 1\n", "", "section-without-parity", config);
  for (const std::string& name : section_scene_names()) {
    INFO(name);
    const SectionMeasure m = measure_section(config, make_parity_scene(name), broken, 2);
    CHECK(m.cap > 0);
    CHECK(m.cap_disagree == m.cap);
    CHECK(m.surface.disagree >= m.cap);
  }
}

TEST_CASE("the csg tables come from the report writer with the text they always had", "[csg]") {
  // A pruning row and a transparency row, as `pp5sim csg` printed them when it formatted its
  // Markdown by hand: headings, alignment, a union's '|' escaped inside backticks, the cost
  // columns' precision. The CSV keeps the values.
  CsgPruning p;
  p.scene = "s";
  p.program = "csg";
  p.expression = "a | b";
  p.pruned_expression = "a";
  p.passes_whole = 6;
  p.passes_pruned = 4;
  p.surface = 100;
  p.cost_whole = {1000, 0.002};
  p.cost_pruned = {800, 0.001};
  const report::Table pruning = csg_pruning_table({p});
  CHECK(report::markdown(pruning) ==
        "| scene | program | expression | pruned | passes unpruned | passes pruned | passes saved "
        "| pixels with a surface | pixels differing (z) | unpruned: Renderer cycles | frame ms | "
        "frames/s | pruned: Renderer cycles | frame ms | frames/s |\n"
        "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
        "| s | csg | `a \\| b` | `a` | 6 | 4 | 2 | 100 | 0 | 1000 | 2.000 | 500.0 | 800 | 1.000 | "
        "1000.0 |\n");
  CHECK_THAT(report::csv(pruning),
             Catch::Contains("s,csg,a | b,a,6,4,2,100,0,1000,2,500,800,1,1000"));
  TransparencyMeasure t;
  t.scene = "glass";
  t.program = "transparent";
  t.layers = 2;
  t.compared = 10;
  t.covered = 8;
  t.too_many = 3;
  t.most = 6;
  t.max_error = 2.3;
  t.max_error_within = 1;
  t.bits = 173;
  t.cost = {5, 0.5};
  CHECK(report::markdown(transparency_table({t})) ==
        "| application | scene | program | layers (passes) | pixels compared | with a surface | "
        "with more layers than passes (most) | differing by more than 3 of 255 | largest error | "
        "largest error where layers <= passes | near an outline (not compared) | bits | "
        "Renderer cycles | frame ms | frames/s |\n"
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
        "| transparency | glass | transparent | 2 | 10 | 8 | 3 (6) | 0 | 2.3 | 1.0 | 0 | 173 | 5 | "
        "500.000 | 2.0 |\n");
}
