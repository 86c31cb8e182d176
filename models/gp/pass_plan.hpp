#pragma once
// The GP side's pass plan (FrameValues::plan, walked by models/renderer/region_stream.hpp):
// which passes a frame makes, the group of primitives each draws and the procedure its
// packets run, derived from the program and the scene.
//
// Contract:
//  - A program that defines `parity` gets the point-in-solid plan: pass 0 (opened by clear)
//    draws the primitives in no solid with their own procedures (the points, in the
//    z-buffer); then one pass per solid of the scene, opened by `pass`, in which only that
//    solid's triangles run `parity`. `pass` runs before each solid's pass, so a program folds
//    the previous solid's parity there and the last one in `shade`.
//  - Any other program gets no plan: its own `option passes`, every packet, its own procedure
//    (every existing program and golden).
//  - `parity` may use only expressions `triangle` uses (the packet is the triangle's):
//    check_pass_plan refuses a program that does otherwise, naming them.
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/display_list/scene.hpp"

namespace pp5 {

std::vector<PlannedPass> make_pass_plan(const Program& program, const Scene& scene);

// Throws std::runtime_error if the program's plan procedures need what its packets lack.
void check_pass_plan(const Program& program);

}  // namespace pp5
