// pp5sim validate: the simulator beside every figure of the published record, and the
// sensitivity of the projected rates to each assumed constant (sim/analysis/validate.hpp).
#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "models/machine.hpp"
#include "sim/analysis/validate.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/output/report_html.hpp"

namespace pp5 {

namespace {

struct ValidateOptions {
  std::string config_path;
  std::vector<std::string> sets;
  std::string out = "out/validate";
  bool sensitivity = true;
  std::vector<int> tessellation{512, 128};
  int joint = 64;
  bool report = false;  // also OUT/report.html
};

int run_validate(const ValidateOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  prepare_output_folder(o.out, "--out");
  const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
    return assemble_file(resolve_firmware(name), assembler_options(c));
  };
  ValidationOptions options;
  options.tessellation_u = o.tessellation[0];
  options.tessellation_v = o.tessellation[1];
  const auto rows = validate_against_record(config, load, options);
  const std::string record_heading =
      "Published figures beside the simulator's projection of the same workload:";
  std::string text =
      record_heading + "\n\n" + validation_markdown(rows) + "\n" + evidence_summary(rows);
  // The page: each table of validate.md with the text around it.
  report::Report page;
  page.title = "The simulator beside the published record";
  {
    report::Section& s = page.add_section("record", "Published figures");
    s.blocks.push_back(report::Paragraph{record_heading});
    report::Table t = validation_table(rows);
    t.id = "record";
    t.csv_file = false;  // validate.csv: the same rows with every value, below
    s.blocks.push_back(std::move(t));
    s.blocks.push_back(report::Preformatted{evidence_summary(rows)});
  }
  // The data behind the shown tables, each value at full precision: the CSV files.
  report::Section data{"data", "Every value", {}};
  {
    report::Table t = validation_data_table(rows);
    t.title = "The published figures (validate.csv)";
    data.blocks.push_back(std::move(t));
  }
  OutputSet outputs;
  if (o.sensitivity) {
    const SensitivityTable table = sensitivity(config, load, default_sensitivity_workloads());
    const std::string heading =
        "Sensitivity: projected triangles/s of the torus (8,192 triangles) at the low and high "
        "end of each fitted or assumed constant's plausible range, the others at their "
        "values:";
    text += "\n" + heading + "\n\n" + sensitivity_markdown(table);
    report::Section& s = page.add_section("sensitivity", "Sensitivity");
    s.blocks.push_back(report::Paragraph{heading});
    report::Table t = sensitivity_table(table);
    t.id = "sensitivity-table";
    t.csv_file = false;  // sensitivity.csv: one row per constant and workload, below
    s.blocks.push_back(std::move(t));
    report::Table rows_by_workload = sensitivity_data_table(table);
    rows_by_workload.title = "Each constant and workload (sensitivity.csv)";
    data.blocks.push_back(std::move(rows_by_workload));
  }
  if (o.joint > 0) {
    JointSensitivityOptions joint;
    joint.samples = o.joint;
    joint.tessellation_u = o.tessellation[0];
    joint.tessellation_v = o.tessellation[1];
    const JointSensitivity j = joint_sensitivity(config, load, joint);
    const std::string heading =
        "Joint sensitivity of the conclusions: the design goal's workload (phong, hand-coded "
        "GPs) with every fitted and assumed constant and the workload choices varied "
        "together:";
    const std::string markdown = joint_sensitivity_markdown(j);
    text += "\n" + heading + "\n\n" + markdown;
    report::Section& s = page.add_section("joint", "Joint sensitivity");
    s.blocks.push_back(report::Paragraph{heading + " " + markdown.substr(0, markdown.find('\n'))});
    report::Table conclusions = joint_sensitivity_table(j);
    conclusions.csv_file = false;  // drawn from the samples (joint.csv)
    s.blocks.push_back(std::move(conclusions));
    s.blocks.push_back(report::Paragraph{joint_bottleneck_text(j).substr(1)});
    report::Table samples = joint_samples_table(j);  // joint.csv
    samples.title = "Every sample (joint.csv)";
    s.blocks.push_back(std::move(samples));
  }
  page.sections.push_back(std::move(data));
  outputs.add(o.out + "/validate.md", text);
  // validate.csv, sensitivity.csv, joint.csv and with --report the page.
  add_report_outputs(outputs, o.out, page, o.report);
  outputs.commit();
  std::cout << text;
  if (o.report) std::cout << fmt::format("\nwrote {}/report.html\n", o.out);
  return 0;
}

}  // namespace

Command add_validate_command(CLI::App& app) {
  auto o = std::make_shared<ValidateOptions>();
  auto* cmd = app.add_subcommand(
      "validate",
      "Every figure the published record gives (design goal, GP rates, ring bandwidth, pixel "
      "memory, Pixel-Powers CSG timing) beside the simulator's projection of the same "
      "workload, the difference, and whether the figure was fitted, derived or is predicted; "
      "then the sensitivity of the torus's projected rates to every assumed constant, one at a "
      "time, and of the headline conclusions to all of them and the workload choices together "
      "(a seeded Latin hypercube). Writes validate.md, validate.csv, sensitivity.csv and "
      "joint.csv into --out.");
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out, "Output folder (default out/validate)");
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_flag("!--no-sensitivity", o->sensitivity,
                "Skip the sensitivity table (about 170 projections of the torus, some seconds)");
  cmd->add_option("--joint", o->joint,
                  "Samples of the joint sensitivity of the conclusions (0: skip it)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--tessellation", o->tessellation,
                  "Tessellation U V of the large torus the full machine renders against the "
                  "design goal (default 512 128: 131,072 triangles)")
      ->expected(2)
      ->check(CLI::Range(3, 4096));
  return {cmd, [o] { return run_validate(*o); }};
}

}  // namespace pp5
