#pragma once
// Frames in sequence on one SystemC context: which frame the units are on and when it began.
// A persistent simulation (sim/simulation.hpp, Session) runs the kernel once per frame; the
// units' threads do frame 0 as soon as the kernel starts, and each later frame when the host
// begins it (Machine::begin_frame), at the simulated time the previous frame ended.
//
// Contract:
//  - frame() and start() are the current frame and its start; every time a unit reports
//    (its statistics, the frame time) is relative to start(), so frame n of a scene reports
//    what a fresh run of that frame reports. Timeline slices and ring messages keep the
//    run's absolute time, so that frames line up one after another.
//  - A unit enrols once, as it is made (enrol() gives its slot), and waits on started(slot)
//    between frames. begin(n) is called by the host between kernel runs, after every unit
//    has been reset; one delta later the clock wakes the units in the order they enrolled,
//    at the same simulated time: the order in which the kernel first starts them (creation
//    order), so that a later frame runs its units in frame 0's order (a Renderer claims its
//    first region dynamically in that order, for one).
#include <deque>
#include <systemc>

namespace pp5 {

class FrameClock : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(FrameClock);
  explicit FrameClock(sc_core::sc_module_name name) : sc_module(name) { SC_THREAD(dispatch); }

  int frame() const { return frame_; }
  sc_core::sc_time start() const { return start_; }
  int enrol() {
    units_.emplace_back();
    return static_cast<int>(units_.size()) - 1;
  }
  const sc_core::sc_event& started(int slot) const {
    return units_[static_cast<std::size_t>(slot)];
  }
  void begin(int frame) {
    frame_ = frame;
    start_ = sc_core::sc_time_stamp();
    begun_.notify(sc_core::SC_ZERO_TIME);
  }

  // Overlapped frames (Machine::overlap): the units run frame after frame on their own, each
  // on the frame it has reached, with no host between frames. released() frames exist (the
  // host releases them before the kernel runs); renderers_finished() is the number of frames
  // every Renderer has finished (the GPs may set up frame n + 1 only once it is n: two frames
  // at most are in flight, so a unit's per-frame state needs two slots, frame & 1). progress()
  // is notified when either changes.
  void set_overlapped(bool on) { overlapped_ = on; }
  bool overlapped() const { return overlapped_; }
  void release(int frames) {
    released_ = frames;
    progress_.notify(sc_core::SC_ZERO_TIME);
  }
  int released() const { return released_; }
  void enrol_renderer() { finished_.push_back(0); }
  void renderer_finished(int renderer) {
    ++finished_[static_cast<std::size_t>(renderer)];
    progress_.notify(sc_core::SC_ZERO_TIME);
  }
  int renderers_finished() const {
    int least = -1;
    for (const int f : finished_) least = least < 0 ? f : (f < least ? f : least);
    return least < 0 ? 0 : least;
  }
  const sc_core::sc_event& progress() const { return progress_; }

 private:
  // Wakes the units one by one, in enrolment order: an immediate notification makes the
  // waiting thread runnable at the back of the kernel's queue.
  void dispatch() {
    for (;;) {
      wait(begun_);
      for (sc_core::sc_event& e : units_) e.notify();
    }
  }

  int frame_ = 0;
  bool overlapped_ = false;
  int released_ = 0;
  std::deque<int> finished_;
  sc_core::sc_event progress_;
  sc_core::sc_time start_;
  sc_core::sc_event begun_;
  std::deque<sc_core::sc_event> units_;
};

}  // namespace pp5
