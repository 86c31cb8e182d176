#pragma once
// A Renderer board as a SystemC module: the timing half. It claims regions, opens one
// (region, pass) stage at a time for input, charges the firmware's cycles for each message
// in its instruction queue as it arrives, and ships finished regions to the frame buffer.
// The functional half is RendererBoard (renderer_board.hpp), which executes the same
// streams on the pixel array; see models/machine.hpp for how the two meet.
//
// Contract:
//  - Busy cycles are exactly the instruction table's cycles (plus packet decoding and the
//    copy of finished colours to the backing store); time advances once per message or
//    procedure block, never per cycle.
//  - A triangle packet's coefficients move into the evaluator at
//    evaluator.coefficient_words_per_cycle; double-buffered (evaluator.double_buffered), the
//    next packet's load overlaps the current packet's execution and only a shortfall stalls.
//  - With renderer.backing_store_overlap, a bsst costs the array one issue cycle and then
//    occupies the backing-store port for its blocks; a bsld waits for the port, then for its
//    own transfer. Waiting for the port counts as a stall, not as busy.
//  - A (region, pass) stage waits for the bins of the GPs whose bin map names the region,
//    so a region no primitive touches costs clear, shade and shipping, and no message.
//  - Every wait is attributed, from the sending GP's activity: to the GPs (it was computing),
//    the ring (it was sending, or the message was crossing) or the Renderers (it was waiting
//    for another Renderer), so the frame time splits into GP, ring and Renderer time.
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <systemc>
#include <vector>

#include "common/units.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/protocol/frame_clock.hpp"
#include "models/protocol/region_scheduler.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/protocol/timeline.hpp"
#include "models/protocol/unit_ports.hpp"
#include "models/renderer/renderer_board.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

class Statistics;
class FrameBuffer;

// What one region ran, recorded by the timing pass for the functional one: the region's
// packets, kept in GP order, which is display-list order, whatever order their messages
// arrived in (no instruction's cost depends on pixel data, so the order changes the image only
// on depth ties, and this way it never changes with timing or load balancing). Its stream is
// RegionStream's over these packets.
struct RegionWork {
  int region = 0;
  int x0 = 0;
  int y0 = 0;
  std::vector<std::shared_ptr<const Packet>> triangles;  // the region's packets
  // Simulated array cycle at which the timing pass started each step (for traces): the steps
  // without a packet in stream order, and the packets pass-major (pass * packets + i).
  std::vector<std::uint64_t> step_start;
  std::vector<std::uint64_t> packet_start;
  // The Renderer's busy cycles (RendererStats::busy) from the region's clear to its copy out:
  // over a Renderer's regions they sum to its busy cycles.
  std::uint64_t busy_cycles = 0;
};

struct RendererStats {
  ArrayCycles busy{};   // cycles executing micro-instructions, decoding packets, copying out
  ArrayCycles stall{};  // cycles waiting for the backing-store port
  // Idle, waiting for a message, while the GP that sent it was computing (waiting_gp), or was
  // sending earlier messages or this one was crossing the ring (waiting_ring), or the GP was
  // itself waiting for other Renderers' queues or stages (waiting_renderers).
  sc_core::sc_time waiting_gp;
  sc_core::sc_time waiting_ring;
  sc_core::sc_time waiting_renderers;
  sc_core::sc_time waiting_ship;  // blocked shipping a region (no overlapped shipping)
  // Of the waits above, those before its first message of the frame (the bin maps, the first
  // bin): in a run of frames, how long it stood idle between frames.
  sc_core::sc_time waiting_first;
  std::uint64_t regions = 0;
  std::uint64_t packets = 0;
  std::uint64_t messages = 0;
  std::uint64_t instructions = 0;  // micro-instructions issued to the array
  std::uint64_t queue_peak_words = 0;
  sc_core::sc_time computed;  // when its array finished its last region
  sc_core::sc_time finished;  // when its last region reached the frame buffer
};

// What a Renderer is wired to (the Machine builds it): the plan it works from, the ring it
// ships regions on, the scheduler that gives it regions and says who sends them, what each
// GP reports of its activity in GP order (a vector the Machine fills once every GP exists),
// the timeline and the frame clock.
struct RendererWiring {
  const MachinePlan& plan;
  FramePlans& plans;  // each frame's plan (its frame values and passes)
  Ring& ring;
  RegionScheduler& scheduler;
  const std::vector<const GpReport*>& gps;
  Timeline& timeline;
  FrameClock& clock;
};

class Renderer : public sc_core::sc_module, public RingEndpoint, public RendererQueue {
 public:
  SC_HAS_PROCESS(Renderer);
  Renderer(sc_core::sc_module_name name, int index, const RendererWiring& wiring);

  // The (region, pass) stage open for input as pass * regions + region, or -1 when none is
  // (the region is always one this Renderer claimed); then room in its queue.
  int open_stage(int regions) const override {
    return open_region_ < 0 ? -1 : open_pass_ * regions + open_region_;
  }
  int open_frame() const override { return frame_; }
  bool has_room(std::uint64_t words) const override { return queued_words_ + words <= capacity_; }
  // A GP takes room for its next message (after has_room), before it starts sending.
  void reserve_room(std::uint64_t words) override;
  // Through the ring: a GP's message has been booked; it is in the queue from its arrival on.
  void receive_bin(std::shared_ptr<const BinMessage> message) override;
  // Through the ring: a GP's bin map has been booked (RegionScheduler::bin_senders has its
  // regions).
  void receive_bin_map(const BinMapArrival& map) override;

  // Host side, between frames: forgets the last frame (its statistics, its regions, its
  // queue's and array's state) before the frame clock begins the next (Machine::begin_frame).
  void reset_frame();

