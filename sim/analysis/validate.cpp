#include "sim/analysis/validate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <memory>
#define SC_INCLUDE_DYNAMIC_PROCESSES
#include <systemc>

#include "common/splitmix.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/machine.hpp"
#include "models/pixel_array/backends.hpp"
#include "models/renderer/renderer_board.hpp"
#include "models/ring/ring.hpp"
#include "sim/analysis/visible_surface.hpp"
#include "sim/kernel.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

// Published figures (../shared/design/pixel-planes-5.md gives each with its source).
constexpr double kDesignGoal = 1.0e6;       // P: "1 M Phong-shaded triangles per second"
constexpr double kReported = 2.0e6;         // S (weak): Usenet, 1991
constexpr double kHandCoded = 1.0e6;        // S: Banks, "well over 1 million polygons/second"
constexpr double kCompiled = 1.0e5;         // S: Banks, "about 100,000 polygons/second"
constexpr double kRingBitsPerSecond = 5e9;  // P: "5 gigabit ring network"
constexpr int kPixelMemoryBits = 208;       // P: bits per pixel processor
// Banks, sec. 5: the two-pass fixed-width algorithm needs a second normal (48 bits), a second
// depth (24) and epsilon scratch (64) beside the PHIGS fields: 136 bits more than fit.
constexpr int kBanksExtraBits = 48 + 24 + 64;
// S/A: Goldfeather, Hultquist & Fuchs, SIGGRAPH 1986 (Pixel-Powers at 10 MHz): 24 CSG
// primitives as about 1,900 quadratic operations in about 7.5 ms.
constexpr int kPixelPowersOperations = 1900;
constexpr double kPixelPowersClockHz = 10e6;
constexpr double kPixelPowersSeconds = 7.5e-3;

const char* kFuchs = "Fuchs et al., SIGGRAPH 1989, abstract (P)";
const char* kBanks = "Banks, Screen-Parallel Calculation of Surface Intersections, sec. 5 (S)";

double pipelined_rate(const FrameResult& r) {
  return r.stats.real("frame.pipelined_triangles_per_second");
}

// The GP side alone: the rate at which the machine's GPs transform and set up the scene's
// triangles, from the geometry clocks the simulation charged.
double gp_rate(const MachineConfig& c, const FrameResult& r) {
  const double clocks = r.stats.real("frame.gp_clocks_per_triangle");
  return clocks > 0 ? c.gp.count * c.gp.clock_hz / clocks : 0;
}

// Senders that keep the ring saturated with queue-sized messages; returns the bits per second
// it delivered (the last arrival bounds the time, so hop latency counts against it).
double measured_ring_bandwidth(const MachineConfig& c) {
  KernelContext kernel;  // declared first: freed after the ring and its senders
  RingParams p;
  p.channels = c.ring.channels;
  p.word_bits = c.ring.word_bits;
  p.clock_hz = c.ring.clock_hz;
  p.hop_latency_cycles = c.ring.hop_latency_cycles;
  // Every GP sends to a Renderer, as bins do: more senders than channels.
  const int senders = std::max(c.gp.count, 2 * c.ring.channels);
  const int stops = senders + c.renderer.count + 1;
  constexpr int kMessages = 64;
  const auto words = static_cast<std::uint64_t>(c.renderer.queue_words);
  Ring ring("validate_ring", p, stops);
  sc_core::sc_time last;
  for (int s = 0; s < senders; ++s) {
    const int to = senders + s % c.renderer.count;
    sc_core::sc_spawn(
        [&ring, &last, s, to, words] {
          for (int m = 0; m < kMessages; ++m) {
            ring.transfer(s, to, words);
            last = std::max(last, sc_core::sc_time_stamp());
          }
        },
        sc_core::sc_gen_unique_name("sender"));
  }
  kernel.run();
  const double bits = static_cast<double>(ring.words()) * p.word_bits;
  return bits / last.to_seconds();
}

// The pixel memory a program needs: the bits it uses (scratch overlays shared, as the
// assembler lays them out) plus those of any field spilled to the backing store.
int needed_bits(const Program& p) {
  int bits = p.bits_used();
  for (const FieldDecl& f : p.fields) bits += f.spilled ? f.width : 0;
  return bits;
}

std::string fit_note(const Program& p) {
  int spilled = 0;
  for (const FieldDecl& f : p.fields) spilled += f.spilled ? 1 : 0;
  if (spilled == 0) return fmt::format("fits: {} of {} bits used", p.bits_used(), p.memory_bits);
  return fmt::format("does not fit: {} fields spill to the backing store", spilled);
}

