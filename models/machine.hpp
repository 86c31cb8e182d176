#pragma once
// The whole Pixel-Planes 5 as a SystemC top level: Graphics Processors, the ring, the
// Renderer boards and the frame buffer, and what they share for one frame.
//
// A triangle's path: the host's display list (the Scene) is split into contiguous blocks,
// one per GP; each GraphicsProcessor transforms, clips, lights and sets up its triangles
// (models/gp/geometry.hpp), charging i860 clocks from the cost model (models/gp/i860.hpp),
// and bins the packets by region. Each Renderer claims regions (statically, region r to
// Renderer r mod count, or dynamically, the next unrendered region when it is nearly done
// with one) and opens one (region, pass) stage at a time for input; a GP sends its bin for a
// stage over the Ring once the stage is open, in messages no larger than the Renderer's
// instruction queue, stalling while the queue is full. The Renderer charges the firmware's
// cycles for each message as it arrives and ships the finished region over the ring to the
// FrameBuffer, from its backing store while it starts the next region.
//
// Protocol that keeps this deadlock-free: a Renderer opens its next stage only when every
// GP has sent its last message of the current one, so its queue never holds a message it
// cannot eventually consume.
//
// Units talk through the ring (models/ring/ring.hpp): each unit that receives messages is
// attached at its stop; region ownership and the bin senders live in the RegionScheduler.
// Machine builds and wires the units and holds what they share; it runs nothing itself.
//
// Timing and function are separated: no instruction's cost depends on pixel data, so the
// modules advance simulated time from the instruction table alone, and record each
// region's packets; after the simulation each Renderer's board executes its regions'
// instruction streams on its pixel array (execute_pixels, models/renderer/execute_pixels.hpp),
// in parallel across boards.
#include <atomic>
#include <functional>
#include <memory>
#include <systemc>
#include <vector>

#include "models/frame_buffer/image.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/protocol/frame_clock.hpp"
#include "models/protocol/packet.hpp"
#include "models/protocol/region_scheduler.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/protocol/timeline.hpp"
#include "models/protocol/unit_ports.hpp"

namespace pp5 {

class GraphicsProcessor;
class Renderer;
class Ring;
class FrameBuffer;
class SetupMemo;
class BoardObserver;
class PixelBoards;

class Machine : public sc_core::sc_module {
 public:
  Machine(sc_core::sc_module_name name, const MachineConfig& config, const Scene& scene,
          const Program& program);
  ~Machine() override;

  // What the units share, without SystemC (models/gp/machine_plan.hpp); the accessors below
  // forward to it.
  const MachinePlan& plan() const { return plan_; }
  // Each frame's plan (FramePlans): the plan above unless overlap() was given a source.
  FramePlans& frame_plans() { return plans_; }
  const MachineConfig& config() const { return plan_.config(); }
  const Program& program() const { return plan_.program(); }
  const Scene& scene() const { return plan_.scene(); }
  const GeometryEngine& geometry() const { return plan_.geometry(); }
  const TimingParams& timing() const { return plan_.timing(); }
  const FrameValues& frame_values() const { return plan_.frame_values(); }
  int passes() const { return plan_.passes(); }

  Ring& ring() { return *ring_; }
  FrameBuffer& frame_buffer() { return *frame_buffer_; }
  Renderer& renderer(int k) { return *renderers_[k]; }
  GraphicsProcessor& gp(int k) { return *gps_[k]; }
  int gp_count() const { return static_cast<int>(gps_.size()); }
  // GPs whose share of the display list is not empty: only these take part in the frame
  // (the others, when there are fewer triangles than GPs, do nothing and send nothing).
  int busy_gp_count() const { return plan_.busy_gp_count(); }
  int renderer_count() const { return static_cast<int>(renderers_.size()); }

