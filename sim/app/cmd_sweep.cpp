// pp5sim sweep: architecture studies over a grid of machine parameters.
//
//   pp5sim sweep --grid gp.count=1,2,4 --grid renderer.count=1,4,16 --out DIR   runs locally
//   pp5sim sweep ... --print-commands   one `pp5sim render` line per run (GNU parallel, Slurm)
//   pp5sim sweep ... --slurm FILE       FILE submits the runs as a Slurm job array, and the
//                                       aggregation as a job that waits for them (afterok)
//   pp5sim sweep aggregate DIR -o sweep.csv   one CSV row per run, from each run's stats.json
//   pp5sim sweep plot sweep.csv -o sweep.svg  throughput against the swept parameters
//
// Each run has its own folder DIR/KEY-VALUE_KEY-VALUE holding config.json and stats.json, as
// `pp5sim render --out` writes them; DIR/sweep.json records the grid for the later steps.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "common/escape.hpp"
#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/machine.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/report_html.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

struct Axis {
  std::string key;
  std::vector<std::string> values;
};

struct SweepOptions {
  std::vector<std::string> grid;
  std::string scene_name = "torus";
  std::string firmware;  // empty: the scene file's "firmware", else phong
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/sweep";
  bool print_commands = false;
  std::string slurm;  // the job-array script to write, or empty
  int threads = default_threads();
  std::vector<int> tessellation;
  // aggregate
  std::string aggregate_dir;
  std::string csv_out;
  bool report = false;  // aggregate: also DIR/report.html
  // plot
  std::string plot_csv;
  std::string plot_out;
  std::string plot_x;
  std::string plot_series;
  std::string plot_y = "triangles_per_second";
};

// Each value is checked against `base`: the configuration with --config and --set applied,
// which is what the point will run with.
std::vector<Axis> parse_grid(const std::vector<std::string>& grid, const MachineConfig& base) {
  if (grid.empty()) {
    throw std::runtime_error("--grid: give at least one, e.g. --grid gp.count=1,2,4,8");
  }
  std::vector<Axis> axes;
  std::set<std::string> seen;
  for (const std::string& g : grid) {
    const auto eq = g.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == g.size()) {
      throw std::runtime_error(
          fmt::format("--grid {}: expected KEY=V1,V2,..., e.g. gp.count=1,2,4", g));
    }
    Axis a;
    a.key = g.substr(0, eq);
    if (!seen.insert(a.key).second) {
      throw std::runtime_error(fmt::format("--grid {}: key '{}' is swept twice", g, a.key));
    }
    std::stringstream values(g.substr(eq + 1));
    std::string v;
    while (std::getline(values, v, ',')) a.values.push_back(v);
    check_sweep_axis("--grid " + g, a.key, a.values, base);
    axes.push_back(std::move(a));
  }
  return axes;
}

std::string run_name(const std::vector<Axis>& axes, const std::vector<std::string>& values) {
  std::string name;
  for (std::size_t k = 0; k < axes.size(); ++k) {
    name += (k ? "_" : "") + axes[k].key + "-" + values[k];
  }
  return name;
}

// The most points one sweep may have: a million runs is days of host time already, and the
// grid is walked, never held, so no size below this can exhaust memory.
constexpr std::uint64_t kMaxSweepPoints = 1000000;

// The values of grid point `index`, the first axis varying slowest.
std::vector<std::string> point(const std::vector<Axis>& axes, std::uint64_t index) {
  std::vector<std::string> values(axes.size());
  for (std::size_t k = axes.size(); k-- > 0;) {
    values[k] = axes[k].values[index % axes[k].values.size()];
    index /= axes[k].values.size();
  }
  return values;
}

// Slurm refuses a job array with more tasks than its MaxArraySize (1001 by default, so
// indices 0..1000); a larger grid must be split or the site's limit raised.
constexpr std::uint64_t kSlurmDefaultMaxArraySize = 1001;