// One Pixel-Powers quadratic operation as this machine's firmware: a quadric evaluated at
// every pixel and compared with the pixel's stored depth, the result left in E.
const char* kQuadricOperation = R"(; Pixel-Powers' quadratic operation (pp5sim validate)
field z 24
field c 8
output c c c
proc clear
  eall
  mov z, 0xFFFFFF
end
proc triangle
  eall
  qcmp.lt z, depth
end
)";

// Runs `operations` quadratic operations on a Renderer's array (the bit backend) with the
// quadrics of spheres spread over the region, and returns the array cycles they cost.
std::uint64_t quadric_operation_cycles(const MachineConfig& c, int operations) {
  const Program program = assemble(kQuadricOperation, "validate-quadric", assembler_options(c));
  const RendererBoardParams board = board_params(c);  // a board's array and evaluator
  PixelBackendParams params;
  params.array = board.array;
  params.evaluator = board.evaluator;
  params.fraction_bits = c.evaluator.fraction_bits;
  auto array = make_pixel_backend("bit", params);
  const TimingParams timing = timing_params(c);
  OwnedValues values;
  auto run = [&](Procedure procedure) {
    std::uint64_t cycles = 0;
    ExecutionContext ctx{*array, values, params.fraction_bits, timing.multiply_window};
    for (const Instruction& ins : program.procedure(procedure).code) {
      const InstructionInfo& info = instruction_info(ins.op);
      info.execute(ins, ctx);
      cycles += info.cost(ins, timing, values).count;
    }
    return cycles;
  };
  run(Procedure::clear);
  std::uint64_t cycles = 0;
  const std::int64_t one = std::int64_t{1} << c.evaluator.fraction_bits;
  for (int k = 0; k < operations; ++k) {
    // A sphere's front depth, to second order about its centre: z0 + s((x-cx)^2 + (y-cy)^2).
    const std::int64_t cx = (k * 37) % c.renderer.region_width;
    const std::int64_t cy = (k * 53) % c.renderer.region_height;
    const std::int64_t s = 64 + k % 64;
    const std::int64_t z0 = 1000000 + 997 * k;
    QuadraticCoefficients q;
    q.A = s * one;
    q.C = s * one;
    q.D = -2 * s * cx * one;
    q.E = -2 * s * cy * one;
    q.F = (z0 + s * (cx * cx + cy * cy)) * one;
    values.expressions[static_cast<int>(Expression::depth)] = q;
    cycles += run(Procedure::triangle);
  }
  return cycles;
}

std::string thousands(double v) {
  const auto n = static_cast<long long>(std::llround(v));
  std::string digits = std::to_string(n < 0 ? -n : n);
  for (int i = static_cast<int>(digits.size()) - 3; i > 0; i -= 3) digits.insert(i, ",");
  return (n < 0 ? "-" : "") + digits;
}

std::string value_text(double v, const std::string& unit) {
  if (unit == "ms") return fmt::format("{:.2f}", v);
  if (unit == "Gb/s") return fmt::format("{:.2f}", v);
  return thousands(v);
}

}  // namespace

