#include "models/gp/i860.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/gp/expressions.hpp"

namespace pp5 {

namespace {

using E = Expression;

bool any(const GpWorkload& w, std::initializer_list<E> es) {
  for (E e : es) {
    if (w.expressions.test(static_cast<int>(e))) return true;
  }
  return false;
}
bool needs_vertex_light(const GpWorkload& w) { return any(w, {E::red, E::green, E::blue}); }
bool needs_normals(const GpWorkload& w) {
  return needs_vertex_light(w) || any(w, {E::nx, E::ny, E::nz});
}
bool needs_flat(const GpWorkload& w) { return any(w, {E::flat_red, E::flat_green, E::flat_blue}); }
// Values interpolated along a clipped edge: position (4) plus the attributes asked for.
std::uint64_t clip_attributes(const GpWorkload& w) {
  std::uint64_t n = 4;
  if (needs_vertex_light(w)) n += 3;
  if (needs_normals(w)) n += 3;
  if (any(w, {E::base_red, E::base_green, E::base_blue})) n += 3;
  if (any(w, {E::opacity})) n += 1;
  return n;
}

// Each light after the first: its N.L and N.H (4 adds, 6 multiplies), clamps (2 compares),
// specular power 16 (4 squarings), scaled by its diffuse and specular and summed (2, 2).
OpCounts extra_lights(const GpWorkload& w) {
  const auto n = static_cast<std::uint64_t>(std::max(0, w.lights - 1));
  return OpCounts{4 + 2 + 2, 6 + 4 + 2, 0, 0, 0, 0, 0} * n;
}

// A reciprocal or reciprocal square root: a seed (frcp/frsqr) and two Newton-Raphson steps.
OpCounts reciprocal() { return {2, 5, 0, 0, 0, 0, 1}; }

}  // namespace

OpCounts& OpCounts::operator+=(const OpCounts& o) {
  fadd += o.fadd;
  fmul += o.fmul;
  load += o.load;
  store += o.store;
  integer += o.integer;
  branch += o.branch;
  chains += o.chains;
  return *this;
}

OpCounts OpCounts::operator*(std::uint64_t k) const {
  return {fadd * k, fmul * k, load * k, store * k, integer * k, branch * k, chains * k};
}

GpCode parse_gp_code(const std::string& name) {
  if (name == "assembly") return GpCode::assembly;
  if (name == "compiled") return GpCode::compiled;
  throw std::invalid_argument("GP code profile '" + name + "' (expected assembly or compiled)");
}

const char* gp_code_name(GpCode code) { return code == GpCode::assembly ? "assembly" : "compiled"; }

OpCounts I860Work::transform_vertex(const GpWorkload&) {
  // 4x4 matrix times (x, y, z, 1): 16 multiplies, 12 adds; load x, y, z.
  OpCounts c{12, 16, 3, 0, 0, 0, 1};
  // Perspective divide: 1/w, then x, y, z times it; viewport scale and offset.
  c += reciprocal();
  c += OpCounts{3, 6, 0, 0, 0, 0, 1};
  // Snap x, y to the sub-pixel grid: multiply, convert to integer (adder unit), 2 stores.
  c += OpCounts{2, 2, 0, 2, 2, 0, 0};
  return c;
}

OpCounts I860Work::clip_test_vertex() {
  // Six compares against +-w, an outcode or-ed together, one branch on the triangle's codes.
  return {6, 0, 0, 0, 6, 1, 0};
}

OpCounts I860Work::normal_vertex(const GpWorkload& w) {
  if (!needs_normals(w)) return {};
  // Load the normal, 3x3 normal matrix (9 multiplies, 6 adds), then normalise: dot product,
  // reciprocal square root, scale.
  OpCounts c{6, 9, 3, 0, 0, 0, 1};
  c += OpCounts{2, 3, 0, 0, 0, 0, 1};
  c += reciprocal();
  c += OpCounts{0, 3, 0, 0, 0, 0, 0};
  return c;
}

OpCounts I860Work::light_vertex(const GpWorkload& w) {
  if (!needs_vertex_light(w)) return {};
  // N.L and N.H (3 multiplies, 2 adds each), clamp at 0 (2 compares), specular power 16 by
  // four squarings, then colour = material * (ambient + diffuse N.L) + specular: 3 x (2, 2).
  // Material colour: 3 loads.
  return OpCounts{4 + 2 + 6, 6 + 4 + 6, 3, 0, 0, 0, 3} + extra_lights(w);
}

OpCounts I860Work::clip_split(const GpWorkload& w) {
  // One new polygon vertex on a clip plane: the distance ratio (2 subtracts and a
  // reciprocal), then each attribute interpolated (1 subtract, 1 multiply-add), stored.
  const std::uint64_t a = clip_attributes(w);
  OpCounts c{2 + 2 * a, 1 + a, 0, a, 4, 2, 1};
  c += reciprocal();
  // The new vertex goes through projection and snapping like any other.
  c += transform_vertex(w);
  return c;
}

OpCounts I860Work::triangle_setup(const GpWorkload& w) {
  // Edge vectors (4 integer subtracts on snapped positions), twice the area (2 multiplies,
  // 1 subtract), back-face and zero-area tests, 1/area for the attribute planes.
  OpCounts c{1, 2, 0, 0, 4 + 2, 2, 1};
  c += reciprocal();
  // Bounding box of pixel centres: 6 compares, 4 conversions to integer, 4 clamps.
  c += OpCounts{10, 0, 0, 0, 4, 2, 0};
  if (needs_flat(w)) {
    // Face normal (cross product: 6 multiplies, 3 subtracts), normalise, light it.
    c += OpCounts{3 + 2, 6 + 3 + 3, 0, 0, 0, 0, 2};
    c += reciprocal();
    c += OpCounts{12, 16, 3, 0, 0, 0, 3};
    c += extra_lights(w);
  }
  return c;
}

OpCounts I860Work::expression_setup(Expression e) {
  // Each expression's count is its registry entry's (models/gp/expressions.cpp).
  return expression_entry(e).cost;
}

OpCounts I860Work::pack(const GpWorkload& w) {
  // Every word of the packet is stored once (a 40-bit coefficient is two words; a constant
  // sends one coefficient, a linear expression three, a quadratic six); the header names the
  // procedure; a counter and pointer per packet.
  return {0, 0, 0, w.packet_words, 3, 0, 0};
}

OpCounts I860Work::bin_region() {
  // Region index (2 integer ops), load the bin's tail, store the link and the new tail, add
  // the packet's length to the bin's, loop branch.
  return {0, 0, 2, 2, 4, 1, 0};
}

OpCounts I860Work::triangle_loop() {
  // Fetch the triangle's three vertex indices and their addresses, loop counter and branch,
  // the clip-code branch.
  return {0, 0, 6, 0, 6, 2, 0};
}

OpCounts I860Work::send_bin() {
  // Build a message descriptor for the ring interface and start it.
  return {0, 0, 4, 4, 12, 2, 0};
}

OpCounts I860Work::triangle(const GpWorkload& w, int pieces, int setups, int regions) {
  OpCounts c = triangle_loop();
  c += (transform_vertex(w) + clip_test_vertex() + normal_vertex(w) + light_vertex(w)) * 3;
  // A convex polygon of n vertices after clipping is a fan of n - 2 triangles.
  if (pieces > 1) c += clip_split(w) * static_cast<std::uint64_t>(pieces - 1);
  OpCounts per_setup = triangle_setup(w) + pack(w);
  for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
    if (w.expressions.test(e)) per_setup += expression_setup(static_cast<Expression>(e));
  }
  c += per_setup * static_cast<std::uint64_t>(setups);
  c += bin_region() * static_cast<std::uint64_t>(regions);
  return c;
}