// --slurm FILE: OUT/commands.txt, one `pp5sim render` command per grid point (as
// --print-commands prints them, for `parallel < OUT/commands.txt`), and FILE, a bash script
// that submits them to Slurm: a job array whose task i runs line i + 1, then `sweep aggregate
// --report` (sweep.csv and report.html) as a job that starts only once every task has succeeded
// (afterok; a failed task cancels it). Both files are written, or neither. Paths in the jobs are
// relative to the folder `sweep` ran in, which the jobs start in (--chdir).
int write_slurm_job(const SweepOptions& o, const std::string& program_path, std::uint64_t points,
                    const std::function<std::string(std::uint64_t)>& command) {
  const fs::path cwd = fs::current_path();
  const fs::path out = fs::absolute(o.out_dir).lexically_normal();
  const fs::path commands = out / "commands.txt";
  std::string lines;
  for (std::uint64_t i = 0; i < points; ++i) lines += command(i) + "\n";
  // Every string that reaches the script is quoted for the place it reaches (a comment, a
  // shell word, an sbatch file-name pattern), and one that no quoting makes safe (a control
  // character, which would end a comment or a line of commands.txt) is refused.
  const std::string q_out = shell_quote(out.string(), "--out");
  const std::string q_commands = shell_quote(commands.string(), "--out");
  const std::string q_cwd = shell_quote(cwd.string(), "the current folder");
  const std::string q_out_pattern = shell_quote(slurm_pattern_literal(out.string()), "--out");
  std::string script = fmt::format(
      R"(#!/bin/bash
# Written by `pp5sim sweep --slurm`: submits the sweep in {out} to Slurm.
#   bash {self}
# - a job array of {points} tasks, one per grid point: task i runs line i + 1 of
#   {commands} (the commands `--print-commands` prints, for GNU parallel);
# - `pp5sim sweep aggregate --report` into {out}/sweep.csv and {out}/report.html, as a job
#   that starts once every task has succeeded (afterok).
# Each task's output goes to {out}/slurm-JOB_TASK.out. Extra sbatch options (partition,
# account, time limit) come from PP5_SBATCH_OPTIONS, e.g. PP5_SBATCH_OPTIONS="-p short".
# Slurm refuses arrays larger than its MaxArraySize (1001 by default).
set -euo pipefail
read -r -a extra <<< "${{PP5_SBATCH_OPTIONS:-}}"
array=$(sbatch --parsable "${{extra[@]}}" --job-name=pp5-sweep --array=0-{last} \
  --ntasks=1 --cpus-per-task=1 --chdir={cwd} --output={out_pattern}/slurm-%A_%a.out <<'TASK'
#!/bin/bash
set -euo pipefail
line=$(sed -n "$((SLURM_ARRAY_TASK_ID + 1))p" {commands})
[ -n "$line" ] || {{ echo "no command for task $SLURM_ARRAY_TASK_ID in {commands}" >&2; exit 1; }}
eval "exec $line"
TASK
)
array=${{array%%;*}}
aggregate=$(sbatch --parsable "${{extra[@]}}" --job-name=pp5-sweep-aggregate \
  --dependency=afterok:"$array" --kill-on-invalid-dep=yes --ntasks=1 --cpus-per-task=1 \
  --chdir={cwd} --output={out_pattern}/slurm-aggregate-%j.out \
  --wrap={aggregate})
aggregate=${{aggregate%%;*}}
echo "submitted job array $array ({points} tasks) and aggregate job $aggregate"
echo "$array $aggregate" > {out}/slurm-jobs.txt
)",
      fmt::arg("out", q_out), fmt::arg("out_pattern", q_out_pattern),
      fmt::arg("self", shell_quote(o.slurm, "--slurm")), fmt::arg("points", points),
      fmt::arg("commands", q_commands), fmt::arg("last", points - 1), fmt::arg("cwd", q_cwd),
      fmt::arg("aggregate",
               shell_quote(fmt::format("{} sweep aggregate {} -o {} --report",
                                       shell_quote(program_path, "the pp5sim executable's path"),
                                       q_out, shell_quote((out / "sweep.csv").string(), "--out")),
                           "--out")));
  OutputSet outputs;
  outputs.add(commands.string(), lines);
  outputs.add(o.slurm, script);
  outputs.commit();
  fs::permissions(o.slurm, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  std::cout << fmt::format(
      "wrote {} ({} commands, for `parallel < {}`) and {} (a Slurm job array "
      "of {} tasks and a dependent `sweep aggregate --report`: bash {})\n",
      commands.string(), points, commands.string(), o.slurm, points, o.slurm);
  if (points > kSlurmDefaultMaxArraySize) {
    std::cerr << fmt::format(
        "warning: {} array tasks: Slurm's default MaxArraySize is {}; split the grid or raise "
        "the cluster's limit\n",
        points, kSlurmDefaultMaxArraySize);
  }
  return 0;
}

int run_aggregate(const SweepOptions& o);