std::vector<ValidationRow> validate_against_record(const MachineConfig& base,
                                                   const ProgramLoader& load,
                                                   const ValidationOptions& options) {
  std::vector<ValidationRow> rows;
  MachineConfig assembly = base;
  assembly.gp.code = MachineConfig::Gp::Code::assembly;
  MachineConfig compiled = base;
  compiled.gp.code = MachineConfig::Gp::Code::compiled;

  // The full machine on a large triangle scene, against the design goal.
  {
    const Scene big = make_builtin_scene("torus", {options.tessellation_u, options.tessellation_v});
    const FrameResult r = project_frame(assembly, big, load("phong", assembly));
    const std::string workload =
        fmt::format("torus, {} triangles, phong, hand-coded GPs, {} GPs, {} Renderers, {} x {}",
                    thousands(static_cast<double>(big.mesh.triangles.size())), base.gp.count,
                    base.renderer.count, base.screen.width, base.screen.height);
    const std::string bottleneck = r.stats.text("timing.bottleneck");
    rows.push_back(
        {"design goal: Phong-shaded triangles/s of the full machine", kFuchs, "1,000,000",
         kDesignGoal, workload + ", one frame", r.triangles_per_second, "triangles/s", "predicted",
         fmt::format("frame {:.2f} ms, bottleneck {}", r.frame_seconds * 1e3, bottleneck)});
    rows.push_back(
        {"design goal, frames pipelined", kFuchs, "1,000,000", kDesignGoal,
         workload + ", GPs on frame n+1 while the Renderers finish frame n", pipelined_rate(r),
         "triangles/s", "predicted",
         fmt::format("period {:.2f} ms", r.stats.real("frame.pipelined_frame_seconds") * 1e3)});
    rows.push_back({"reported: Phong-shaded polygons/s", "Usenet, 1991 (S, weak)", "2,000,000",
                    kReported, workload + ", frames pipelined", pipelined_rate(r), "triangles/s",
                    "predicted", "a second-hand figure; scene and shading unknown"});
  }

  // The GPs alone, transforming and setting up Phong triangles: the two code profiles.
  {
    const Scene torus = make_builtin_scene("torus");
    const FrameResult fast = project_frame(assembly, torus, load("phong", assembly));
    const FrameResult slow = project_frame(compiled, torus, load("phong", compiled));
    const std::string workload = fmt::format(
        "GP geometry of the torus (8,192 triangles, phong): {} GPs x {} MHz / i860 clocks per "
        "triangle",
        base.gp.count, base.gp.clock_hz / 1e6);
    ValidationRow hand{"transform + Phong, hand-coded i860 assembly",
                       kBanks,
                       "well over 1,000,000",
                       kHandCoded,
                       workload,
                       gp_rate(assembly, fast),
                       "triangles/s",
                       "predicted",
                       fmt::format("fitted to 1.2 M on one unclipped triangle; {:.0f} clocks per "
                                   "torus triangle",
                                   fast.stats.real("frame.gp_clocks_per_triangle"))};
    hand.id = "banks.hand_coded_rate";
    rows.push_back(hand);
    ValidationRow slow_row{
        "transform + Phong, compiled C",
        kBanks,
        "about 100,000",
        kCompiled,
        workload + ", gp.code=compiled",
        gp_rate(compiled, slow),
        "triangles/s",
        "predicted",
        fmt::format("{:.0f} clocks per triangle", slow.stats.real("frame.gp_clocks_per_triangle"))};
    slow_row.id = "banks.compiled_rate";
    rows.push_back(slow_row);
  }

  // The ring's bandwidth, measured by saturating the Ring module.
  rows.push_back({"ring bandwidth", kFuchs, "5 gigabit", kRingBitsPerSecond / 1e9,
                  fmt::format("every GP sends queue-sized messages ({} words) to Renderers "
                              "back to back",
                              base.renderer.queue_words),
                  measured_ring_bandwidth(base) / 1e9, "Gb/s", "derived",
                  fmt::format("ring.channels x ring.word_bits x ring.clock_hz = {} x {} x {:g} "
                              "MHz; the organisation is assumed",
                              base.ring.channels, base.ring.word_bits, base.ring.clock_hz / 1e6)});

  // Pixel memory: what fits in 208 bits.
  {
    const Program phong = load("phong", base);
    const Program epsilon = load("epsilon", base);
    const Program folded = load("epsilon_folded", base);
    rows.push_back({"208 bits per pixel hold Phong rendering", kFuchs, "208 bits", kPixelMemoryBits,
                    "phong.pp5's fields (z, colour, normal, scratch)",
                    static_cast<double>(needed_bits(phong)), "bits", "predicted", fit_note(phong)});
    rows.push_back(
        {"two-pass fixed-width epsilon does not fit beside the PHIGS fields (136 bits more)",
         kBanks, fmt::format("more than {} bits", kPixelMemoryBits), kPixelMemoryBits,
         "epsilon.pp5's fields", static_cast<double>(needed_bits(epsilon)), "bits", "predicted",
         fmt::format("{}; Banks: the PHIGS fields + {} bits exceed 208", fit_note(epsilon),
                     kBanksExtraBits)});
    rows.push_back({"folded epsilon ran on the machine", kBanks,
                    fmt::format("at most {} bits", kPixelMemoryBits), kPixelMemoryBits,
                    "epsilon_folded.pp5's fields", static_cast<double>(needed_bits(folded)), "bits",
                    "predicted", fit_note(folded)});
  }

  // Pixel-Powers' CSG timing, at its 10 MHz, on this machine's instruction set.
  {
    const std::uint64_t cycles = quadric_operation_cycles(base, kPixelPowersOperations);
    rows.push_back({"Pixel-Powers: 24 CSG primitives as about 1,900 quadratic operations",
                    "Goldfeather, Hultquist & Fuchs, SIGGRAPH 1986 (S)", "about 7.5 ms at 10 MHz",
                    kPixelPowersSeconds * 1e3,
                    "1,900 quadrics evaluated and compared with a 24-bit depth on the bit backend "
                    "(eall; qcmp.lt z, depth), at 10 MHz",
                    static_cast<double>(cycles) / kPixelPowersClockHz * 1e3, "ms", "predicted",
                    fmt::format("{:.1f} array cycles per operation against about 39",
                                static_cast<double>(cycles) / kPixelPowersOperations)});
  }
  // A figure some fit consumed is fitted, whatever the row said: the table decides.
  for (ValidationRow& r : rows) {
    if (r.id.empty()) continue;
    r.consumed_by = fits_consuming(r.id);
    if (!r.consumed_by.empty()) r.status = "fitted";
  }
  return rows;
}

