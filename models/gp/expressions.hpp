#pragma once
// The GP-side expression registry: one entry per value the GP can send with a primitive
// (firmware/isa/interface.hpp's Expression, whose kExpressions gives each its name and
// meaning: the firmware's contract). An entry adds what the GP needs to compute and send
// it: its form (how many coefficients travel), its i860 operation cost, and the function
// that computes its coefficients from a set-up context.
//
// Contract:
//  - expression_registry()[k].id == Expression(k): one entry per Expression, in enum order.
//  - compute(context, out) writes the expression's coefficients and returns true, or returns
//    false when a coefficient does not fit evaluator.coefficient_bits (the GP then drops
//    the primitive and counts it as `overflow`). It reads only the context: results are a
//    pure function of the primitive, the scene and the machine parameters. Its one side
//    effect may be a count of its own in context.counts (the side tests' SetupCounts::sides).
//  - The form bounds what compute may write: a constant sets only F, a linear expression D,
//    E and F (value D x + E y + F), a quadratic one any of the six. The packet carries
//    coefficients(form) coefficients for it.
//  - An entry with needs_adjacency reads context.adjacency (never null for it): the GP
//    builds the scene's mesh adjacency once, and only when such an expression is needed.
//  - An entry with widens may admit pixel centres up to half a snapped unit outside the
//    snapped triangle; set-up bins the triangle to every region such a centre lies in, and
//    does not drop a triangle that snapping flattens (SetupContext::area2 == 0).
//  - cost is charged once per set-up of a primitive whose procedure uses the expression
//    (I860Work::expression_setup).
#include <array>
#include <bitset>
#include <cstdint>
#include <utility>

#include "firmware/isa/interface.hpp"
#include "models/display_list/mesh_adjacency.hpp"
#include "models/display_list/scene.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"

namespace pp5 {

enum class ExpressionForm { constant, linear, quadratic };
const char* expression_form_name(ExpressionForm form);
// Coefficients a packet carries for an expression of this form: 1, 3 or 6.
int coefficients(ExpressionForm form);

// What an expression's set-up may read: the primitive on the screen (here a triangle; a
// kind with another shape adds its own member), its snapped vertices and the quantities
// every attribute plane shares, computed once per primitive by GeometryEngine::setup.
struct ScreenSphere;
struct SetupContext {
  const GeometryParams& params;
  const Camera& camera;
  const ScreenTriangle& triangle;
  // The scene mesh's face/face adjacency (triangle.source indexes it), or null when no
  // needed expression asks for it. A clipped triangle is one piece of triangle.source: its
  // edges need not be the source's.
  const MeshAdjacency* adjacency = nullptr;
  // The scene's mesh (its vertices' positions), set together with adjacency: a neighbour's
  // plane is computed from the neighbour's own vertices.
  const Mesh* mesh = nullptr;
  // Where an entry counts what it decided (SetupCounts::sides); null when nobody counts.
  SetupCounts* counts = nullptr;
  // The frame's parameters (light 0's), set when a needed expression folds one in
  // (ExpressionEntry::reads_frame); null otherwise.
  const ParameterValues* frame = nullptr;
  // The sphere being set up (the sphere kind, models/gp/sphere.hpp), or null for a triangle:
  // only the sphere_* entries read it, and only the sphere kind asks for them.
  const ScreenSphere* sphere = nullptr;

  // Vertices snapped to 1/scale pixel (scale = 2^subpixel_bits), half = scale / 2.
  std::array<std::int64_t, 3> xs{};
  std::array<std::int64_t, 3> ys{};
  std::int64_t scale = 1;
  std::int64_t half = 0;
  std::int64_t area2 = 0;  // twice the signed area, in snapped units; 0 only if widens
  // Vertices in pixel-index coordinates (the centre of pixel X is at X + 0.5, so a vertex at
  // x sits at index coordinate x - 0.5), and the determinant of their plane system.
  std::array<double, 3> u{};
  std::array<double, 3> w{};
  double det = 0;
  double f_scale = 1;    // 2^fraction_bits
  double depth_max = 0;  // 2^depth_bits - 1

