// Helpers shared by the subcommands.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <thread>

#include "sim/app/commands.hpp"

namespace fs = std::filesystem;

namespace pp5 {

std::string resolve_firmware(const std::string& name) {
  if (fs::exists(name)) return name;
  const fs::path builtin = fs::path(PP5_SOURCE_DIR) / "firmware" / "programs" / (name + ".pp5");
  if (fs::exists(builtin)) return builtin.string();
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(builtin.parent_path())) {
    if (entry.path().extension() == ".pp5") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  throw std::runtime_error(fmt::format(
      "--firmware {}: no such file, and no built-in program of that name (built-in: {})", name,
      fmt::join(names, " ")));
}

std::string firmware_for(const std::string& option, const Scene& scene) {
  return resolve_firmware(!option.empty()           ? option
                          : !scene.firmware.empty() ? scene.firmware
                                                    : "phong");
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