std::string SensitivityWorkload::label() const {
  return fmt::format("{} ({})", program, name_of(code));
}

std::vector<SensitivityWorkload> default_sensitivity_workloads() {
  using Code = MachineConfig::Gp::Code;
  return {{"phong", Code::assembly},
          {"threshold", Code::compiled},
          {"epsilon", Code::compiled},
          {"transparent", Code::compiled}};
}

SensitivityTable sensitivity(const MachineConfig& base, const ProgramLoader& load,
                             const std::vector<SensitivityWorkload>& workloads,
                             const std::vector<std::string>& only) {
  const Scene torus = make_builtin_scene("torus");
  // A set-up memo per workload (its program's expressions are part of the key): the points
  // that change no geometry parameter replay the torus's set-up (models/gp/setup_memo.hpp).
  std::vector<std::unique_ptr<SetupMemo>> memos;
  for (std::size_t k = 0; k < workloads.size(); ++k)
    memos.push_back(std::make_unique<SetupMemo>(torus));
  const auto torus_shared = std::make_shared<const Scene>(torus);
  auto rate = [&](MachineConfig c, const SensitivityWorkload& w,
                  const std::vector<std::string>& sets, bool sequence = false) {
    c.gp.code = w.code;
    // An end of a range may not combine with what --config/--set changed (a result width
    // below the coefficients they asked for): that point is not a machine, and has no rate.
    try {
      if (!sets.empty()) c.set(sets);
    } catch (const ConfigError&) {
      return std::nan("");
    }
    // The program is assembled for the point: its layout follows memory and block sizes.
    SetupMemo& memo = *memos[static_cast<std::size_t>(&w - workloads.data())];
    // A key of a run of frames (frames.*) changes nothing in one frame: its rows are the
    // sustained rate of three frames overlapped (Session::run_frames), simulated, its
    // default column included.
    if (sequence) {
      Session session(c, torus_shared, std::make_shared<const Program>(load(w.program, c)), 1);
      return session.run_frames(3, {}, false).sustained_triangles_per_second;
    }
    return project_frame(c, torus, load(w.program, c), &memo).triangles_per_second;
  };
  SensitivityTable table;
  table.workloads = workloads;
  for (const SensitivityWorkload& w : workloads) table.defaults.push_back(rate(base, w, {}));
  std::vector<double> sustained;  // the defaults of a run of frames, made when first needed
  for (const ParameterInfo& p : describe_parameters()) {
    if (p.low.empty() || p.high.empty()) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), p.key) == only.end()) continue;
    SensitivityRow row{p.key, p.calibration, p.low, p.high, {}};
    const bool sequence = p.key.rfind("frames.", 0) == 0;
    row.sustained = sequence;
    if (sequence && sustained.empty()) {
      for (const SensitivityWorkload& w : workloads) sustained.push_back(rate(base, w, {}, true));
    }
    for (std::size_t k = 0; k < workloads.size(); ++k) {
      const double at_default = sequence ? sustained[k] : table.defaults[k];
      row.rates.push_back({rate(base, workloads[k], p.low, sequence), at_default,
                           rate(base, workloads[k], p.high, sequence)});
    }
    table.rows.push_back(std::move(row));
  }
  return table;
}