GpClocks I860Model::clocks(const OpCounts& ops, std::uint64_t loop_iterations) const {
  const I860Params& p = params_;
  const double counted = counted_clocks(p, p.code, ops, loop_iterations);
  if (p.overhead_form == I860Params::OverheadForm::add) {
    // The left-out work as a fixed cost: what it adds to the hand-coded loop, in any profile.
    const double fixed =
        (p.overhead_factor - 1) * counted_clocks(p, GpCode::assembly, ops, loop_iterations);
    return GpClocks(static_cast<std::uint64_t>(std::llround(counted + fixed)));
  }
  return GpClocks(static_cast<std::uint64_t>(std::llround(counted * p.overhead_factor)));
}

double I860Model::counted_clocks(const I860Params& p, GpCode code, const OpCounts& ops,
                                 std::uint64_t loop_iterations) {
  double clocks = 0;
  if (code == GpCode::assembly) {
    // Dual-instruction mode: a core and a floating-point instruction each clock; a
    // dual-operation instruction pairs a multiply with an add. Each dependency chain fills
    // and drains the pipeline once. The loop fits the instruction cache.
    const double fp = static_cast<double>(std::max(ops.fadd, ops.fmul));
    clocks = std::max(fp, static_cast<double>(ops.core())) +
             static_cast<double>(ops.chains) * p.fp_latency_clocks;
    if (p.assembly_code_bytes > p.icache_bytes) {
      clocks += static_cast<double>(loop_iterations) *
                std::ceil(static_cast<double>(p.assembly_code_bytes) / p.icache_line_bytes) *
                p.icache_miss_clocks;
    }
  } else {
    // One instruction per clock; scalar floating-point operations wait for their result;
    // each load waits until its value can be used; branch delay slots stay empty.
    clocks = static_cast<double>(ops.floating()) * p.fp_latency_clocks +
             static_cast<double>(ops.load) * p.load_use_clocks +
             static_cast<double>(ops.store + ops.integer) + 2.0 * static_cast<double>(ops.branch);
    // A loop body larger than the cache evicts itself: every line misses on every pass.
    if (p.compiled_code_bytes > p.icache_bytes) {
      clocks += static_cast<double>(loop_iterations) *
                std::ceil(static_cast<double>(p.compiled_code_bytes) / p.icache_line_bytes) *
                p.icache_miss_clocks;
    }
  }
  return clocks;
}

GpClocks I860Model::reference_triangle(const GpWorkload& w) const {
  return clocks(I860Work::triangle(w, 1, 1, 1), 1);
}

double I860Model::reference_rate(const GpWorkload& w, int gps, double clock_hz) const {
  return gps * clock_hz / static_cast<double>(reference_triangle(w).count);
}

}  // namespace pp5
