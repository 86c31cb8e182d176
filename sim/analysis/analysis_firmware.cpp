#include "sim/analysis/analysis_firmware.hpp"

#include <fmt/format.h>

namespace pp5 {

std::string zbuffer_colour_firmware(const std::string& comment, int depth_bits,
                                    const std::string& depth, const std::string& colour) {
  return fmt::format(R"(; {comment}
field z      {bits}
field red     8
field green   8
field blue    8
output red green blue

proc clear
  eall
  mov z, {far}
  mov red, 0
  mov green, 0
  mov blue, 0
end

proc triangle
  eall
  qtest.ge edge0
  qtest.ge edge1
  qtest.ge edge2
  qcmp.lt z, {depth}
  qload z, {depth}
  qload red, {colour}_red
  qload green, {colour}_green
  qload blue, {colour}_blue
end
)",
                     fmt::arg("comment", comment), fmt::arg("bits", depth_bits),
                     fmt::arg("far", (1ull << depth_bits) - 1), fmt::arg("depth", depth),
                     fmt::arg("colour", colour));
}

std::string coverage_firmware(const std::string& comment, const std::vector<std::string>& tests) {
  std::string body;
  for (const std::string& t : tests) body += fmt::format("  qtest.ge {}\n", t);
  return fmt::format(R"(; {}
field count  8
field zero   8
output count zero zero

proc clear
  eall
  mov count, 0
  mov zero, 0
end

proc triangle
  eall
{}  add count, 1
end
)",
                     comment, body);
}

}  // namespace pp5
