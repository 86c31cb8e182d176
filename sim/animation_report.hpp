#pragma once
// report.html of an animation (pp5sim animate --report): the run's summary, the animation,
// every frame's figures as a table and charts, each frame's image, the summed regions heat
// map, the timeline over all frames and the configuration, through the report writer
// (sim/output/report.hpp).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/config/machine_config.hpp"
#include "sim/output/report.hpp"
#include "sim/run_report.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

struct AnimationFrameRow {
  double start_seconds = 0;
  double frame_seconds = 0;
  double triangles_per_second = 0;
  std::string bottleneck;
  double gp_utilisation_max = 0;
  double renderer_utilisation_max = 0;
  double ring_utilisation = 0;
  std::uint64_t renderer_busy_cycles = 0;
};

struct AnimationReportInput {
  std::string title;     // "animation of scene 'torus' (...)"
  std::string subtitle;  // what moves
  const MachineConfig* config = nullptr;
  RunSummary summary;
  double fps = 0;
  std::vector<AnimationFrameRow> frames;
  std::vector<std::string> frame_pngs;  // per frame (empty: no pixels)
  std::string gif;                      // animation.gif ("" for none)
  std::string regions_png;              // the summed heat map ("" for none)
  // The timeline's busy time per unit (its events as they were written: a long run's
  // timeline is not held in memory), or null.
  const TimelineBusy* timeline = nullptr;
};

report::Report animation_report(const AnimationReportInput& in);

}  // namespace pp5
