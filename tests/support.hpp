#pragma once
// Helpers shared by the test files.
#include <nlohmann/json.hpp>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"

namespace pp5::test {

// A built-in firmware program, assembled for `config`.
inline Program load_program(const std::string& name, const MachineConfig& config) {
  return assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/" + name + ".pp5",
                       assembler_options(config));
}

// Frame statistics without the host's wall-clock figures, which differ from run to run.
inline nlohmann::json without_host(nlohmann::json stats) {
  stats.erase("host");
  return stats;
}

}  // namespace pp5::test
