#include "models/config/machine_config.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <variant>

#include "common/read_file.hpp"
#include "common/strict_json.hpp"

namespace pp5 {

namespace {

// A choice-valued key: an enum in MachineConfig, read and written as its index into the
// entry's `choices`.
struct ChoiceRef {
  void* target;
  int (*get)(const void*);
  void (*put)(void*, int);
};
template <class Enum>
ChoiceRef choice(Enum* e) {
  return {e, [](const void* t) { return static_cast<int>(*static_cast<const Enum*>(t)); },
          [](void* t, int v) { *static_cast<Enum*>(t) = static_cast<Enum>(v); }};
}

// A frame parameter: set, or left to its default.
using FrameRef = std::optional<std::int64_t>*;

using Ref = std::variant<int*, double*, ChoiceRef, FrameRef>;

struct Entry {
  std::string key;
  const char* unit;
  const char* confidence;
  double default_value;
  double min;
  double max;
  const char* description;
  Ref (*ref)(MachineConfig&);
  // Choice keys: the allowed values separated by '|', in the enum's order, the first being
  // the default.
  const char* choices = nullptr;
  // Frame parameters: the Parameter index; where a computed one comes from (nullptr: it is
  // settable); whether default and range are given for gp.depth_bits = 24 and scale with
  // 2^(gp.depth_bits - 24).
  int frame = -1;
  const char* computed_from = nullptr;
  bool depth_scaled = false;
  // Timing constants: how the value was obtained, and for a fitted or assumed one the ends of
  // its plausible range as --set assignments separated by spaces (ParameterInfo).
  Calibration calibration = Calibration::none;
  const char* basis = nullptr;
  const char* low = nullptr;
  const char* high = nullptr;
  // Fitted constants: the published figures (PublishedFigure ids, separated by spaces) whose
  // value the fit consumed, so that reproducing them is no evidence (pp5sim validate).
  const char* consumes = nullptr;
};

// A timing constant (or a model's form) whose value was chosen so that a published figure
// comes out: `basis` names the figure and its source, `consumes` its id (published_figures).
Entry fitted(Entry e, const char* consumes, const char* basis, const char* low, const char* high) {
  e.calibration = Calibration::fitted;
  e.consumes = consumes;
  e.basis = basis;
  e.low = low;
  e.high = high;
  return e;
}
// A timing constant that follows from a published or data-sheet figure, or from other keys.
Entry derived(Entry e, const char* basis) {
  e.calibration = Calibration::derived;
  e.basis = basis;
  return e;
}
// A timing constant no source gives: why this value, and its plausible range.
Entry assumed(Entry e, const char* basis, const char* low, const char* high) {
  e.calibration = Calibration::assumed;
  e.basis = basis;
  e.low = low;
  e.high = high;
  return e;
}

std::vector<std::string> split_words(const char* text) {
  std::vector<std::string> out;
  std::istringstream in(text ? text : "");
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

std::vector<std::string> split_choices(const char* choices) {
  std::vector<std::string> out;
  std::string cur;
  for (const char* c = choices; *c; ++c) {
    if (*c == '|') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += *c;
    }
  }
  out.push_back(cur);
  return out;
}

constexpr int kReferenceDepthBits = 24;

// A settable frame parameter: integer, default and range as declared.
Entry settable(Parameter k, const char* unit, double default_value, double min, double max,
               const char* description, bool depth_scaled = false) {
  Entry e{std::string("frame.") + parameter_name(k),
          unit,
          "A",
          default_value,
          min,
          max,
          description,
          nullptr};
  e.frame = static_cast<int>(k);
  e.depth_scaled = depth_scaled;
  return e;
}

// A frame parameter the GP computes: `from` says from what (shown in the table and in the
// error when someone tries to set it).
Entry computed(Parameter k, const char* unit, const char* description, const char* from) {
  Entry e{std::string("frame.") + parameter_name(k), unit, "A", 0, 0, 0, description, nullptr};
  e.frame = static_cast<int>(k);
  e.computed_from = from;
  return e;
}

// The single declaration of every machine parameter. Confidence: P = the 1989 SIGGRAPH
// paper, S = a secondary source, A = an assumption of this simulator (see
// ../shared/design/pixel-planes-5.md for the sources).
const std::vector<Entry>& parameter_table() {
  static const std::vector<Entry> table = {
      {"screen.width", "pixels", "P", 1280, 64, 8192,
       "Width of the frame; the paper's frame buffer is 1280 x 1024.",
       [](MachineConfig& c) -> Ref { return &c.screen.width; }},
      {"screen.height", "pixels", "P", 1024, 1, 8192, "Height of the frame.",
       [](MachineConfig& c) -> Ref { return &c.screen.height; }},

      derived({"gp.count", "processors", "P", 32, 1, 64,
               "Graphics Processors (Intel i860); the paper's machine has up to 32.",
               [](MachineConfig& c) -> Ref { return &c.gp.count; }},
              "the paper's full machine: up to 32 GPs (P, abstract)"),
      derived({"gp.clock_hz", "Hz", "S", 40e6, 1e6, 1e9, "i860 clock.",
               [](MachineConfig& c) -> Ref { return &c.gp.clock_hz; }},
              "i860 XR at 40 MHz (S: Stony Brook volume-rendering report; Kesteloot)"),
      {"gp.subpixel_bits", "bits", "A", 4, 0, 8,
       "Vertex positions are snapped to 1/2^n pixel before edge set-up, so that edge "
       "coefficients are exact integers and shared edges own each pixel exactly once.",
       [](MachineConfig& c) -> Ref { return &c.gp.subpixel_bits; }},
      derived({"gp.significand_bits", "bits", "A", 62, 4, 62,
               "The GP's arithmetic: significant bits it keeps of every value it computes and "
               "sends, rounded to nearest (ties to even) like a float's significand: each "
               "coefficient of the edges (edge0..2, wide0..2), the attribute and depth planes "
               "(before they are reduced modulo the coefficient width), the accurate program's "
               "side tests (and the planes they are differenced from), the sphere's conic, depth "
               "and normal quadratics, and constants. 24 is IEEE single (the i860's, which the "
               "machine's set-up code used), 53 IEEE double, 62 exact (nothing is rounded). "
               "Fewer bits move an edge by up to 2^-n times twice the farthest pixel's distance "
               "from the origin (Rossignac 9.3.3) and a plane by 2^-n of its magnitude there. "
               "Only the values sent are rounded: the vertex transform stays in double and the "
               "vertices are snapped to gp.subpixel_bits.",
               [](MachineConfig& c) -> Ref { return &c.gp.significand_bits; }},
              "exact by default, so that a figure shows the method's own error: every coefficient "
              "is an integer below 2^61 (evaluator.coefficient_bits <= 62), so 62 keeps them "
              "all; the machine's i860 set-up code computed in single precision, 24"),
      derived({"gp.edge_significand_bits", "bits", "A", 62, 4, 62,
               "The same key as gp.significand_bits (its earlier name, when only the edges were "
               "rounded): setting either sets the GP's arithmetic for every value it sends.",
               [](MachineConfig& c) -> Ref { return &c.gp.significand_bits; }},
              "an alias of gp.significand_bits"),
      {"gp.depth_bits", "bits", "A", 24, 8, 32,
       "Range of the depth expression: 0 at the near plane to 2^n - 1 at the far plane.",
       [](MachineConfig& c) -> Ref { return &c.gp.depth_bits; }},
      {"gp.code", "profile", "S", 0, 0, 0,
       "Quality of the GP's per-triangle code: 'assembly' (hand-coded, dual-instruction mode, "
       "scheduled pipelines, fits the instruction cache; over 1 M Phong triangles/s with 32 "
       "GPs) or 'compiled' (C: one instruction per clock, unscheduled, about 100 K/s).",
       [](MachineConfig& c) -> Ref { return choice(&c.gp.code); }, "assembly|compiled"},
      derived(
          {"gp.fp_latency_clocks", "i860 clocks", "S", 3, 1, 10,
           "Stages of the i860's floating-point adder and single-precision multiplier pipelines: "
           "what an unscheduled operation waits for its result, and what a scheduled chain pays "
           "once to fill and drain.",
           [](MachineConfig& c) -> Ref { return &c.gp.fp_latency_clocks; }},
          "the i860's 3-stage adder and single-precision multiplier pipelines (Intel i860 "
          "Programmer's Reference Manual 240329-002; Kohn & Margulis, IEEE Micro 9(4), 1989)"),
      assumed({"gp.load_use_clocks", "i860 clocks", "A", 2, 1, 10,
               "Clocks from a load's issue until compiled code can use its value (one delay slot).",
               [](MachineConfig& c) -> Ref { return &c.gp.load_use_clocks; }},
              "one load delay slot for unscheduled code; the i860's load pipeline has 3 stages, so "
              "1 (the value forwarded) to 3 (the whole pipeline)",
              "gp.load_use_clocks=1", "gp.load_use_clocks=3"),
      derived({"gp.icache_bytes", "bytes", "S", 4096, 256, 1048576, "i860 XR instruction cache.",
               [](MachineConfig& c) -> Ref { return &c.gp.icache_bytes; }},
              "i860 XR: 4 KB instruction cache (reference manual)"),
      derived({"gp.icache_line_bytes", "bytes", "S", 32, 4, 256, "Instruction-cache line.",
               [](MachineConfig& c) -> Ref { return &c.gp.icache_line_bytes; }},
              "i860 XR: 32-byte cache lines (reference manual)"),
      fitted({"gp.icache_miss_clocks", "i860 clocks", "A", 6, 0, 1000,
              "Refilling one instruction-cache line from GP memory.",
              [](MachineConfig& c) -> Ref { return &c.gp.icache_miss_clocks; }},
             "banks.compiled_rate",
             "to the compiled rate: 'about 100,000 polygons/second' (S: Banks, sec. 5). No source "
             "gives the GP board's memory timing; its plausible range is 4 (a 64-bit bus in burst, "
             "4 transfers of 1 clock) to 16 (4 transfers of a 4-clock DRAM access), and 6 was "
             "chosen in it because the compiled rate then comes out at 100 K (only 6 or 7 do: 4 "
             "gives 124,611/s, 16 gives 50,605/s), jointly with gp.compiled_code_bytes",
             "gp.icache_miss_clocks=4", "gp.icache_miss_clocks=16"),
      assumed({"gp.assembly_code_bytes", "bytes", "A", 3584, 256, 1048576,
               "Size of the hand-coded per-triangle loop; the sources say it fits the 4 KB cache.",
               [](MachineConfig& c) -> Ref { return &c.gp.assembly_code_bytes; }},
              "the hand-coded loop fits the 4 KB cache (S: Banks), its size is not given; it costs "
              "nothing while it fits, so 2 KB to 4 KB",
              "gp.assembly_code_bytes=2048", "gp.assembly_code_bytes=4096"),
      fitted({"gp.compiled_code_bytes", "bytes", "A", 12288, 256, 1048576,
              "Size of the compiled per-triangle loop (about 3x the hand-coded one), which does "
              "not fit the instruction cache.",
              [](MachineConfig& c) -> Ref { return &c.gp.compiled_code_bytes; }},
             "banks.compiled_rate",
             "to the compiled rate: 'about 100,000 polygons/second' (S: Banks, sec. 5), jointly "
             "with gp.icache_miss_clocks (the two set the refill term, 59% of the compiled "
             "triangle's clocks). The sources say only that the compiled loop does not fit the "
             "cache; 2x to 4x the hand-coded loop (8 KB to 16 KB) is plausible and moves the "
             "compiled rate by +25% and -16%; 12 KB was kept because it gives 100 K",
             "gp.compiled_code_bytes=8192", "gp.compiled_code_bytes=16384"),
      fitted(
          {"gp.overhead_factor", "ratio", "A", 3.26, 1, 100,
           "Clocks of the counted operations are multiplied by this for the work the count leaves "
           "out (display-list traversal, PPHIGS state, the message-passing OS), in either code "
           "profile. Fitted: the hand-coded Phong triangle then runs at 1.2 M/s on 32 GPs. The "
           "compiled rate, about 100 K/s, is no prediction either: gp.icache_miss_clocks and "
           "gp.compiled_code_bytes were fitted to it, and gp.overhead_form (multiply or add) to "
           "the gap between the two (docs/timing.md).",
           [](MachineConfig& c) -> Ref { return &c.gp.overhead_factor; }},
          "banks.hand_coded_rate",
          "to the hand-coded rate: transform + Phong 'well over 1 million polygons/second' on the "
          "32-GP machine (S: Banks, Screen-Parallel Calculation of Surface Intersections, sec. 5), "
          "taken as 1.2 M; the range refits it to 1.5 M (2.61) and 1.05 M (3.73)",
          "gp.overhead_factor=2.61", "gp.overhead_factor=3.73"),
      fitted({"gp.overhead_form", "form", "A", 0, 0, 0,
              "How gp.overhead_factor applies: 'multiply' scales either code profile's counted "
              "clocks (the work the count leaves out runs as the build's own code), 'add' adds "
              "(gp.overhead_factor - 1) x the hand-coded clocks of the same operations to either "
              "profile (a fixed cost per primitive, whichever build). The hand-coded rate is the "
              "same under both; the compiled one is 100 K/s multiplied, 275 K/s added.",
              [](MachineConfig& c) -> Ref { return choice(&c.gp.overhead_form); }, "multiply|add"},
             "banks.hand_coded_rate banks.compiled_rate",
             "to the tenfold gap between the hand-coded and compiled rates (S: Banks, sec. 5): the "
             "multiplier was chosen because it reproduces it (a fixed cost gives 4.4x); Banks puts "
             "the gap down to code properties, which a multiplier keeps (docs/timing.md)",
             "gp.overhead_form=multiply", "gp.overhead_form=add"),
      {"gp.cull_back_faces", "flag", "A", 0, 0, 1,
       "GP library option: 1 drops triangles that face away from the eye (the silhouette "
       "remedy for closed opaque surfaces); 0 draws both sides, lit two-sided.",
       [](MachineConfig& c) -> Ref { return &c.gp.cull_back_faces; }},
      assumed(
          {"gp.multipass", "policy", "A", 0, 0, 0,
           "What a GP does for the second and later passes of a multipass program "
           "(transparency): 'resend' the binned packets it kept, or 'retraverse' its share "
           "of the display list, transforming and setting it up again (costed on the i860 "
           "model like the first pass). The image is identical; only the time differs.",
           [](MachineConfig& c) -> Ref { return choice(&c.gp.multipass); }, "resend|retraverse"},
          "PPHIGS's policy is not published; resend costs ring time only and fits the GP's "
          "memory, retraverse repeats the geometry every pass (docs/timing.md, Multipass)",
          "gp.multipass=resend", "gp.multipass=retraverse"),
      assumed(
          {"gp.send_order", "rule", "A", 0, 0, 0,
           "Which of several GPs waiting to send takes a Renderer's queue room first, when a "
           "stage they owe opens or frees room at one instant: 'nearest' (the fewest ring hops "
           "to the Renderer, ties to the lower GP: its message would arrive first), 'lowest' "
           "(the lowest-numbered GP) or 'round_robin' (in turn: the GP after the one woken last "
           "goes first). The image is identical; only the time differs.",
           [](MachineConfig& c) -> Ref { return choice(&c.gp.send_order); },
           "nearest|lowest|round_robin"},
          "the machine's flow control between GPs and Renderers is not published; nearest "
          "follows from the ring, the others are arbiters it might have had",
          "gp.send_order=lowest", "gp.send_order=round_robin"),
      assumed(
          {"ring.channels", "channels", "A", 8, 1, 64,
           "Parallel channels of the ring; 8 x 32 bits x 20 MHz = 5.12 Gb/s matches the paper's "
           "5 Gb/s, but 4 x 40 MHz fits as well.",
           [](MachineConfig& c) -> Ref { return &c.ring.channels; }},
          "the paper gives 5 Gb/s only (P); 4 channels at 40 MHz or 16 at 10 MHz carry the same "
          "(the range keeps ring.clock_hz at 5.12 Gb/s)",
          "ring.channels=4 ring.clock_hz=4e7", "ring.channels=16 ring.clock_hz=1e7"),
      assumed({"ring.word_bits", "bits", "A", 32, 8, 128, "Width of one channel.",
               [](MachineConfig& c) -> Ref { return &c.ring.word_bits; }},
              "not published; 16-bit channels at 40 MHz or 64-bit ones at 10 MHz carry the same "
              "5.12 Gb/s (a 40-bit coefficient takes 3, 2 or 1 words)",
              "ring.word_bits=16 ring.clock_hz=4e7", "ring.word_bits=64 ring.clock_hz=1e7"),
      derived(
          {"ring.clock_hz", "Hz", "A", 20e6, 1e6, 1e9,
           "Ring clock: one word per channel per cycle.",
           [](MachineConfig& c) -> Ref { return &c.ring.clock_hz; }},
          "from the published 5 Gb/s (P, abstract): 5.12 Gb/s / (ring.channels x ring.word_bits)"),
      assumed({"ring.hop_latency_cycles", "ring cycles", "A", 1, 0, 1000,
               "Latency of one hop from a ring stop to the next.",
               [](MachineConfig& c) -> Ref { return &c.ring.hop_latency_cycles; }},
              "the ring's latency and protocol are not published; 0 to 4 ring cycles a hop",
              "ring.hop_latency_cycles=0", "ring.hop_latency_cycles=4"),

      derived({"renderer.count", "boards", "P", 16, 1, 32,
               "Renderer boards; the paper's machine has up to 16.",
               [](MachineConfig& c) -> Ref { return &c.renderer.count; }},
              "the paper's full machine: up to 16 Renderers (P, abstract)"),
      derived({"renderer.clock_hz", "Hz", "P", 40e6, 1e6, 1e9,
               "Array clock: one micro-instruction cycle every 25 ns.",
               [](MachineConfig& c) -> Ref { return &c.renderer.clock_hz; }},
              "chips designed to run at 40 MHz, 25 ns per micro-instruction (P, abstract)"),
      {"renderer.region_width", "pixels", "P", 128, 64, 1024,
       "Width of the SIMD array and so of a screen region (a multiple of 64).",
       [](MachineConfig& c) -> Ref { return &c.renderer.region_width; }},
      {"renderer.region_height", "pixels", "P", 128, 1, 1024, "Height of the SIMD array.",
       [](MachineConfig& c) -> Ref { return &c.renderer.region_height; }},
      {"renderer.memory_bits", "bits", "P", 208, 16, 1024,
       "Local memory of each pixel processor (ask 'what if' with 256).",
       [](MachineConfig& c) -> Ref { return &c.renderer.memory_bits; }},
      {"renderer.enable_stack_depth", "levels", "A", 8, 1, 64,
       "Saved Enable values per pixel for nested conditionals.",
       [](MachineConfig& c) -> Ref { return &c.renderer.enable_stack_depth; }},
      {"renderer.backing_store_bits", "bits", "P", 4096, 0, 65536,
       "Off-chip backing store per pixel (video RAM).",
       [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_bits; }},
      derived({"renderer.block_bits", "bits", "S", 32, 1, 64, "Backing-store transfer unit.",
               [](MachineConfig& c) -> Ref { return &c.renderer.block_bits; }},
              "the backing store is moved in 32-bit blocks (S: Kesteloot)"),
      assumed({"renderer.backing_store_cycles_per_block", "array cycles", "A", 64, 1, 100000,
               "Time to move one block between pixel memory and backing store; 'much slower than "
               "local memory' is all the sources say.",
               [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_cycles_per_block; }},
              "'much slower than local memory' (S: Kesteloot) is all the sources say: 16 to 256 "
              "array cycles a block",
              "renderer.backing_store_cycles_per_block=16",
              "renderer.backing_store_cycles_per_block=256"),
      derived(
          {"renderer.backing_store_overlap", "0 or 1", "P", 1, 0, 1,
           "1: backing-store transfers are asynchronous, as the paper says: a store (bsst) "
           "occupies the backing-store port while the array goes on, a load (bsld) waits only for "
           "the port and its own blocks. 0: every transfer stops the array for its full time.",
           [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_overlap; }},
          "backing-store transfers are asynchronous, overlapping other operations (P/S: abstract; "
          "Kesteloot)"),
      assumed(
          {"renderer.overlap_shipping", "0 or 1", "A", 1, 0, 1,
           "1: a finished region's colours are moved to the backing store and cross the ring from "
           "there while the array starts its next region (one region in flight per board). 0: the "
           "Renderer waits until its region has reached the frame buffer.",
           [](MachineConfig& c) -> Ref { return &c.renderer.overlap_shipping; }},
          "follows from the asynchronous backing store, but no source says finished regions leave "
          "from it; 0 (the Renderer waits for its region to reach the frame buffer) or 1",
          "renderer.overlap_shipping=0", "renderer.overlap_shipping=1"),
      assumed({"renderer.queue_words", "ring words", "A", 4096, 64, 1048576,
               "Capacity of a Renderer's instruction queue. A GP's bin travels in messages of at "
               "most this size, and a GP stalls until the queue has room for its next message.",
               [](MachineConfig& c) -> Ref { return &c.renderer.queue_words; }},
              "the controller's queue is not published: 1,024 to 16,384 words",
              "renderer.queue_words=1024", "renderer.queue_words=16384"),
      assumed(
          {"renderer.balancing", "mode", "A", 0, 0, 0,
           "Assignment of screen regions to Renderers: 'static' (region r to Renderer r mod "
           "count) or 'dynamic' (a Renderer takes the next unrendered region when it finishes "
           "one). The image is identical; only the time differs.",
           [](MachineConfig& c) -> Ref { return choice(&c.renderer.balancing); }, "static|dynamic"},
          "'Renderers can be reassigned to any region' (P); the policy is not given: static or "
          "dynamic",
          "renderer.balancing=static", "renderer.balancing=dynamic"),
      assumed(
          {"renderer.multiply_microcode", "mode", "A", 0, 0, 0,
           "The multiply's microcode (mul; mac is unaffected). 'full': one pass per multiplier "
           "bit j, adding over the destination from bit j to its top. 'window': a pass adds only "
           "the partial product's window, bits j to j + width(a) (the carry out of an unsigned "
           "a's top bit is the last bit it can reach, as the sum so far is below 2^(j + "
           "width(a))); a signed a still needs the full pass. The product is the same; only the "
           "time differs.",
           [](MachineConfig& c) -> Ref { return choice(&c.renderer.multiply_microcode); },
           "full|window"},
          "the array's multiply microcode is not published: the plain shift-and-add (full) or "
          "the windowed pass a careful microcoder would write (window)",
          "renderer.multiply_microcode=full", "renderer.multiply_microcode=window"),
      assumed({"renderer.packet_overhead_cycles", "array cycles", "A", 8, 0, 100000,
               "Controller cycles to decode one instruction packet and start its procedure.",
               [](MachineConfig& c) -> Ref { return &c.renderer.packet_overhead_cycles; }},
              "the controller's instruction set is not published: 2 to 32 array cycles a packet",
              "renderer.packet_overhead_cycles=2", "renderer.packet_overhead_cycles=32"),

      assumed({"evaluator.coefficient_bits", "bits", "A", 40, 8, 62,
               "Signed width of each coefficient the expression evaluator accepts.",
               [](MachineConfig& c) -> Ref { return &c.evaluator.coefficient_bits; }},
              "coefficient widths are not published: 40 (the least that draws the torus: at 38, "
              "which holds a 24-bit depth with 12 fraction bits, 2,215 of its 8,192 triangles "
              "have coefficients that do not fit) to 48",
              "evaluator.coefficient_bits=40",
              "evaluator.coefficient_bits=48 evaluator.result_bits=48"),
      assumed(
          {"evaluator.result_bits", "bits", "A", 40, 8, 64,
           "Width of the value the evaluator delivers; values wrap modulo 2^n.",
           [](MachineConfig& c) -> Ref { return &c.evaluator.result_bits; }},
          "not published; at least evaluator.coefficient_bits: 40 to 48 (qtest streams every bit)",
          "evaluator.result_bits=40", "evaluator.result_bits=48"),
      assumed(
          {"evaluator.fraction_bits", "bits", "A", 12, 0, 24,
           "Fraction bits of interpolated attributes (depth, colour, normal); they stream out of "
           "the evaluator first, LSB first, before the integer bits a field loads.",
           [](MachineConfig& c) -> Ref { return &c.evaluator.fraction_bits; }},
          "not published: 8 to 14 (24 depth bits + fraction + 2 must fit the 40-bit coefficients)",
          "evaluator.fraction_bits=8", "evaluator.fraction_bits=14"),
      assumed(
          {"evaluator.latency_cycles", "array cycles", "A", 8, 0, 1000,
           "Pipeline latency of the evaluator tree (about log2 of 128 levels plus input stages).",
           [](MachineConfig& c) -> Ref { return &c.evaluator.latency_cycles; }},
          "a tree of about log2(128) = 7 levels plus input stages; not published: 4 to 16",
          "evaluator.latency_cycles=4", "evaluator.latency_cycles=16"),

      assumed({"evaluator.bit_order", "mode", "A", 0, 0, 0,
               "The order the evaluator delivers a value's bits in (timing only). 'lsb_first': the "
               "fraction bits first, so qload and qcmp stop after the field's top bit, and qtest "
               "streams every bit to reach the sign. 'msb_first': the sign first, so a qtest.ge or "
               "qtest.lt (an edge test) takes one bit, and qload and qcmp stream the integer bits "
               "from the top down to the field's lowest (result_bits - fraction_bits), with the "
               "same latency.",
               [](MachineConfig& c) -> Ref { return choice(&c.evaluator.bit_order); },
               "lsb_first|msb_first"},
              "not published: a tree of bit-serial adders delivers LSB first (Fuchs et al.); an "
              "MSB-first tree (sign first, same latency) is the alternative that makes edge tests "
              "cheap",
              "evaluator.bit_order=lsb_first", "evaluator.bit_order=msb_first"),
      assumed({"evaluator.coefficient_words_per_cycle", "words/cycle", "A", 1, 1, 64,
               "Ring words of a packet's coefficients moved from the instruction queue into the "
               "evaluator's input registers per array cycle.",
               [](MachineConfig& c) -> Ref { return &c.evaluator.coefficient_words_per_cycle; }},
              "not published: 1 or 2 ring words a cycle into the evaluator",
              "evaluator.coefficient_words_per_cycle=1", "evaluator.coefficient_words_per_cycle=2"),
      assumed({"evaluator.double_buffered", "0 or 1", "A", 1, 0, 1,
               "1: the evaluator holds a second set of coefficient registers, so the next packet's "
               "coefficients load while the current packet executes. 0: loading stops the array.",
               [](MachineConfig& c) -> Ref { return &c.evaluator.double_buffered; }},
              "not published: 0 (loading stops the array) or 1", "evaluator.double_buffered=0",
              "evaluator.double_buffered=1"),
      assumed({"frame_buffer.bits_per_pixel", "bits", "A", 32, 8, 64,
               "Bits per pixel sent from a Renderer to the frame buffer (24-bit colour in a word).",
               [](MachineConfig& c) -> Ref { return &c.frame_buffer.bits_per_pixel; }},
              "24-bit colour (P: the frame buffer), sent packed (24) or in a word (32)",
              "frame_buffer.bits_per_pixel=24", "frame_buffer.bits_per_pixel=32"),
      assumed({"frames.gp_bins", "buffers", "A", 2, 1, 2,
               "Bin buffers per GP in a run of frames: 2, the GP sets up frame n + 1 into the "
               "second while the Renderers take frame n's bins from the first (whenever it has "
               "nothing of frame n it can send), stalling only when both are full; 1, it sets "
               "up frame n + 1 once the last of frame n's bins has gone. A single frame is the "
               "same either way.",
               [](MachineConfig& c) -> Ref { return &c.frames.gp_bins; }},
              "the sources say the GPs transform frame n + 1 while the Renderers draw frame n "
              "(P), not how many bin buffers a GP kept: one or two",
              "frames.gp_bins=1", "frames.gp_bins=2"),
      assumed({"frames.gp_start", "policy", "A", 0, 0, 0,
               "When a GP may start frame n + 1 in a run of frames: 'overlap', as soon as it "
               "has a free bin buffer and every Renderer has finished frame n - 1 (the frame "
               "buffer swaps at the end of a frame, when its last region arrives); "
               "'after_frame', only once every Renderer has finished frame n (no overlap). A "
               "single frame is the same either way.",
               [](MachineConfig& c) -> Ref { return choice(&c.frames.gp_start); },
               "overlap|after_frame"},
              "the machine was a frame engine whose rating is a sustained rate (P); when a GP "
              "was let loose on the next frame is not published",
              "frames.gp_start=after_frame", "frames.gp_start=overlap"),
      assumed({"frames.gp_send", "policy", "A", 0, 0, 0,
               "When a GP sends a region's packets: 'after_geometry', once it has set up its "
               "whole share of the display list (its bin map, then its bins); 'when_full', a "
               "message of a bin as soon as it is full (its next packet would not fit the "
               "Renderer's queue) and the Renderer has the region's stage open, interrupting "
               "the set-up, which goes on after it (the bin map and each bin's last message "
               "follow the set-up). The Renderer then takes a stage's messages before every "
               "bin map is in. Event timing only (the analytic level assumes after_geometry).",
               [](MachineConfig& c) -> Ref { return choice(&c.frames.gp_send); },
               "after_geometry|when_full"},
              "no source says when a GP shipped a bin: the paper and Banks describe binning by "
              "region, not when a bin left; a bin cannot be complete before the GP's whole "
              "share is set up, and a full message could go earlier",
              "frames.gp_send=after_geometry", "frames.gp_send=when_full"),

      // Not the machine: how much of it a run simulates (README "Fidelity levels").
      {"fidelity.pixels", "level", "A", 0, 0, 0,
       "What executes the firmware on the pixel arrays: 'bit' (bit-serial on bit-planes, as "
       "the hardware; traces need it), 'word' (a whole field at a time: bit-identical pixel "
       "memory, no per-bit state) or 'none' (timing only: no image).",
       [](MachineConfig& c) -> Ref { return choice(&c.fidelity.pixels); }, "bit|word|none"},
      {"fidelity.timing", "level", "A", 0, 0, 0,
       "Where the frame time comes from: 'event' (the SystemC model of every unit, with "
       "contention) or 'analytic' (each unit's work from the same cost tables and a "
       "recurrence over the messages with queueing at channels, GPs and queues, no events; "
       "its error against 'event' is measured on held-out machines, docs/timing.md).",
       [](MachineConfig& c) -> Ref { return choice(&c.fidelity.timing); }, "event|analytic"},
      {"fidelity.window_x", "regions", "A", 0, 0, 1024,
       "First column of regions whose pixels execute; the others are timed only (black).",
       [](MachineConfig& c) -> Ref { return &c.fidelity.window_x; }},
      {"fidelity.window_y", "regions", "A", 0, 0, 1024,
       "First row of regions whose pixels execute.",
       [](MachineConfig& c) -> Ref { return &c.fidelity.window_y; }},
      {"fidelity.window_columns", "regions", "A", 0, 0, 1024,
       "Columns of regions whose pixels execute, from window_x; 0: to the screen's edge.",
       [](MachineConfig& c) -> Ref { return &c.fidelity.window_columns; }},
      {"fidelity.window_rows", "regions", "A", 0, 0, 1024,
       "Rows of regions whose pixels execute, from window_y; 0: to the screen's edge.",
       [](MachineConfig& c) -> Ref { return &c.fidelity.window_rows; }},

      // The firmware's frame parameters (firmware/isa/interface.hpp names them), sent once per
      // frame; `pp5sim isa` lists them from here. Settable: firmware options of the
      // highlighting and transparency programs. Computed: the GP's, from the scene and the
      // settable ones.
      computed(Parameter::light_x, "x 127",
               "Eye-space unit vector toward the light, x times 127: the scene's first light, "
               "or in the `light` procedure the light it runs for.",
               "the scene's lights (direction)"),
      computed(Parameter::light_y, "x 127", "Light direction y times 127.",
               "the scene's lights (direction)"),
      computed(Parameter::light_z, "x 127", "Light direction z times 127.",
               "the scene's lights (direction)"),
      computed(Parameter::half_x, "x 127",
               "Eye-space half vector (light + view, normalised), x times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::half_y, "x 127", "Half vector y times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::half_z, "x 127", "Half vector z times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::ambient, "1/255", "Ambient reflection, 0..255 (255 = 1.0).",
               "the scene's ambient (scene file \"ambient\", 0 to 1)"),
      computed(Parameter::diffuse, "1/255",
               "Diffuse reflection, 0..255, of the light bound (see the `light` procedure).",
               "the scene's lights (\"diffuse\", 0 to 1)"),
      computed(Parameter::specular, "1/255", "Specular reflection, 0..255, of the light bound.",
               "the scene's lights (\"specular\", 0 to 1)"),
      computed(Parameter::background_red, "1/255", "Background red, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      computed(Parameter::background_green, "1/255", "Background green, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      computed(Parameter::background_blue, "1/255", "Background blue, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      settable(Parameter::highlight_red, "1/255", 255, 0, 255, "Intersection highlight red."),
      settable(Parameter::highlight_green, "1/255", 230, 0, 255, "Highlight green."),
      settable(Parameter::highlight_blue, "1/255", 0, 0, 255, "Highlight blue."),
      settable(Parameter::highlight_opacity, "1/256", 256, 0, 256,
               "Highlight opacity (256 = opaque)."),
      computed(Parameter::highlight_keep, "1/256",
               "256 - highlight_opacity: the weight of the surface colour.",
               "frame.highlight_opacity (derived)"),
      settable(Parameter::threshold, "depth units", 32768, 0, 16777215,
               "The threshold programs flag where |depth - stored depth| < threshold. Default and "
               "range are for gp.depth_bits = 24 and scale with 2^(gp.depth_bits - 24): the "
               "default is 1/512 of the depth range at any depth_bits.",
               true),
      settable(Parameter::delta, "1/16 pixel", 24, 0, 1024,
               "Half-width of fixed-width curves (epsilon programs; also the highlight "
               "report's truth)."),
      computed(Parameter::epsilon_scale, "slope units",
               "(delta/16)^2 * 4^6, so that dz^2 < epsilon_scale * |slope difference|^2 with "
               "slopes in units of 64 depth units per pixel.",
               "frame.delta (derived)"),
      settable(Parameter::silhouette, "x 127", 0, 0, 127,
               "Silhouette remedy: ignore the flag where the frontmost |normal z| * 127 < "
               "silhouette (0: off)."),
      settable(Parameter::surface_opacity, "1/256", 128, 0, 256,
               "Opacity of every surface in the transparency programs."),
      computed(Parameter::surface_keep, "1/256", "256 - surface_opacity.",
               "frame.surface_opacity (derived)"),
      computed(Parameter::normal_epsilon_scale, "slope units",
               "(delta/16)^2 * S^2 / 256, S = depth units per pixel per unit of eye-space slope "
               "at the camera's target distance (epsilon_normal: slopes recovered from "
               "normals).",
               "frame.delta, gp.depth_bits and the scene's camera (derived)"),
      settable(Parameter::layers, "passes", 4, 1, 64,
               "Layers the multipass programs peel (transparent*): their pass count, as they "
               "say `option passes layers`; each pass resends the region's triangles. A CSG "
               "program that peels (defines `next_layer`, csg_layers) peels this many layers "
               "of each literal of a product of two or more."),
  };
  return table;
}

Ref ref_of(const Entry& e, MachineConfig& c) {
  if (e.frame >= 0) return &c.frame.set[static_cast<std::size_t>(e.frame)];
  return e.ref(c);
}

const Entry* find_parameter(const std::string& key) {
  for (const auto& p : parameter_table()) {
    if (key == p.key) return &p;
  }
  return nullptr;
}

const Entry& frame_entry(Parameter k) {
  static const std::vector<const Entry*> by_index = [] {
    std::vector<const Entry*> v(static_cast<std::size_t>(Parameter::count), nullptr);
    for (const auto& e : parameter_table()) {
      if (e.frame >= 0) v[static_cast<std::size_t>(e.frame)] = &e;
    }
    for (const Entry* e : v) {
      if (!e) throw std::logic_error("a frame parameter is missing from the configuration table");
    }
    return v;
  }();
  return *by_index[static_cast<std::size_t>(k)];
}

std::string format_value(double v, bool is_int) {
  if (is_int) return fmt::format("{}", static_cast<long long>(v));
  return fmt::format("{:g}", v);
}

// A depth-scaled bound: declared for 24 bits, scaled to `depth_bits` (the range's top is one
// below a power of two at every depth).
std::int64_t scale_to_depth(double value, int depth_bits, bool is_max) {
  const double scaled = std::ldexp(is_max ? value + 1 : value, depth_bits - kReferenceDepthBits);
  return std::llround(scaled) - (is_max ? 1 : 0);
}

void assign(MachineConfig& config, const Entry& p, const nlohmann::json& value,
            const std::string& origin) {
  const Ref ref = ref_of(p, config);
  if (auto* c = std::get_if<ChoiceRef>(&ref)) {
    const auto allowed = split_choices(p.choices);
    if (value.is_string()) {
      for (std::size_t i = 0; i < allowed.size(); ++i) {
        if (allowed[i] == value.get<std::string>()) {
          c->put(c->target, static_cast<int>(i));
          return;
        }
      }
    }
    throw ConfigError(fmt::format("{}: key '{}' must be one of \"{}\" (got {})", origin, p.key,
                                  fmt::join(allowed, "\", \""), value.dump()));
  }
  if (p.computed_from) {
    throw ConfigError(fmt::format("{}: key '{}' cannot be set: the GP computes it from {}", origin,
                                  p.key, p.computed_from));
  }
  const bool is_int = !std::holds_alternative<double*>(ref);
  // An integer too large for 64 bits arrives from the JSON parser as a float: it is a whole
  // number out of range, not a fraction (the user wrote 99999999999999999999, not 1.5).
  if (is_int && value.is_number_float() && !std::holds_alternative<FrameRef>(ref)) {
    const double d = value.get<double>();
    if (std::isfinite(d) && d == std::trunc(d) && !(d >= p.min && d <= p.max)) {
      throw ConfigError(fmt::format("{}: key '{}' = {} is out of range [{}, {}] {}", origin, p.key,
                                    value.dump(), format_value(p.min, true),
                                    format_value(p.max, true), p.unit));
    }
  }
  if (!value.is_number() || (is_int && !value.is_number_integer())) {
    throw ConfigError(fmt::format("{}: key '{}' must be {} (got {})", origin, p.key,
                                  is_int ? "an integer" : "a number", value.dump()));
  }
  if (auto* f = std::get_if<FrameRef>(&ref)) {
    // The range of a depth-scaled key depends on gp.depth_bits, which may be set after it:
    // validate() checks every frame value once all keys are in.
    if (value.is_number_unsigned() && value.get<std::uint64_t>() > INT64_MAX) {
      throw ConfigError(
          fmt::format("{}: key '{}' = {} is out of range", origin, p.key, value.dump()));
    }
    **f = value.get<std::int64_t>();
    return;
  }
  const double v = value.get<double>();
  if (!(v >= p.min && v <= p.max)) {
    throw ConfigError(fmt::format("{}: key '{}' = {} is out of range [{}, {}] {}", origin, p.key,
                                  value.dump(), format_value(p.min, is_int),
                                  format_value(p.max, is_int), p.unit));
  }
  if (is_int) {
    *std::get<int*>(ref) = value.get<int>();
  } else {
    *std::get<double*>(ref) = v;
  }
}

// `assigned`: the keys set so far in this document, so that one given both flat
// ("renderer.count") and nested ({"renderer": {"count"}}) is refused like a repeated key.
void apply(MachineConfig& config, const nlohmann::json& node, const std::string& prefix,
           const std::string& origin, std::set<std::string>& assigned) {
  if (!node.is_object()) {
    throw ConfigError(fmt::format("{}: '{}' must be an object of parameters", origin,
                                  prefix.empty() ? "<top level>" : prefix));
  }
  for (const auto& [name, value] : node.items()) {
    const std::string key = prefix.empty() ? name : prefix + "." + name;
    if (const Entry* p = find_parameter(key)) {
      if (!assigned.insert(key).second) {
        throw ConfigError(fmt::format(
            "{}: key '{}' is given twice (once as a dotted name, once nested in its section); "
            "give it once",
            origin, key));
      }
      assign(config, *p, value, origin);
      continue;
    }
    bool is_section = false;
    for (const auto& p : parameter_table()) {
      if (p.key.rfind(key + ".", 0) == 0) is_section = true;
    }
    if (!is_section) {
      std::string known;
      const std::string parent = prefix.empty() ? "" : prefix + ".";
      for (const auto& p : parameter_table()) {
        const std::string k = p.key;
        if (k.rfind(parent, 0) != 0) continue;
        const std::string rest = k.substr(parent.size());
        const std::string head = rest.substr(0, rest.find('.'));
        if (known.find("'" + head + "'") == std::string::npos) {
          known += (known.empty() ? "" : ", ") + ("'" + head + "'");
        }
      }
      throw ConfigError(
          fmt::format("{}: unknown key '{}' (expected one of {})", origin, key, known));
    }
    apply(config, value, key, origin, assigned);
  }
}

void validate(const MachineConfig& c, const std::string& origin) {
  auto fail = [&](const std::string& what) {
    throw ConfigError(fmt::format("{}: {}", origin, what));
  };
  if (c.renderer.region_width % 64 != 0) {
    fail(
        "key 'renderer.region_width' must be a multiple of 64 (the array is stored 64 pixels "
        "to a host word)");
  }
  if (c.frames.gp_send == MachineConfig::Frames::GpSend::when_full &&
      c.fidelity.timing == MachineConfig::Fidelity::Timing::analytic) {
    fail(
        "key 'frames.gp_send' = when_full needs fidelity.timing=event (the analytic level's "
        "GPs send after their whole set-up: after_geometry)");
  }
  if (c.evaluator.result_bits < c.evaluator.coefficient_bits) {
    fail("key 'evaluator.result_bits' must be at least 'evaluator.coefficient_bits'");
  }
  if (c.gp.depth_bits + c.evaluator.fraction_bits + 2 > c.evaluator.coefficient_bits) {
    fail(
        fmt::format("keys 'gp.depth_bits' ({}) + 'evaluator.fraction_bits' ({}) + 2 must not "
                    "exceed 'evaluator.coefficient_bits' ({}): depth would not fit a coefficient",
                    c.gp.depth_bits, c.evaluator.fraction_bits, c.evaluator.coefficient_bits));
  }
  if (c.renderer.backing_store_bits % c.renderer.block_bits != 0) {
    fail("key 'renderer.backing_store_bits' must be a multiple of 'renderer.block_bits'");
  }
  if (c.fidelity.window_x >= c.regions_x() || c.fidelity.window_y >= c.regions_y()) {
    fail(fmt::format(
        "keys 'fidelity.window_x' ({}) and 'fidelity.window_y' ({}) must name a region of the "
        "screen, which has {} x {} regions",
        c.fidelity.window_x, c.fidelity.window_y, c.regions_x(), c.regions_y()));
  }
  for (int k = 0; k < static_cast<int>(Parameter::count); ++k) {
    if (const auto& v = c.frame.set[static_cast<std::size_t>(k)]) {
      check_frame_parameter(static_cast<Parameter>(k), *v, c.gp.depth_bits, origin);
    }
  }
}

}  // namespace

MachineConfig MachineConfig::defaults() {
  MachineConfig c;
  for (const auto& p : parameter_table()) {
    const Ref ref = ref_of(p, c);
    if (auto* i = std::get_if<int*>(&ref)) {
      **i = static_cast<int>(p.default_value);
    } else if (auto* choice = std::get_if<ChoiceRef>(&ref)) {
      choice->put(choice->target, 0);
    } else if (auto* d = std::get_if<double*>(&ref)) {
      **d = p.default_value;
    } else {
      std::get<FrameRef>(ref)->reset();  // unset: the default, resolved with the frame
    }
  }
  return c;
}

MachineConfig MachineConfig::from_json(const nlohmann::json& doc, const std::string& origin) {
  MachineConfig c = defaults();
  std::set<std::string> assigned;
  apply(c, doc, "", origin, assigned);
  validate(c, origin);
  return c;
}

MachineConfig MachineConfig::from_file(const std::string& path) {
  nlohmann::json doc;
  try {
    // A configuration is a few kilobytes; 1 MiB is far beyond any.
    doc = parse_strict_json(read_regular_file(path, 1u << 20, "a machine configuration (JSON)"),
                            path);
  } catch (const std::runtime_error& e) {
    throw ConfigError(e.what());
  }
  return from_json(doc, path);
}

void MachineConfig::set(const std::vector<std::string>& assignments) {
  MachineConfig result = *this;
  std::string origin = "--set";
  for (const std::string& assignment : assignments) {
    const auto eq = assignment.find('=');
    origin = fmt::format("--set {}", assignment);
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError(fmt::format("{}: expected KEY=VALUE, e.g. renderer.count=8", origin));
    }
    const std::string key = assignment.substr(0, eq);
    const std::string text = assignment.substr(eq + 1);
    const Entry* p = find_parameter(key);
    if (!p && key.rfind("frame.", 0) == 0) {
      throw ConfigError(
          fmt::format("{}: unknown key '{}': no frame parameter '{}' (pp5sim isa "
                      "lists them)",
                      origin, key, key.substr(6)));
    }
    if (!p) {
      throw ConfigError(
          fmt::format("{}: unknown key '{}' (pp5sim config --describe lists them)", origin, key));
    }
    nlohmann::json value;
    try {
      value = p->choices ? nlohmann::json(text) : nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception&) {
      throw ConfigError(
          fmt::format("{}: value '{}' of key '{}' is not a number", origin, text, key));
    }
    assign(result, *p, value, origin);
  }
  validate(result, assignments.size() == 1 ? origin : "--set");
  *this = result;
}

nlohmann::json MachineConfig::to_json() const {
  nlohmann::json doc = nlohmann::json::object();
  MachineConfig copy = *this;
  for (const auto& p : parameter_table()) {
    const std::string& key = p.key;
    const auto dot = key.find('.');
    const Ref ref = ref_of(p, copy);
    // Frame parameters: only those the configuration sets. An unset one is not fixed by the
    // configuration: its default follows gp.depth_bits, and a scene file may set it.
    if (auto* f = std::get_if<FrameRef>(&ref)) {
      if (**f) doc[key.substr(0, dot)][key.substr(dot + 1)] = ***f;
      continue;
    }
    auto& slot = doc[key.substr(0, dot)][key.substr(dot + 1)];
    if (auto* i = std::get_if<int*>(&ref)) {
      slot = **i;
    } else if (auto* choice = std::get_if<ChoiceRef>(&ref)) {
      slot = split_choices(p.choices)[static_cast<std::size_t>(choice->get(choice->target))];
    } else {
      slot = *std::get<double*>(ref);
    }
  }
  return doc;
}

std::vector<ParameterInfo> describe_parameters() {
  std::vector<ParameterInfo> rows;
  MachineConfig scratch;
  for (const auto& p : parameter_table()) {
    ParameterInfo row;
    row.key = p.key;
    row.unit = p.unit;
    row.confidence = p.confidence;
    row.description = p.description;
    if (p.computed_from) {
      row.default_value = "computed";
      row.range = fmt::format("from {}", p.computed_from);
      row.computed = true;
    } else if (p.choices) {
      const auto allowed = split_choices(p.choices);
      row.default_value = allowed.front();
      row.range = fmt::format("{}", fmt::join(allowed, ", "));
    } else {
      const bool is_int = !std::holds_alternative<double*>(ref_of(p, scratch));
      row.default_value = format_value(p.default_value, is_int);
      row.range = format_value(p.min, is_int) + " .. " + format_value(p.max, is_int);
      if (p.depth_scaled) row.range += " (x 2^(gp.depth_bits - 24))";
    }
    row.calibration = p.calibration;
    row.basis = p.basis ? p.basis : "";
    row.low = split_words(p.low);
    row.high = split_words(p.high);
    row.consumes = split_words(p.consumes);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<std::string> fits_consuming(const std::string& id) {
  std::vector<std::string> keys;
  for (const auto& p : parameter_table()) {
    for (const std::string& figure : split_words(p.consumes)) {
      if (figure == id) keys.push_back(p.key);
    }
  }
  return keys;
}

std::string name_of(MachineConfig::Gp::Code code) {
  return split_choices(find_parameter("gp.code")->choices)[static_cast<std::size_t>(code)];
}

std::string name_of(MachineConfig::Renderer::Balancing balancing) {
  return split_choices(
      find_parameter("renderer.balancing")->choices)[static_cast<std::size_t>(balancing)];
}

std::string name_of(MachineConfig::Gp::OverheadForm form) {
  return split_choices(find_parameter("gp.overhead_form")->choices)[static_cast<std::size_t>(form)];
}

std::string name_of(MachineConfig::Renderer::MultiplyMicrocode microcode) {
  return split_choices(
      find_parameter("renderer.multiply_microcode")->choices)[static_cast<std::size_t>(microcode)];
}

std::string name_of(MachineConfig::Evaluator::BitOrder order) {
  return split_choices(
      find_parameter("evaluator.bit_order")->choices)[static_cast<std::size_t>(order)];
}

std::string name_of(MachineConfig::Gp::Multipass multipass) {
  return split_choices(
      find_parameter("gp.multipass")->choices)[static_cast<std::size_t>(multipass)];
}

std::string name_of(MachineConfig::Gp::SendOrder order) {
  return split_choices(find_parameter("gp.send_order")->choices)[static_cast<std::size_t>(order)];
}

const char* calibration_name(Calibration c) {
  switch (c) {
    case Calibration::fitted:
      return "fitted";
    case Calibration::derived:
      return "derived";
    case Calibration::assumed:
      return "assumed";
    case Calibration::none:
      break;
  }
  return "-";
}

std::string name_of(MachineConfig::Fidelity::Pixels pixels) {
  return split_choices(
      find_parameter("fidelity.pixels")->choices)[static_cast<std::size_t>(pixels)];
}

std::string name_of(MachineConfig::Fidelity::Timing timing) {
  return split_choices(
      find_parameter("fidelity.timing")->choices)[static_cast<std::size_t>(timing)];
}

bool frame_parameter_computed(Parameter k) { return frame_entry(k).computed_from != nullptr; }

std::int64_t frame_parameter_default(Parameter k, int depth_bits) {
  const Entry& e = frame_entry(k);
  if (e.computed_from) {
    throw ConfigError(
        fmt::format("key '{}' has no default: the GP computes it from {}", e.key, e.computed_from));
  }
  if (e.depth_scaled) return scale_to_depth(e.default_value, depth_bits, false);
  return static_cast<std::int64_t>(e.default_value);
}

void check_frame_parameter(Parameter k, std::int64_t value, int depth_bits,
                           const std::string& origin) {
  const Entry& e = frame_entry(k);
  if (e.computed_from) {
    throw ConfigError(fmt::format("{}: key '{}' cannot be set: the GP computes it from {}", origin,
                                  e.key, e.computed_from));
  }
  const std::int64_t lo =
      e.depth_scaled ? scale_to_depth(e.min, depth_bits, false) : static_cast<std::int64_t>(e.min);
  const std::int64_t hi =
      e.depth_scaled ? scale_to_depth(e.max, depth_bits, true) : static_cast<std::int64_t>(e.max);
  if (value < lo || value > hi) {
    throw ConfigError(fmt::format(
        "{}: key '{}' = {} is out of range [{}, {}] {}{}", origin, e.key, value, lo, hi, e.unit,
        e.depth_scaled ? fmt::format(" (at gp.depth_bits = {})", depth_bits) : std::string()));
  }
}

std::int64_t resolved_frame_parameter(const MachineConfig& c, Parameter k) {
  const auto& v = c.frame.set[static_cast<std::size_t>(k)];
  return v ? *v : frame_parameter_default(k, c.gp.depth_bits);
}

}  // namespace pp5
