#pragma once
// The SystemC kernel as the simulator uses it: one simulation context per run, which runs
// frame after frame and is freed when the run ends.

#include <atomic>
#include <systemc>

namespace pp5 {

// A simulation context of its own, made current on construction and deleted on
// destruction. SystemC allows one elaboration per context, and a context may run
// (sc_start) any number of times: a run of many frames elaborates its machine once and runs
// the kernel once per frame. Everything elaborated in the context (modules, spawned
// processes, events) must be destroyed before it: declare the KernelContext before them.
// Several may live at once (a session beside a one-frame run, two Python sessions); one runs
// at a time per process (SystemC's current context is a global).
class KernelContext {
 public:
  KernelContext();
  ~KernelContext();
  KernelContext(const KernelContext&) = delete;
  KernelContext& operator=(const KernelContext&) = delete;
  // sc_start() until no event is left; may be called again after more events are notified.
  void run();
  // The same run, in slices of simulated time with `cancel` checked between them: returns
  // false, with events still pending, once it is true (the caller then frees the context's
  // modules, which hold a run half done), else true. The events run in the same order as
  // run()'s, so the results are run()'s; a slice is sized to take some milliseconds of host
  // time, so a cancel is seen within about that.
  bool run(const std::atomic<bool>* cancel);
  // Advances simulated time to `t` (running whatever events lie before it); nothing if `t` is
  // not later than now.
  void run_until(sc_core::sc_time t);
  // Makes this context SystemC's current one again (several may live at once: a session
  // beside a one-frame run, or two Python sessions); run() and run_until() do so themselves.
  void make_current();

 private:
  sc_core::sc_simcontext* context_;
};

// For tests that build modules without an owner of the context: a fresh context made current
// (the previous one, if it was used, is left alive: objects of an earlier test may still
// refer to it). A run of the simulator uses KernelContext.
void fresh_kernel();

// sc_start() until no event is left.
void run_kernel();

}  // namespace pp5
