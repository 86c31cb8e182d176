#pragma once
// A Graphics Processor (Intel i860) as a SystemC module: transforms, clips, lights and sets
// up its share of the display list, bins the packets by region, then sends each region's
// bin over the ring to the Renderer that claims the region. The arithmetic is
// GeometryEngine's; the time is the i860 cost model's (models/gp/i860.hpp), in i860 clocks.
//
// Contract: geometry for the whole share first (one kernel event), then bins in the order
// (pass, region) as their Renderers open them (with frames.gp_send=when_full, a bin's full
// messages go while the geometry goes on, its last message and the bin map after it); a
// bin travels in messages no larger than the
// Renderer's queue, and the GP stalls while the queue has no room or the stage is not open.
// With a multipass program, gp.multipass says where later passes' packets come from: the
// bins kept from the first traversal (resend), or a new traversal of the whole share per
// pass, charged like the first and done when the GP has nothing it can send (retraverse).
#include <functional>
#include <memory>
#include <systemc>
#include <vector>

#include "common/units.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/gp/region_bins.hpp"
#include "models/protocol/frame_clock.hpp"
#include "models/protocol/region_scheduler.hpp"
#include "models/protocol/timeline.hpp"
#include "models/protocol/unit_ports.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

class Statistics;

struct GpStats {
  GpClocks busy{};                     // clocks computing (geometry and starting messages)
  GpClocks geometry{};                 // of which transform, clip, light, set-up, binning
  OpCounts ops;                        // the i860 operations of the geometry
  sc_core::sc_time waiting_stage;      // waiting for a Renderer to open a stage
  sc_core::sc_time waiting_queue;      // waiting for room in a Renderer's queue
  sc_core::sc_time waiting_ring;       // waiting for its ring interface to send
  sc_core::sc_time waiting_start;      // overlapped: waiting until it may start the frame
  std::uint64_t triangles_in = 0;      // scene triangles it transformed
  std::uint64_t packets = 0;           // triangle packets it sent (one per region touched)
  std::uint64_t messages = 0;          // ring messages it sent
  std::uint64_t ring_words = 0;        // words of those messages
  std::uint64_t screen_triangles = 0;  // triangles after clipping that reached set-up
  SetupCounts setup;
  // Painter's depth sort (Scene::depth_sort), run before the geometry: its clocks (prepare,
  // merge, checks; in busy too), its ring messages and words (in messages and ring_words
  // too), and when its last phase ended (relative to the frame's start; zero without a sort).
  GpClocks sort{};
  std::uint64_t sort_messages = 0;
  std::uint64_t sort_words = 0;
  sc_core::sc_time sort_done;
  sc_core::sc_time geometry_started;  // in the run's time
  sc_core::sc_time geometry_done;
  sc_core::sc_time finished;  // relative to the frame's start; overlapped, the run's time
};

// One frame of an overlapped run, as a GP did it (GraphicsProcessor::history).
struct GpFrameRecord {
  int frame = 0;
  GpStats stats;  // times in the run's time
};

// What a GP is wired to (the Machine builds it): the plan it works from and each frame's
// (the scene's: FramePlans), the ring it sends on, the scheduler that says who owns a region, each
// Renderer's queue in Renderer order (a vector the Machine fills once every Renderer exists), the
// timeline and the frame clock.
struct GpWiring {
  const MachinePlan& plan;
  FramePlans& plans;
  Ring& ring;
  RegionScheduler& scheduler;
  const std::vector<RendererQueue*>& renderers;
  Timeline& timeline;
  FrameClock& clock;
};

class GraphicsProcessor : public sc_core::sc_module, public GpReport, public RingEndpoint {
 public:
  SC_HAS_PROCESS(GraphicsProcessor);
  GraphicsProcessor(sc_core::sc_module_name name, int index, int first, int last,
                    const GpWiring& wiring);