namespace {

// One end of a range as a single numeric assignment of `key`, if it is one.
bool numeric_end(const std::vector<std::string>& end, const std::string& key, double& value) {
  if (end.size() != 1 || end[0].rfind(key + "=", 0) != 0) return false;
  const std::string text = end[0].substr(key.size() + 1);
  char* stop = nullptr;
  value = std::strtod(text.c_str(), &stop);
  return stop != nullptr && *stop == '\0' && !text.empty();
}

// The assignments that put constant `p` at quantile u of its range.
std::vector<std::string> at_quantile(const ParameterInfo& p, double u) {
  double lo = 0, hi = 0;
  if (numeric_end(p.low, p.key, lo) && numeric_end(p.high, p.key, hi)) {
    const bool integer = p.default_value.find_first_of(".e") == std::string::npos;
    double v = lo > 0 && hi / lo >= 4 ? lo * std::pow(hi / lo, u) : lo + u * (hi - lo);
    if (integer) return {fmt::format("{}={}", p.key, std::llround(v))};
    return {fmt::format("{}={:.6g}", p.key, v)};
  }
  if (u < 1.0 / 3) return p.low;
  if (u < 2.0 / 3) return {};
  return p.high;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(at);
  const double f = at - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

ConclusionShare share_of(const std::string& conclusion, const std::string& measure,
                         const std::vector<double>& values, int holds) {
  ConclusionShare c;
  c.conclusion = conclusion;
  c.measure = measure;
  c.low = quantile(values, 0.05);
  c.median = quantile(values, 0.5);
  c.high = quantile(values, 0.95);
  c.min = values.empty() ? 0 : *std::min_element(values.begin(), values.end());
  c.max = values.empty() ? 0 : *std::max_element(values.begin(), values.end());
  c.holds = holds;
  c.samples = static_cast<int>(values.size());
  return c;
}

}  // namespace

JointSensitivity joint_sensitivity(const MachineConfig& base, const ProgramLoader& load,
                                   const JointSensitivityOptions& options) {
  JointSensitivity out;
  out.options = options;
  std::vector<ParameterInfo> constants;
  for (const ParameterInfo& p : describe_parameters()) {
    if (p.low.empty() || p.high.empty()) continue;
    // Its conclusions are one frame's (and its pipelined closed form's): a key of a run of
    // frames (frames.*) changes nothing there (the sensitivity table measures those keys on
    // the sustained rate).
    if (p.key.rfind("frames.", 0) == 0) continue;
    constants.push_back(p);
    out.varied.push_back(p.key);
  }
  // Workload choices after the constants: scene, triangle size, back-face culling; then the
  // painter's choices: back faces removed first, splitting, per region bin, the factor.
  const std::size_t dimensions = constants.size() + 7;
  out.varied.insert(
      out.varied.end(),
      {"scene (torus, figure-eight)", "triangle size (x 1/4, 1, 4 triangles)", "gp.cull_back_faces",
       "painter's: back faces removed first", "painter's: splitting", "painter's: per region bin",
       "painter's: sort x gp.overhead_factor"});
  const int n = std::max(1, options.samples);
  SplitMix64 random{options.seed};
  // Latin hypercube: each dimension's n strata in a random order, a random point in each.
  std::vector<std::vector<double>> u(dimensions, std::vector<double>(static_cast<std::size_t>(n)));
  for (auto& column : u) {
    std::vector<int> strata(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) strata[static_cast<std::size_t>(i)] = i;
    for (int i = n - 1; i > 0; --i) {
      const auto j = static_cast<std::size_t>(random.next() % static_cast<std::uint64_t>(i + 1));
      std::swap(strata[static_cast<std::size_t>(i)], strata[j]);
    }
    for (int i = 0; i < n; ++i) {
      column[static_cast<std::size_t>(i)] =
          (strata[static_cast<std::size_t>(i)] + random.unit()) / static_cast<double>(n);
    }
  }
  std::vector<double> gaps, pipelined_gaps, renderer_share, painter_ratio;
  int renderers = 0, below = 0, pipelined_below = 0, zbuffer_faster = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = static_cast<std::size_t>(i);
    JointSample sample;
    // Ends that move linked keys go last, so that their keys win over a single key's value
    // (a 48-bit coefficient end brings its 48 result bits with it).
    std::vector<std::string> linked;
    for (std::size_t d = 0; d < constants.size(); ++d) {
      const std::vector<std::string> a = at_quantile(constants[d], u[d][s]);
      (a.size() > 1 ? linked : sample.sets)
          .insert((a.size() > 1 ? linked : sample.sets).end(), a.begin(), a.end());
    }
    sample.sets.insert(sample.sets.end(), linked.begin(), linked.end());
    const double scene_u = u[constants.size()][s];
    const double size_u = u[constants.size() + 1][s];
    const bool cull = u[constants.size() + 2][s] >= 0.5;
    sample.sets.push_back(cull ? "gp.cull_back_faces=1" : "gp.cull_back_faces=0");
    const int size = size_u < 1.0 / 3 ? 0 : size_u < 2.0 / 3 ? 1 : 2;  // 1/4, 1, 4 triangles
    const int tu = std::max(8, options.tessellation_u * (1 << size) / 2);
    const int tv = std::max(4, options.tessellation_v * (1 << size) / 2);
    const bool eight = scene_u >= 0.5;
    sample.scene = fmt::format("{} {} x {}", eight ? "figure-eight" : "torus", tu, tv);
    const Scene scene = make_builtin_scene(eight ? "figure-eight" : "torus", {tu, tv});
    sample.triangles = static_cast<int>(scene.mesh.triangles.size());
    MachineConfig c = base;
    c.gp.code = MachineConfig::Gp::Code::assembly;
    try {
      c.set(sample.sets);
      c.set(std::vector<std::string>{"fidelity.pixels=none", "fidelity.timing=" + options.level});
    } catch (const ConfigError& e) {
      out.skipped.push_back(e.what());  // ends that do not combine: no machine
      continue;
    }
    const FrameResult r = project_frame(c, scene, load("phong", c));
    sample.rate = r.triangles_per_second;
    sample.pipelined_rate = pipelined_rate(r);
    sample.bottleneck = r.stats.text("timing.bottleneck");
    sample.painter_over_zbuffer = std::nan("");
    if (i < options.painter_samples) {
      PainterOptions painter;
      const std::size_t at = constants.size() + 3;
      painter.remove_back_faces = u[at][s] >= 0.5;
      painter.split_rounds = u[at + 1][s] >= 0.5 ? 8 : 0;
      const bool per_region = u[at + 2][s] >= 0.5;
      painter.overhead_factor = u[at + 3][s] >= 0.5;
      sample.painter_choices = fmt::format(
          "{}, {}, {}, {}", painter.remove_back_faces ? "back faces removed" : "every face",
          painter.split_rounds ? "split" : "unsplit", per_region ? "per region" : "whole screen",
          painter.overhead_factor ? "x factor" : "own counts");
      const PainterTiming t =
          painter_against_zbuffer(c, make_builtin_scene("torus"), load("gouraud", c),
                                  load("painter", c), painter, per_region);
      sample.painter_over_zbuffer = t.painter_seconds() / t.zbuffer_seconds - 1;
      painter_ratio.push_back(sample.painter_over_zbuffer);
      if (sample.painter_over_zbuffer > 0) ++zbuffer_faster;
    }
    gaps.push_back(sample.rate / kDesignGoal - 1);
    pipelined_gaps.push_back(sample.pipelined_rate / kDesignGoal - 1);
    if (sample.rate < kDesignGoal) ++below;
    if (sample.pipelined_rate < kDesignGoal) ++pipelined_below;
    const double share = r.stats.real("timing.renderer_seconds") / r.frame_seconds;
    renderer_share.push_back(share);
    if (sample.bottleneck == "Renderers") ++renderers;
    out.points.push_back(std::move(sample));
  }
  out.conclusions.push_back(share_of("the bottleneck is the Renderers",
                                     "Renderers' share of the critical path", renderer_share,
                                     renderers));
  out.conclusions.push_back(share_of("one frame falls short of the design goal (1 M/s)",
                                     "rate / 1 M - 1, one frame", gaps, below));
  out.conclusions.push_back(share_of("frames pipelined fall short of the design goal",
                                     "rate / 1 M - 1, pipelined", pipelined_gaps, pipelined_below));
  if (!painter_ratio.empty()) {
    out.conclusions.push_back(share_of(
        "the z-buffer is faster than painter's (the torus, 8,192 triangles)",
        "painter's time (frame + sort) / z-buffer frame - 1", painter_ratio, zbuffer_faster));
  }
  return out;
}

