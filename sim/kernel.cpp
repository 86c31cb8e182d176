#include "sim/kernel.hpp"

#include <cstdlib>
#include <systemc>

namespace pp5 {

void fresh_kernel() {
  setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0);
  if (sc_core::sc_get_status() == sc_core::SC_ELABORATION && sc_core::sc_delta_count() == 0 &&
      sc_core::sc_get_top_level_objects().empty()) {
    return;
  }
  sc_core::sc_curr_simcontext = new sc_core::sc_simcontext();
  sc_core::sc_default_global_context = sc_core::sc_curr_simcontext;
}

void run_kernel() { sc_core::sc_start(); }

}  // namespace pp5
