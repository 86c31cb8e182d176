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
#include <map>
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

// The same, from a timeline's events given one at a time (a run of many frames writes its
// timeline out as it goes: sim/output/timeline_file.hpp), in bounded memory: every busy
// interval is kept while there are at most `exact_limit` of them, and tracks() gives exactly
// what timeline_tracks gives for the same events. Beyond that, each track's busy time is
// summed in kBins bins over a span that doubles as the run grows (two bins merged into one),
// overlapping slices merged first among the last kWindow intervals of a track: tracks() then
// gives each bin's busy time as one interval at the bin's start, so a chart of C columns
// over the run places busy time within one bin (the run's length / kBins at most, twice
// that after a doubling) of where it was. Memory: kBins doubles a track.
class TimelineBusy {
 public:
  static constexpr std::size_t kBins = 16384;
  static constexpr std::size_t kWindow = 64;
  explicit TimelineBusy(std::size_t exact_limit = std::size_t{1} << 17);
  void add(const nlohmann::json& event);
  std::vector<report::Track> tracks(double* end_seconds) const;
  bool exact() const { return exact_; }

 private:
  using Key = std::pair<int, int>;  // pid, tid
  struct Binned {
    std::map<double, double> window;  // start -> end, disjoint, merged
    std::vector<double> bins;         // busy seconds per bin
  };
  void to_bins();
  void bin_interval(Binned& b, double start, double end) const;
  void grow_span(double end);
  void window_add(Binned& b, double start, double end);
  std::size_t exact_limit_;
  bool exact_ = true;
  std::size_t intervals_ = 0;
  double end_ = 0;
  double span_ = 0;  // the bins' span (binned mode)
  std::map<Key, std::string> names_;
  std::map<Key, std::vector<std::pair<double, double>>> busy_;  // exact mode
  std::map<Key, Binned> binned_;                                // binned mode
};

}  // namespace pp5