  // Ring stops: GPs first, then Renderers, then the frame buffer.
  int gp_stop(int k) const { return plan_.gp_stop(k); }
  int renderer_stop(int k) const { return plan_.renderer_stop(k); }
  int frame_buffer_stop() const { return plan_.frame_buffer_stop(); }
  int ring_stops() const { return plan_.ring_stops(); }

  // Which Renderer renders which region, and which GPs send it packets.
  RegionScheduler& scheduler() { return scheduler_; }
  const RegionScheduler& scheduler() const { return scheduler_; }
  // The Renderers' ring stops, in Renderer order: where a bin map goes.
  const std::vector<int>& renderer_stops() const { return renderer_stops_; }
  std::uint64_t bin_map_words() const { return plan_.bin_map_words(); }
  const I860Model& i860() const { return plan_.i860(); }
  const GpWorkload& gp_workload() const { return plan_.gp_workload(); }

  // Frames in sequence (models/protocol/frame_clock.hpp): frame 0 runs when the kernel first
  // starts; begin_frame(n), between kernel runs, resets every unit and begins frame n at the
  // current simulated time, which the next kernel run then simulates.
  void begin_frame(int frame);
  // The scene of the frames from the next begin_frame on (MachinePlan::set_scene: the same
  // primitives, moved); between kernel runs. `scene` must outlive the machine or the next call.
  void set_scene(const Scene& scene) { plan_.set_scene(scene); }
  // When the current frame ends, in the run's time: its last region's arrival at the frame
  // buffer, which may lie after the units' last event (a region's trip is booked, not
  // waited for, when shipping overlaps). The host runs the kernel up to it before
  // begin_frame.
  sc_core::sc_time frame_end() const;
  const FrameClock& clock() const { return clock_; }
  // Frames overlapped (sim/simulation.hpp, Session::run_frames): before the kernel first
  // runs, releases `frames` frames that the units then run one after another on their own,
  // a GP setting up frame n + 1 while the Renderers still draw frame n (frames.gp_bins,
  // frames.gp_start); each unit keeps a record of every frame it finished
  // (GraphicsProcessor::history, Renderer::history). No begin_frame between them. With
  // `plans`, each frame works from the plan it makes (an animation: FramePlans), else from
  // plan().
  void overlap(int frames, FramePlans::Source plans = {});

  // The timeline: when on, modules record slices of activity.
  void record_timeline(bool on);
  bool timeline_on() const { return timeline_.on(); }
  Timeline& timeline() { return timeline_; }
  const std::vector<TimelineSlice>& slices() const { return timeline_.slices(); }
  std::uint64_t packet_words(const ExpressionSet& expressions) const {
    return plan_.packet_words(expressions);
  }
  std::uint64_t region_words() const { return plan_.region_words(); }
  void use_setup_memo(SetupMemo& memo) { plan_.use_setup_memo(memo); }
  SetupMemo* setup_memo() const { return plan_.setup_memo(); }

 private:
  static std::string fmt_name(const char* base, int k);

  MachinePlan plan_;
  FramePlans plans_{plan_};
  std::unique_ptr<Ring> ring_;
  std::unique_ptr<FrameBuffer> frame_buffer_;
  std::vector<std::unique_ptr<Renderer>> renderers_;
  std::vector<std::unique_ptr<GraphicsProcessor>> gps_;
  RegionScheduler scheduler_;
  std::vector<int> renderer_stops_;
  Timeline timeline_;
  FrameClock clock_{"frame_clock"};
  // What each unit sees of the others (models/protocol/unit_ports.hpp), filled as they are
  // made: the GPs see the Renderers' queues, the Renderers what the GPs report.
  std::vector<RendererQueue*> renderer_queues_;
  std::vector<const GpReport*> gp_reports_;
};

// The functional half of the frame: every Renderer's board executes the regions its timing
// pass recorded (models/renderer/execute_pixels.hpp).
void execute_pixels(Machine& machine, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe = {},
                    const std::atomic<bool>* cancel = nullptr, PixelBoards* boards = nullptr);

}  // namespace pp5
