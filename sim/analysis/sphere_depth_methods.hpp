#pragma once
// The sphere depth methods `pp5sim spheres` sets beside the quadric (phong.pp5's
// `sphere_depth`): each a firmware program with a `sphere` procedure that draws the sphere's
// depth its own way, and the same triangles, lights and shading as phong.pp5.
//  - sphere_pp4.pp5: Pixel-Planes 4's paraboloid (`sphere_depth_paraboloid`).
//  - sphere_sqrt.pp5: the exact depth, the square root taken bit-serially in pixel memory
//    (`sphere_depth_base`, `sphere_radicand`, `sphere_root_shift`).
// Which primitive each pixel shows is read from the same program with its `light` and `shade`
// procedures taken out, so that the output holds the unlit colours the `triangle` and
// `sphere` procedures load, z-buffered on the program's own depth code.
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"

namespace pp5 {

struct SphereDepthMethod {
  const char* label;     // the table's row
  const char* firmware;  // a shipped program's name (firmware/programs/NAME.pp5)
};
const std::vector<SphereDepthMethod>& sphere_depth_methods();

// `source` (a program's text) without its `light` and `shade` procedures; throws
// std::invalid_argument naming `name` if it has no `sphere` procedure or a procedure is not
// closed.
std::string unshaded_source(const std::string& source, const std::string& name);

// The program file at `path`, assembled without its light and shade (see above).
Program unshaded_program(const std::string& path, const MachineConfig& config);

}  // namespace pp5
