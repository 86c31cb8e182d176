// Helpers shared by the subcommands.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "common/escape.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/report_html.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// Where the built-in programs are, in the order searched: beside the executable as installed
// (bin/pp5sim finds ../share/pp5sim/programs, through /proc/self/exe, so a moved installation
// still works), then the source tree the binary was built from (the build tree's pp5sim).
std::string& extra_programs_dir() {
  static std::string dir;
  return dir;
}

std::vector<fs::path> program_dirs() {
  std::vector<fs::path> dirs;
  if (!extra_programs_dir().empty()) dirs.push_back(extra_programs_dir());
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error) dirs.push_back((exe.parent_path() / PP5_PROGRAMS_FROM_BIN).lexically_normal());
  dirs.push_back(fs::path(PP5_SOURCE_DIR) / "firmware" / "programs");
  return dirs;
}

std::optional<fs::path> builtin_programs_dir() {
  for (const fs::path& dir : program_dirs()) {
    std::error_code error;
    if (fs::is_directory(dir, error)) return dir;
  }
  return std::nullopt;
}

}  // namespace

void set_builtin_programs_dir(const std::string& dir) { extra_programs_dir() = dir; }

bool names_a_file(const std::string& firmware) {
  return firmware.find('/') != std::string::npos ||
         (firmware.size() >= 4 && firmware.compare(firmware.size() - 4, 4, ".pp5") == 0);
}

