// Helpers shared by the subcommands.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <thread>

#include "sim/app/commands.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// Where the built-in programs are, in the order searched: beside the executable as installed
// (bin/pp5sim finds ../share/pp5sim/programs, through /proc/self/exe, so a moved installation
// still works), then the source tree the binary was built from (the build tree's pp5sim).
std::vector<fs::path> program_dirs() {
  std::vector<fs::path> dirs;
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
  command.add_option_function<std::vector<std::string>>(
      "--param", append("frame."),
      "Set a frame parameter, NAME=VALUE (repeatable): short for --set frame.NAME=VALUE, e.g. "
      "--param highlight_opacity=128 (pp5sim isa lists them)");
}

std::string markdown_cell(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

int default_threads() {
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace pp5
