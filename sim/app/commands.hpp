#pragma once
// The subcommands of pp5sim. Each lives in its own file, sim/app/cmd_NAME.cpp, and is added to
// the program by one line in main.cpp: add_NAME_command registers its options on the CLI11 app
// and returns the function that runs it once the command line has been parsed.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "models/config/machine_config.hpp"
#include "sim/output/output_set.hpp"
#include "sim/output/report.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

struct Command {
  CLI::App* app = nullptr;   // the subcommand, to test whether it was given
  std::function<int()> run;  // its action; returns the exit status
};

Command add_render_command(CLI::App& app);
Command add_isa_command(CLI::App& app);
Command add_asm_command(CLI::App& app);
Command add_config_command(CLI::App& app);
Command add_stats_command(CLI::App& app);
Command add_scenes_command(CLI::App& app);
Command add_sweep_command(CLI::App& app);
// The metrics of one run as sweep.csv's columns, after the swept keys: (column, statistic).
const std::vector<std::pair<std::string, std::string>>& sweep_metric_columns();
// Checks one swept key's values as pp5sim sweep does: each set alone on `base` (the
// configuration every point starts from), none empty, none twice. Throws
// std::invalid_argument "WHERE: ..." (WHERE names the axis as the caller was given it) whose
// text names the key: the sweep command's messages, and the Python module's.
void check_sweep_axis(const std::string& where, const std::string& key,
                      const std::vector<std::string>& values, const MachineConfig& base);
Command add_trace_command(CLI::App& app);
Command add_highlight_command(CLI::App& app);
Command add_extremes_command(CLI::App& app);
Command add_validate_command(CLI::App& app);
Command add_visible_command(CLI::App& app);
Command add_fidelity_command(CLI::App& app);
Command add_scanconvert_command(CLI::App& app);
Command add_csg_command(CLI::App& app);
Command add_spheres_command(CLI::App& app);
Command add_animate_command(CLI::App& app);

// Shared by the commands.

// A firmware argument: a path (it has a '/' or ends in .pp5) names a file; a bare name names a
// built-in program, never a file of that name in the current directory. The built-in
// programs are found beside the executable (PREFIX/bin/pp5sim reads
// PREFIX/share/pp5sim/programs, wherever PREFIX was moved), else in the source tree the
// binary was built from. Throws with the list of built-in names if there is no such program.
std::string resolve_firmware(const std::string& name);
bool names_a_file(const std::string& firmware);
// A folder searched first for the built-in programs: the Python module's installed programs
// (its executable is python3, from whose folder the programs are not found).
void set_builtin_programs_dir(const std::string& dir);
// The built-in programs' names, sorted (empty if none are found).
std::vector<std::string> builtin_program_names();
// The --firmware option's help: how a name is resolved, and the built-in names.
std::string firmware_help();
// The program a command runs on `scene`: --firmware when given (`option` not empty), else the
// scene file's "firmware", else phong; resolved as resolve_firmware does.
std::string firmware_for(const std::string& option, const Scene& scene);

// The defaults, or a JSON file, then the --set KEY=VALUE overrides.
MachineConfig load_config(const std::string& path, const std::vector<std::string>& sets);

// The usual --config, --set and --param options, bound to `path` and `sets`: each --set
// KEY=VALUE is appended to `sets`, and each --param NAME=VALUE as frame.NAME=VALUE (the
// shorthand for a frame parameter), --set ones first.
void add_config_options(CLI::App& command, std::string& path, std::vector<std::string>& sets);

// --fidelity SPEC: comma-separated levels and KEY=VALUE items, turned into --set assignments
// of the fidelity.* keys in order (a later item wins). Throws std::invalid_argument naming
// the item for anything else.
inline constexpr const char* kFidelityHelp =
    "bit (the default: bit-serial pixels, event timing), word (pixels a whole field at a "
    "time, bit-identical), timing (no pixels, event timing), analytic (no pixels, closed-form "
    "timing), or items pixels=bit|word|none, timing=event|analytic, window=COLUMNSxROWS+X+Y "
    "(regions whose pixels execute) or window=all, separated by commas, e.g. "
    "pixels=word,window=2x2+4+3";
std::vector<std::string> fidelity_assignments(const std::string& spec);
// Adds --fidelity SPEC to a command, appending its assignments to `sets`; add it after
// add_config_options so that it applies after --set.
void add_fidelity_option(CLI::App& command, std::vector<std::string>& sets);

// Traces, snapshots and anything else that reads per-bit-cycle state need the most detailed
// level: for any other, prints an error naming `what` and the level, and returns true (the
// caller then exits with status 2).
bool refuse_below_bit_level(const MachineConfig& config, const std::string& what);
// The same check's message (without "pp5sim: error: "), or empty at the bit level.
std::string below_bit_level(const MachineConfig& config, const std::string& what);

// One word for a POSIX shell (a generated script, a line of commands.txt): returned as it is
// when it holds only [A-Za-z0-9._-/=,+], else in single quotes (a quote inside as '\''). A
// string with a control character (a newline above all, which would end a comment of the
// script or split a line of commands.txt) is refused with an error naming `what`.
std::string shell_quote(const std::string& s, const std::string& what);
// A path as a literal in an sbatch --output/--error file-name pattern: '%' doubled.
std::string slurm_pattern_literal(const std::string& s);

// An analysis's report files (sim/output/report.hpp), beside its Markdown: each table of `r`
// as DIR/ID.csv (the table's id; not the tables marked csv_file = false), and when `html`
// DIR/report.html, one self-contained page.
// Added to `outputs`, so they are written with the analysis's other files, or none of them.
void add_report_outputs(OutputSet& outputs, const std::string& dir, const report::Report& r,
                        bool html);
// The --report flag of an analysis that writes into the folder `out_help` names.
void add_report_flag(CLI::App& command, bool& report, const std::string& out_help);

// A sensible default for --threads: the host's hardware threads.
int default_threads();

}  // namespace pp5
