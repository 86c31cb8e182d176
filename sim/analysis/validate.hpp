#pragma once
// The simulator against the published record (`pp5sim validate`): every figure the sources
// give (../shared/design/pixel-planes-5.md) beside the simulator's projection of the same
// workload, and how far each projection moves over the plausible range of every assumed or
// fitted timing constant (the sensitivity table).
//
// Contract:
//  - Every simulated value comes from running the models on the workload the row names
//    (project_frame for frames, the Ring module for bandwidth, the assembler for pixel
//    memory, the bit backend and the instruction table for the Pixel-Powers operation);
//    none is read back from a configuration constant or a published figure.
//  - Each row says whether its figure was fitted (the simulator was tuned to it, so matching
//    it is a consistency check), derived (the configuration follows from it) or predicted.
//    A figure is fitted when any fitted key of the configuration table names it as consumed
//    (fits_consuming), so marking a constant fitted reaches the report without code here;
//    only predictions count as evidence (evidence_summary).
//  - The sensitivity table varies one constant at a time, to each end of its declared
//    plausible range (ParameterInfo::low/high: the --set assignments that put the machine
//    there), from `base`; every other key stays as in `base`. Constants come from the
//    configuration table, so a new assumed constant joins the table without code here.
//    An end that does not combine with `base` (a ConfigError: e.g. result bits below the
//    coefficient bits `base` asks for) has the rate NaN, printed '-'.
//  - Deterministic: the same inputs give the same rows.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/output/report.hpp"