int run_sweep(const SweepOptions& o, const std::string& program_path) {
  // Each point's configuration is the base (file and --set) with its axes set, built when it
  // is needed rather than all held at once.
  const MachineConfig base = load_config(o.config_path, o.sets);
  const std::vector<Axis> axes = parse_grid(o.grid, base);
  std::uint64_t points = 1;
  for (const Axis& a : axes) {
    if (points > kMaxSweepPoints / a.values.size()) {
      throw std::runtime_error(fmt::format(
          "--grid: the grid has more than {} points; split the sweep into several (each with its "
          "own --out) or sweep fewer values",
          kMaxSweepPoints));
    }
    points *= a.values.size();
  }
  auto config_of = [&](std::uint64_t i) {
    const std::vector<std::string> values = point(axes, i);
    std::vector<std::string> sets;
    for (std::size_t k = 0; k < axes.size(); ++k) sets.push_back(axes[k].key + "=" + values[k]);
    MachineConfig c = base;
    c.set(sets);
    return c;
  };
  SceneOptions scene_options;
  if (o.tessellation.size() == 2) {
    scene_options.tessellation_u = o.tessellation[0];
    scene_options.tessellation_v = o.tessellation[1];
  }
  const Scene scene = load_scene(o.scene_name, scene_options);
  const std::string firmware = firmware_for(o.firmware, scene);
  // Check every point's whole configuration, and the program against each distinct pixel
  // memory, before writing anything.
  // The program, assembled once for each distinct pixel memory, is kept for the points.
  std::map<std::tuple<int, int, int, int>, Program> assembled;
  auto program_of = [&](const MachineConfig& c) -> const Program& {
    const AssemblerOptions a = assembler_options(c);
    const auto key =
        std::make_tuple(a.memory_bits, a.backing_store_bits, a.block_bits, a.enable_stack_depth);
    auto it = assembled.find(key);
    if (it == assembled.end()) it = assembled.emplace(key, assemble_file(firmware, a)).first;
    return it->second;
  };
  for (std::uint64_t i = 0; i < points; ++i) program_of(config_of(i));

  // Point i's `pp5sim render` command, the same for GNU parallel and Slurm.
  auto command = [&](const std::vector<std::string>& values, const fs::path& dir) {
    std::string line =
        fmt::format("{} render --scene {} --firmware {}",
                    shell_quote(program_path, "the pp5sim executable's path"),
                    shell_quote(o.scene_name, "--scene"), shell_quote(firmware, "--firmware"));
    if (!o.config_path.empty()) line += " --config " + shell_quote(o.config_path, "--config");
    if (o.tessellation.size() == 2) {
      line += fmt::format(" --tessellation {} {}", o.tessellation[0], o.tessellation[1]);
    }
    for (const std::string& s : o.sets) line += " --set " + shell_quote(s, "--set");
    for (std::size_t k = 0; k < axes.size(); ++k) {
      line += " --set " + shell_quote(axes[k].key + "=" + values[k], "--grid");
    }
    return line + " --threads 1 --out " + shell_quote(dir.string(), "--out");
  };
  // Every string that will reach a command line or the Slurm script is checked before
  // anything is written (shell_quote refuses a control character, naming the option).
  if (o.print_commands || !o.slurm.empty()) {
    for (const Axis& a : axes) {
      for (const std::string& v : a.values) shell_quote(a.key + "=" + v, "--grid");
    }
    const std::vector<std::string> first = point(axes, 0);
    (void)command(first, fs::path(o.out_dir) / run_name(axes, first));
  }
  if (!o.slurm.empty()) {
    shell_quote(fs::absolute(o.out_dir).string(), "--out");
    shell_quote(o.slurm, "--slurm");
    shell_quote(fs::current_path().string(), "the current folder");
  }
  prepare_output_folder(o.out_dir, "--out");
  nlohmann::json grid = nlohmann::json::object();
  for (const Axis& a : axes) grid[a.key] = a.values;
  write_file_atomically((fs::path(o.out_dir) / "sweep.json").string(),
                        nlohmann::json{{"grid", grid},
                                       {"order",
                                        [&] {
                                          std::vector<std::string> k;
                                          for (const Axis& a : axes) k.push_back(a.key);
                                          return k;
                                        }()},
                                       {"scene", o.scene_name},
                                       {"firmware", firmware}}
                                .dump(2) +
                            "\n");
  if (!o.slurm.empty()) {
    return write_slurm_job(o, program_path, points, [&](std::uint64_t i) {
      const std::vector<std::string> values = point(axes, i);
      return command(values, fs::path(o.out_dir) / run_name(axes, values));
    });
  }
  // Points that differ only in what set-up does not read (GP and Renderer counts, the ring,
  // clocks) replay the first one's set-up (models/gp/setup_memo.hpp).
  SetupMemo setup_memo(scene);
  for (std::uint64_t i = 0; i < points; ++i) {
    const std::vector<std::string> values = point(axes, i);
    const fs::path dir = fs::path(o.out_dir) / run_name(axes, values);
    if (o.print_commands) {
      std::cout << command(values, dir) << "\n";
      continue;
    }
    const MachineConfig config = config_of(i);
    const FrameResult r =
        simulate_frame(config, scene, program_of(config), o.threads, {}, nullptr, &setup_memo);
    prepare_output_folder(dir.string(), "--out");
    // A run's two files together, or neither (sim/output).
    OutputSet outputs;
    outputs.add((dir / "config.json").string(), config.to_json().dump(2) + "\n");
    outputs.add((dir / "stats.json").string(), r.stats_json.dump(2) + "\n");
    outputs.commit();
    std::cerr << fmt::format("[{}/{}] {}: {:.3f} ms, {:.0f} triangles/s, bottleneck {}\n", i + 1,
                             points, dir.filename().string(), r.frame_seconds * 1e3,
                             r.triangles_per_second, r.stats.text("timing.bottleneck"));
  }
  if (!o.print_commands && o.report) {
    // --report: aggregate at once, into OUT/sweep.csv and OUT/report.html.
    std::cout << fmt::format("{} runs in {}\n", points, o.out_dir);
    SweepOptions aggregate = o;
    aggregate.aggregate_dir = o.out_dir;
    aggregate.csv_out.clear();
    return run_aggregate(aggregate);
  }
  if (!o.print_commands) {
    std::cout << fmt::format("{} runs in {}; next: pp5sim sweep aggregate {} -o sweep.csv\n",
                             points, o.out_dir, o.out_dir);
  }
  return 0;
}