std::vector<std::string> builtin_program_names() {
  std::vector<std::string> names;
  if (const auto dir = builtin_programs_dir()) {
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(*dir, error)) {
      if (entry.path().extension() == ".pp5") names.push_back(entry.path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string resolve_firmware(const std::string& name) {
  if (names_a_file(name)) {
    // Whether it is a file the assembler may read (not a FIFO, a device or a folder) is the
    // reader's to say (common/read_file.hpp), with what it found.
    std::error_code error;
    if (!fs::exists(name, error)) {
      throw std::runtime_error(fmt::format("--firmware {}: no such file", name));
    }
    return name;
  }
  // A bare name is a built-in program, never a file of that name in the current directory.
  const auto dir = builtin_programs_dir();
  if (!dir) {
    std::vector<std::string> searched;
    for (const fs::path& d : program_dirs()) searched.push_back(d.string());
    throw std::runtime_error(
        fmt::format("--firmware {}: the built-in programs are not installed (looked in {})", name,
                    fmt::join(searched, " and ")));
  }
  const fs::path builtin = *dir / (name + ".pp5");
  std::error_code error;
  if (fs::is_regular_file(builtin, error)) return builtin.string();
  throw std::runtime_error(fmt::format(
      "--firmware {}: no built-in program of that name (built-in: {}); a file is named by a path "
      "with a '/' or ending in .pp5, e.g. ./{}.pp5",
      name, fmt::join(builtin_program_names(), " "), name));
}

std::string firmware_for(const std::string& option, const Scene& scene) {
  return resolve_firmware(!option.empty()           ? option
                          : !scene.firmware.empty() ? scene.firmware
                                                    : "phong");
}

std::string firmware_help() {
  return fmt::format(
      "Firmware program: a bare name is a built-in program ({}), never a file of that name in "
      "the current directory; a path (with a '/' or ending in .pp5) is a file [the scene file's "
      "\"firmware\", else phong]",
      fmt::join(builtin_program_names(), ", "));
}

MachineConfig load_config(const std::string& path, const std::vector<std::string>& sets) {
  MachineConfig config = path.empty() ? MachineConfig::defaults() : MachineConfig::from_file(path);
  config.set(sets);
  return config;
}

void add_config_options(CLI::App& command, std::string& path, std::vector<std::string>& sets) {
  command.add_option("-c,--config", path,
                     "Machine configuration (JSON); unspecified keys take their defaults");
  // Both append, in the order CLI11 runs option callbacks (the order they are added here).
  auto append = [&sets](const std::string& prefix) {
    return [&sets, prefix](const std::vector<std::string>& items) {
      for (const std::string& item : items) sets.push_back(prefix + item);
    };
  };
  command.add_option_function<std::vector<std::string>>(
      "--set", append(""),
      "Override one parameter, KEY=VALUE (repeatable), e.g. --set renderer.count=8 or --set "
      "frame.threshold=8192 (pp5sim config --describe lists the keys)");
  // CLI11 runs every --set before every --param, whatever their order on the command line:
  // a frame parameter given by both would take --param's value even where --set came last.
  // So giving one key both ways is an error that names it.
  auto append_params = [&sets](const std::vector<std::string>& items) {
    for (const std::string& item : items) {
      const std::string key = "frame." + item.substr(0, item.find('='));
      for (const std::string& s : sets) {
        if (s.substr(0, s.find('=')) == key) {
          throw CLI::ValidationError(fmt::format(
              "--param {}: {} is also given by --set {}; give a frame parameter once (--param "
              "NAME=VALUE is short for --set frame.NAME=VALUE)",
              escape_for_message(item), escape_for_message(key), escape_for_message(s)));
        }
      }
      sets.push_back("frame." + item);
    }
  };
  command.add_option_function<std::vector<std::string>>(
      "--param", append_params,
      "Set a frame parameter, NAME=VALUE (repeatable): short for --set frame.NAME=VALUE, e.g. "
      "--param highlight_opacity=128 (pp5sim isa lists them)");
}

std::vector<std::string> fidelity_assignments(const std::string& spec) {
  std::vector<std::string> sets;
  auto bad = [&](const std::string& what) {
    return std::invalid_argument(fmt::format("--fidelity {}: {} ({})", spec, what, kFidelityHelp));
  };
  std::size_t start = 0;
  while (start <= spec.size()) {
    const std::size_t comma = std::min(spec.find(',', start), spec.size());
    const std::string item = spec.substr(start, comma - start);
    start = comma + 1;
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      if (item == "bit" || item == "word") {
        sets.push_back("fidelity.pixels=" + item);
        sets.push_back("fidelity.timing=event");
      } else if (item == "timing") {
        sets.push_back("fidelity.pixels=none");
        sets.push_back("fidelity.timing=event");
      } else if (item == "analytic") {
        sets.push_back("fidelity.pixels=none");
        sets.push_back("fidelity.timing=analytic");
      } else {
        throw bad(fmt::format("'{}' is not a level", item));
      }
      continue;
    }
    const std::string key = item.substr(0, eq);
    const std::string value = item.substr(eq + 1);
    if (key == "pixels" || key == "timing") {
      // The configuration checks the value against the key's choices, naming both.
      sets.push_back("fidelity." + key + "=" + value);
    } else if (key == "window") {
      if (value == "all") {
        for (const char* k : {"x", "y", "columns", "rows"}) {
          sets.push_back(fmt::format("fidelity.window_{}=0", k));
        }
        continue;
      }
      // COLUMNSxROWS+X+Y, in regions (the X11 geometry form).
      int columns = 0, rows = 0, x = 0, y = 0;
      char sep1 = 0, sep2 = 0, sep3 = 0;
      std::istringstream in(value);
      if (!(in >> columns >> sep1 >> rows >> sep2 >> x >> sep3 >> y) || sep1 != 'x' ||
          sep2 != '+' || sep3 != '+' || in.peek() != std::char_traits<char>::eof() || columns < 1 ||
          rows < 1 || x < 0 || y < 0) {
        throw bad(
            fmt::format("window '{}' is not COLUMNSxROWS+X+Y in regions, e.g. 2x2+0+0", value));
      }
      sets.push_back(fmt::format("fidelity.window_x={}", x));
      sets.push_back(fmt::format("fidelity.window_y={}", y));
      sets.push_back(fmt::format("fidelity.window_columns={}", columns));
      sets.push_back(fmt::format("fidelity.window_rows={}", rows));
    } else {
      throw bad(fmt::format("unknown key '{}'", key));
    }
  }
  return sets;
}

void add_fidelity_option(CLI::App& command, std::vector<std::string>& sets) {
  command.add_option_function<std::string>(
      "--fidelity",
      [&sets](const std::string& spec) {
        try {
          for (std::string& s : fidelity_assignments(spec)) sets.push_back(std::move(s));
        } catch (const std::invalid_argument& e) {
          throw CLI::ValidationError(e.what());
        }
      },
      std::string("How much of the machine to simulate (docs/concepts/fidelity.md): ") +
          kFidelityHelp + ". Applied after --set.");
}

std::string below_bit_level(const MachineConfig& config, const std::string& what) {
  using F = MachineConfig::Fidelity;
  const F& f = config.fidelity;
  const bool whole =
      f.window_x == 0 && f.window_y == 0 && f.window_columns == 0 && f.window_rows == 0;
  if (f.pixels == F::Pixels::bit && f.timing == F::Timing::event && whole) return "";
  return fmt::format(
      "{} needs per-bit state, which only fidelity.pixels=bit with "
      "fidelity.timing=event and every region executing has; this run asks for pixels={}, "
      "timing={}{} (drop --fidelity, or use --fidelity bit,window=all)",
      what, name_of(f.pixels), name_of(f.timing), whole ? "" : " and a window of regions");
}

bool refuse_below_bit_level(const MachineConfig& config, const std::string& what) {
  const std::string message = below_bit_level(config, what);
  if (message.empty()) return false;
  std::cerr << "pp5sim: error: " << message << "\n";
  return true;
}

std::string shell_quote(const std::string& s, const std::string& what) {
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7F) {
      throw std::runtime_error(fmt::format(
          "{} '{}': holds a control character ({}), which cannot be written into a shell script "
          "or a list of one command per line; choose a name without one",
          what, escape_for_message(s),
          c == '\n' ? "a newline" : fmt::format("byte 0x{:02x}", static_cast<unsigned>(c))));
    }
  }
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789._-/=,+") == std::string::npos) {
    return s;
  }
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string slurm_pattern_literal(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '%' ? std::string("%%") : std::string(1, c);
  return out;
}

