// The reference subcommands: pp5sim isa, asm, config, stats and scenes.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/machine.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

namespace {

std::string isa_reference() {
  report::Table table;
  table.columns = {report::code_column("instruction"), report::text_column("operands"),
                   report::text_column("effect"), report::text_column("cycles")};
  for (const auto& i : instruction_table()) {
    table.add_row({i.syntax, i.operands[0] ? i.operands : "-", i.effect, i.cycles});
  }
  std::string out = report::markdown(table);
  // Which costs rest on an unpublished property of the machine, grouped by property.
  std::vector<std::pair<std::string, std::vector<std::string>>> bases;
  for (const auto& i : instruction_table()) {
    if (i.basis[0] == '\0') continue;
    auto at =
        std::find_if(bases.begin(), bases.end(), [&](const auto& b) { return b.first == i.basis; });
    if (at == bases.end()) at = bases.insert(bases.end(), {i.basis, {}});
    at->second.push_back(fmt::format("`{}`", i.mnemonic));
  }
  out += "\nEvery cost is one array cycle per bit walked (bit-serial ALU); beyond that:\n\n";
  for (const auto& [basis, names] : bases) {
    out += fmt::format("- {}: {}.\n", fmt::join(names, ", "), basis);
  }
  out +=
      "\nOperand letters: F field (written), R field (read), V field or constant, K constant "
      "(integer or frame parameter), E expression, B backing-store block. A V operand may also be "
      "a constant expression (slope_x, flat_red, ...) in a primitive's procedure: its integer part "
      "is broadcast as a literal is, without the evaluator.\n"
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
  // And a run of frames' (render --frames: a frame's stats.json, run.json).
  for (StatisticInfo& i : describe_run_statistics(resolve_firmware("phong")))
    described.emplace(i.name, std::move(i));
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
  report::Table table;
  table.columns = {
      report::code_column("key"),   report::text_column("value"),
      report::text_column("unit"),  report::text_column("calibration"),
      report::text_column("basis"), report::text_column("plausible range (low .. high)")};
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
    table.add_row(
        {p.key, value, p.unit, std::string(calibration_name(p.calibration)), p.basis, range});
  }
  return report::markdown(table);
}

// 1234567 -> "1,234,567".
std::string grouped(std::uint64_t v) {
  std::string digits = std::to_string(v);
  for (int k = static_cast<int>(digits.size()) - 3; k > 0; k -= 3) digits.insert(k, ",");
  return digits;
}

// What a rewrite that broadcasts a constant expression (ExpressionInfo::constant) rests on.
constexpr const char* kBroadcastBasis =
    "the Renderer's sequencer broadcasting a packet's constant coefficient as an instruction's "
    "immediate operand, as it broadcasts a literal (assumed; not published)";