nlohmann::json read_json(const fs::path& path) {
  // A run's files are kilobytes; 64 MiB is far beyond any.
  return parse_strict_json(read_regular_file(path.string(), 64u << 20, "a JSON file of a sweep"),
                           path.string());
}

// A written run's statistics, to read by name.
Statistics read_statistics(const fs::path& path) {
  try {
    return Statistics::from_json(read_json(path));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: {}", path.string(), e.what()));
  }
}

// A configuration value or a statistic as a typed cell (the CSV writes integers exactly and
// reals with 9 significant digits).
report::Cell sweep_cell(const nlohmann::json& v) {
  if (v.is_string()) return report::Cell(v.get<std::string>());
  if (v.is_boolean()) return report::Cell(std::string(v.get<bool>() ? "true" : "false"));
  if (v.is_number_integer()) return report::Cell(static_cast<std::int64_t>(v.get<long long>()));
  if (v.is_number()) {
    const double d = v.get<double>();
    return report::Cell::shown_as(report::Cell(d), fmt::format("{:.9g}", d));
  }
  return report::Cell(v.dump());
}

report::Cell sweep_cell(const StatValue& v) {
  if (const auto* text = std::get_if<std::string>(&v)) return report::Cell(*text);
  if (const auto* integer = std::get_if<std::int64_t>(&v)) return report::Cell(*integer);
  const double d = std::get<double>(v);
  return report::Cell::shown_as(report::Cell(d), fmt::format("{:.9g}", d));
}

// What each statistic is (unit, description), by pattern, from a frame of the smallest
// machine running `firmware`; empty if that cannot run (the report then shows no units).
std::map<std::string, StatisticInfo> sweep_statistic_infos(const std::string& firmware) {
  std::map<std::string, StatisticInfo> infos;
  try {
    for (const StatisticInfo& i : describe_statistics(resolve_firmware(firmware)))
      infos[i.name] = i;
  } catch (const std::exception& e) {
    std::cerr << fmt::format("pp5sim: warning: no units for the report ({})\n", e.what());
  }
  return infos;
}

report::Column sweep_column(const std::string& key, const std::string& name,
                            const std::map<std::string, StatisticInfo>& infos) {
  report::Column c = report::text_column(key);
  const auto it = infos.find(stat_pattern(name));
  if (it != infos.end()) {
    c.unit = it->second.unit == stat_unit::name ? "" : it->second.unit;
    c.description = name + ": " + it->second.description;
    c.kind = it->second.kind == StatKind::text      ? report::Kind::text
             : it->second.kind == StatKind::integer ? report::Kind::integer
                                                    : report::Kind::real;
  }
  c.key = key;
  c.heading = key;
  return c;
}

