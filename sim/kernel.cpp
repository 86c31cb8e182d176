#include "sim/kernel.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <systemc>
#include <vector>

namespace pp5 {

namespace {
void quiet_systemc() { setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0); }
}  // namespace

namespace {
// The contexts alive, oldest first: when one goes, the newest left becomes current.
std::vector<sc_core::sc_simcontext*>& live_contexts() {
  static std::vector<sc_core::sc_simcontext*> live;
  return live;
}
}  // namespace

KernelContext::KernelContext() : context_(nullptr) {
  quiet_systemc();
  context_ = new sc_core::sc_simcontext();
  live_contexts().push_back(context_);
  make_current();
}

KernelContext::~KernelContext() {
  const bool was_current = sc_core::sc_curr_simcontext == context_;
  auto& live = live_contexts();
  live.erase(std::remove(live.begin(), live.end(), context_), live.end());
  delete context_;
  if (was_current || sc_core::sc_curr_simcontext == nullptr) {
    // Another context still alive becomes current; with none, the next use of SystemC makes a
    // new default context (sc_get_curr_simcontext).
    sc_core::sc_curr_simcontext = live.empty() ? nullptr : live.back();
    sc_core::sc_default_global_context = sc_core::sc_curr_simcontext;
  }
}

void KernelContext::make_current() {
  sc_core::sc_curr_simcontext = context_;
  sc_core::sc_default_global_context = context_;
}

void KernelContext::run() {
  make_current();
  sc_core::sc_start();
}

bool KernelContext::run(const std::atomic<bool>* cancel) {
  if (cancel == nullptr) {
    run();
    return true;
  }
  return run(cancel, {});
}

bool KernelContext::run(const std::atomic<bool>* cancel, const std::function<bool()>& done) {
  make_current();
  using clock = std::chrono::steady_clock;
  // Slices start at a simulated microsecond and double (to a simulated millisecond) while one
  // takes under 2 ms of host time, halving above 20 ms: few sc_start calls, and a cancel seen
  // within some ms.
  if (slice_ == sc_core::SC_ZERO_TIME) slice_ = sc_core::sc_time(1, sc_core::SC_US);
  // A context not started yet has no pending activity before its initialisation: run it and
  // the first delta cycle.
  if (sc_core::sc_get_status() == sc_core::SC_ELABORATION) sc_core::sc_start(sc_core::SC_ZERO_TIME);
  for (;;) {
    // sc_stop (a unit's error) ends the run as it ends sc_start().
    if (!sc_core::sc_pending_activity() || sc_core::sc_get_status() == sc_core::SC_STOPPED)
      return true;
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return false;
    if (done && done()) return true;
    // To the next event and a slice beyond it (SC_EXIT_ON_STARVATION does not move time past
    // the last event it ran, as sc_start() does not).
    const sc_core::sc_time left = sc_core::sc_max_time() - sc_core::sc_time_stamp();
    const sc_core::sc_time next = sc_core::sc_time_to_pending_activity();
    const auto t0 = clock::now();
    sc_core::sc_start(left - next > slice_ ? next + slice_ : left, sc_core::SC_EXIT_ON_STARVATION);
    const auto host = clock::now() - t0;
    if (host < std::chrono::milliseconds(2) && slice_ < sc_core::sc_time(1, sc_core::SC_MS))
      slice_ = slice_ * 2.0;
    else if (host > std::chrono::milliseconds(20) && slice_ > sc_core::sc_time(1, sc_core::SC_NS))
      slice_ = slice_ / 2.0;
  }
}

void KernelContext::run_until(sc_core::sc_time t) {
  make_current();
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