// The rewrites table: for each BEFORE:AFTER pair of programs, bits, cycles per triangle
// packet (the triangle procedure priced by the instruction table with the scene's frame
// parameters, as the listing and the Renderer price it), the projected polygons/s on the
// scene with hand-coded (assembly) and compiled GP code, and where the cycles went, by
// instruction, each instruction whose cost rests on an unpublished property marked.
std::string rewrites_table(const MachineConfig& config, const Scene& scene,
                           const std::vector<std::string>& pairs) {
  MachineConfig assembly = config;
  assembly.set(std::vector<std::string>{"gp.code=assembly"});
  MachineConfig compiled = config;
  compiled.set(std::vector<std::string>{"gp.code=compiled"});
  const TimingParams timing = timing_params(config);
  OwnedValues values{};
  values.parameters = GeometryEngine(geometry_params(config), scene).frame_parameters();
  struct Measured {
    int bits = 0;
    std::uint64_t cycles = 0;
    std::optional<std::uint64_t> sphere_cycles;  // the sphere procedure's, if it has one
    std::array<std::uint64_t, static_cast<int>(Opcode::count)> by_op{};
    double assembly = 0, compiled = 0;
    bool broadcasts = false;  // the triangle names a constant expression as a broadcast operand
    bool sphere_broadcasts = false;  // ... the sphere procedure does
  };
  auto broadcasts_in = [](const ProcedureCode& code) {
    bool any = false;
    for (const Instruction& ins : code.code) {
      const char* letters = instruction_info(ins.op).operands;
      for (int k = 0; letters[k] != '\0'; ++k) {
        any |= letters[k] == 'V' && ins.operands[k].kind == Operand::Kind::expression;
      }
    }
    return any;
  };
  auto measure = [&](const std::string& name) {
    const Program program = assemble_file(resolve_firmware(name), assembler_options(config));
    const ProcedureCode& code = program.procedure(Procedure::triangle);
    if (!code.defined) {
      throw std::runtime_error(fmt::format("asm --rewrites: {} defines no triangle", name));
    }
    Measured m;
    m.bits = program.bits_used();
    m.broadcasts = broadcasts_in(code);
    for (const Instruction& ins : code.code) {
      const std::uint64_t c = instruction_cost(ins, timing, values).count;
      m.cycles += c;
      m.by_op[static_cast<int>(ins.op)] += c;
    }
    const ProcedureCode& sphere = program.procedure(Procedure::sphere);
    if (sphere.defined) {
      std::uint64_t c = 0;
      for (const Instruction& ins : sphere.code) c += instruction_cost(ins, timing, values).count;
      m.sphere_cycles = c;
      m.sphere_broadcasts = broadcasts_in(sphere);
    }
    m.assembly = project_frame(assembly, scene, program).triangles_per_second;
    m.compiled = project_frame(compiled, scene, program).triangles_per_second;
    return m;
  };
  // Each cell "before -> after"; its value (CSV, sorting) the after figure.
  report::Table table;
  table.id = "rewrites";
  table.columns = {
      report::left_aligned(
          report::text_column("program", "The program before -> after the rewrite"),
          "program, before -> after"),
      report::left_aligned(
          report::integer_column("bits", "bits", "Pixel-memory bits, before -> after"),
          fmt::format("bits of {}", config.renderer.memory_bits)),
      report::left_aligned(
          report::integer_column("cycles per triangle packet", "array cycles",
                                 "The triangle procedure's cycles, before -> after"),
          "cycles per triangle packet"),
      report::left_aligned(
          report::integer_column("cycles per sphere packet", "array cycles",
                                 "The sphere procedure's cycles, before -> after (- where "
                                 "neither program draws spheres)"),
          "cycles per sphere packet"),
      report::left_aligned(
          report::real_column("polygons/s, hand-coded", "polygons/s", 0,
                              "Projected rate with hand-coded GP code, before -> after"),
          fmt::format("{} polygons/s, hand-coded GP code", scene.name)),
      report::left_aligned(
          report::real_column("polygons/s, compiled", "polygons/s", 0,
                              "Projected rate with compiled GP code, before -> after"),
          fmt::format("{} polygons/s, compiled GP code", scene.name)),
      report::left_aligned(
          report::text_column("cycles saved per triangle, by instruction",
                              "Cycles the rewrite saves in the triangle procedure, per "
                              "instruction (negative: spends)"),
          "cycles saved per triangle, by instruction"),
  };
  auto arrow = [](report::Cell after, const std::string& a, const std::string& b) {
    return report::Cell::shown_as(std::move(after), fmt::format("{} -> {}", a, b));
  };
  std::vector<const char*> notes;
  for (const std::string& pair : pairs) {
    const auto colon = pair.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == pair.size()) {
      throw std::runtime_error(
          fmt::format("asm --rewrites: '{}' is not BEFORE:AFTER (two program names)", pair));
    }
    const Measured a = measure(pair.substr(0, colon));
    const Measured b = measure(pair.substr(colon + 1));
    std::vector<std::pair<std::int64_t, int>> deltas;
    for (int op = 0; op < static_cast<int>(Opcode::count); ++op) {
      const auto d =
          static_cast<std::int64_t>(a.by_op[op]) - static_cast<std::int64_t>(b.by_op[op]);
      if (d != 0) deltas.emplace_back(d, op);
    }
    std::stable_sort(deltas.begin(), deltas.end(), [](const auto& x, const auto& y) {
      return std::abs(x.first) > std::abs(y.first);
    });
    std::vector<std::string> saved;
    for (const auto& [d, op] : deltas) {
      const InstructionInfo& info = instruction_info(static_cast<Opcode>(op));
      std::string mark;
      if (info.basis[0] != '\0') {
        auto at = std::find(notes.begin(), notes.end(), info.basis);
        if (at == notes.end()) at = notes.insert(notes.end(), info.basis);
        mark = std::string(static_cast<std::size_t>(at - notes.begin()) + 1, '*');
      }
      saved.push_back(fmt::format("{} {}{}", info.mnemonic,
                                  d > 0 ? grouped(static_cast<std::uint64_t>(d))
                                        : "-" + grouped(static_cast<std::uint64_t>(-d)),
                                  mark));
    }
    auto broadcast_mark = [&notes] {
      auto at = std::find(notes.begin(), notes.end(), kBroadcastBasis);
      if (at == notes.end()) at = notes.insert(notes.end(), kBroadcastBasis);
      return std::string(static_cast<std::size_t>(at - notes.begin()) + 1, '*');
    };
    if (b.broadcasts && !a.broadcasts) {
      saved.push_back(fmt::format("(constant expressions broadcast{})", broadcast_mark()));
    }
    // A sphere figure that moved because the after program broadcasts its constants.
    const std::string sphere_mark =
        b.sphere_broadcasts && !a.sphere_broadcasts && a.sphere_cycles != b.sphere_cycles
            ? broadcast_mark()
            : std::string();
    table.add_row(
        {arrow(pair.substr(colon + 1), pair.substr(0, colon), pair.substr(colon + 1)),
         arrow(b.bits, std::to_string(a.bits), std::to_string(b.bits)),
         arrow(b.cycles, grouped(a.cycles), grouped(b.cycles)),
         !a.sphere_cycles && !b.sphere_cycles
             ? report::Cell::missing()
             : arrow(b.sphere_cycles ? report::Cell(*b.sphere_cycles) : report::Cell::missing(),
                     a.sphere_cycles ? grouped(*a.sphere_cycles) : "-",
                     (b.sphere_cycles ? grouped(*b.sphere_cycles) : "-") + sphere_mark),
         arrow(b.assembly, grouped(static_cast<std::uint64_t>(std::llround(a.assembly))),
               grouped(static_cast<std::uint64_t>(std::llround(b.assembly)))),
         arrow(b.compiled, grouped(static_cast<std::uint64_t>(std::llround(a.compiled))),
               grouped(static_cast<std::uint64_t>(std::llround(b.compiled)))),
         saved.empty() ? report::Cell::missing()
                       : report::Cell(fmt::format("{}", fmt::join(saved, ", ")))});
  }
  std::string out = report::markdown(table);
  for (std::size_t k = 0; k < notes.size(); ++k) {
    out += fmt::format("\n`{}` the figure rests on {}.\n", std::string(k + 1, '*'), notes[k]);
  }
  return out;
}

