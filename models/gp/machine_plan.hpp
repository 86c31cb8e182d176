#pragma once
// What every unit of one frame shares, without a SystemC module: the configuration, the
// scene's geometry, the program and its frame values, the GP cost model, the ring's stops
// and the sizes of what crosses the ring. The event model's Machine holds one and builds its
// modules around it; the analytic timing model (models/renderer/analytic.hpp) needs nothing
// more, so a frame timed analytically builds no module and runs no kernel.
//
// Contract:
//  - Constructing it checks the program against the scene and the configuration (pass plan,
//    expressions each primitive kind supplies, packets that fit the Renderer's queue) and
//    throws std::runtime_error naming the key or procedure, as the Machine did.
//  - It holds references to the scene and the program: both must outlive it.
//  - The host spreads the display list over the GPs in contiguous blocks (gp_block), so that
//    the concatenation of the GPs' bins is in display-list order.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/display_list/scene.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"
#include "models/protocol/region_stream.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

class SetupMemo;

// The machine configuration seen by each plain-C++ part.
GeometryParams geometry_params(const MachineConfig& config);
TimingParams timing_params(const MachineConfig& config);
I860Params i860_params(const MachineConfig& config);
RingParams ring_params(const MachineConfig& config);
AssemblerOptions assembler_options(const MachineConfig& config);

class MachinePlan {
 public:
  MachinePlan(const MachineConfig& config, const Scene& scene, const Program& program);

  const MachineConfig& config() const { return config_; }
  const Program& program() const { return program_; }
  const Scene& scene() const { return *scene_; }
  const GeometryEngine& geometry() const { return *geometry_; }
  const TimingParams& timing() const { return timing_; }
  // The values of clear, pass and shade, and of each light's `light` procedure; a packet
  // binds frame.parameters when it runs (RegionStream); it never carries them.
  const FrameValues& frame_values() const { return frame_values_; }
  // Times the GPs send each region's triangles this frame (Program::pass_count).
  int passes() const { return RegionStream::pass_count(program_, frame_values_); }

  int gp_count() const { return config_.gp.count; }
  int renderer_count() const { return config_.renderer.count; }
  // GP k's share of the display list: primitives [first, second).
  std::pair<int, int> gp_block(int k) const;
  // GPs whose share is not empty: only these take part in the frame (the others, when
  // there are fewer primitives than GPs, do nothing and send nothing).
  int busy_gp_count() const { return busy_gps_; }

  // Ring stops: GPs first, then Renderers, then the frame buffer.
  int gp_stop(int k) const { return k; }
  int renderer_stop(int k) const { return gp_count() + k; }
  int frame_buffer_stop() const { return gp_count() + renderer_count(); }
  int ring_stops() const { return frame_buffer_stop() + 1; }
  // The ring's latency from stop `from` to stop `to` (Ring::hop_delay, without a Ring).
  sc_core::sc_time hop_delay(int from, int to) const;

  // Words of one bin map on the ring: a header word and one bit per region.
  std::uint64_t bin_map_words() const;
  // Ring words of a packet carrying `expressions`, each by its form (models/gp/expressions.hpp).
  std::uint64_t packet_words(const ExpressionSet& expressions) const;
  // Ring words of one finished region on its way to the frame buffer.
  std::uint64_t region_words() const;

  // The depth sort the GPs run before their geometry (the scene's: Scene::depth_sort), null
  // for none; checked to be made for gp.count GPs.
  const DepthSortWork* depth_sort() const { return scene_->depth_sort.get(); }

  // The GP cost model and what the firmware asks of each triangle.
  const I860Model& i860() const { return i860_; }
  const GpWorkload& gp_workload() const { return workload_; }

  // Keep the GPs' set-up in `memo` for later frames of the same scene, or replay it from
  // there if an earlier frame's key matches (models/gp/setup_memo.hpp); before the frame
  // runs. The memo must outlive the frame. Throws if it was made for another scene.
  void use_setup_memo(SetupMemo& memo);
  SetupMemo* setup_memo() const { return setup_memo_; }

  // A host's flag (null: none) that the GPs' geometry pass checks between primitives: once it
  // is true the pass stops short, and the frame is incomplete (a frame being cancelled, which
  // its caller discards: Session::set_cancel). A host setting, not part of the plan: const.
  void set_cancel(const std::atomic<bool>* flag) const { cancel_ = flag; }
  bool cancelled() const { return cancel_ != nullptr && cancel_->load(std::memory_order_relaxed); }

  // The next frame's scene, between frames (an animation): the geometry, frame values and
  // pass plan are those of `scene`, checked as the constructor checks them. It must have as
  // many primitives of each kind as the current scene (the GPs' shares of the display list
  // are fixed when the machine is built), else std::runtime_error naming both counts. The
  // set-up memo is dropped (it was made for the other scene). `scene` must outlive the plan.
  void set_scene(const Scene& scene);
  // Throws what set_scene throws if `scene` has not as many primitives of each kind as this
  // plan's scene.
  void check_same_primitives(const Scene& scene) const;

 private:
  // What the constructor and set_scene derive from the scene, with their checks.
  void derive_from_scene();
  // Per primitive kind (primitive_kinds()), its primitives in `scene`.
  static std::vector<int> primitive_counts(const Scene& scene);
  MachineConfig config_;
  const Scene* scene_;
  const Program& program_;
  // In place, so that a reference to it stays valid across set_scene.
  std::optional<GeometryEngine> geometry_;
  TimingParams timing_;
  FrameValues frame_values_;
  I860Model i860_;
  GpWorkload workload_;
  RingParams ring_;
  sc_core::sc_time ring_cycle_;  // 1 / ring.clock_hz
  int busy_gps_ = 0;
  SetupMemo* setup_memo_ = nullptr;
  mutable const std::atomic<bool>* cancel_ = nullptr;
};

// The plan each frame works from. Frames of one scene share the machine's plan; a run of
// overlapped frames whose scene changes (an animation: Session::run_frames with a scene per
// frame) gives each frame in flight a plan of its own (its camera, lights, transformed
// geometry, frame values and pass plan), so that the GPs set up frame n + 1 from frame
// n + 1's scene while the Renderers still draw frame n with frame n's values.
//
// Contract:
//  - of(n) is frame n's plan: the base plan without a source; with one, the plan the source
//    made for n, made when a unit first asks for frame n (the source is called once per
//    frame, in frame order, frames skipped included).
//  - Two frames at most are in flight (FrameClock): frame n's plan takes the slot of frame
//    n - 2 (n & 1), which every unit has finished by the time any unit asks for frame n; a
//    plan asked for after its slot was taken is a logic_error.
//  - The source runs inside the kernel (a unit's thread): it must not throw (the Session
//    catches what its own source throws and stops the kernel).
class FramePlans {
 public:
  using Source = std::function<std::shared_ptr<const MachinePlan>(int frame)>;
  explicit FramePlans(const MachinePlan& base) : base_(&base) {}
  const MachinePlan& of(int frame);
  void set_source(Source source) {
    source_ = std::move(source);
    slots_[0].reset();
    slots_[1].reset();
    slot_frame_[0] = slot_frame_[1] = -1;
    made_ = 0;
  }
  bool per_frame() const { return static_cast<bool>(source_); }

 private:
  const MachinePlan* base_;
  Source source_;
  std::shared_ptr<const MachinePlan> slots_[2];
  int slot_frame_[2] = {-1, -1};
  int made_ = 0;  // frames the source has made a plan for
};

}  // namespace pp5