namespace pp5 {

// Assembles a firmware program by name ("phong", ...) for a configuration.
using ProgramLoader = std::function<Program(const std::string& name, const MachineConfig& config)>;

struct ValidationRow {
  std::string figure;          // what the record says
  std::string source;          // where, with its confidence (P, S)
  std::string published;       // the figure as the source gives it ("well over 1,000,000")
  double published_value = 0;  // the number compared with (the bound of an inequality)
  std::string workload;        // what the simulator ran
  double simulated = 0;
  std::string unit;
  std::string status;  // "fitted", "derived" or "predicted"
  std::string note;    // what else the run showed (a second figure, a caveat)
  // The figure's id in the configuration table's fits (ParameterInfo::consumes), if any, and
  // the fitted keys whose fit consumed it: then the status is "fitted" whatever the row
  // would otherwise say, and the figure is no evidence.
  std::string id = {};
  std::vector<std::string> consumed_by = {};
  // Only a prediction is evidence for the model: a fitted figure comes out by construction.
  bool evidence() const { return status == "predicted"; }
  // (simulated - published_value) / published_value
  double difference() const {
    return published_value != 0 ? (simulated - published_value) / published_value : 0;
  }
};

struct ValidationOptions {
  // The large triangle scene the full machine runs against the design goal: the torus at
  // this tessellation (512 x 128: 131,072 triangles).
  int tessellation_u = 512;
  int tessellation_v = 128;
};

std::vector<ValidationRow> validate_against_record(const MachineConfig& base,
                                                   const ProgramLoader& load,
                                                   const ValidationOptions& options = {});

// One workload of the sensitivity table: a program on the torus with a GP code profile.
struct SensitivityWorkload {
  std::string program;
  MachineConfig::Gp::Code code;
  std::string label() const;  // "phong (assembly)"
};
// The four: Phong on hand-coded assembly; threshold, epsilon and transparency on
// compiled C (the code Banks modified).
std::vector<SensitivityWorkload> default_sensitivity_workloads();

struct SensitivityRow {
  std::string key;
  Calibration calibration = Calibration::none;
  std::vector<std::string> low, high;  // the assignments of the range's ends
  // Per workload: projected triangles/s at the low end, the default and the high end.
  std::vector<std::array<double, 3>> rates;
  // A key of a run of frames (frames.*): the rates are sustained over three frames overlapped
  // (Session::run_frames), the default's included, not one frame's.
  bool sustained = false;
};

struct SensitivityTable {
  std::vector<SensitivityWorkload> workloads;
  std::vector<double> defaults;  // per workload, at `base`
  std::vector<SensitivityRow> rows;
};

// Rates are projected on the built-in torus (8,192 triangles) for every workload, at `base`
// and at each end of every fitted or assumed constant's range.
// `only`, if not empty, restricts the rows to those keys.
SensitivityTable sensitivity(const MachineConfig& base, const ProgramLoader& load,
                             const std::vector<SensitivityWorkload>& workloads,
                             const std::vector<std::string>& only = {});

// Joint sensitivity of the headline conclusions (docs/timing.md "Sensitivity of the
// conclusions"): every fitted or assumed constant with a plausible range and the workload
// choices vary together, by a Latin hypercube with a seeded generator (splitmix64, the same
// on every host). A constant with one numeric key at each end takes a value between them
// (geometrically when the ends differ fourfold or more, rounded for an integer key); a
// choice, or ends that move linked keys, takes the low end, the default or the high end.
// Workload choices: the scene (the torus or the figure-eight), its tessellation (triangle
// size: the scene's triangles x 1/4, 1 or 4 about `options`' torus), back-face culling; the
// ring's arbitration is gp.send_order among the constants. The workload is the design
// goal's: phong on hand-coded GPs at `base`'s screen. Frames run at `level` (analytic by
// default: validated against the event level on held-out machines).
struct JointSensitivityOptions {
  int samples = 64;
  std::uint64_t seed = 0x3403;
  std::string level = "analytic";  // fidelity.timing of every sample
  int tessellation_u = 512;        // the torus at the middle triangle size
  int tessellation_v = 128;
  // Painter's against the z-buffer, on the built-in torus (8,192 triangles) at the first
  // `painter_samples` samples' machines, with the painter's choices varied too (back faces
  // removed first, splitting, per region bin, the overhead factor on the sort).
  int painter_samples = 16;
};

struct JointSample {
  std::vector<std::string> sets;  // over `base`
  std::string scene;
  int triangles = 0;
  double rate = 0;            // triangles/s, one frame
  double pipelined_rate = 0;  // triangles/s, frames pipelined
  std::string bottleneck;
  // Painter's (its frame plus its sort) over the z-buffer's frame, minus 1; NaN where not run.
  double painter_over_zbuffer = 0;
  std::string painter_choices;
};

// A headline conclusion and how it fares over the samples.
struct ConclusionShare {
  std::string conclusion;                // what the default machine says
  std::string measure;                   // what is measured per sample
  double low = 0, median = 0, high = 0;  // the measure's 5th percentile, median, 95th
  double min = 0, max = 0;
  int holds = 0;  // samples where the conclusion holds
  int samples = 0;
};

struct JointSensitivity {
  JointSensitivityOptions options;
  std::vector<std::string> varied;  // the constants and workload choices varied
  std::vector<JointSample> points;
  std::vector<std::string> skipped;  // samples whose ends do not combine, with the error
  std::vector<ConclusionShare> conclusions;
};

JointSensitivity joint_sensitivity(const MachineConfig& base, const ProgramLoader& load,
                                   const JointSensitivityOptions& options = {});
// The joint sensitivity as tables (sim/output/report.hpp): the conclusions, and every sample
// (written as joint.csv); then as Markdown: a line of what was sampled, the conclusions'
// table and the line of bottlenecks (joint_bottleneck_text).
report::Table joint_sensitivity_table(const JointSensitivity& joint);
report::Table joint_samples_table(const JointSensitivity& joint);
std::string joint_bottleneck_text(const JointSensitivity& joint);
std::string joint_sensitivity_markdown(const JointSensitivity& joint);

// The record's table (Markdown through the report writer), and the same rows with every value
// at full precision as data (validate.csv: the published value and its unit apart, the
// difference as a fraction, evidence 1 or 0).
report::Table validation_table(const std::vector<ValidationRow>& rows);
std::string validation_markdown(const std::vector<ValidationRow>& rows);
// Which figures are evidence: the predictions, each with its difference, and the figures a
// fit consumed (with the keys), which are not.
std::string evidence_summary(const std::vector<ValidationRow>& rows);
report::Table validation_data_table(const std::vector<ValidationRow>& rows);
report::Table sensitivity_table(const SensitivityTable& table);
std::string sensitivity_markdown(const SensitivityTable& table);
// One row per constant and workload (sensitivity.csv).
report::Table sensitivity_data_table(const SensitivityTable& table);

}  // namespace pp5
