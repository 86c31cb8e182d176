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
#include <memory>
#include <systemc>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/display_list/scene.hpp"
#include "models/frame_buffer/image.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"
#include "models/renderer/packet.hpp"
#include "models/renderer/region_scheduler.hpp"
#include "models/renderer/region_stream.hpp"

namespace pp5 {

class GraphicsProcessor;
class Renderer;
class Ring;
class FrameBuffer;
class SetupMemo;

// One slice of activity for the timeline (Chrome trace-event format, see simulation.cpp).
enum class Unit { gp, ring, renderer, frame_buffer };
struct TimelineSlice {
  Unit unit;
  int index;  // GP, ring channel, Renderer
  std::string name;
  sc_core::sc_time start;
  sc_core::sc_time end;
};

// The machine configuration seen by each plain-C++ part.
GeometryParams geometry_params(const MachineConfig& config);
TimingParams timing_params(const MachineConfig& config);
I860Params i860_params(const MachineConfig& config);
struct RendererBoardParams;
class BoardObserver;
RendererBoardParams board_params(const MachineConfig& config);
AssemblerOptions assembler_options(const MachineConfig& config);

class Machine : public sc_core::sc_module {
 public:
  Machine(sc_core::sc_module_name name, const MachineConfig& config, const Scene& scene,
          const Program& program);
  ~Machine() override;

  const MachineConfig& config() const { return config_; }
  const Program& program() const { return program_; }
  const Scene& scene() const { return scene_; }
  const GeometryEngine& geometry() const { return geometry_; }
  const TimingParams& timing() const { return timing_; }
  // The values of clear, pass and shade, and of each light's `light` procedure; a packet
  // binds frame.parameters when it runs (RegionStream); it never carries them.
  const FrameValues& frame_values() const { return frame_values_; }
  // Times the GPs send each region's triangles this frame (Program::pass_count).
  int passes() const { return RegionStream::pass_count(program_, frame_values_); }

  Ring& ring() { return *ring_; }
  FrameBuffer& frame_buffer() { return *frame_buffer_; }
  Renderer& renderer(int k) { return *renderers_[k]; }
  GraphicsProcessor& gp(int k) { return *gps_[k]; }
  int gp_count() const { return static_cast<int>(gps_.size()); }
  // GPs whose share of the display list is not empty: only these take part in the frame
  // (the others, when there are fewer triangles than GPs, do nothing and send nothing).
  int busy_gp_count() const { return busy_gps_; }
  int renderer_count() const { return static_cast<int>(renderers_.size()); }

  // Ring stops: GPs first, then Renderers, then the frame buffer.
  int gp_stop(int k) const { return k; }
  int renderer_stop(int k) const { return gp_count() + k; }
  int frame_buffer_stop() const { return gp_count() + renderer_count(); }
  int ring_stops() const { return frame_buffer_stop() + 1; }

  // Which Renderer renders which region, and which GPs send it packets.
  RegionScheduler& scheduler() { return scheduler_; }
  const RegionScheduler& scheduler() const { return scheduler_; }
  // The Renderers' ring stops, in Renderer order: where a bin map goes.
  const std::vector<int>& renderer_stops() const { return renderer_stops_; }
  // Words of one bin map on the ring: a header word and one bit per region.
  std::uint64_t bin_map_words() const;

  // The GP cost model and what the firmware asks of each triangle.
  const I860Model& i860() const { return i860_; }
  const GpWorkload& gp_workload() const { return workload_; }

  // The timeline: when on, modules record slices of activity.
  void record_timeline(bool on);
  bool timeline_on() const { return timeline_on_; }
  void add_slice(Unit unit, int index, std::string name, sc_core::sc_time start,
                 sc_core::sc_time end) {
    if (timeline_on_) slices_.push_back({unit, index, std::move(name), start, end});
  }
  const std::vector<TimelineSlice>& slices() const { return slices_; }
  // Ring words of a packet carrying `expressions`, each by its form (models/gp/expressions.hpp).
  std::uint64_t packet_words(const ExpressionSet& expressions) const;

  // Keep the GPs' set-up in `memo` for later frames of the same scene, or replay it from
  // there if an earlier frame's key matches (models/gp/setup_memo.hpp); before the frame
  // runs. The memo must outlive the frame. Throws if it was made for another scene.
  void use_setup_memo(SetupMemo& memo);
  SetupMemo* setup_memo() const { return setup_memo_; }
  std::uint64_t region_words() const;

 private:
  static std::string fmt_name(const char* base, int k);

  MachineConfig config_;
  const Scene& scene_;
  const Program& program_;
  GeometryEngine geometry_;
  TimingParams timing_;
  FrameValues frame_values_;
  std::unique_ptr<Ring> ring_;
  std::unique_ptr<FrameBuffer> frame_buffer_;
  std::vector<std::unique_ptr<Renderer>> renderers_;
  std::vector<std::unique_ptr<GraphicsProcessor>> gps_;
  I860Model i860_;
  GpWorkload workload_;
  RegionScheduler scheduler_;
  std::vector<int> renderer_stops_;
  int busy_gps_ = 0;
  bool timeline_on_ = false;
  std::vector<TimelineSlice> slices_;
  SetupMemo* setup_memo_ = nullptr;
};

}  // namespace pp5
