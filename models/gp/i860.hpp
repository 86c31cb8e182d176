#pragma once
// The Graphics Processor's cost model, as plain C++: the operations an Intel i860 executes
// for one primitive (transform, clip, lighting, coefficient set-up, binning, message
// packing), and a pipeline model that turns them into i860 clocks under one of two code
// profiles. docs/timing.md derives every count and the calibration.
//
// Contract:
//  - Operation counts depend only on what the firmware asks for (its expressions), the
//    packet's size in words and how many regions and clip pieces a triangle makes; never on
//    the host's arithmetic. The same triangle always costs the same clocks.
//  - Hand-coded assembly issues one core and one floating-point operation per clock
//    (dual-instruction mode), and a multiply with an add (dual-operation instructions);
//    pipelines are scheduled, so each dependency chain pays its pipeline depth once.
//  - Compiled C issues one operation per clock, waits out each floating-point result
//    (scalar, unpipelined mode) and each load, leaves branch delay slots empty, and misses
//    the instruction cache on every line of a loop body larger than the cache.
//  - Both profiles multiply by one calibrated factor (gp.overhead_factor) for the work the
//    count leaves out (display-list traversal, PPHIGS state, the message-passing OS); with
//    gp.overhead_form=add the left-out work is instead a fixed cost, (factor - 1) x the
//    hand-coded clocks of the same operations, in either profile. Factor and form are both
//    fitted (docs/timing.md).
#include <bitset>
#include <cstdint>
#include <string>

#include "common/units.hpp"
#include "firmware/isa/interface.hpp"

namespace pp5 {

// Operations of one unit of GP work.
struct OpCounts {
  std::uint64_t fadd = 0;     // floating-point adder: add, subtract, compare, convert
  std::uint64_t fmul = 0;     // floating-point multiplier (reciprocal seeds included)
  std::uint64_t load = 0;     // loads from the data cache
  std::uint64_t store = 0;    // stores
  std::uint64_t integer = 0;  // core integer and logic operations
  std::uint64_t branch = 0;   // branches
  std::uint64_t chains = 0;   // dependent floating-point chains (pipeline fill and drain)

  OpCounts& operator+=(const OpCounts& o);
  OpCounts operator+(const OpCounts& o) const {
    OpCounts r = *this;
    r += o;
    return r;
  }
  OpCounts operator*(std::uint64_t k) const;
  std::uint64_t floating() const { return fadd + fmul; }
  std::uint64_t core() const { return load + store + integer + branch; }
};

enum class GpCode { assembly, compiled };
GpCode parse_gp_code(const std::string& name);  // "assembly" or "compiled"
const char* gp_code_name(GpCode code);

// The i860 facts and the assumptions of the cost model (from the machine configuration).
struct I860Params {
  GpCode code = GpCode::assembly;
  int fp_latency_clocks = 3;        // adder and single-precision multiplier pipelines: 3 stages
  int load_use_clocks = 2;          // a load's result is usable this many clocks after issue
  int icache_bytes = 4096;          // instruction cache
  int icache_line_bytes = 32;       // instruction-cache line
  int icache_miss_clocks = 6;       // refilling one line from memory
  int assembly_code_bytes = 3584;   // the hand-coded per-triangle loop (fits the cache)
  int compiled_code_bytes = 12288;  // the compiled per-triangle loop (does not)
  double overhead_factor = 1.0;     // calibrated: work the count leaves out
  // How the factor applies: multiplying the profile's counted clocks, or adding
  // (factor - 1) x the hand-coded clocks of the same operations (a fixed cost per primitive).
  enum class OverheadForm { multiply, add };
  OverheadForm overhead_form = OverheadForm::multiply;
};

// What the firmware asks of the GP for each triangle.
struct GpWorkload {
  std::bitset<static_cast<int>(Expression::count)> expressions;
  std::uint64_t packet_words = 0;  // ring words of one triangle packet
  int lights = 1;                  // the scene's lights, each summed into vertex and face colours
};

// Per-primitive operation counts. Each function is one stage of the GP's loop.
struct I860Work {
  static OpCounts transform_vertex(const GpWorkload& w);  // model-view-projection, divide
  static OpCounts clip_test_vertex();                     // six plane compares, outcodes
  static OpCounts normal_vertex(const GpWorkload& w);     // normal transform and normalise
  static OpCounts light_vertex(const GpWorkload& w);      // diffuse + specular at a vertex
  static OpCounts clip_split(const GpWorkload& w);        // one extra polygon vertex
  static OpCounts triangle_setup(const GpWorkload& w);    // area, bounding box, flat light
  static OpCounts expression_setup(Expression e);         // coefficients of one expression
  static OpCounts pack(const GpWorkload& w);              // writing one packet's words
  static OpCounts bin_region();                           // linking a packet into a bin
  static OpCounts triangle_loop();                        // fetch and loop overhead
  static OpCounts send_bin();                             // starting one bin's message

  // A scene triangle that transforms to `pieces` screen triangles (0 if clipped away),
  // `setups` of which reach coefficient set-up, packed once each and binned `regions` times.
  static OpCounts triangle(const GpWorkload& w, int pieces, int setups, int regions);
};

class I860Model {
 public:
  explicit I860Model(const I860Params& params) : params_(params) {}

  // Clocks for `ops` of the per-triangle loop, including instruction-cache refills for
  // `loop_iterations` passes through the loop body.
  GpClocks clocks(const OpCounts& ops, std::uint64_t loop_iterations) const;
  // Clocks of one reference triangle (one piece, one region) of `w`, and the rate of
  // `gps` processors at `clock_hz` for it.
  GpClocks reference_triangle(const GpWorkload& w) const;
  double reference_rate(const GpWorkload& w, int gps, double clock_hz) const;

  const I860Params& params() const { return params_; }

 private:
  // The counted operations' clocks under `code`, before the overhead.
  static double counted_clocks(const I860Params& p, GpCode code, const OpCounts& ops,
                               std::uint64_t loop_iterations);
  I860Params params_;
};

}  // namespace pp5
