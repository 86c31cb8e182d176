#pragma once
// The analytic timing level against the event level, on grids of machines chosen before
// either model's results were looked at (docs/timing.md "Analytic timing: validation").
//
// Contract:
//  - analytic_tuning_grid(balancing): the 48 machines the analytic level may be adjusted on
//    (the torus at 640 x 512; phong, threshold, flat, transparent; 4 and 32 GPs; 2, 8 and 16
//    Renderers; 1 and 8 ring channels), with static or dynamic balancing.
//  - analytic_heldout_grid(count, seed): `count` machines drawn with a seeded generator
//    (splitmix64, so the same on every host) over scenes, programs, screens and every
//    timing knob the analytic level claims to follow (GPs, Renderers, channels, queue
//    words, balancing, shipping overlap, hop latency, double buffering, code profile). It
//    is never used to adjust the model: the test asserts the targets on it.
//  - validate_analytic runs each machine at both levels (fidelity.pixels=none) and reports
//    the frame-time error |analytic - event| / event (mean and worst), the bottleneck's
//    agreement (timing.bottleneck) and Kendall's tau-b between the two levels' frame times;
//    the same for the closed form without contention (analytic.closed_form_seconds), so the
//    gain of the recurrence is shown beside it; and the error of the machines with static
//    and with dynamic balancing apart.
//  - Deterministic: the same grid gives the same figures.
#include <cstdint>
#include <string>
#include <vector>

#include "sim/analysis/validate.hpp"
#include "sim/output/report.hpp"

namespace pp5 {

struct GridMachine {
  std::string scene;
  std::string program;
  std::vector<std::string> sets;  // --set assignments over the defaults
  std::string label() const;
};

// balancing: "static" (the default's, as first tuned) or "dynamic" (the same 48 machines with
// renderer.balancing=dynamic, the grid the dynamic claims were derived and checked on).
std::vector<GridMachine> analytic_tuning_grid(const std::string& balancing = "static");
// The seeds of the seeded grids (docs/timing.md "Validation of the analytic level"). Drawn
// and looked at in turn: 0x34 showed a fault under dynamic balancing (claims by least work);
// 0x3434, drawn after that fix, showed another (a GP serving Renderers in Renderer order,
// not stage order); 0x3435, 0x3436 and 0x3437, fixed before the second fix was measured on
// them, were then looked at to find what their worst machines had in common (the ring's
// bookings). 0x3438, 0x3439 and 0x343a were then fixed and held out; the worst machine of
// 0x3439 (52.3%) was looked at and led to three changes (the scheduler's send order,
// arrival-order consumption, empty stages opening at their start). 0x343b, 0x343c and
// 0x343d were then fixed and held out, and measured once; 0x343d failed (17.4%), its worst
// machine was looked at and led to a fourth change (the double-buffered load's stall), so
// all of them are reported as "looked at" (kLookedAtSeeds; 0x343b and 0x343c were not
// looked at, but were measured before that change). 0x343e, 0x343f and 0x3440 were then
// fixed and held out, and measured once; 0x3440 failed (22.6%), its worst machine was looked
// at and led to a fifth change (without overlapped shipping, a finished region's trip booked
// in request order, the array waiting for it while the next stages open), so they too are
// "looked at". The held-out seeds below (0x3441, 0x3442, 0x3443) were chosen and committed
// after that change and before either model was run on their machines; the test asserts on
// the first.
constexpr std::uint64_t kLookedAtSeed = 0x3434;
constexpr std::uint64_t kLookedAtSeeds[] = {0x3434, 0x3435, 0x3436, 0x3437, 0x3438, 0x3439, 0x343a,
                                            0x343b, 0x343c, 0x343d, 0x343e, 0x343f, 0x3440};
constexpr std::uint64_t kHeldOutSeeds[] = {0x3441, 0x3442, 0x3443};
constexpr std::uint64_t kHeldOutSeed = kHeldOutSeeds[0];
std::vector<GridMachine> analytic_heldout_grid(int count = 120, std::uint64_t seed = kHeldOutSeed);

struct AnalyticPoint {
  GridMachine machine;
  double event_seconds = 0;
  double analytic_seconds = 0;
  double closed_form_seconds = 0;
  std::string event_bottleneck;
  std::string analytic_bottleneck;
  double error() const { return (analytic_seconds - event_seconds) / event_seconds; }
};

struct AnalyticValidation {
  std::string grid;  // "tuning" or "held-out"
  std::vector<AnalyticPoint> points;
  double mean_error = 0;   // of |error|
  double worst_error = 0;  // of |error|
  std::string worst_at;
  int bottleneck_agree = 0;
  double kendall_tau = 0;
  double closed_form_mean_error = 0;
  double closed_form_worst_error = 0;
  double closed_form_tau = 0;
  // The error of the machines with each balancing mode (renderer.balancing).
  struct Mode {
    int machines = 0;
    double mean_error = 0;
    double worst_error = 0;
  };
  Mode static_balancing, dynamic_balancing;
};

AnalyticValidation validate_analytic(const std::string& grid,
                                     const std::vector<GridMachine>& machines,
                                     const ProgramLoader& load);

// Kendall's tau-b of two equally long series (ties in either counted as neither).
double kendall_tau(const std::vector<double>& x, const std::vector<double>& y);

// The grids' table (sim/output/report.hpp), and it in Markdown.
report::Table analytic_validation_table(const std::vector<AnalyticValidation>& grids);
std::string analytic_validation_markdown(const std::vector<AnalyticValidation>& grids);

}  // namespace pp5
