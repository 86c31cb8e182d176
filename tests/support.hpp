#pragma once
// Helpers shared by the test files.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "common/statistics.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"

namespace pp5::test {

// The folder of the built-in firmware programs, with its trailing slash.
inline const std::string kProgramsDir = PP5_SOURCE_DIR "/firmware/programs/";

// A built-in firmware program, assembled for `config`.
inline Program load_program(const std::string& name, const MachineConfig& config) {
  return assemble_file(kProgramsDir + name + ".pp5", assembler_options(config));
}

// A count statistic (an integer that cannot be negative), for comparing with unsigned counts.
inline std::uint64_t count(const Statistics& stats, const std::string& name) {
  const std::int64_t v = stats.integer(name);
  if (v < 0) throw std::out_of_range("statistic '" + name + "' is negative");
  return static_cast<std::uint64_t>(v);
}

// Frame statistics without the host's wall-clock figures, which differ from run to run.
inline nlohmann::json without_host(nlohmann::json stats) {
  stats.erase("host");
  return stats;
}

}  // namespace pp5::test
