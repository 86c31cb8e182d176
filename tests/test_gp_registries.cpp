// The GP's registries: expressions (models/gp/expressions.hpp) and primitive kinds
// (models/gp/primitive_kind.hpp).
#include <catch2/catch.hpp>
#include <cstring>
#include <memory>
#include <vector>

#include "models/config/machine_config.hpp"
#include "models/gp/expressions.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/machine.hpp"
#include "sim/scene/scene.hpp"

using namespace pp5;

namespace {

GeometryParams small_params() {
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 256;
  c.screen.height = 256;
  return geometry_params(c);
}

ExpressionSet all_expressions() {
  ExpressionSet s;
  s.set();
  return s;
}

}  // namespace

TEST_CASE("expression registry: one entry per Expression, named as the firmware names it",
          "[gp_registry]") {
  const auto& reg = expression_registry();
  REQUIRE(reg.size() == static_cast<std::size_t>(Expression::count));
  for (int k = 0; k < static_cast<int>(Expression::count); ++k) {
    CHECK(static_cast<int>(reg[static_cast<std::size_t>(k)].id) == k);
    CHECK(std::strcmp(reg[static_cast<std::size_t>(k)].name(), kExpressions[k].name) == 0);
    CHECK(expression_index(reg[static_cast<std::size_t>(k)].name()) == k);
    CHECK(reg[static_cast<std::size_t>(k)].compute != nullptr);
    // The cost model charges the entry's count.
    const OpCounts a = I860Work::expression_setup(static_cast<Expression>(k));
    const OpCounts& b = reg[static_cast<std::size_t>(k)].cost;
    CHECK(a.fadd == b.fadd);
    CHECK(a.fmul == b.fmul);
    CHECK(a.store == b.store);
    CHECK(a.chains == b.chains);
  }
  CHECK(expression_entry(Expression::flat_red).form == ExpressionForm::constant);
  CHECK(expression_entry(Expression::slope_y).form == ExpressionForm::constant);
  CHECK(expression_entry(Expression::depth).form == ExpressionForm::linear);
  CHECK(coefficients(ExpressionForm::constant) == 1);
  CHECK(coefficients(ExpressionForm::linear) == 3);
  CHECK(coefficients(ExpressionForm::quadratic) == 6);
  // Only accurate scan conversion's side tests read the adjacency, so set-up builds it only
  // for a program that sends them.
  for (int k = 0; k < static_cast<int>(Expression::count); ++k) {
    const auto e = static_cast<Expression>(k);
    ExpressionSet one;
    one.set(static_cast<std::size_t>(k));
    CHECK(needs_adjacency(one) ==
          (e == Expression::side0 || e == Expression::side1 || e == Expression::side2));
  }
}

TEST_CASE("expression registry: every coefficient set-up writes respects its form",
          "[gp_registry]") {
  const Scene scene = make_builtin_scene("torus", {32, 8});
  const GeometryEngine engine(small_params(), scene);
  SetupCounts counts;
  std::vector<ScreenTriangle> screen;
  int checked = 0;
  for (int i = 0; i < static_cast<int>(scene.mesh.triangles.size()); ++i) {
    screen.clear();
    engine.transform(i, screen, counts);
    for (const ScreenTriangle& t : screen) {
      SetupResult r;
      if (!engine.setup(t, all_expressions(), r, counts)) continue;
      ++checked;
      for (const ExpressionEntry& e : expression_registry()) {
        const QuadraticCoefficients& q = r.values.expressions[static_cast<std::size_t>(e.id)];
        if (e.form != ExpressionForm::quadratic) {
          CHECK(q.is_linear());
        }
        if (e.form == ExpressionForm::constant) {
          CHECK(q.D == 0);
          CHECK(q.E == 0);
        }
      }
      // Edges carry a gradient on any triangle with area.
      const QuadraticCoefficients& e0 =
          r.values.expressions[static_cast<std::size_t>(Expression::edge0)];
      CHECK((e0.D != 0 || e0.E != 0));
    }
  }
  CHECK(checked > 100);
}

TEST_CASE("GeometryEngine::setup computes only the expressions asked for", "[gp_registry]") {
  const Scene scene = make_builtin_scene("two-triangles");
  const GeometryEngine engine(small_params(), scene);
  ExpressionSet needed;
  needed.set(static_cast<int>(Expression::edge1));
  needed.set(static_cast<int>(Expression::flat_green));
  SetupCounts counts;
  std::vector<ScreenTriangle> screen;
  engine.transform(0, screen, counts);
  REQUIRE_FALSE(screen.empty());
  SetupResult some;
  SetupResult all;
  REQUIRE(engine.setup(screen[0], needed, some, counts));
  REQUIRE(engine.setup(screen[0], all_expressions(), all, counts));
  for (int k = 0; k < static_cast<int>(Expression::count); ++k) {
    const QuadraticCoefficients& q = some.values.expressions[static_cast<std::size_t>(k)];
    const QuadraticCoefficients& a = all.values.expressions[static_cast<std::size_t>(k)];
    if (needed.test(k)) {
      // The same coefficients whatever else is computed with them.
      CHECK(q.D == a.D);
      CHECK(q.E == a.E);
      CHECK(q.F == a.F);
    } else {
      CHECK((q.D == 0 && q.E == 0 && q.F == 0));
    }
  }
  CHECK(some.values.expressions[static_cast<std::size_t>(Expression::flat_green)].F != 0);
}

