#pragma once
// A run's results as a Report (sim/output/report.hpp): what `pp5sim render --report` writes
// as report.html, and the tables the summary prints.
//
// Contract:
//  - run_report() reads only its input: the frame and heat map as encoded PNGs (empty for
//    none), the statistics (every one, with its unit and description), the configuration
//    against the defaults, the program's bit budget, the timeline (when recorded) and the
//    warnings the run printed. The same input gives the same report.
//  - bit_budget() is the table the summary prints (text()) and the report shows.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/statistics.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/output/report.hpp"
#include "sim/output/report_html.hpp"

namespace pp5 {

struct FrameResult;

struct RunReportInput {
  std::string title;     // "scene 'torus' (8192 triangles), firmware phong"
  std::string subtitle;  // the scene's description
  const MachineConfig* config = nullptr;
  const Program* program = nullptr;
  const FrameResult* result = nullptr;
  std::string frame_png;                     // encoded, or empty (no pixels)
  std::string regions_png;                   // encoded, or empty
  const nlohmann::json* timeline = nullptr;  // the Chrome trace document, or null
  std::vector<std::string> warnings;
};

report::Report run_report(const RunReportInput& in);

// Field, bits, where: the program's pixel memory, as the summary prints it.
report::Table bit_budget(const Program& program);
// Every statistic: name, value, unit, description.
report::Table statistics_table(const Statistics& stats);
// Every configuration key: key, value, default, unit, calibration, description; `differs`
// gets the keys whose value is not the default.
report::Table configuration_table(const MachineConfig& config, std::vector<std::string>* differs);
// A section "Configuration": what differs from the defaults, then the whole table.
void add_configuration_section(report::Report& rep, const MachineConfig& config);
// The busy intervals of each GP, ring channel and Renderer in a timeline document, and the
// time of its last event (seconds).
std::vector<report::Track> timeline_tracks(const nlohmann::json& timeline, double* end_seconds);

}  // namespace pp5
