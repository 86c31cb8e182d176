#include "sim/analysis/analytic_validation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "common/splitmix.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

std::string GridMachine::label() const {
  std::string out = scene + " " + program;
  for (const std::string& s : sets) out += " " + s;
  return out;
}

std::vector<GridMachine> analytic_tuning_grid(const std::string& balancing) {
  std::vector<GridMachine> grid;
  for (const char* program : {"phong", "threshold", "flat", "transparent"}) {
    for (int gps : {4, 32}) {
      for (int renderers : {2, 8, 16}) {
        for (int channels : {1, 8}) {
          grid.push_back({"torus",
                          program,
                          {"screen.width=640", "screen.height=512", fmt::format("gp.count={}", gps),
                           fmt::format("renderer.count={}", renderers),
                           fmt::format("ring.channels={}", channels)}});
          if (balancing != "static") grid.back().sets.push_back("renderer.balancing=" + balancing);
        }
      }
    }
  }
  return grid;
}

std::vector<GridMachine> analytic_heldout_grid(int count, std::uint64_t seed) {
  SplitMix64 random{seed};
  // Triangle scenes with any program; sphere scenes with the programs that draw spheres.
  const std::vector<std::string> triangle_scenes = {"torus", "sphere", "figure-eight",
                                                    "folded-slab"};
  const std::vector<std::string> triangle_programs = {"phong", "threshold", "flat", "gouraud",
                                                      "transparent"};
  const std::vector<std::string> sphere_scenes = {"molecule", "spheres-and-triangles"};
  const std::vector<std::string> sphere_programs = {"phong", "threshold"};
  const std::vector<std::string> screens = {"512 512", "640 512", "1280 1024"};
  const std::vector<int> channels = {1, 2, 4, 8, 16};
  const std::vector<int> queue = {1024, 2048, 4096, 8192, 16384};
  std::vector<GridMachine> grid;
  for (int i = 0; i < count; ++i) {
    GridMachine m;
    if (random.below(4) == 0) {
      m.scene = random.pick(sphere_scenes);
      m.program = random.pick(sphere_programs);
    } else {
      m.scene = random.pick(triangle_scenes);
      m.program = random.pick(triangle_programs);
    }
    const std::string& screen = random.pick(screens);
    const auto space = screen.find(' ');
    m.sets = {"screen.width=" + screen.substr(0, space),
              "screen.height=" + screen.substr(space + 1),
              fmt::format("gp.count={}", 1 + random.below(32)),
              fmt::format("renderer.count={}", 1 + random.below(16)),
              fmt::format("ring.channels={}", random.pick(channels)),
              fmt::format("renderer.queue_words={}", random.pick(queue)),
              random.below(2) ? "renderer.balancing=dynamic" : "renderer.balancing=static",
              fmt::format("renderer.overlap_shipping={}", random.below(2)),
              fmt::format("ring.hop_latency_cycles={}", random.below(5)),
              fmt::format("evaluator.double_buffered={}", random.below(2)),
              random.below(2) ? "gp.code=compiled" : "gp.code=assembly"};
    grid.push_back(std::move(m));
  }
  return grid;
}

double kendall_tau(const std::vector<double>& x, const std::vector<double>& y) {
  double concordant = 0, discordant = 0, ties_x = 0, ties_y = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (std::size_t j = i + 1; j < x.size(); ++j) {
      const double dx = x[i] - x[j];
      const double dy = y[i] - y[j];
      if (dx == 0 && dy == 0) continue;
      if (dx == 0) {
        ++ties_x;
      } else if (dy == 0) {
        ++ties_y;
      } else if ((dx > 0) == (dy > 0)) {
        ++concordant;
      } else {
        ++discordant;
      }
    }
  }
  const double denominator =
      std::sqrt((concordant + discordant + ties_x) * (concordant + discordant + ties_y));
  return denominator > 0 ? (concordant - discordant) / denominator : 0;
}