report::Table joint_sensitivity_table(const JointSensitivity& j) {
  using namespace report;
  Table t;
  t.id = "joint-conclusions";
  t.columns = {
      text_column("conclusion", "What the default machine says"),
      text_column("measure", "What is measured per sample"),
      left_aligned(
          real_column("5% .. 95% (median)", "%", 0,
                      "The measure's 5th to 95th percentile over the samples (its median)")),
      left_aligned(real_column("min .. max", "%", 0, "The measure's range over the samples")),
      left_aligned(real_column("holds in", "%", 0, "The samples where the conclusion holds")),
  };
  for (const ConclusionShare& c : j.conclusions) {
    const bool percent = c.measure.find("share") == std::string::npos;
    auto v = [percent](double x) {
      return percent ? fmt::format("{:+.0f}%", 100 * x) : fmt::format("{:.0f}%", 100 * x);
    };
    const double holds = c.samples ? 100.0 * c.holds / c.samples : 0.0;
    t.add_row(
        {c.conclusion, c.measure,
         Cell::shown_as(100 * c.median,
                        fmt::format("{} .. {} ({})", v(c.low), v(c.high), v(c.median))),
         Cell::shown_as(100 * c.max, fmt::format("{} .. {}", v(c.min), v(c.max))),
         Cell::shown_as(holds, fmt::format("{} of {} ({:.0f}%)", c.holds, c.samples, holds))});
  }
  return t;
}

