#pragma once
// The timeline of a run: slices of activity the units record when it is on (written as
// Chrome trace events by sim/simulation.cpp). Each unit holds a reference to the one the
// Machine owns; a unit that records nothing pays one test of `on()`.
#include <string>
#include <systemc>
#include <utility>
#include <vector>

namespace pp5 {

enum class Unit { gp, ring, renderer, frame_buffer };

struct TimelineSlice {
  Unit unit;
  int index;  // GP, ring channel, Renderer
  std::string name;
  sc_core::sc_time start;
  sc_core::sc_time end;
  int frame = 0;  // the frame of the run the slice belongs to
};

class Timeline {
 public:
  void record(bool on) { on_ = on; }
  bool on() const { return on_; }
  // The frame later slices belong to (a session sets it as each frame starts).
  void set_frame(int frame) { frame_ = frame; }
  void add(Unit unit, int index, std::string name, sc_core::sc_time start, sc_core::sc_time end) {
    if (on_) slices_.push_back({unit, index, std::move(name), start, end, frame_});
  }
  const std::vector<TimelineSlice>& slices() const { return slices_; }
  void clear() { slices_.clear(); }

 private:
  bool on_ = false;
  int frame_ = 0;
  std::vector<TimelineSlice> slices_;
};

}  // namespace pp5
