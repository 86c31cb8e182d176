#pragma once
// The conventional frame buffer: a ring stop that receives finished regions and assembles
// the frame. Timing arrives through the ring (receive_region); the pixel values, computed
// after the simulation, through store_region.
#include <systemc>
#include <utility>
#include <vector>

#include "models/frame_buffer/image.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

class Statistics;

class FrameBuffer : public sc_core::sc_module, public RingEndpoint {
 public:
  // A width x height screen in regions of region_width x region_height. `image` false: timing
  // only, no pixel arrives; the frame taken holds no pixels (as the analytic model's), and
  // store_region is refused.
  FrameBuffer(sc_core::sc_module_name name, int width, int height, int region_width,
              int region_height, int regions, bool image = true);

  // A region's pixels arrive over the ring (timing; the arrival may lie in the future of the
  // sender, whose ring interface sends while its array works on).
  void receive_region(const RegionArrival& region) override;
  // A region's pixel values (function), for the region whose top-left pixel is (x0, y0): kept
  // by reference (FrameImage), not copied. Distinct regions may arrive from several threads.
  void store_region(int x0, int y0, RegionPixels pixels);
  // The frame's own bytes for that region (FrameImage::own_bytes): a board writes a region's
  // pixels there, then store_region(x0, y0) stores them.
  std::uint8_t* region_bytes(int x0, int y0);
  void store_region(int x0, int y0);

  // Host side, between frames: a new frame begins at `start` (the times below are then
  // relative to it, except arrivals(), which keeps the run's time for the timeline), with
  // no region received and a new image (its bytes those of `storage`, an image done with,
  // where they can be: FrameImage's constructor).
  void begin_frame(sc_core::sc_time start, FrameImage storage = {});

  // Hands the assembled frame over; the frame buffer is empty afterwards.
  FrameImage take_image() { return std::move(image_); }
  // Simulated time at which the last region arrived: the frame time.
  sc_core::sc_time frame_complete() const { return last_ - start_; }
  int regions_received() const { return received_; }
  const std::vector<sc_core::sc_time>& arrivals() const { return arrival_; }
  // Registers frame.simulated_seconds (models/frame_buffer/frame_buffer_statistics.cpp).
  void register_statistics(Statistics& stats) const;

 private:
  int width_, height_, region_width_, region_height_;
  bool has_image_;
  sc_core::sc_time start_;
  FrameImage image_;
  std::vector<sc_core::sc_time> arrival_;
  sc_core::sc_time last_;
  int received_ = 0;
};

}  // namespace pp5