report::Table joint_samples_table(const JointSensitivity& j) {
  using namespace report;
  Table t;
  t.id = "joint";
  t.columns = {integer_column("sample"),
               text_column("scene"),
               integer_column("triangles", "triangles"),
               real_column("rate", "triangles/s", -1, "Projected rate, one frame"),
               real_column("pipelined_rate", "triangles/s", -1, "Projected rate, frames pipelined"),
               text_column("bottleneck"),
               real_column("painter_over_zbuffer", "", -1,
                           "Painter's time (frame + sort) / z-buffer frame - 1"),
               text_column("painter_choices"),
               text_column("sets", "The sample's assignments")};
  for (auto& c : t.columns) c.key = c.name;
  for (std::size_t k = 0; k < j.points.size(); ++k) {
    const JointSample& p = j.points[k];
    t.add_row({static_cast<std::int64_t>(k), p.scene, static_cast<std::int64_t>(p.triangles),
               p.rate, p.pipelined_rate, p.bottleneck, p.painter_over_zbuffer, p.painter_choices,
               fmt::format("{}", fmt::join(p.sets, " "))});
  }
  return t;
}

std::string joint_sensitivity_markdown(const JointSensitivity& j) {
  std::string out = fmt::format(
      "{} samples (Latin hypercube, seed {:#x}, {} timing; {} drawn, {} not a "
      "machine), varying together: {}.\n\n",
      j.points.size(), j.options.seed, j.options.level, j.points.size() + j.skipped.size(),
      j.skipped.size(), fmt::join(j.varied, ", "));
  out += report::markdown(joint_sensitivity_table(j));
  out += joint_bottleneck_text(j);
  return out;
}

std::string joint_bottleneck_text(const JointSensitivity& j) {
  // Which bottleneck the samples name.
  int gps = 0, ring = 0, ren = 0;
  for (const JointSample& p : j.points) {
    gps += p.bottleneck == "GPs";
    ring += p.bottleneck == "ring";
    ren += p.bottleneck == "Renderers";
  }
  return fmt::format("\nBottleneck over the samples: Renderers {}, GPs {}, ring {}.\n", ren, gps,
                     ring);
}

namespace {
std::string consumed_text(const ValidationRow& r) {
  if (r.consumed_by.empty()) return "-";
  std::string out;
  for (const std::string& k : r.consumed_by) out += (out.empty() ? "`" : ", `") + k + "`";
  return out;
}
}  // namespace

report::Table validation_table(const std::vector<ValidationRow>& rows) {
  using namespace report;
  Table t;
  t.id = "validate";
  t.columns = {
      text_column("published figure", "What the record says"),
      text_column("source", "Where, with its confidence (P, S)"),
      text_column("published", "The figure as the source gives it"),
      left_aligned(
          real_column("simulated", "", -1, "The simulator's projection, in the row's unit")),
      left_aligned(real_column("difference", "%", 0, "(simulated - published) / published")),
      text_column("status", "fitted, derived or predicted"),
      text_column("consumed by the fit of", "The configuration keys fitted to this figure"),
      text_column("evidence", "Whether the figure tests the model (a prediction)"),
      text_column("simulated workload", "What the simulator ran"),
      text_column("note", "What else the run showed"),
  };
  for (const ValidationRow& r : rows) {
    t.add_row({r.figure, r.source, r.published,
               Cell::shown_as(r.simulated, value_text(r.simulated, r.unit) + " " + r.unit),
               Cell::shown_as(100 * r.difference(), fmt::format("{:+.0f}%", 100 * r.difference())),
               r.status, consumed_text(r), r.evidence() ? "yes" : "no", r.workload, r.note});
  }
  return t;
}

std::string validation_markdown(const std::vector<ValidationRow>& rows) {
  return report::markdown(validation_table(rows));
}

std::string evidence_summary(const std::vector<ValidationRow>& rows) {
  std::string predicted, fitted, derived;
  int n_predicted = 0, n_fitted = 0, n_derived = 0;
  for (const ValidationRow& r : rows) {
    if (r.evidence()) {
      ++n_predicted;
      predicted +=
          fmt::format("- {}: {} {} against {} ({:+.0f}%)\n", r.figure,
                      value_text(r.simulated, r.unit), r.unit, r.published, 100 * r.difference());
    } else if (r.status == "fitted") {
      ++n_fitted;
      fitted += fmt::format("- {}: consumed by the fit of {}\n", r.figure, consumed_text(r));
    } else {
      ++n_derived;
      derived += fmt::format("- {}\n", r.figure);
    }
  }
  return fmt::format(
      "Evidence: {} of the {} figures are predictions, the only ones that test the model:\n{}"
      "{} figures were consumed by a fit (reproducing them is a consistency check, not "
      "evidence):\n{}{} figures were used to derive the configuration:\n{}",
      n_predicted, rows.size(), predicted, n_fitted, fitted, n_derived, derived);
}