int run_aggregate(const SweepOptions& o) {
  const fs::path dir(o.aggregate_dir);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw std::runtime_error(fmt::format(
        "{}: {}, expected the output folder of a 'pp5sim sweep' run (it holds sweep.json)",
        dir.string(), fs::exists(dir, ec) ? "is not a folder" : "no such folder"));
  }
  const nlohmann::json sweep = read_json(dir / "sweep.json");
  // sweep.json names the run folders read: it is checked to be what `sweep` writes (keys
  // of letters, digits, '_' and '.', each swept once; values that are one folder-name
  // component, each once), so that a forged one reads nothing outside DIR.
  const std::string where = (dir / "sweep.json").string();
  auto bad = [&](const std::string& what) {
    return std::runtime_error(fmt::format("{}: {} (expected what 'pp5sim sweep' writes)", where,
                                          escape_for_message(what)));
  };
  std::vector<std::string> keys;
  std::vector<Axis> axes;
  try {
    if (!sweep.is_object() || !sweep.contains("order") || !sweep.contains("grid") ||
        !sweep.at("order").is_array() || !sweep.at("grid").is_object()) {
      throw bad("no 'order' list and 'grid' object");
    }
    keys = sweep.at("order").get<std::vector<std::string>>();
    std::set<std::string> seen;
    for (const auto& k : keys) {
      const bool name =
          !k.empty() && k.size() <= 64 &&
          k.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_.") == std::string::npos;
      if (!name) throw bad("'order' holds '" + k + "', not a configuration key");
      if (!seen.insert(k).second) throw bad("'order' names '" + k + "' twice");
      if (!sweep.at("grid").contains(k)) throw bad("'order' names '" + k + "', not in 'grid'");
      Axis a{k, sweep.at("grid").at(k).get<std::vector<std::string>>()};
      std::set<std::string> given;
      for (const std::string& v : a.values) {
        if (v.empty() || v.size() > 64 || v == "." || v == ".." ||
            v.find('/') != std::string::npos || !is_display_text(v) || !given.insert(v).second) {
          throw bad("'grid." + k + "' holds '" + v +
                    "', not a value once (a folder name: no '/', no control bytes)");
        }
      }
      axes.push_back(std::move(a));
    }
    if (seen.size() != sweep.at("grid").size()) throw bad("'grid' has keys 'order' does not list");
  } catch (const nlohmann::json::exception& e) {
    throw bad(json_error_text(e));
  }
  std::uint64_t points = 1;
  for (const Axis& a : axes) {
    if (a.values.empty() || points > kMaxSweepPoints / a.values.size()) {
      throw std::runtime_error(
          fmt::format("{}: the grid has no values on axis '{}' or more than {} points",
                      (dir / "sweep.json").string(), a.key, kMaxSweepPoints));
    }
    points *= a.values.size();
  }
  std::vector<fs::path> runs;
  for (std::uint64_t i = 0; i < points; ++i) runs.push_back(dir / run_name(axes, point(axes, i)));
  std::sort(runs.begin(), runs.end());
  // The units come from the statistics' registry; reading it runs a tiny frame, so only for
  // the report.
  const std::map<std::string, StatisticInfo> infos =
      o.report ? sweep_statistic_infos(sweep.value("firmware", std::string("phong")))
               : std::map<std::string, StatisticInfo>{};
  // One row per run (sweep.csv), and for the report one with every statistic.
  report::Table table;
  table.id = "runs";
  for (const auto& k : keys) {
    report::Column c = report::text_column(k, "A swept configuration key");
    c.key = k;
    table.columns.push_back(c);
  }
  for (const auto& [column, name] : sweep_metric_columns())
    table.columns.push_back(sweep_column(column, name, infos));
  for (const char* level : {"fidelity_pixels", "fidelity_timing"}) {
    report::Column c = report::text_column(level, "The level each row was simulated at");
    table.columns.push_back(c);
  }
  report::Table every;  // the report's plot: the swept keys and every statistic
  every.id = "statistics";
  struct Row {
    std::vector<double> order;
    std::vector<report::Cell> cells;
    std::vector<report::Cell> all;
  };
  std::vector<Row> sorted_rows;
  int rows = 0;
  int missing = 0;
  for (const fs::path& run : runs) {
    if (!fs::exists(run / "stats.json") || !fs::exists(run / "config.json")) {
      // The first ten by name, then how many in all (a million would be a million lines).
      if (missing < 10) {
        std::cerr << fmt::format(
            "pp5sim: warning: {}: no stats.json or config.json (not run yet?)\n", run.string());
      }
      ++missing;
      continue;
    }
    const nlohmann::json config = read_json(run / "config.json");
    const Statistics stats = read_statistics(run / "stats.json");
    Row row;
    for (const auto& k : keys) {
      const auto dot = k.find('.');
      const nlohmann::json& v = config.at(k.substr(0, dot)).at(k.substr(dot + 1));
      row.order.push_back(v.is_number() ? v.get<double>() : 0.0);
      row.cells.push_back(sweep_cell(v));
    }
    for (const auto& [column, name] : sweep_metric_columns()) {
      if (!stats.contains(name)) {
        throw std::runtime_error(fmt::format("{}: no '{}' in stats.json (from an older pp5sim?)",
                                             (run / "stats.json").string(), name));
      }
      row.cells.push_back(sweep_cell(stats.value(name)));
    }
    // A run from before the fidelity keys was simulated at the only level there was.
    const auto level = [&](const char* key, const char* before) {
      const auto f = config.find("fidelity");
      if (f == config.end() || !f->contains(key)) return report::Cell(before);
      return sweep_cell(f->at(key));
    };
    row.cells.push_back(level("pixels", "bit"));
    row.cells.push_back(level("timing", "event"));
    if (o.report) {
      const std::vector<StatisticInfo> names = stats.infos();
      if (every.columns.empty()) {
        for (std::size_t k = 0; k < keys.size(); ++k) every.columns.push_back(table.columns[k]);
        for (const StatisticInfo& i : names)
          every.columns.push_back(sweep_column(i.name, i.name, infos));
      }
      row.all.assign(row.cells.begin(), row.cells.begin() + static_cast<long>(keys.size()));
      for (std::size_t k = keys.size(); k < every.columns.size(); ++k) {
        const std::string& name = every.columns[k].key;
        row.all.push_back(stats.contains(name) ? sweep_cell(stats.value(name)) : report::Cell());
      }
    }
    sorted_rows.push_back(std::move(row));
    ++rows;
  }
  if (missing > 10) {
    std::cerr << fmt::format("pp5sim: warning: ... and {} more runs without them ({} of {})\n",
                             missing - 10, missing, runs.size());
  }
  // Rows in the grid's numeric order (folder names sort as text).
  std::stable_sort(sorted_rows.begin(), sorted_rows.end(),
                   [](const Row& a, const Row& b) { return a.order < b.order; });
  for (Row& r : sorted_rows) {
    table.add_row(r.cells);
    if (o.report) every.add_row(r.all);
  }
  if (rows == 0) throw std::runtime_error(fmt::format("{}: no finished runs", dir.string()));
  const std::string out = o.csv_out.empty() ? (dir / "sweep.csv").string() : o.csv_out;
  OutputSet outputs;
  outputs.add(out, report::csv(table));
  const std::string report_path = (dir / "report.html").string();
  if (o.report) {
    report::Report r;
    r.title = fmt::format("pp5sim sweep: {} runs of scene '{}', firmware {}", rows,
                          sweep.value("scene", std::string("?")),
                          fs::path(sweep.value("firmware", std::string("?"))).stem().string());
    std::string grid;
    for (const Axis& a : axes)
      grid +=
          (grid.empty() ? "" : "; ") + a.key + " = " + fmt::format("{}", fmt::join(a.values, ", "));
    r.subtitle = "Grid: " + grid;
    report::Section& plot = r.add_section("plot", "Any statistic against the swept keys");
    plot.blocks.push_back(report::Paragraph{
        "Choose the statistic (y), the swept key on the x axis and the key whose values make "
        "the lines. Every statistic of every run's stats.json is here."});
    plot.blocks.push_back(report::RawHtml{
        report::html_plot(every, keys, "frame.projected_triangles_per_second"), ""});
    report::Section& runs_section = r.add_section("runs", "Runs");
    runs_section.blocks.push_back(report::Paragraph{
        "sweep.csv: one row per run. Click a heading to sort; a heading's tooltip says what "
        "the column is."});
    runs_section.blocks.push_back(table);
    if (missing) {
      runs_section.blocks.push_back(report::Note{
          report::Note::Level::warning,
          fmt::format("{} runs of the grid have no stats.json or config.json (not run yet?)",
                      missing)});
    }
    outputs.add(report_path, report::html(r));
  }
  outputs.commit();
  std::cout << fmt::format("wrote {} ({} runs{})\n", out, rows,
                           missing ? fmt::format(", {} missing", missing) : "");
  if (o.report) std::cout << fmt::format("wrote {}\n", report_path);
  return 0;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name, const std::string& path) const {
    for (std::size_t k = 0; k < header.size(); ++k) {
      if (header[k] == name) return static_cast<int>(k);
    }
    throw std::runtime_error(
        fmt::format("{}: no column '{}' (columns: {})", path, name, fmt::join(header, ", ")));
  }
};

