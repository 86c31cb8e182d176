// The reference subcommands: pp5sim isa, asm, config, stats and scenes.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/machine.hpp"
#include "sim/app/commands.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

std::string isa_reference() {
  std::string out = "| instruction | operands | effect | cycles |\n|---|---|---|---|\n";
  for (const auto& i : instruction_table()) {
    out += fmt::format("| `{}` | {} | {} | {} |\n", i.syntax, i.operands[0] ? i.operands : "-",
                       markdown_cell(i.effect), markdown_cell(i.cycles));
  }
  out +=
      "\nOperand letters: F field (written), R field (read), V field or constant, K constant "
      "(integer or frame parameter), E expression, B backing-store block.\n"
      "Conditions: lt le eq ne ge gt.\n\nExpressions (procedure triangle only):\n\n";
  for (const auto& e : kExpressions) out += fmt::format("- `{}`: {}\n", e.name, e.meaning);
  out +=
      "\nFrame parameters (any procedure; from the configuration table's `frame.` section: set "
      "the settable ones with --param NAME=VALUE, --set frame.NAME=VALUE, a config file or a "
      "scene file's \"parameters\"):\n\n";
  for (const ParameterInfo& p : describe_parameters()) {
    if (p.key.rfind("frame.", 0) != 0) continue;
    const std::string name = p.key.substr(6);
    if (p.computed) {
      out += fmt::format("- `{}`: {} Computed {}.\n", name, p.description, p.range);
    } else {
      out += fmt::format("- `{}`: {} Default {}, range {}, {}.\n", name, p.description,
                         p.default_value, p.range, p.unit);
    }
  }
  out += "\nProcedures:\n\n";
  for (int k = 0; k < static_cast<int>(Procedure::count); ++k) {
    out += fmt::format("- `{}`: {}\n", kProcedureNames[k], kProcedureMeaning[k]);
  }
  return out;
}

std::string value_text(const StatValue& v) {
  if (const auto* text = std::get_if<std::string>(&v)) return *text;
  if (const auto* integer = std::get_if<std::int64_t>(&v)) return std::to_string(*integer);
  return fmt::format("{:.9g}", std::get<double>(v));
}

struct StatsOptions {
  bool describe = false;
  std::string file;
};

// `pp5sim stats FILE`: every statistic of a written stats.json with its unit; a name the
// simulator does not register (a file from another version) is an error.
int print_stats_file(const std::string& path) {
  const std::string text = read_regular_file(path, 64u << 20, "a stats.json");
  Statistics file;
  try {
    file = Statistics::from_json(parse_strict_json(text, path));
  } catch (const std::exception& e) {
    const std::string what = e.what();
    // parse_strict_json names the file itself; from_json does not.
    throw std::runtime_error(what.rfind(path, 0) == 0 ? what : fmt::format("{}: {}", path, what));
  }
  // What a run at any fidelity level may write: the analytic and pixel-less levels register
  // statistics of their own (analytic.busiest_seconds, ...).
  std::map<std::string, StatisticInfo> described;
  for (const std::vector<std::string>& level :
       {std::vector<std::string>{}, fidelity_assignments("timing"),
        fidelity_assignments("analytic")}) {
    for (StatisticInfo& i : describe_statistics(resolve_firmware("phong"), level))
      described.emplace(i.name, std::move(i));
  }
  for (const StatisticInfo& i : file.infos()) {
    const auto it = described.find(stat_pattern(i.name));
    if (it == described.end()) {
      throw std::runtime_error(
          fmt::format("{}: '{}' is not a statistic of this pp5sim", path, i.name));
    }
    // Text (a name) has no unit to print.
    const bool text = it->second.kind == StatKind::text;
    std::cout << fmt::format("{} = {}{}{}\n", i.name, value_text(file.value(i.name)),
                             text ? "" : " ", text ? "" : it->second.unit);
  }
  return 0;
}

struct ConfigOptions {
  std::string path;
  std::vector<std::string> sets;
  bool describe = false;
  bool calibration = false;
  std::string program;
};

// The timing constants of `config` (the defaults, or what --config/--set made them), each
// with its calibration mark, its basis and its plausible range.
std::string calibration_table(const MachineConfig& config) {
  const nlohmann::json values = config.to_json();
  std::string out =
      "| key | value | unit | calibration | basis | plausible range (low .. high) |\n"
      "|---|---|---|---|---|---|\n";
  for (const ParameterInfo& p : describe_parameters()) {
    if (p.calibration == Calibration::none) continue;
    const auto dot = p.key.find('.');
    const nlohmann::json& v = values.at(p.key.substr(0, dot)).at(p.key.substr(dot + 1));
    const std::string value = v.is_string()         ? v.get<std::string>()
                              : v.is_number_float() ? fmt::format("{:g}", v.get<double>())
                                                    : v.dump();
    const std::string range =
        p.low.empty() ? "-"
                      : fmt::format("{} .. {}", fmt::join(p.low, " "), fmt::join(p.high, " "));
    out +=
        fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", p.key, value, p.unit,
                    calibration_name(p.calibration), markdown_cell(p.basis), markdown_cell(range));
  }
  return out;
}

}  // namespace