report::Table validation_data_table(const std::vector<ValidationRow>& rows) {
  using namespace report;
  Table t;
  t.id = "validate";
  t.columns = {text_column("figure"),
               text_column("source"),
               text_column("published"),
               real_column("published_value", "", -1),
               real_column("simulated", "", -1),
               text_column("unit"),
               real_column("difference", "", -1),
               text_column("status"),
               text_column("consumed_by"),
               integer_column("evidence"),
               text_column("workload"),
               text_column("note")};
  for (const ValidationRow& r : rows) {
    std::string consumed;
    for (const std::string& k : r.consumed_by) consumed += (consumed.empty() ? "" : " ") + k;
    t.add_row({r.figure, r.source, r.published, r.published_value, r.simulated, r.unit,
               r.difference(), r.status, consumed, r.evidence() ? 1 : 0, r.workload, r.note});
  }
  return t;
}

namespace {
std::string assignments_text(const std::vector<std::string>& sets, const std::string& key) {
  // The key's own value first, linked keys after it in parentheses.
  std::string own, linked;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (s.substr(0, eq) == key) {
      own = s.substr(eq + 1);
    } else {
      linked += (linked.empty() ? "" : ", ") + s;
    }
  }
  return linked.empty() ? own : fmt::format("{} ({})", own, linked);
}
// A rate in thousands; '-' where the point was not a valid machine (NaN).
std::string kilo(double rate) {
  return std::isnan(rate) ? std::string("-") : fmt::format("{:.0f}", rate / 1e3);
}
std::string change(double rate, double base) {
  return std::isnan(rate) ? std::string("-") : fmt::format("{:+.0f}%", 100 * (rate - base) / base);
}
}  // namespace

report::Table sensitivity_table(const SensitivityTable& table) {
  using namespace report;
  Table t;
  t.id = "sensitivity";
  t.columns = {code_column("constant", "A fitted or assumed configuration key"),
               text_column("mark", "fitted or assumed"),
               text_column("low", "The low end of its plausible range (linked keys after it)"),
               text_column("high", "The high end of its plausible range (linked keys after it)")};
  for (const SensitivityWorkload& w : table.workloads) {
    t.columns.push_back(left_aligned(real_column(
        w.label(), "K triangles/s", 0,
        fmt::format("Projected triangles/s of the torus with {}, at the low .. high end (the "
                    "change from the defaults); sorted by the low end",
                    w.label()))));
  }
  // The defaults' row: its first cell plain text in the code column (a missing value shown
  // as "(defaults)" is not put in backticks).
  std::vector<Cell> defaults = {Cell::shown_as(Cell::missing(), "(defaults)"), "", "", ""};
  for (double d : table.defaults) {
    defaults.push_back(std::isnan(d) ? Cell::shown_as(Cell::missing(), "- K")
                                     : Cell::shown_as(d / 1e3, kilo(d) + " K"));
  }
  t.add_row(std::move(defaults));
  for (const SensitivityRow& r : table.rows) {
    // A key of a run of frames is measured on sustained rates, against the sustained default.
    std::vector<Cell> row = {r.key,
                             std::string(calibration_name(r.calibration)) +
                                 (r.sustained ? " (sustained rate, 3 frames)" : ""),
                             assignments_text(r.low, r.key), assignments_text(r.high, r.key)};
    for (const auto& v : r.rates) {
      const std::string text = fmt::format("{} .. {} K ({} .. {})", kilo(v[0]), kilo(v[2]),
                                           change(v[0], v[1]), change(v[2], v[1]));
      row.push_back(std::isnan(v[0]) ? Cell::shown_as(Cell::missing(), text)
                                     : Cell::shown_as(v[0] / 1e3, text));
    }
    t.add_row(std::move(row));
  }
  return t;
}

std::string sensitivity_markdown(const SensitivityTable& t) {
  return report::markdown(sensitivity_table(t));
}

report::Table sensitivity_data_table(const SensitivityTable& table) {
  using namespace report;
  Table t;
  t.id = "sensitivity";
  t.columns = {text_column("key"),
               text_column("mark"),
               text_column("low"),
               text_column("high"),
               text_column("workload"),
               real_column("rate_low", "", -1),
               real_column("rate_default", "", -1),
               real_column("rate_high", "", -1)};
  auto rate = [](double v) { return std::isnan(v) ? Cell::missing() : Cell(v); };
  for (const SensitivityRow& r : table.rows) {
    for (std::size_t k = 0; k < table.workloads.size(); ++k) {
      t.add_row({r.key, std::string(calibration_name(r.calibration)),
                 assignments_text(r.low, r.key), assignments_text(r.high, r.key),
                 table.workloads[k].label(), rate(r.rates[k][0]), rate(r.rates[k][1]),
                 rate(r.rates[k][2])});
    }
  }
  return t;
}

}  // namespace pp5
