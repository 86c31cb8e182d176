// Calibration and validation (issue 17): every timing constant says how it was obtained, the
// plausible ranges are machines the configuration accepts, `pp5sim validate` projects what it
// reports by running the models, and the GP's multipass policy costs what it says.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "models/machine.hpp"
#include "sim/analysis/validate.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {
const ProgramLoader kLoad = [](const std::string& name, const MachineConfig& c) {
  return load_program(name, c);
};
}  // namespace

TEST_CASE("calibration: every timing constant is marked, and each range is a valid machine",
          "[calibration]") {
  std::set<std::string> keys;
  for (const ParameterInfo& p : describe_parameters()) {
    keys.insert(p.key);
    INFO(p.key);
    // A clock, a latency or a cycle count is a timing constant: it must say where it is from.
    const bool timing = p.unit.find("clocks") != std::string::npos ||
                        p.unit.find("cycles") != std::string::npos || p.unit == "Hz";
    if (timing) CHECK(p.calibration != Calibration::none);
    if (p.calibration == Calibration::none) {
      CHECK(p.low.empty());
      continue;
    }
    CHECK(!p.basis.empty());
    if (p.calibration == Calibration::derived) {
      CHECK(p.low.empty());
      continue;
    }
    // Fitted and assumed: both ends are machines the configuration accepts, and each moves
    // the key itself.
    REQUIRE(!p.low.empty());
    REQUIRE(!p.high.empty());
    for (const auto& end : {p.low, p.high}) {
      MachineConfig c = MachineConfig::defaults();
      CHECK_NOTHROW(c.set(end));
      bool moves_key = false;
      for (const std::string& s : end) moves_key = moves_key || s.rfind(p.key + "=", 0) == 0;
      CHECK(moves_key);
    }
  }
  // Every fitted constant names the published figure it consumed, by id and in its basis:
  // the overhead factor the hand-coded rate, the refill constants the compiled rate, the
  // overhead's form the gap between the two.
  std::set<std::string> fitted;
  for (const ParameterInfo& p : describe_parameters()) {
    INFO(p.key);
    if (p.calibration == Calibration::fitted) {
      fitted.insert(p.key);
      CHECK(!p.consumes.empty());
      CHECK_THAT(p.basis, Catch::Contains("polygons/second") || Catch::Contains("rates"));
    } else {
      CHECK(p.consumes.empty());
    }
  }
  CHECK(fitted == std::set<std::string>{"gp.overhead_factor", "gp.icache_miss_clocks",
                                        "gp.compiled_code_bytes", "gp.overhead_form"});
  CHECK(fits_consuming("banks.compiled_rate") == std::vector<std::string>{"gp.icache_miss_clocks",
                                                                          "gp.compiled_code_bytes",
                                                                          "gp.overhead_form"});
  CHECK(fits_consuming("fuchs.design_goal").empty());
  CHECK(keys.count("gp.multipass") == 1);
}

TEST_CASE("project_frame: the timing model alone gives simulate_frame's time and statistics",
          "[calibration][validate]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=3", "renderer.count=2"});
  const Scene scene = make_builtin_scene("torus", {32, 8});
  const Program program = load_program("phong", config);
  const FrameResult full = simulate_frame(config, scene, program, 1);
  const FrameResult projected = project_frame(config, scene, program);
  CHECK(projected.frame_seconds == full.frame_seconds);
  CHECK(without_host(projected.stats_json) == without_host(full.stats_json));
}

TEST_CASE("gp.multipass: retraversal costs one traversal per pass and changes no pixel",
          "[calibration][gp]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=256", "screen.height=256", "gp.count=2", "renderer.count=2"});
  const Scene scene = make_builtin_scene("crossing-quads");
  const Program program = load_program("transparent", config);
  REQUIRE(program.multipass());
  const int passes = 3;  // the program's layer count, frame.layers
  config.set("frame.layers=" + std::to_string(passes));
  const FrameResult resend = simulate_frame(config, scene, program, 2);
  config.set("gp.multipass=retraverse");
  const FrameResult retraverse = simulate_frame(config, scene, program, 2);
  CHECK(resend.image.flat().rgb == retraverse.image.flat().rgb);
  for (std::size_t k = 0; k < resend.stats.elements("gp"); ++k) {
    const std::string p = fmt::format("gp.{}.", k);
    const auto once = count(resend.stats, p + "geometry_clocks");
    CHECK(count(retraverse.stats, p + "geometry_clocks") == once * passes);
    CHECK(count(retraverse.stats, p + "busy_clocks") - count(resend.stats, p + "busy_clocks") ==
          once * (passes - 1));
    CHECK(count(retraverse.stats, p + "operations.fmul") ==
          count(resend.stats, p + "operations.fmul") * passes);
  }
  CHECK(retraverse.frame_seconds >= resend.frame_seconds);
  // A single-pass program never retraverses: the policies agree to the last statistic.
  const Program phong = load_program("phong", config);
  const FrameResult a = simulate_frame(config, scene, phong, 1);
  config.set("gp.multipass=resend");
  const FrameResult b = simulate_frame(config, scene, phong, 1);
  CHECK(without_host(a.stats_json) == without_host(b.stats_json));
}

