#pragma once
// The SystemC kernel as the simulator uses it: a fresh kernel for every frame.

namespace pp5 {

// SystemC allows one elaboration per kernel; a new simulation context gives every frame a
// fresh kernel, so that one process can simulate many frames. The old context is left
// alive on purpose: objects of the previous run may still refer to it while they unwind.
// An untouched kernel is used as it is.
void fresh_kernel();

// sc_start() until no event is left.
void run_kernel();

}  // namespace pp5
