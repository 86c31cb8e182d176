#pragma once
// The SystemC kernel as the simulator uses it: one simulation context per run, which runs
// frame after frame and is freed when the run ends.

#include <atomic>
#include <functional>
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
  // The same slices (with `cancel` checked between them, when given), until `done()` holds,
  // checked between slices as well: returns false once cancelled, else true, once `done()`
  // holds or no event is left (the caller tells which). The kernel may have run a slice
  // beyond the moment `done()` became true; stopping between slices changes nothing of what
  // the units do (run()'s events in run()'s order), so a run of many calls gives run()'s
  // results.
  bool run(const std::atomic<bool>* cancel, const std::function<bool()>& done);
  // Advances simulated time to `t` (running whatever events lie before it); nothing if `t` is
  // not later than now.
  void run_until(sc_core::sc_time t);
  // Makes this context SystemC's current one again (several may live at once: a session
  // beside a one-frame run, or two Python sessions); run() and run_until() do so themselves.
  void make_current();

 private:
  sc_core::sc_simcontext* context_;
  sc_core::sc_time slice_;  // run()'s slice of simulated time, kept from call to call
};

// For tests that build modules without an owner of the context: a fresh context made current
// (the previous one, if it was used, is left alive: objects of an earlier test may still
// refer to it). A run of the simulator uses KernelContext.
void fresh_kernel();

// sc_start() until no event is left.
void run_kernel();

}  // namespace pp5