TEST_CASE("depth_minus/plus_threshold are depth's plane offset by the frame's threshold",
          "[gp_registry]") {
  Scene scene = make_builtin_scene("two-triangles");
  scene.parameters["threshold"] = 12345;
  const GeometryEngine engine(small_params(), scene);
  ExpressionSet needed;
  needed.set(static_cast<int>(Expression::depth));
  needed.set(static_cast<int>(Expression::depth_minus_threshold));
  needed.set(static_cast<int>(Expression::depth_plus_threshold));
  CHECK(needs_frame_parameters(needed));
  SetupCounts counts;
  std::vector<ScreenTriangle> screen;
  engine.transform(0, screen, counts);
  REQUIRE_FALSE(screen.empty());
  SetupResult r;
  REQUIRE(engine.setup(screen[0], needed, r, counts));
  const auto at = [&](Expression e) { return r.values.expressions[static_cast<std::size_t>(e)]; };
  const std::int64_t offset = std::int64_t{12345} << small_params().fraction_bits;
  for (const auto& [e, sign] : {std::pair{Expression::depth_minus_threshold, -1},
                                std::pair{Expression::depth_plus_threshold, 1}}) {
    CHECK(at(e).D == at(Expression::depth).D);
    CHECK(at(e).E == at(Expression::depth).E);
    CHECK(at(e).F == at(Expression::depth).F + sign * offset);
  }
}

TEST_CASE("primitive kinds: the triangle kind runs the triangle procedure on the mesh",
          "[gp_registry]") {
  const auto& kinds = primitive_kinds();
  REQUIRE(kinds.size() >= 1);
  const PrimitiveKind& tri = *kinds[kTriangleKind];
  CHECK(std::strcmp(tri.name(), "triangle") == 0);
  CHECK(tri.procedure() == Procedure::triangle);

  const Scene scene = make_builtin_scene("sphere", {12, 6});
  const GeometryEngine engine(small_params(), scene);
  CHECK(tri.count(scene) == static_cast<int>(scene.mesh.triangles.size()));
  const DisplayList& list = engine.display_list();
  REQUIRE(list.size() == static_cast<int>(scene.mesh.triangles.size()));

  // The kind's worker gives what GeometryEngine gives, piece by piece, and its cost is the
  // triangle's.
  std::unique_ptr<PrimitiveWorker> worker = tri.start(engine);
  SetupCounts a;
  SetupCounts b;
  std::vector<ScreenTriangle> screen;
  std::vector<int> ra;
  std::vector<int> rb;
  for (int i = 0; i < list.size(); ++i) {
    const PrimitiveRef ref = list.at(i);
    REQUIRE(ref.kind == kTriangleKind);
    REQUIRE(ref.index == i);
    const int pieces = worker->transform(ref.index, a);
    screen.clear();
    engine.transform(i, screen, b);
    REQUIRE(pieces == static_cast<int>(screen.size()));
    for (int p = 0; p < pieces; ++p) {
      SetupResult x;
      SetupResult y;
      const bool ok = worker->setup(p, all_expressions(), x, a);
      REQUIRE(ok == engine.setup(screen[static_cast<std::size_t>(p)], all_expressions(), y, b));
      if (!ok) continue;
      CHECK(x.x_min == y.x_min);
      CHECK(x.y_max == y.y_max);
      ra.clear();
      rb.clear();
      worker->bin(x, ra);
      engine.bin(y, rb);
      CHECK(ra == rb);
    }
  }
  CHECK(a.degenerate == b.degenerate);
  CHECK(a.no_pixels == b.no_pixels);

  GpWorkload w;
  w.expressions = all_expressions();
  w.packet_words = 61;
  const OpCounts k = tri.operations(w, PrimitiveTally{2, 2, 3});
  const OpCounts t = I860Work::triangle(w, 2, 2, 3);
  CHECK(k.fadd == t.fadd);
  CHECK(k.store == t.store);
  CHECK(k.chains == t.chains);
}