AnalyticValidation validate_analytic(const std::string& grid,
                                     const std::vector<GridMachine>& machines,
                                     const ProgramLoader& load) {
  AnalyticValidation v;
  v.grid = grid;
  std::vector<double> event, analytic, closed;
  for (const GridMachine& m : machines) {
    MachineConfig config = MachineConfig::defaults();
    config.set(m.sets);
    config.set(std::vector<std::string>{"fidelity.pixels=none", "fidelity.timing=event"});
    const Scene scene = make_builtin_scene(m.scene);
    const Program program = load(m.program, config);
    const FrameResult e = project_frame(config, scene, program);
    config.set("fidelity.timing=analytic");
    const FrameResult a = project_frame(config, scene, program);
    AnalyticPoint p;
    p.machine = m;
    p.event_seconds = e.frame_seconds;
    p.analytic_seconds = a.frame_seconds;
    p.closed_form_seconds = a.stats.real("analytic.closed_form_seconds");
    p.event_bottleneck = e.stats.text("timing.bottleneck");
    p.analytic_bottleneck = a.stats.text("timing.bottleneck");
    const double error = std::abs(p.error());
    v.mean_error += error;
    if (error > v.worst_error) v.worst_error = error, v.worst_at = m.label();
    const double closed_error = std::abs(p.closed_form_seconds - p.event_seconds) / p.event_seconds;
    v.closed_form_mean_error += closed_error;
    v.closed_form_worst_error = std::max(v.closed_form_worst_error, closed_error);
    if (p.event_bottleneck == p.analytic_bottleneck) ++v.bottleneck_agree;
    AnalyticValidation::Mode& mode =
        std::find(m.sets.begin(), m.sets.end(), "renderer.balancing=dynamic") != m.sets.end()
            ? v.dynamic_balancing
            : v.static_balancing;
    ++mode.machines;
    mode.mean_error += error;
    mode.worst_error = std::max(mode.worst_error, error);
    event.push_back(p.event_seconds);
    analytic.push_back(p.analytic_seconds);
    closed.push_back(p.closed_form_seconds);
    v.points.push_back(std::move(p));
  }
  if (!v.points.empty()) {
    v.mean_error /= static_cast<double>(v.points.size());
    v.closed_form_mean_error /= static_cast<double>(v.points.size());
  }
  for (AnalyticValidation::Mode* mode : {&v.static_balancing, &v.dynamic_balancing}) {
    if (mode->machines > 0) mode->mean_error /= mode->machines;
  }
  v.kendall_tau = kendall_tau(event, analytic);
  v.closed_form_tau = kendall_tau(event, closed);
  return v;
}

report::Table analytic_validation_table(const std::vector<AnalyticValidation>& grids) {
  using namespace report;
  Table t;
  t.id = "analytic-grids";
  t.columns = {
      text_column("grid", "tuning (the machines it was adjusted on), looked at, or held-out"),
      left_aligned(integer_column("machines", "machines")),
      text_column("model", "The analytic level's recurrence, or a closed form without contention"),
      left_aligned(
          real_column("mean error", "%", 1, "Mean |frame-time error| against the event level")),
      left_aligned(real_column("worst error", "%", 1, "Largest |frame-time error|")),
      text_column("static: worst (mean)",
                  "Worst and mean error over the grid's machines with static balancing"),
      text_column("dynamic: worst (mean)",
                  "Worst and mean error over the grid's machines with dynamic balancing"),
      left_aligned(integer_column("bottleneck agrees", "machines",
                                  "Machines where the bottleneck agrees with the event level's")),
      left_aligned(real_column("Kendall tau", "", 3,
                               "Rank correlation of the frame times with the event level's")),
      text_column("worst machine", "Where the recurrence's error is largest"),
  };
  // "12.3%": the unit follows the number in the cell, as the table always showed it.
  auto pct = [](double share) {
    return Cell::shown_as(100 * share, fmt::format("{:.1f}%", 100 * share));
  };
  const auto mode_cell = [](const AnalyticValidation::Mode& m) {
    return m.machines == 0 ? std::string("-")
                           : fmt::format("{:.1f}% ({:.1f}%, {} machines)", 100 * m.worst_error,
                                         100 * m.mean_error, m.machines);
  };
  for (const AnalyticValidation& v : grids) {
    const auto n = static_cast<std::int64_t>(v.points.size());
    t.add_row({v.grid, n, "contention recurrence", pct(v.mean_error), pct(v.worst_error),
               mode_cell(v.static_balancing), mode_cell(v.dynamic_balancing),
               Cell::shown_as(static_cast<std::int64_t>(v.bottleneck_agree),
                              fmt::format("{} of {}", v.bottleneck_agree, n)),
               v.kendall_tau, v.worst_at});
    t.add_row({v.grid, n, "closed form, no contention", pct(v.closed_form_mean_error),
               pct(v.closed_form_worst_error), "", "", Cell::missing(), v.closed_form_tau, ""});
  }
  return t;
}

std::string analytic_validation_markdown(const std::vector<AnalyticValidation>& grids) {
  return report::markdown(analytic_validation_table(grids));
}

}  // namespace pp5