  // The gradient (per pixel in x and y) of the plane through the three vertices' values f.
  std::pair<double, double> gradient(const std::array<double, 3>& f) const;
  // The fixed-point plane through the vertices' values f, exact (to rounding) at vertex 0,
  // each coefficient kept to the GP's arithmetic (gp_round) before C is reduced modulo the
  // coefficient width; false if a coefficient does not fit.
  bool plane(const std::array<double, 3>& f, QuadraticCoefficients& out) const;
  // Edge e's function (from vertex e to vertex (e + 1) % 3) on the snapped vertices: exact
  // integers, >= 0 inside. `outward` (value units, >= 0) moves the line outward; with
  // top_left_rule a centre exactly on the (unmoved) edge belongs to the triangle only on a
  // left or top edge. Each coefficient is then kept to params.significand_bits (gp_round; a
  // moved-out line first moved out by the rounding's reach too). False if a coefficient
  // does not fit.
  bool edge(int e, std::int64_t outward, bool top_left_rule, QuadraticCoefficients& out) const;
  // A constant in fixed point (value * 2^fraction_bits; value is an integer), kept to the GP's
  // arithmetic.
  QuadraticCoefficients constant(double value) const;
  // Vertex k's depth in depth units, clamped half a unit inside the range.
  double depth(int k) const;
};

struct ExpressionEntry {
  Expression id;
  ExpressionForm form;
  OpCounts cost;  // i860 operations of one set-up
  bool needs_adjacency;
  bool (*compute)(const SetupContext& context, QuadraticCoefficients& out);
  // The expression can be >= 0 on pixel centres outside the snapped triangle (it classifies
  // against the unsnapped one, at most half a snapped unit away): set-up then widens the
  // triangle's pixel bounding box, and so its binning, by one snapped unit, and keeps a
  // triangle that snapping flattens to zero area (its attribute planes then take their
  // gradients from the unsnapped positions; area2 is 0 in its context).
  bool widens = false;
  // The expression folds a frame parameter in (SetupContext::frame).
  bool reads_frame = false;

  const char* name() const { return kExpressions[static_cast<int>(id)].name; }
  const char* meaning() const { return kExpressions[static_cast<int>(id)].meaning; }
};

const std::array<ExpressionEntry, static_cast<int>(Expression::count)>& expression_registry();
inline const ExpressionEntry& expression_entry(Expression e) {
  return expression_registry()[static_cast<std::size_t>(e)];
}
// True if any expression in `set` reads the mesh adjacency.
bool needs_adjacency(const ExpressionSet& set);
// True if any expression in `set` widens the bounding box (ExpressionEntry::widens).
bool widens_bounds(const ExpressionSet& set);
// True if any expression in `set` reads the frame's parameters (ExpressionEntry::reads_frame).
bool needs_frame_parameters(const ExpressionSet& set);

// v rounded to `bits` significant bits (to nearest, ties to even, symmetric about 0): what
// the GP keeps of a coefficient it sends (gp.significand_bits); v itself at 62 or more.
std::int64_t round_significand(std::int64_t v, int bits);
// The GP's arithmetic, the one rounding every path applies to what it computes: an integer
// coefficient (before any reduction modulo the coefficient width), or a real intermediate
// (the accurate program's planes), kept to params.significand_bits significant bits.
__int128 gp_round(__int128 v, const GeometryParams& params);
double gp_round(double v, const GeometryParams& params);

// Ring words of one coefficient: coefficient_bits rounded up to whole ring words.
int coefficient_words(int coefficient_bits, int word_bits);
// Ring words of a packet carrying `set`: a header word naming the procedure (and kind), then
// for each expression in `set`, in Expression order, coefficients(form) coefficients of
// coefficient_words words each (docs/architecture.md, "Packet format").
std::uint64_t packet_words(const ExpressionSet& set, int coefficient_words);

}  // namespace pp5
