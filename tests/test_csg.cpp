// Parity and depth-interval applications (issue 15): the pass plan that draws one solid per
// pass, point in solid by parity against a double-precision ray caster.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/pass_plan.hpp"
#include "models/machine.hpp"
#include "models/renderer/region_stream.hpp"

using namespace pp5;

namespace {

const char* kParitySource = R"(
field z 24
field par 1
field inside 1
field red 8
field green 8
field blue 8
output red green blue
proc clear
  eall
  mov z, 0xFFFFFF
  mov par, 0
  mov inside, 0
end
proc triangle
  eall
  qtest.ge edge0
  qcmp.lt z, depth
  qload z, depth
end
proc parity
  eall
  qtest.ge edge0
  qcmp.gt z, depth
  xor par, 1
end
proc pass
  eall
  or inside, par
  mov par, 0
end
)";

}  // namespace

TEST_CASE("a pass plan draws each solid in its own pass with the plan's procedure", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  const Program program = assemble(kParitySource, "plan", assembler_options(config));
  Scene scene;
  scene.solids = {{"a", 2, 4}, {"b", 4, 5}};
  CHECK(scene.solid_of_triangle(0) == -1);
  CHECK(scene.solid_of_triangle(3) == 0);
  CHECK(scene.solid_of_triangle(4) == 1);
  CHECK(scene.solid_of_triangle(5) == -1);
  FrameValues values;
  values.plan = make_pass_plan(program, scene);
  REQUIRE(values.plan.size() == 3);
  std::vector<Packet> packets(5);
  for (int i = 0; i < 5; ++i) {
    packets[static_cast<std::size_t>(i)].primitive = i;
    packets[static_cast<std::size_t>(i)].group = i < 2 ? -1 : i < 4 ? 0 : 1;
  }
  const RegionStream stream(program, values);
  CHECK(stream.passes() == 3);
  std::vector<std::string> ran;
  stream.for_each(packets, [&](const RegionStep& step) {
    if (!step.code.defined) return;
    std::string s = kProcedureNames[static_cast<int>(step.procedure)];
    if (step.packet) s += std::to_string(step.packet->primitive);
    ran.push_back(s);
  });
  const std::vector<std::string> expected = {"clear",   "triangle0", "triangle1", "pass",
                                             "parity2", "parity3",   "pass",      "parity4"};
  CHECK(ran == expected);

  // Without `parity`, no plan: the program's own passes, every packet its own procedure.
  const Program plain = assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/flat.pp5",
                                      assembler_options(config));
  CHECK(make_pass_plan(plain, scene).empty());
}

TEST_CASE("parity may use only what the triangle's packets carry", "[csg]") {
  const MachineConfig config = MachineConfig::defaults();
  std::string source = kParitySource;
  source.replace(source.find("qtest.ge edge0\n  qcmp.gt"), 14, "qtest.ge edge1");
  const Program program = assemble(source, "bad-parity", assembler_options(config));
  CHECK_THROWS_WITH(check_pass_plan(program), Catch::Contains("'parity' uses expression 'edge1'") &&
                                                  Catch::Contains("bad-parity"));
}
