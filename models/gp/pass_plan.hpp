#pragma once
// The GP side's pass plan (FrameValues::plan and FrameValues::closing, walked by
// models/protocol/region_stream.hpp): which passes a frame makes, the procedures that open
// each, the group of primitives each draws, which of their faces, and the procedure its
// packets run, derived from the program and the scene.
//
// Contract:
//  - A program that defines `parity` gets the point-in-solid plan: pass 0 (opened by clear)
//    draws the primitives in no solid with their own procedures (the points, in the
//    z-buffer); then one pass per solid of the scene, opened by `pass`, in which only that
//    solid's triangles run `parity`. `pass` runs before each solid's pass, so a program folds
//    the previous solid's parity there and the last one in `shade`.
//  - A program that defines `surface`, on a scene with a CSG expression (Scene::csg, a sum of
//    products), gets the CSG plan (Goldfeather, Molnar, Turk and Fuchs): if the scene has
//    primitives in no solid, pass 0 (clear) draws them with their own procedures; then for
//    each product, for each literal L of it:
//      a surface pass: L's solid's front faces (back faces for a complemented literal) run
//      `surface`, opened by `candidate` (and by clear if it is the frame's first pass);
//      for each other literal M of the product, a classification pass: M's solid's faces,
//      all of them, run `parity`;
//    each classification is folded, before the next pass or after the last, by `keep_inside`
//    (M positive) or `keep_outside` (M complemented), and each literal's candidate by
//    `merge`, after the last fold. The last literal's folds and merge are the closing
//    procedures. A program that also defines `next_layer` peels: in a product of two or more
//    literals each literal's surface and classification passes repeat `layers` times (the
//    frame parameter, from the FrameValues; 1 if they hold none), the repeats opened by
//    `next_layer` instead of `candidate`, so that its k-th nearest surface is a candidate in
//    round k. On a scene without a CSG expression such a program gets no plan.
//  - Goldfeather's geometric pruning comes first (when Scene::prune_csg): with each solid's
//    bounding box (its triangles' vertices and its spheres, in world space), a product whose
//    positive literals' boxes have an empty intersection is dropped (it is empty), and a
//    complemented literal whose box misses that intersection is dropped from its product
//    (subtracting it removes nothing). Boxes that touch are kept. A product with no positive
//    literal is kept whole. The pixels drawn are the same; passes are saved.
//  - Any other program gets no plan: its own `option passes`, every packet, its own procedure
//    (every existing program and golden).
//  - `parity` and `surface` may use only expressions `triangle` uses (the packet is the
//    triangle's): check_pass_plan refuses a program that does otherwise, naming them.
//  - A quadric sphere of a solid is two packets (near hemisphere: front face; far: back
//    face) and runs planned_procedure's counterpart, sphere_surface or sphere_parity, which
//    may use only expressions `sphere` uses; set_pass_plan throws std::runtime_error, naming
//    the procedure and the solid, if the scene's solids have spheres and the program lacks
//    the counterpart of a procedure its plan runs.
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/display_list/scene.hpp"

namespace pp5 {

// The plan's passes (with no frame parameters: one layer).
std::vector<PlannedPass> make_pass_plan(const Program& program, const Scene& scene);

// The plan's passes and its closing procedures, into `values` (whose frame parameters give
// `layers`).
void set_pass_plan(const Program& program, const Scene& scene, FrameValues& values);

// The scene's expression after Goldfeather's pruning (the scene's own if !prune_csg), and the
// passes the pruning saves for `program` on `scene` (0 for a program without a CSG plan).
CsgProducts pruned_csg(const Scene& scene);
int pruned_passes(const Program& program, const Scene& scene);

// Throws std::runtime_error if the program's plan procedures need what its packets lack.
void check_pass_plan(const Program& program);

}  // namespace pp5