void add_report_outputs(OutputSet& outputs, const std::string& dir, const report::Report& r,
                        bool html) {
  const std::filesystem::path folder(dir);
  for (const report::Section& section : r.sections) {
    for (const report::Block& block : section.blocks) {
      if (const auto* table = std::get_if<report::Table>(&block)) {
        if (!table->csv_file) continue;
        if (table->id.empty()) throw std::logic_error("add_report_outputs: a table without an id");
        outputs.add((folder / (table->id + ".csv")).string(), report::csv(*table));
      }
    }
  }
  if (html) outputs.add((folder / "report.html").string(), report::html(r));
}

void add_report_flag(CLI::App& command, bool& report, const std::string& out_help) {
  command.add_flag("--report", report,
                   "Also write " + out_help +
                       "/report.html: one self-contained page with the tables (sortable, "
                       "searchable, each column's unit and meaning in its tooltip) and images");
}

int default_threads() {
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// The metrics of one run as sweep.csv's columns: (column, statistic), in its order.
const std::vector<std::pair<std::string, std::string>>& sweep_metric_columns() {
  static const std::vector<std::pair<std::string, std::string>> columns = {
      {"frame_seconds", "frame.simulated_seconds"},
      {"triangles_per_second", "frame.projected_triangles_per_second"},
      {"pipelined_triangles_per_second", "frame.pipelined_triangles_per_second"},
      {"gp_clocks_per_triangle", "frame.gp_clocks_per_triangle"},
      {"bottleneck", "timing.bottleneck"},
      {"gp_seconds", "timing.gp_seconds"},
      {"ring_seconds", "timing.ring_seconds"},
      {"renderer_seconds", "timing.renderer_seconds"},
      {"gp_utilisation", "timing.gp_utilisation_mean"},
      {"ring_utilisation", "timing.ring_utilisation"},
      {"renderer_utilisation", "timing.renderer_utilisation_mean"},
  };
  return columns;
}

void check_sweep_axis(const std::string& where, const std::string& key,
                      const std::vector<std::string>& values, const MachineConfig& base) {
  std::set<std::string> given;
  for (const std::string& v : values) {
    if (v.empty()) throw std::invalid_argument(fmt::format("{}: empty value", where));
    // Two equal values would be two runs of one point (into one folder, for the command).
    if (!given.insert(v).second) {
      throw std::invalid_argument(
          fmt::format("{}: value '{}' is given twice for '{}'", where, v, key));
    }
    // Each value must be valid on its own: the error names the key.
    MachineConfig probe = base;
    try {
      probe.set(key + "=" + v);
    } catch (const ConfigError& e) {
      throw std::invalid_argument(fmt::format("{}: {}", where, e.what()));
    }
  }
}

}  // namespace pp5