  const GpStats& stats() const { return stats_; }
  // Host side, between frames: forgets the last frame (its statistics and activity) before
  // the frame clock begins the next (Machine::begin_frame).
  void reset_frame();
  // Registers gp.INDEX.* (models/gp/gp_statistics.cpp); read once the frame has run.
  void register_statistics(Statistics& stats, double frame_seconds) const;
  // How the GP spent [from, to): so that a Renderer's wait for this GP can be attributed.
  GpActivityTimes activity(sc_core::sc_time from, sc_core::sc_time to) const override;
  // Overlapped frames (FrameClock::overlapped): every frame it has finished sending, in order.
  // Each record is final once it is there; a streaming run hands it over and releases it.
  const std::vector<GpFrameRecord>& history() const { return history_; }
  // Overlapped frames: hands over the record of `frame`, which must be the oldest it keeps,
  // and forgets it, with its activity before `before` (a time from which on no Renderer asks
  // about it: every Renderer is past the frame). Between kernel runs; a frame's record kept
  // until then.
  GpFrameRecord release_frame(int frame, sc_core::sc_time before);
  bool takes_part() const { return first_ != last_; }
  // The depth sort's messages from other GPs (the Machine attaches the GP at its stop).
  void receive_sort(const SortArrival& message) override;

 private:
  // Painter's (Scene::depth_sort): this GP's part of the sort of `frame`, in simulated time:
  // its phases spent as clocks, its runs, order and records sent and awaited as ring
  // messages (DepthSortWork's steps), each phase a timeline slice.
  void depth_sort_phase(const DepthSortWork& work, int frame);
  // Waits until `count` sort messages of `kind` for `frame` have fully arrived.
  void await_sort(SortArrival::Kind kind, int frame, int count);
  void send_sort(const std::vector<int>& to_gps, SortArrival::Kind kind, std::uint64_t words,
                 int frame);
  void run();
  void run_frame();
  void run_overlapped();
  bool may_start(int frame) const;
  // frames.gp_send=when_full: the set-up of the frame being sent, going on while its full
  // messages go out; its time is spent piece by piece in send_bins.
  struct Growing {
    const std::vector<std::uint64_t>* done_after = nullptr;  // geometry_pass's, per primitive
    sc_core::sc_time spent;                                  // of its geometry time
    sc_core::sc_time total;
    bool done() const { return !(spent < total); }
  };
  // The geometry phase of `frame` into `bins`, adding to `stats`: one kernel event. With
  // `growing` (frames.gp_send=when_full) no time passes: send_bins spends it.
  void geometry(RegionBins& bins, GpStats& stats, int frame, Growing* growing = nullptr);
  // The next frame's set-up, done ahead while this frame's bins go out (frames.gp_bins=2).
  struct Ahead {
    bool possible = false;
    int frame = 0;
    RegionBins* bins = nullptr;
    bool started = false;
    bool done = false;
    sc_core::sc_time remaining;  // of its geometry time
  };
  void start_ahead(Ahead& ahead);
  // After a piece of the ahead set-up's time that began at t0.
  void finish_ahead_piece(Ahead& ahead, sc_core::sc_time t0);
  // Sends `bins` of `frame` (bin map first) as Renderers open its stages; with `ahead`, does
  // the next frame's set-up whenever nothing can be sent.
  // With `growing`, a bin's message goes as soon as it is full and its packets are set up,
  // and the bin map once the set-up is done.
  void send_bins(const RegionBins& bins, int frame, Ahead* ahead, Growing* growing = nullptr);
  bool sends_when_full() const;
  void spend(GpClocks clocks);
  void send(std::shared_ptr<BinMessage> message, int frame);
  // Tells every Renderer which regions this GP has packets for (RegionScheduler::add_bin_senders),
  // in one message around the ring.
  void send_bin_map(int frame);
  void begin(GpActivity a);
  RendererQueue& queue(int renderer) const {
    return *wiring_.renderers[static_cast<std::size_t>(renderer)];
  }