TEST_CASE("validate: every projection comes from running the models", "[validate]") {
  MachineConfig config = MachineConfig::defaults();
  ValidationOptions small;
  small.tessellation_u = 64;
  small.tessellation_v = 16;
  const auto rows = validate_against_record(config, kLoad, small);
  auto find = [](const std::vector<ValidationRow>& rs, const std::string& start) {
    for (const ValidationRow& r : rs) {
      if (r.figure.rfind(start, 0) == 0) return r;
    }
    FAIL("no row " << start);
    return ValidationRow{};
  };
  for (const ValidationRow& r : rows) {
    INFO(r.figure);
    CHECK((r.status == "fitted" || r.status == "derived" || r.status == "predicted"));
    CHECK(r.simulated > 0);
    CHECK(!r.source.empty());
  }
  // The ring delivers what its organisation carries (the last messages' hops aside) ...
  const ValidationRow ring = find(rows, "ring bandwidth");
  CHECK(ring.simulated == Approx(5.12).epsilon(0.01));
  // ... and the GP rate is the simulated clocks': twice the overhead, half the rate.
  const ValidationRow fast = find(rows, "transform + Phong, hand-coded");
  CHECK(fast.status == "fitted");
  CHECK(!fast.evidence());
  // The compiled rate was consumed by the fits of the refill constants and the overhead's
  // form: it is a consistency check, not evidence. The design goal was consumed by none.
  const ValidationRow slow = find(rows, "transform + Phong, compiled");
  CHECK(slow.status == "fitted");
  CHECK(!slow.evidence());
  CHECK(slow.consumed_by == fits_consuming("banks.compiled_rate"));
  CHECK(find(rows, "design goal: ").evidence());
  const std::string evidence = evidence_summary(rows);
  CHECK_THAT(evidence, Catch::Contains("consumed by the fit of `gp.icache_miss_clocks`"));
  CHECK_THAT(evidence, !Catch::Contains("- transform + Phong, compiled C: 1"));
  // A Pixel-Powers operation costs eall and qcmp of a 24-bit field, from the instruction table.
  const ValidationRow csg = find(rows, "Pixel-Powers");
  const double per_op =
      1 + (config.evaluator.fraction_bits + 24 + config.evaluator.latency_cycles + 1);
  CHECK(csg.simulated == Approx(1900 * per_op / 10e6 * 1e3).epsilon(1e-9));

  MachineConfig other = config;
  other.set({"gp.overhead_factor=6.52", "ring.channels=4", "evaluator.latency_cycles=16"});
  const auto moved = validate_against_record(other, kLoad, small);
  CHECK(find(moved, "transform + Phong, hand-coded").simulated ==
        Approx(fast.simulated / 2).epsilon(0.01));
  CHECK(find(moved, "ring bandwidth").simulated == Approx(2.56).epsilon(0.01));
  CHECK(find(moved, "Pixel-Powers").simulated > csg.simulated);
  CHECK(find(moved, "design goal: ").simulated < find(rows, "design goal: ").simulated);
  // The report's tables have a row per figure.
  const std::string md = validation_markdown(rows);
  const std::string csv = report::csv(validation_data_table(rows));
  CHECK(std::count(csv.begin(), csv.end(), '\n') == static_cast<long>(rows.size() + 1));
  CHECK_THAT(md, Catch::Contains("| fitted |"));
}

TEST_CASE("sensitivity: each end of a range is projected, and the rates move the right way",
          "[validate]") {
  const MachineConfig config = MachineConfig::defaults();
  const std::vector<SensitivityWorkload> workloads = {
      {"threshold", MachineConfig::Gp::Code::compiled},
      {"transparent", MachineConfig::Gp::Code::compiled}};
  const SensitivityTable t =
      sensitivity(config, kLoad, workloads, {"gp.icache_miss_clocks", "gp.multipass"});
  REQUIRE(t.rows.size() == 2);
  const SensitivityRow& miss = t.rows[0].key == "gp.icache_miss_clocks" ? t.rows[0] : t.rows[1];
  const SensitivityRow& multipass = t.rows[0].key == "gp.multipass" ? t.rows[0] : t.rows[1];
  // Compiled code misses the instruction cache: a slower refill is a slower machine.
  CHECK(miss.rates[0][0] > miss.rates[0][1]);
  CHECK(miss.rates[0][1] > miss.rates[0][2]);
  // threshold has one pass: the policy changes nothing; transparent has four, and
  // retraversing them costs time (resend is the default, the low end).
  CHECK(multipass.rates[0][0] == multipass.rates[0][2]);
  CHECK(multipass.rates[1][0] == multipass.rates[1][1]);
  CHECK(multipass.rates[1][2] < multipass.rates[1][1]);
  const std::string md = sensitivity_markdown(t);
  CHECK_THAT(md, Catch::Contains("`gp.multipass` | assumed | resend | retraverse |"));
  CHECK_THAT(report::csv(sensitivity_data_table(t)),
             Catch::StartsWith("key,mark,low,high,workload"));
}

