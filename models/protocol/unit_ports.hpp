#pragma once
// What a GP and a Renderer know of each other, and nothing more: the GP sees a Renderer's
// input queue (RendererQueue), the Renderer sees what a sending GP was doing (GpReport), so
// that it can say whose its wait was. Both reach each other's messages only through the ring
// (models/ring/ring.hpp) and share region ownership through the RegionScheduler
// (region_scheduler.hpp). The Machine (models/machine.hpp) wires the implementations.
//
// Contract:
//  - RendererQueue: open_stage(regions) is the (region, pass) stage open for input as
//    pass * regions + region, or -1; open_frame() the frame that stage belongs to (frames
//    overlap: a GP on frame n must not send to a Renderer already on n + 1); has_room(words) says
//    whether a message of `words` fits the queue now; reserve_room(words) takes that room before
//    the message is sent (the GP calls it after has_room, at the same instant). The ring delivers
//    the message itself.
//  - GpReport: activity(from, to) splits [from, to) of simulated time into what the GP was
//    doing: computing, sending on the ring, or waiting for a Renderer (or done).
#include <cstdint>
#include <systemc>

namespace pp5 {

class RendererQueue {
 public:
  virtual ~RendererQueue() = default;
  virtual int open_stage(int regions) const = 0;
  virtual int open_frame() const = 0;
  virtual bool has_room(std::uint64_t words) const = 0;
  virtual void reserve_room(std::uint64_t words) = 0;
};

// What a GP is doing: computing, sending on the ring, or waiting for a Renderer (its queue
// full, or no stage open for the GP's remaining bins).
enum class GpActivity { compute, ring, renderer, done };

// Time spent in each activity over an interval, in seconds.
struct GpActivityTimes {
  double compute = 0;
  double ring = 0;
  double renderer = 0;
};

class GpReport {
 public:
  virtual ~GpReport() = default;
  virtual GpActivityTimes activity(sc_core::sc_time from, sc_core::sc_time to) const = 0;
};

}  // namespace pp5