  int index_;
  int first_;  // display-list range [first_, last_)
  int last_;
  GpWiring wiring_;
  int clock_slot_ = 0;  // FrameClock::enrol
  const MachinePlan& plan_;
  std::vector<int> renderer_stops_;  // where the bin map goes
  sc_core::sc_time clock_;
  GpStats stats_;
  GpStats ahead_;  // overlapped: the next frame's, set up ahead
  // Overlapped: the two bin buffers. Members, not locals of run_overlapped: an SC_THREAD that
  // never returns is not unwound when the simulation ends, so its locals would never be freed.
  RegionBins overlap_bins_[2];
  // frames.gp_send=when_full: geometry_pass's clocks per primitive, per bin buffer.
  std::vector<std::uint64_t> done_after_[2];
  int frame_ = 0;  // overlapped: the frame it is sending
  std::vector<GpFrameRecord> history_;
  std::vector<SortArrival> sort_in_;  // sort messages received, not yet consumed
  sc_core::sc_event sort_arrived_;
  // When each activity began, in time order.
  std::vector<std::pair<sc_core::sc_time, GpActivity>> activity_{
      {sc_core::SC_ZERO_TIME, GpActivity::compute}};
};

// What the cost model charges for one primitive of `kind`: the plan's workload with the
// expressions of the kind's procedure and its packet's words.
GpWorkload kind_workload(const MachinePlan& plan, const PrimitiveKind& kind);
// The i860 operations of one primitive of `kind` with `tally`, and their clocks: they depend
// on nothing else (PrimitiveKind's contract).
struct PrimitiveCost {
  OpCounts ops;
  GpClocks clocks{};
};
PrimitiveCost primitive_cost(const MachinePlan& plan, const PrimitiveKind& kind,
                             const GpWorkload& workload, const PrimitiveTally& tally);

// A GP's geometry phase as plain C++ (no simulated time): transforms, clips, sets up and
// bins the display-list range [first, last), adding its operations, i860 geometry clocks,
// packets and set-up counts to `stats` and leaving a bin per region it has packets for in
// `*bins`, each in display-list order (no bins when `bins` is null: the analytic timing model fills
// the plan's set-up memo and reads the bins from its summary). GraphicsProcessor::run and the
// analytic timing model (models/renderer/analytic.hpp) both use it, so both see the same
// packets and clocks. With `done_after`, it leaves there, for each primitive of the range in
// order, the geometry clocks spent from the range's start to the end of that primitive (when
// its packets are ready: frames.gp_send=when_full). It stops short once the plan is cancelled
// (MachinePlan::set_cancel).
void geometry_pass(const MachinePlan& machine, int first, int last, GpStats& stats,
                   RegionBins* bins, std::vector<std::uint64_t>* done_after = nullptr);

// The parts fill_setup_memo splits the display list into: one per thread, each of
// `least_part` primitives at least. On the development machine (a virtual machine) a
// thread's first touch of fresh memory cost more than the set-up it took over below about
// 100,000 primitives (a torus of 131,072 triangles broke even, one of 524,288 took 0.45 s
// less on 2 threads): hence the default.
constexpr int kLeastSetupPart = 65536;
int setup_parts(const MachinePlan& plan, int threads, int least_part = kLeastSetupPart);
// Fills the plan's set-up memo, if it has one and it holds nothing yet, by geometry_pass over
// the whole display list, in setup_parts() contiguous parts on up to `threads` host threads:
// the records are the same with any number (each primitive's set-up depends on nothing
// else), and the GPs of the frame then replay them. Host speed only.
void fill_setup_memo(const MachinePlan& plan, int threads, int least_part = kLeastSetupPart);

// Registers gp.INDEX.* from `g` (GraphicsProcessor::register_statistics, or one frame's record
// of an overlapped run); `g` must outlive the reads.
void register_gp_statistics(Statistics& stats, int index, const GpStats& g, double clock_hz,
                            double frame_seconds);

// Registers setup.*: the packets and the set-up counts summed over `gps`.
void register_setup_statistics(Statistics& stats, std::vector<const GraphicsProcessor*> gps);
// The same from the GPs' statistics (the analytic model has no GraphicsProcessor modules).
void register_setup_statistics(Statistics& stats, std::vector<const GpStats*> gps);

}  // namespace pp5