TEST_CASE("the GP's arithmetic reaches every expression of every primitive kind", "[gp_registry]") {
  // gp.significand_bits is said to round every value the GP sends. Walk both registries:
  // every expression a kind supplies must have some coefficient, on some primitive of a
  // scene, that changes when the GP keeps 6 significant bits instead of all of them (62, the
  // default: exact; the goldens hold the default's results). A new expression whose set-up
  // forgets the GP's arithmetic fails here.
  Scene scene = make_builtin_scene("torus", {32, 8});
  const glm::vec3 centre = scene.camera.target;
  // Colours and opacities of more than 6 significant bits (255 x 0.35 = 89: 1011001).
  scene.spheres = {{centre + glm::vec3(0.3f, 0.2f, 0.4f), 0.45f, glm::vec3(0.9f, 0.4f, 0.35f)},
                   {centre + glm::vec3(-0.5f, -0.3f, 0.2f), 0.3f, glm::vec3(0.37f, 0.7f, 0.5f)}};
  for (std::size_t v = 0; v < scene.mesh.vertices.size(); ++v)
    scene.mesh.vertices[v].opacity = 0.3f + 0.5f * static_cast<float>(v % 7) / 7.0f;
  MachineConfig exact = MachineConfig::defaults();
  exact.set(std::vector<std::string>{"screen.width=256", "screen.height=256"});
  MachineConfig coarse = exact;
  coarse.set(std::vector<std::string>{"gp.significand_bits=6"});
  MachineConfig alias = exact;
  alias.set(std::vector<std::string>{"gp.edge_significand_bits=6"});
  CHECK(geometry_params(alias).significand_bits == 6);
  CHECK(geometry_params(exact).significand_bits == 62);
  const GeometryEngine e_exact(geometry_params(exact), scene);
  const GeometryEngine e_coarse(geometry_params(coarse), scene);
  for (const PrimitiveKind* kind : primitive_kinds()) {
    INFO("kind " << kind->name());
    std::unique_ptr<PrimitiveWorker> a = kind->start(e_exact);
    std::unique_ptr<PrimitiveWorker> b = kind->start(e_coarse);
    std::vector<int> moved(static_cast<std::size_t>(Expression::count), 0);
    // Whether every coefficient of the exact set-up already fits 6 significant bits (a small
    // integer such as sphere_root_shift, 0..15): then rounding cannot move it.
    std::vector<int> fits(static_cast<std::size_t>(Expression::count), 1);
    auto six_bits = [](std::int64_t v) {
      std::uint64_t m = v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
      while (m != 0 && (m & 1) == 0) m >>= 1;
      return m < 64;
    };
    int both = 0;
    SetupCounts ca, cb;
    for (int i = 0; i < kind->count(scene); ++i) {
      const int pieces = a->transform(i, ca);
      REQUIRE(pieces == b->transform(i, cb));
      for (int p = 0; p < pieces; ++p) {
        SetupResult x, y;
        if (!a->setup(p, all_expressions(), x, ca) || !b->setup(p, all_expressions(), y, cb))
          continue;
        ++both;
        for (int k = 0; k < static_cast<int>(Expression::count); ++k) {
          const auto& q = x.values.expressions[static_cast<std::size_t>(k)];
          const auto& r = y.values.expressions[static_cast<std::size_t>(k)];
          moved[static_cast<std::size_t>(k)] +=
              q.A != r.A || q.B != r.B || q.C != r.C || q.D != r.D || q.E != r.E || q.F != r.F;
          if (!(six_bits(q.A) && six_bits(q.B) && six_bits(q.C) && six_bits(q.D) && six_bits(q.E) &&
                six_bits(q.F)))
            fits[static_cast<std::size_t>(k)] = 0;
        }
      }
    }
    CHECK(both > 1);
    for (const ExpressionEntry& e : expression_registry()) {
      if (!kind->supplies(e.id)) continue;
      INFO("expression " << e.name());
      CHECK((moved[static_cast<std::size_t>(e.id)] > 0 || fits[static_cast<std::size_t>(e.id)]));
    }
  }
}

TEST_CASE("packet words follow the forms: a header, then 1, 3 or 6 coefficients each",
          "[gp_registry]") {
  ExpressionSet edges;
  for (Expression e : {Expression::edge0, Expression::edge1, Expression::edge2}) {
    edges.set(static_cast<int>(e));
  }
  CHECK(coefficient_words(40, 32) == 2);
  CHECK(coefficient_words(32, 32) == 1);
  CHECK(packet_words(ExpressionSet{}, 2) == 1);
  CHECK(packet_words(edges, 2) == 1 + 3 * 3 * 2);
  ExpressionSet flat = edges;
  for (Expression e : {Expression::flat_red, Expression::flat_green, Expression::flat_blue}) {
    flat.set(static_cast<int>(e));
  }
  CHECK(packet_words(flat, 2) == 1 + (3 * 3 + 3 * 1) * 2);
  CHECK(packet_words(flat, 1) == 1 + 3 * 3 + 3 * 1);
  ExpressionSet slopes = edges;
  slopes.set(static_cast<int>(Expression::depth));
  slopes.set(static_cast<int>(Expression::slope_x));
  slopes.set(static_cast<int>(Expression::slope_y));
  CHECK(packet_words(slopes, 2) == 1 + (4 * 3 + 2 * 1) * 2);
}