Csv read_csv(const std::string& path) {
  // One row per run of at most a million runs.
  std::istringstream in(read_regular_file(path, 1u << 30, "a sweep CSV (sweep aggregate's)"));
  Csv csv;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (n == 1) {
      csv.header = cells;
    } else if (!line.empty()) {
      if (cells.size() != csv.header.size()) {
        throw std::runtime_error(
            fmt::format("{}:{}: {} cells, expected {}", path, n, cells.size(), csv.header.size()));
      }
      csv.rows.push_back(cells);
    }
  }
  if (csv.rows.empty()) throw std::runtime_error(fmt::format("{}: no rows", path));
  return csv;
}

double number(const std::string& text, const std::string& path, const std::string& column) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    // inf and nan parse, and an axis to infinity drew gigabytes of grid lines.
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw std::runtime_error(fmt::format("{}: column '{}' has '{}', which is not a finite number",
                                       path, escape_for_message(column), escape_for_message(text)));
}

std::string svg_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else
      out += c;
  }
  return out;
}

std::string si(double v) {
  if (v >= 1e6) return fmt::format("{:g}M", v / 1e6);
  if (v >= 1e3) return fmt::format("{:g}K", v / 1e3);
  return fmt::format("{:g}", v);
}

// Throughput against the first swept parameter, one line per value of the second, on
// log-log axes (sweeps of counts are geometric).
int run_plot(const SweepOptions& o) {
  const Csv csv = read_csv(o.plot_csv);
  const std::string x_name = o.plot_x.empty() ? csv.header.at(0) : o.plot_x;
  const int xc = csv.column(x_name, o.plot_csv);
  const int yc = csv.column(o.plot_y, o.plot_csv);
  int sc = -1;
  if (!o.plot_series.empty()) {
    sc = csv.column(o.plot_series, o.plot_csv);
  } else if (xc != 1 && csv.header.size() > 1 && csv.header[1] != sweep_metric_columns()[0].first) {
    sc = 1;
  } else if (xc != 0 && csv.header[0] != sweep_metric_columns()[0].first) {
    sc = 0;
  }
  // Lines in the order their values first appear (the CSV is in grid order).
  std::vector<std::pair<std::string, std::vector<std::pair<double, double>>>> series;
  for (const auto& row : csv.rows) {
    const std::string s = sc >= 0 ? row[sc] : "";
    auto it =
        std::find_if(series.begin(), series.end(), [&](const auto& e) { return e.first == s; });
    if (it == series.end()) it = series.insert(series.end(), {s, {}});
    it->second.push_back(
        {number(row[xc], o.plot_csv, x_name), number(row[yc], o.plot_csv, o.plot_y)});
  }
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (auto& [s, pts] : series) {
    std::sort(pts.begin(), pts.end());
    for (const auto& [x, y] : pts) {
      if (x <= 0 || y <= 0) {
        throw std::runtime_error(fmt::format("{}: log axes need positive values ({}={}, {}={})",
                                             o.plot_csv, x_name, x, o.plot_y, y));
      }
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  const double lx0 = std::log10(x0), lx1 = std::max(std::log10(x1), lx0 + 1e-9);
  const double ly0 = std::floor(std::log10(y0)), ly1 = std::ceil(std::log10(y1) + 1e-9);
  // Grid lines are drawn per decade: bounded before they are.
  constexpr double kMaxDecades = 40;
  if (ly1 - ly0 > kMaxDecades) {
    throw std::runtime_error(
        fmt::format("{}: {} runs from {:g} to {:g}, {} decades; the plot draws at most {}",
                    o.plot_csv, escape_for_message(o.plot_y), y0, y1, ly1 - ly0, kMaxDecades));
  }
  const int W = 760, H = 480, L = 90, R = 170, T = 50, B = 60;
  auto px = [&](double x) { return L + (std::log10(x) - lx0) / (lx1 - lx0) * (W - L - R); };
  auto py = [&](double y) { return H - B - (std::log10(y) - ly0) / (ly1 - ly0) * (H - T - B); };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
      "fill=\"white\"/>\n",
      W, H);
  svg += fmt::format(
      "<text x=\"{}\" y=\"24\" font-size=\"15\" text-anchor=\"middle\">{} against {}"
      "</text>\n",
      W / 2, svg_escape(o.plot_y), svg_escape(x_name));
  for (double d = ly0; d <= ly1 + 1e-9; d += 1) {
    for (int m = 1; m < 10; ++m) {
      const double y = std::pow(10.0, d) * m;
      if (std::log10(y) > ly1 + 1e-9) break;
      svg += fmt::format("<line x1=\"{}\" x2=\"{}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\"/>\n",
                         L, W - R, py(y), py(y), m == 1 ? "#bbb" : "#eee");
      if (m == 1 || m == 2 || m == 5) {
        svg += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", L - 6,
                           py(y) + 4, si(y));
      }
    }
  }
  std::set<double> xs;
  for (const auto& [s, pts] : series) {
    for (const auto& p : pts) xs.insert(p.first);
  }
  for (double x : xs) {
    svg += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{}\" y2=\"{}\" stroke=\"#eee\"/>\n",
                       px(x), px(x), T, H - B);
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{:g}</text>\n", px(x),
                       H - B + 18, x);
  }
  svg += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" "
      "stroke=\"black\"/>\n",
      L, T, W - L - R, H - T - B);
  svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{} (log scale)</text>\n",
                     (L + W - R) / 2, H - 16, svg_escape(x_name));
  svg += fmt::format(
      "<text transform=\"translate(20,{}) rotate(-90)\" text-anchor=\"middle\">{} "
      "(log scale)</text>\n",
      (T + H - B) / 2, svg_escape(o.plot_y));
  static const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                  "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  int k = 0;
  for (const auto& [s, pts] : series) {
    const char* colour = colours[k % 10];
    std::string path;
    for (const auto& [x, y] : pts) {
      path += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
      svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\" fill=\"{}\"/>\n", px(x),
                         py(y), colour);
    }
    svg += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n",
                       path, colour);
    if (sc >= 0) {
      const int ly = T + 10 + 20 * k;
      svg += fmt::format(
          "<line x1=\"{}\" x2=\"{}\" y1=\"{}\" y2=\"{}\" stroke=\"{}\" "
          "stroke-width=\"2\"/>\n",
          W - R + 12, W - R + 36, ly, ly, colour);
      svg += fmt::format("<text x=\"{}\" y=\"{}\">{} = {}</text>\n", W - R + 42, ly + 4,
                         svg_escape(csv.header[sc]), svg_escape(s));
    }
    ++k;
  }
  svg += "</svg>\n";
  const std::string out =
      o.plot_out.empty() ? (fs::path(o.plot_csv).replace_extension(".svg")).string() : o.plot_out;
  write_file_atomically(out, svg);
  std::cout << fmt::format("wrote {} ({} series, {} points)\n", out, series.size(),
                           csv.rows.size());
  return 0;
}

}  // namespace