TEST_CASE("sensitivity: a key of a run of frames is measured on the sustained rate", "[validate]") {
  // frames.gp_start changes nothing in one frame: its row is three frames overlapped,
  // simulated, against the same run's default (mutation: measuring it on one frame gives
  // +0% at both ends).
  const SensitivityTable t =
      sensitivity(MachineConfig::defaults(), kLoad, {{"phong", MachineConfig::Gp::Code::assembly}},
                  {"frames.gp_start"});
  REQUIRE(t.rows.size() == 1);
  const SensitivityRow& row = t.rows[0];
  CHECK(row.sustained);
  // The default (overlap) is the high end; frames apart (the low end) are slower.
  CHECK(row.rates[0][2] == row.rates[0][1]);
  CHECK(row.rates[0][0] < row.rates[0][1]);
  CHECK(row.rates[0][1] != t.defaults[0]);
  CHECK_THAT(sensitivity_markdown(t),
             Catch::Contains("| `frames.gp_start` | assumed (sustained rate, 3 frames) |"));
}

TEST_CASE("sensitivity: an end that does not combine with the configuration has no rate",
          "[validate]") {
  MachineConfig config = MachineConfig::defaults();
  config.set(std::vector<std::string>{"evaluator.coefficient_bits=44", "evaluator.result_bits=44"});
  const SensitivityTable t = sensitivity(
      config, kLoad, {{"phong", MachineConfig::Gp::Code::assembly}}, {"evaluator.result_bits"});
  REQUIRE(t.rows.size() == 1);
  // 40 result bits below 44-bit coefficients is no machine; 48 is one.
  CHECK(std::isnan(t.rows[0].rates[0][0]));
  CHECK(t.rows[0].rates[0][2] > 0);
  CHECK_THAT(sensitivity_markdown(t), Catch::Contains("| - .. "));
}

TEST_CASE("joint sensitivity: a seeded Latin hypercube over constants and workload choices",
          "[validate]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=512", "screen.height=512", "gp.count=8", "renderer.count=4"});
  JointSensitivityOptions options;
  options.samples = 9;
  options.tessellation_u = 32;
  options.tessellation_v = 8;
  options.painter_samples = 1;
  const JointSensitivity a = joint_sensitivity(config, kLoad, options);
  REQUIRE(a.points.size() == 9);
  CHECK(a.skipped.empty());
  // Deterministic: the same seed gives the same samples and figures.
  const JointSensitivity b = joint_sensitivity(config, kLoad, options);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    CHECK(a.points[i].sets == b.points[i].sets);
    CHECK(a.points[i].rate == b.points[i].rate);
  }
  // A Latin hypercube: a numeric constant takes one value in each ninth of its range.
  std::vector<double> factors;
  std::set<std::string> scenes, culling;
  for (const JointSample& p : a.points) {
    for (const std::string& s : p.sets) {
      if (s.rfind("gp.overhead_factor=", 0) == 0) factors.push_back(std::stod(s.substr(19)));
      if (s.rfind("gp.cull_back_faces=", 0) == 0) culling.insert(s);
    }
    scenes.insert(p.scene.substr(0, p.scene.find(' ')));
  }
  REQUIRE(factors.size() == 9);
  std::sort(factors.begin(), factors.end());
  for (std::size_t i = 0; i < factors.size(); ++i) {
    const double lo = 2.61 + (3.73 - 2.61) * static_cast<double>(i) / 9;
    CHECK(factors[i] >= lo - 1e-4);
    CHECK(factors[i] <= lo + (3.73 - 2.61) / 9 + 1e-4);
  }
  CHECK(scenes.size() == 2);
  CHECK(culling.size() == 2);
  // Each conclusion's share is counted from the samples themselves.
  REQUIRE(a.conclusions.size() == 4);
  // Painter's against the z-buffer at the first sample only.
  CHECK(std::isfinite(a.points[0].painter_over_zbuffer));
  CHECK(std::isnan(a.points[1].painter_over_zbuffer));
  CHECK(a.conclusions[3].samples == 1);
  CHECK(a.conclusions[3].holds == (a.points[0].painter_over_zbuffer > 0 ? 1 : 0));
  int below = 0, renderers = 0;
  for (const JointSample& p : a.points) {
    below += p.rate < 1e6;
    renderers += p.bottleneck == "Renderers";
  }
  CHECK(a.conclusions[0].holds == renderers);
  CHECK(a.conclusions[1].holds == below);
  CHECK(a.conclusions[1].min <= a.conclusions[1].median);
  CHECK(a.conclusions[1].median <= a.conclusions[1].max);
  CHECK_THAT(joint_sensitivity_markdown(a), Catch::Contains("holds in"));
  // Another seed draws other machines.
  options.seed = 7;
  CHECK(joint_sensitivity(config, kLoad, options).points[0].sets != a.points[0].sets);
}
