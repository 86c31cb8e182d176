#pragma once
// The subcommands of pp5sim. Each lives in its own file, sim/app/cmd_NAME.cpp, and is added to
// the program by one line in main.cpp: add_NAME_command registers its options on the CLI11 app
// and returns the function that runs it once the command line has been parsed.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "models/config/machine_config.hpp"
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
Command add_trace_command(CLI::App& app);
Command add_highlight_command(CLI::App& app);
Command add_extremes_command(CLI::App& app);
Command add_spheres_command(CLI::App& app);

// Shared by the commands.

// A firmware argument: a path (it has a '/' or ends in .pp5) names a file; a bare name names a
// built-in program, never a file of that name in the current directory. The built-in
// programs are found beside the executable (PREFIX/bin/pp5sim reads
// PREFIX/share/pp5sim/programs, wherever PREFIX was moved), else in the source tree the
// binary was built from. Throws with the list of built-in names if there is no such program.
std::string resolve_firmware(const std::string& name);
bool names_a_file(const std::string& firmware);
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

// Markdown table cells must not contain a bare '|'.
std::string markdown_cell(const std::string& text);

// A sensible default for --threads: the host's hardware threads.
int default_threads();

}  // namespace pp5
