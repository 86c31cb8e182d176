#include "sim/kernel.hpp"

#include <cstdlib>
#include <systemc>

namespace pp5 {

namespace {
void quiet_systemc() { setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0); }
}  // namespace

KernelContext::KernelContext() {
  quiet_systemc();
  sc_core::sc_curr_simcontext = new sc_core::sc_simcontext();
  sc_core::sc_default_global_context = sc_core::sc_curr_simcontext;
}

KernelContext::~KernelContext() {
  delete sc_core::sc_curr_simcontext;
  // The next use of SystemC makes a new default context (sc_get_curr_simcontext).
  sc_core::sc_curr_simcontext = nullptr;
  sc_core::sc_default_global_context = nullptr;
}

void KernelContext::run() { sc_core::sc_start(); }

void KernelContext::run_until(sc_core::sc_time t) {
  if (t > sc_core::sc_time_stamp()) sc_core::sc_start(t - sc_core::sc_time_stamp());
}

void fresh_kernel() {
  quiet_systemc();
  if (sc_core::sc_get_status() == sc_core::SC_ELABORATION && sc_core::sc_delta_count() == 0 &&
      sc_core::sc_get_top_level_objects().empty()) {
    return;
  }
  sc_core::sc_curr_simcontext = new sc_core::sc_simcontext();
  sc_core::sc_default_global_context = sc_core::sc_curr_simcontext;
}

void run_kernel() { sc_core::sc_start(); }

}  // namespace pp5