Command add_isa_command(CLI::App& app) {
  auto* isa =
      app.add_subcommand("isa", "Print the micro-instruction set and the firmware interface");
  return {isa, [] {
            std::cout << isa_reference();
            return 0;
          }};
}

Command add_asm_command(CLI::App& app) {
  auto o = std::make_shared<ConfigOptions>();
  auto* cmd =
      app.add_subcommand("asm", "Assemble a firmware program and print its field map and listing");
  cmd->add_option("program", o->program,
                  "A built-in program's name, or a path (with a '/' or ending in .pp5) to a file")
      ->required();
  add_config_options(*cmd, o->path, o->sets);
  return {cmd, [o] {
            const MachineConfig config = load_config(o->path, o->sets);
            const Program program =
                assemble_file(resolve_firmware(o->program), assembler_options(config));
            std::cout << listing(program, timing_params(config));
            return 0;
          }};
}

Command add_config_command(CLI::App& app) {
  auto o = std::make_shared<ConfigOptions>();
  auto* cmd = app.add_subcommand(
      "config", "Print the resolved machine configuration as JSON, or describe every parameter");
  add_config_options(*cmd, o->path, o->sets);
  cmd->add_flag("--describe", o->describe,
                "A table of every parameter: default, range, unit, source, calibration, meaning");
  cmd->add_flag("--calibration", o->calibration,
                "A table of the timing constants only: value, how it was obtained (fitted, "
                "derived, assumed), from what, and the plausible range of fitted and assumed "
                "ones (the ends `pp5sim validate` projects)");
  return {cmd, [o] {
            if (o->describe && o->calibration) {
              throw std::runtime_error("config: give --describe or --calibration, not both");
            }
            if (o->calibration) {
              std::cout << calibration_table(load_config(o->path, o->sets));
              return 0;
            }
            if (!o->describe) {
              std::cout << load_config(o->path, o->sets).to_json().dump(2) << "\n";
              return 0;
            }
            std::cout << "| key | default | range | unit | conf. | calibration | meaning |\n"
                         "|---|---|---|---|---|---|---|\n";
            for (const auto& p : describe_parameters()) {
              std::cout << fmt::format("| `{}` | {} | {} | {} | {} | {} | {} |\n", p.key,
                                       p.default_value, p.range, p.unit, p.confidence,
                                       calibration_name(p.calibration),
                                       markdown_cell(p.description));
            }
            std::cout << "\nConfidence (conf.): where the value comes from: P published (SIGGRAPH "
                         "1989), S secondary source, A assumption. Calibration: how a timing "
                         "constant was obtained: fitted (to a published figure), derived (from a "
                         "published figure or other keys), assumed (no source; with a plausible "
                         "range), - (not a timing constant). The timing constants, with the "
                         "basis of each (`pp5sim config --calibration`):\n\n";
            std::cout << calibration_table(MachineConfig::defaults());
            return 0;
          }};
}

Command add_stats_command(CLI::App& app) {
  auto o = std::make_shared<StatsOptions>();
  auto* cmd = app.add_subcommand(
      "stats",
      "Describe the statistics a run writes to stats.json, or print a stats.json file "
      "with units");
  cmd->add_flag("--describe", o->describe,
                "A table of every statistic: name (N: an index), kind, unit, meaning");
  cmd->add_option("file", o->file, "A stats.json to print, one statistic a line with its unit");
  return {cmd, [o] {
            if (o->describe == !o->file.empty()) {
              throw std::runtime_error("stats: give --describe or a stats.json file (one of them)");
            }
            if (!o->file.empty()) return print_stats_file(o->file);
            std::cout << "| statistic | kind | unit | meaning |\n|---|---|---|---|\n";
            for (const StatisticInfo& i : describe_statistics(resolve_firmware("phong"))) {
              std::cout << fmt::format("| `{}` | {} | {} | {} |\n", i.name, stat_kind_name(i.kind),
                                       i.unit, markdown_cell(i.description));
            }
            return 0;
          }};
}

Command add_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "List the built-in scenes");
  return {cmd, [] {
            for (const auto& name : builtin_scene_names()) {
              std::cout << fmt::format("{:<14} {}\n", name, make_builtin_scene(name).description);
            }
            return 0;
          }};
}

}  // namespace pp5
