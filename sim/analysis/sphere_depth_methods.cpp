#include "sim/analysis/sphere_depth_methods.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "models/gp/machine_plan.hpp"
#include "sim/simulation.hpp"

namespace pp5 {

const std::vector<SphereDepthMethod>& sphere_depth_methods() {
  static const std::vector<SphereDepthMethod> methods = {
      {"paraboloid (Pixel-Planes 4)", "sphere_pp4"},
      {"square root in pixel memory", "sphere_sqrt"},
  };
  return methods;
}

std::string unshaded_source(const std::string& source, const std::string& name) {
  std::istringstream in(source);
  std::string line, out;
  bool skipping = false, open = false, sphere = false;
  int number = 0, opened = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line.substr(0, line.find_first_of(";#")));
    std::string first, second;
    words >> first >> second;
    if (first == "proc") {
      if (open)
        throw std::invalid_argument(
            fmt::format("{}:{}: 'proc {}' inside the procedure opened at line {}", name, number,
                        second, opened));
      open = true;
      opened = number;
      skipping = second == "light" || second == "shade";
      sphere = sphere || second == "sphere";
    }
    if (!skipping) out += line + "\n";
    if (first == "end") {
      open = false;
      skipping = false;
    }
  }
  if (open)
    throw std::invalid_argument(fmt::format("{}:{}: the procedure has no 'end'", name, opened));
  if (!sphere) throw std::invalid_argument(fmt::format("{}: no 'proc sphere'", name));
  return out;
}

Program unshaded_program(const std::string& path, const MachineConfig& config) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot open the program", path));
  std::ostringstream text;
  text << in.rdbuf();
  return assemble(unshaded_source(text.str(), path), path + " (unshaded)",
                  assembler_options(config));
}

}  // namespace pp5
