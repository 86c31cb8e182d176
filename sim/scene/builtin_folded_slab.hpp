#pragma once
// The built-in scene "folded-slab" (make_builtin_scene): a closed slab whose front is folded
// into steep ridges just in front of its flat back, the provoking case of Rossignac's edge
// round-off. 1,696 triangles; fixed geometry; deterministic.
#include "sim/scene/scene.hpp"

namespace pp5 {

Scene make_folded_slab();

}  // namespace pp5
