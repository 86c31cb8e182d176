// pp5sim validate: the simulator beside every figure of the published record, and the
// sensitivity of the projected rates to each assumed constant (sim/analysis/validate.hpp).
#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "models/machine.hpp"
#include "sim/analysis/validate.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"

namespace pp5 {

namespace {

struct ValidateOptions {
  std::string config_path;
  std::vector<std::string> sets;
  std::string out = "out/validate";
  bool sensitivity = true;
  std::vector<int> tessellation{512, 128};
  int joint = 64;
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
  std::string report =
      "Published figures beside the simulator's projection of the same workload:\n\n" +
      validation_markdown(rows) + "\n" + evidence_summary(rows);
  OutputSet outputs;
  outputs.add(o.out + "/validate.csv", validation_csv(rows));
  if (o.sensitivity) {
    const SensitivityTable table = sensitivity(config, load, default_sensitivity_workloads());
    report +=
        "\nSensitivity: projected triangles/s of the torus (8,192 triangles) at the low and high "
        "end of each fitted or assumed constant's plausible range, the others at their "
        "values:\n\n" +
        sensitivity_markdown(table);
    outputs.add(o.out + "/sensitivity.csv", sensitivity_csv(table));
  }
  if (o.joint > 0) {
    JointSensitivityOptions joint;
    joint.samples = o.joint;
    joint.tessellation_u = o.tessellation[0];
    joint.tessellation_v = o.tessellation[1];
    const JointSensitivity j = joint_sensitivity(config, load, joint);
    report +=
        "\nJoint sensitivity of the conclusions: the design goal's workload (phong, hand-coded "
        "GPs) with every fitted and assumed constant and the workload choices varied "
        "together:\n\n" +
        joint_sensitivity_markdown(j);
    std::string csv =
        "sample,scene,triangles,rate,pipelined_rate,bottleneck,painter_over_zbuffer,"
        "painter_choices,sets\n";
    for (std::size_t k = 0; k < j.points.size(); ++k) {
      const JointSample& p = j.points[k];
      csv += fmt::format("{},{},{},{:.9g},{:.9g},{},{:.6g},{},{}\n", k, p.scene, p.triangles,
                         p.rate, p.pipelined_rate, p.bottleneck, p.painter_over_zbuffer,
                         p.painter_choices, fmt::join(p.sets, " "));
    }
    outputs.add(o.out + "/joint.csv", csv);
  }
  outputs.add(o.out + "/validate.md", report);
  outputs.commit();
  std::cout << report;
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