Command add_sweep_command(CLI::App& app) {
  auto o = std::make_shared<SweepOptions>();
  auto* sweep = app.add_subcommand(
      "sweep",
      "Architecture studies: render a scene for every point of a grid of machine parameters "
      "(or print one pp5sim command per point), then aggregate the runs into a CSV and plot it");
  sweep->require_subcommand(0, 1);
  sweep->add_option("-g,--grid", o->grid,
                    "A swept parameter, KEY=V1,V2,... (repeatable; every combination runs), e.g. "
                    "--grid gp.count=1,2,4,8,16,32 --grid renderer.count=1,2,4,8,16");
  sweep
      ->add_option("-s,--scene", o->scene_name,
                   "Scene: a built-in name, a mesh file or a scene file")
      ->capture_default_str();
  sweep->add_option("-f,--firmware", o->firmware, firmware_help());
  add_config_options(*sweep, o->config_path, o->sets);
  add_fidelity_option(*sweep, o->sets);
  sweep->add_option("-o,--out", o->out_dir, "Folder for sweep.json and one folder per run")
      ->capture_default_str();
  sweep->add_flag("--print-commands", o->print_commands,
                  "Do not run: print one `pp5sim render` command per run, for GNU parallel "
                  "(`| parallel`) or a Slurm job array; then run `sweep aggregate`");
  sweep
      ->add_option("--slurm", o->slurm,
                   "Do not run: write FILE, a bash script that submits one Slurm job-array task "
                   "per run and `sweep aggregate --report` (OUT/sweep.csv, OUT/report.html) as a "
                   "job after them (afterok), and "
                   "OUT/commands.txt, the runs' commands (also for `parallel < OUT/commands.txt`)")
      ->excludes("--print-commands");
  sweep->add_option("-j,--threads", o->threads, "Host threads for each run's pixel arrays")
      ->check(CLI::Range(1, 256));
  sweep->add_option("--tessellation", o->tessellation, "Tessellation U V of the scene")
      ->expected(2);

  auto* aggregate =
      sweep->add_subcommand("aggregate", "Collect every run's stats.json under DIR into one CSV");
  aggregate->add_option("dir", o->aggregate_dir, "The sweep's output folder")->required();
  aggregate->add_option("-o,--out", o->csv_out, "CSV file [DIR/sweep.csv]");
  sweep
      ->add_flag("--report", o->report,
                 "After the runs, aggregate them into OUT/sweep.csv and write OUT/report.html "
                 "(as `sweep aggregate OUT --report`)")
      ->excludes("--print-commands")
      ->excludes("--slurm");
  aggregate->add_flag("--report", o->report,
                      "Also write DIR/report.html: one self-contained page that plots any "
                      "statistic of the runs against the swept keys, and the runs' table");

  auto* plot = sweep->add_subcommand(
      "plot", "Draw a metric of the CSV against a swept parameter, one line per value of another");
  plot->add_option("csv", o->plot_csv, "The CSV of `sweep aggregate`")->required();
  plot->add_option("-o,--out", o->plot_out, "SVG file [CSV with .svg]");
  plot->add_option("-x", o->plot_x, "Column on the x axis [the first swept parameter]");
  plot->add_option("--series", o->plot_series,
                   "Column whose values make the lines [the second swept parameter]");
  plot->add_option("-y", o->plot_y, "Column on the y axis")->capture_default_str();

  return {sweep, [o, aggregate, plot] {
            if (*aggregate) return run_aggregate(*o);
            if (*plot) return run_plot(*o);
            std::error_code ec;
            const fs::path self = fs::read_symlink("/proc/self/exe", ec);
            return run_sweep(*o, ec ? std::string("pp5sim") : self.string());
          }};
}

}  // namespace pp5