  const RendererStats& stats() const { return stats_; }
  // Overlapped frames (FrameClock::overlapped): every frame it has finished, in order.
  struct FrameRecord {
    int frame = 0;
    sc_core::sc_time began;  // when it took the frame's first region, in the run's time
    RendererStats stats;     // computed and finished relative to `began`
    std::vector<RegionWork> work;
  };
  // Each record is final once it is there; a streaming run hands it over and releases it.
  const std::vector<FrameRecord>& history() const { return history_; }
  // Overlapped frames: hands over the record of `frame`, which must be the oldest it keeps,
  // and forgets it (its regions' packets go with it). Between kernel runs.
  FrameRecord release_frame(int frame);
  // Registers renderer.INDEX.* (models/renderer/renderer_statistics.cpp); read once the frame
  // has run.
  void register_statistics(Statistics& stats, double frame_seconds) const;
  const std::vector<RegionWork>& work() const { return work_; }
  // The functional model: runs this board's regions on its pixel array; with `executes`,
  // only the regions it accepts (the others leave the frame buffer as it was).
  void execute(RendererBoard& board, const Program& program, FrameBuffer& frame_buffer,
               const FrameValues& frame_values,
               const std::function<bool(const RegionWork&)>& executes = {}) const;

 private:
  struct Stage {
    int region;
    int pass;
  };
  void run();
  void run_frame();
  void run_overlapped();
  void open_next_stage();
  // Opens the next stage if the open one has all its input: every GP's bin map and the last
  // message of every GP that has packets for it. A stage nobody has packets for is complete
  // as soon as the maps are in, but the next opens only once the Renderer starts on it, so
  // a run of empty regions is not all claimed at once.
  void advance();
  bool maps_complete() const { return maps_delivered_[frame_ & 1] == plan_.busy_gp_count(); }
  // Empties the bin-map slot of `frame` (frame & 1) for frame + 2.
  void forget_maps(int frame, sc_core::sc_time base);
  // Waits until every bin map has arrived; the wait is the GPs' (before the last map was
  // asked for) and the ring's (after).
  void wait_for_bin_maps();
  // Adds one procedure's time at the array's cursor. A region-wide step (clear, pass, light,
  // shade) binds values that are the same in every region (the frame's, or a light's): its
  // cycles are summed once per frame and reused, unless it moves blocks through the
  // backing-store port, whose timing depends on the port's state.
  void charge(const ProcedureCode& procedure, const PacketValues& values, bool region_wide = false);
  // Loads a packet's coefficients into the evaluator before it runs.
  void load_coefficients(const Packet& packet, sc_core::sc_time arrival);
  // Advances simulated time to the cursor (one kernel event).
  void catch_up();
  void ship(int region);

  struct RegionWideCost {
    const ProcedureCode* code;
    const QuadraticCoefficients *expressions_begin, *expressions_end;
    const ParameterValues* parameters;
    ArrayCycles cycles;  // the procedure's, packet overhead included
  };
  std::vector<RegionWideCost> region_wide_costs_;

  int index_;
  RendererWiring wiring_;
  int clock_slot_ = 0;  // FrameClock::enrol
  const MachinePlan& plan_;
  sc_core::sc_time cycle_;
  std::uint64_t capacity_;
  int open_region_ = -1;
  int open_pass_ = -1;
  int lasts_delivered_ = 0;
  bool open_started_ = false;  // processing of the open stage has begun
  int frame_ = 0;              // the frame it is on
  // Per frame & 1: a GP on frame n + 1 may send its bin map while this Renderer is on n.
  int maps_delivered_[2] = {0, 0};
  sc_core::sc_time maps_requested_[2];  // the last GP's
  sc_core::sc_time maps_arrival_[2];    // the last map's
  sc_core::sc_event maps_complete_;
  std::deque<Stage> stages_;  // opened, not yet processed
  std::vector<std::shared_ptr<const BinMessage>> queue_;
  std::uint64_t queued_words_ = 0;
  sc_core::sc_event arrived_;
  sc_core::sc_time cursor_;             // the array's time within a block
  sc_core::sc_time port_free_;          // the backing-store port's
  sc_core::sc_time ship_free_;          // the ring interface's, for outgoing regions
  sc_core::sc_time coefficients_free_;  // the evaluator's spare coefficient registers
  RendererStats stats_;
  std::vector<RegionWork> work_;
  std::vector<FrameRecord> history_;
};

// Runs `work` (one board's regions, in order) on `board` and stores each region's colours in
// the frame buffer: Renderer::execute with its recorded work, and the analytic model's
// (models/renderer/analytic.hpp) with its own. `executes` as for Renderer::execute.
void execute_regions(const std::vector<RegionWork>& work, RendererBoard& board,
                     const Program& program, FrameBuffer& frame_buffer, const FrameValues& values,
                     const std::function<bool(const RegionWork&)>& executes = {});

// Registers renderers_total.* (sums over `renderers`) and primitives_per_region.R for each of
// the `regions` screen regions.
void register_renderer_totals(Statistics& stats, std::vector<const Renderer*> renderers,
                              int regions);
// The same from each Renderer's statistics and regions (one frame's records of an overlapped
// run), which must outlive the reads.
void register_renderer_totals(Statistics& stats, std::vector<const RendererStats*> renderers,
                              std::vector<const std::vector<RegionWork>*> works, int regions);
// Registers renderer.INDEX.* from `st` (Renderer::register_statistics, or one frame's record);
// `st` must outlive the reads.
void register_renderer_statistics(Statistics& stats, int index, const RendererStats& st,
                                  double array_hz, double frame_seconds);

}  // namespace pp5