// The multiply-microcode table: for each shipped program with a mul, each procedure that has
// one, its cycles per packet under renderer.multiply_microcode = full and = window (the
// scene's frame parameters bound, as the listing prices them); the rest of the configuration
// as given.
std::string multiply_microcode_table(const MachineConfig& config, const Scene& scene) {
  MachineConfig full = config;
  full.set(std::vector<std::string>{"renderer.multiply_microcode=full"});
  MachineConfig window = config;
  window.set(std::vector<std::string>{"renderer.multiply_microcode=window"});
  const TimingParams t_full = timing_params(full);
  const TimingParams t_window = timing_params(window);
  OwnedValues values{};
  values.parameters = GeometryEngine(geometry_params(config), scene).frame_parameters();
  report::Table table;
  table.id = "multiply-microcode";
  table.columns = {
      report::left_aligned(report::text_column("program"), "program"),
      report::left_aligned(report::text_column("procedure"), "procedure"),
      report::left_aligned(
          report::integer_column("mul", "instructions", "mul instructions in the procedure"),
          "mul"),
      report::left_aligned(report::integer_column("cycles per packet, full", "array cycles",
                                                  "renderer.multiply_microcode = full"),
                           "cycles per packet, full"),
      report::left_aligned(report::integer_column("cycles per packet, window", "array cycles",
                                                  "renderer.multiply_microcode = window"),
                           "cycles per packet, window*"),
      report::left_aligned(
          report::integer_column("saved", "array cycles", "full - window (the share of full)"),
          "saved"),
  };
  for (const std::string& name : builtin_program_names()) {
    const Program program = assemble_file(resolve_firmware(name), assembler_options(config));
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      const ProcedureCode& code = program.procedures[static_cast<std::size_t>(p)];
      const auto muls = std::count_if(code.code.begin(), code.code.end(),
                                      [](const Instruction& i) { return i.op == Opcode::mul; });
      if (!code.defined || muls == 0) continue;
      const std::uint64_t a = procedure_cost(code, t_full, values).count;
      const std::uint64_t b = procedure_cost(code, t_window, values).count;
      table.add_row({name, kProcedureNames[p], static_cast<std::int64_t>(muls),
                     report::Cell::shown_as(a, grouped(a)), report::Cell::shown_as(b, grouped(b)),
                     report::Cell::shown_as(a - b, fmt::format("{} ({:.0f}%)", grouped(a - b),
                                                               100.0 * static_cast<double>(a - b) /
                                                                   static_cast<double>(a)))});
    }
  }
  std::string out = report::markdown(table);
  out += fmt::format("\n`*` the figure rests on {}.\n", instruction_info(Opcode::mul).basis);
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
                  "A built-in program's name, or a path (with a '/' or ending in .pp5) to a file");
  add_config_options(*cmd, o->path, o->sets);
  auto scene = std::make_shared<std::string>("torus");
  auto rewrites = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--rewrites", *rewrites,
                  "Instead of a listing, a table comparing programs given as BEFORE:AFTER: bits, "
                  "cycles per triangle packet, projected polygons/s on the scene with hand-coded "
                  "and compiled GP code, and the cycles saved by instruction");
  auto microcode = std::make_shared<bool>(false);
  cmd->add_flag("--multiply-microcode", *microcode,
                "Instead of a listing, a table of every shipped program's procedures with a mul: "
                "cycles per packet under renderer.multiply_microcode = full and = window");
  cmd->add_option("--scene", *scene,
                  "Built-in scene or scene file whose frame parameters (lights, and any it sets) "
                  "price the listing: a `mac` by a frame parameter costs what that value's set "
                  "bits cost")
      ->capture_default_str();
  return {cmd, [o, scene, rewrites, microcode] {
            const MachineConfig config = load_config(o->path, o->sets);
            const Scene s = load_scene(*scene);
            if (*microcode) {
              if (!rewrites->empty() || !o->program.empty()) {
                throw std::runtime_error(
                    "asm: --multiply-microcode takes no program and no --rewrites");
              }
              std::cout << multiply_microcode_table(config, s);
              return 0;
            }
            if (rewrites->empty() == o->program.empty()) {
              throw std::runtime_error("asm: give a program, or --rewrites, not both");
            }
            if (!rewrites->empty()) {
              std::cout << rewrites_table(config, s, *rewrites);
              return 0;
            }
            const auto parameters = GeometryEngine(geometry_params(config), s).frame_parameters();
            const Program program =
                assemble_file(resolve_firmware(o->program), assembler_options(config));
            std::cout << listing(program, timing_params(config), parameters,
                                 fmt::format("scene '{}'", s.name));
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
            report::Table table;
            table.columns = {report::code_column("key"),    report::text_column("default"),
                             report::text_column("range"),  report::text_column("unit"),
                             report::text_column("conf."),  report::text_column("calibration"),
                             report::text_column("meaning")};
            for (const auto& p : describe_parameters()) {
              table.add_row({p.key, p.default_value, p.range, p.unit, p.confidence,
                             std::string(calibration_name(p.calibration)), p.description});
            }
            std::cout << report::markdown(table);
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
            report::Table table;
            table.columns = {report::code_column("statistic"), report::text_column("kind"),
                             report::text_column("unit"), report::text_column("meaning")};
            std::set<std::string> listed;
            for (const StatisticInfo& i : describe_statistics(resolve_firmware("phong"))) {
              table.add_row({i.name, stat_kind_name(i.kind), i.unit, i.description});
              listed.insert(i.name);
            }
            // A run of frames (render --frames N): what a frame's stats.json adds, and the
            // run's own (run.json).
            for (const StatisticInfo& i : describe_run_statistics(resolve_firmware("phong"))) {
              if (listed.insert(i.name).second)
                table.add_row({i.name, stat_kind_name(i.kind), i.unit, i.description});
            }
            std::cout << report::markdown(table);
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
