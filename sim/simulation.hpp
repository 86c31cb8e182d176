#pragma once
// Runs one frame through the whole machine and gathers what it produced: the image, the
// statistics and the human-readable summary. A library entry point, so that tests, the
// command-line program and sweeps share it; each call is the one-frame case of a Session
// (below), with a SystemC context of its own that it frees.
#include <atomic>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "common/statistics.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/image/region_map.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

class BoardObserver;
class SetupMemo;

struct FrameResult {
  // The frame buffer's frame, region by region (image.flat() for one RgbImage). A timing-only
  // frame (fidelity.pixels=none) holds no pixels: image.has_pixels() is false.
  FrameImage image;
  // Every module's statistics, frozen at the end of the frame: read them by name as typed
  // values (stats.real("frame.simulated_seconds")); `pp5sim stats --describe` lists them.
  Statistics stats;
  // The same as stats.json's document (stats.to_json()), to write and to compare whole.
  nlohmann::json stats_json;
  double frame_seconds = 0;         // simulated
  double triangles_per_second = 0;  // projected for the real machine
  // Every region the Renderers rendered, with its Renderer and busy cycles (regions.png).
  std::vector<RegionLoad> regions;
};

// `memo`, if given, keeps the GPs' set-up of `scene` for the next frame of another
// configuration, or replays it from an earlier one (models/gp/setup_memo.hpp): the same
// results, without transforming and setting up every primitive again. host.timing_seconds
// then leaves out the set-up it replayed.
// `observe`, if given, attaches an observer to Renderer k's board (tracing, snapshots).
// With `timeline`, the run also records every unit's activity and stores it there as a
// Chrome trace-event document (ui.perfetto.dev and chrome://tracing open it).
// `setup_seconds`: the caller's host time making the scene and assembling the program, which
// the frame reports as host.setup_seconds (Session::set_setup_seconds).
FrameResult simulate_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                           int threads,
                           const std::function<BoardObserver*(int renderer)>& observe = {},
                           nlohmann::json* timeline = nullptr, SetupMemo* memo = nullptr,
                           double setup_seconds = 0);

// A simulation that persists across frames: it owns one SystemC context, the Machine
// elaborated in it, the assembled program and the scene, and runs frame after frame
// (models/protocol/frame_clock.hpp). Each frame() returns that frame's own result: its image,
// and its statistics frozen when it ends, with every time relative to the frame's start, so
// that a frame reports what a run of that frame alone reports. simulate_frame and
// project_frame are the one-frame case of a Session.
//
// Contract:
//  - frame n starts when frame n - 1 has ended (the units' last events), on the same
//    machine, whose units begin each frame as new (Machine::begin_frame).
//  - `memo` as for simulate_frame; it must outlive the session.
//  - fidelity.timing=analytic runs no kernel: each frame is the analytic model's.
//  - With `timeline`, frame() stores the run's timeline so far (every frame recorded with a
//    timeline on, in the run's simulated time).
class Machine;

// The scene of each frame of a run (Session::run_frames): called once per frame, in frame
// order, before the frame is set up. The default gives the session's scene to every frame.
using SceneSource = std::function<std::shared_ptr<const Scene>(int frame)>;

// A run's timeline handed out as it is recorded, so that a long run keeps none of it
// (Session::stream_timeline): Chrome trace events, each part in recording order. The units'
// tracks (Part::units) come before any frame runs; once each frame is handed over, the
// slices and ring messages recorded since the hand-over before (Part::slices,
// Part::messages), which the machine then drops; after the last frame, the frame buffer's
// region arrivals (Part::arrivals). The events of every part, in the order units, slices,
// messages, arrivals, are the "traceEvents" of the document run_frames stores in `timeline`.
class TimelineStream {
 public:
  enum class Part { units, slices, messages, arrivals };
  virtual ~TimelineStream() = default;
  virtual void add(Part part, const nlohmann::json& event) = 0;
};

// One frame of a run of frames looked at closely (Session::run_frames): its boards observed
// (traces, snapshots); the run's other frames are then timing only.
struct ObservedFrame {
  int frame = -1;  // none
  std::function<BoardObserver*(int renderer)> observe;
};

// What a run of frames did, over all its frames so far (Session::summary).
struct RunSummary {
  int frames = 0;
  double simulated_seconds = 0;  // the frames' simulated times, summed
  double shortest_frame_seconds = 0;
  double longest_frame_seconds = 0;
  double host_seconds = 0;  // host.seconds, summed
  // The caller's host time before the run (making the scene, assembling the program:
  // Session::set_setup_seconds), not in host_seconds; the first frame's host.setup_seconds.
  double setup_seconds = 0;

  // A run of overlapped frames (Session::run_frames), as simulated; at
  // fidelity.timing=analytic, the closed-form estimate instead (overlapped false).
  bool overlapped = false;
  // Sustained frame period: from the end of the first frame to the end of the last, over the
  // frames between (the first frame's time when there is one frame).
  double sustained_frame_seconds = 0;
  double sustained_triangles_per_second = 0;  // display-list triangles / period
  double sustained_spheres_per_second = 0;    // display-list spheres / period
  // Frame latency, mean and longest: from the first GP starting a frame's set-up to its last
  // region reaching the frame buffer.
  double mean_latency_seconds = 0;
  double longest_latency_seconds = 0;
  // The GPs' busy time (geometry and starting messages), and their time waiting for the
  // Renderers (a stage to open, room in a queue, or the frame before to let them start),
  // each over the busy GPs x the GPs' part of the run (from the first set-up to the last GP's
  // last message): in a GP-bound run the GPs never wait (the rest is sending on the ring).
  double gp_busy_share = 0;
  double gp_wait_share = 0;
  // Time the Renderers stood idle between frames (in each frame after the first, their waits
  // before its first message: the bin maps, the first bin) over the Renderers x the run after
  // the first frame: near 0 when the next frame's bins are ready as they finish a frame.
  double renderer_wait_share = 0;
  // Frames whose first region started on a GP's set-up before the frame before had its last
  // region on a Renderer (the overlap happened), of frames - 1.
  int overlapped_frames = 0;
  // The units' totals over the run (0 at the analytic level). What a frame's statistics do
  // not hold when frames overlap (the ring's channels and contention) is only here.
  std::uint64_t gp_busy_clocks = 0;        // summed over the GPs
  std::uint64_t renderer_busy_cycles = 0;  // summed over the Renderers
  std::uint64_t ring_messages = 0;
  std::uint64_t ring_words = 0;
  std::uint64_t ring_contention_cycles = 0;  // ring cycles messages waited for a channel
  double ring_channel_utilisation_max = 0;   // the busiest channel's busy time / the run
  // The closed-form estimate (frame.pipelined_frame_seconds of one frame alone), when the
  // caller computed it (simulate_frames), and its error against the simulated period.
  double estimate_frame_seconds = 0;
  double estimate_error() const {
    return sustained_frame_seconds > 0 && estimate_frame_seconds > 0
               ? estimate_frame_seconds / sustained_frame_seconds - 1
               : 0;
  }
  // The run.* statistics (docs/reference/statistics.md), frozen.
  Statistics statistics() const;
  // One text line of the sustained figures.
  std::string sustained_text() const;
  double mean_frame_seconds() const { return frames ? simulated_seconds / frames : 0; }
  // Host seconds per simulated second (below 1 the simulator keeps up with the machine).
  double host_over_simulated() const {
    return simulated_seconds > 0 ? host_seconds / simulated_seconds : 0;
  }
  // One line for people: frames, mean (shortest .. longest) frame time, host per frame.
  std::string text() const;
};

// Thrown by Session::frame when its cancel flag turned true during the frame.
class FrameCancelled : public std::runtime_error {
 public:
  FrameCancelled() : std::runtime_error("the frame was cancelled") {}
};

class Session {
 public:
  Session(const MachineConfig& config, std::shared_ptr<const Scene> scene,
          std::shared_ptr<const Program> program, int threads, SetupMemo* memo = nullptr,
          const std::atomic<bool>* cancel = nullptr);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // Simulates the next frame; with `pixels` false, its timing only (as project_frame).
  FrameResult frame(const std::function<BoardObserver*(int renderer)>& observe = {},
                    nlohmann::json* timeline = nullptr, bool pixels = true);

  // Simulates `count` frames overlapped, as the machine ran them: a GP sets up frame n + 1
  // while the Renderers still draw frame n (frames.gp_bins, frames.gp_start), the Renderers
  // take frame n + 1's regions once they have finished frame n's, and a frame ends (the frame
  // buffer swaps) when its last region arrives. `on_frame(n, result)` is called for each
  // frame in order: its image (with `pixels`), its regions, frame_seconds the time since the
  // frame before ended (the first: since the run began), and its statistics (frame.index,
  // frame.start_seconds, frame.end_seconds, frame.latency_seconds, ...). `scenes` gives the
  // scene of each frame (default: the session's). Returns the summary with the sustained
  // figures. Only on a new session (no frame simulated yet); with `timeline`, the whole
  // run's, on which the overlap shows. At fidelity.timing=analytic each frame is the analytic
  // model's and the sustained period is its closed-form estimate.
  //
  // The run streams: the kernel runs on the calling thread, in slices, until every unit has
  // finished the next frame; that frame is then handed over (its records released from the
  // units), its pixels execute on a helper thread while the kernel simulates later frames, and
  // once they are done its statistics are built, on_frame is called (on the calling thread)
  // and the frame is freed. At most three frames are handed over and not yet delivered, so
  // memory stays flat whatever `count`. The cancel flag is checked between kernel slices and
  // between frames; FrameCancelled or an error from `scenes` or `on_frame` ends the run (the
  // frames delivered before it stay delivered).
  // `observed`, if it names a frame, has that frame's boards observed (traces and snapshots of
  // a frame as the run drew it); the other frames are then timing only (no pixels).
  const RunSummary& run_frames(int count,
                               const std::function<void(int frame, FrameResult& result)>& on_frame,
                               bool pixels = true, const SceneSource& scenes = {},
                               nlohmann::json* timeline = nullptr,
                               const ObservedFrame& observed = {});
  // run_frames hands its timeline to `stream` as it records it (null: none), when it is given
  // no `timeline` document to store; the stream must outlive the run.
  void stream_timeline(TimelineStream* stream) { timeline_stream_ = stream; }
  // Frames simulated so far, and the run's summary over them.
  int frames() const { return frames_; }
  const RunSummary& summary() const { return summary_; }
  const MachineConfig& config() const { return config_; }
  const Scene& scene() const { return *scene_; }
  const Program& program() const { return *program_; }
  // The scene of the frames from the next frame() on (an animation: sim/animation.hpp). It
  // must hold as many primitives of each kind as the session's scene (the GPs' shares of the
  // display list stay), else the next frame() throws std::runtime_error naming both counts.
  // The set-up memo is made again for it (one given to the constructor is no longer used).
  void set_scene(std::shared_ptr<const Scene> scene);
  // The event model's machine (null at fidelity.timing=analytic).
  const Machine* machine() const;
  // A flag checked during each frame() (null: none): between slices of the SystemC run
  // (KernelContext::run), between the pixel execution's regions, and at the analytic level
  // after the set-up and the model as well. Once it is true, frame() throws FrameCancelled;
  // the session is then to be destroyed (its machine holds a frame half done). Given to the
  // constructor, it is checked during the set-up memo's filling as well (FrameCancelled).
  void set_cancel(const std::atomic<bool>* flag) { cancel_ = flag; }
  // The caller's host time making the scene and assembling the program, reported by the first
  // frame as host.setup_seconds (later frames report 0); not part of host.seconds.
  void set_setup_seconds(double seconds) { setup_seconds_ = seconds; }

 private:
  struct Event;
  MachineConfig config_;
  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const Scene> next_scene_;  // set_scene's, until the next frame()
  std::shared_ptr<const Program> program_;
  int threads_;
  SetupMemo* memo_;
  const std::atomic<bool>* cancel_ = nullptr;
  TimelineStream* timeline_stream_ = nullptr;
  std::unique_ptr<Event> event_;
  double startup_seconds_ = 0;
  double setup_seconds_ = 0;
  int frames_ = 0;
  RunSummary summary_;
  FrameResult counted(FrameResult r);
};

// A run of `count` frames of `scene`, overlapped (Session::run_frames), with the closed-form
// estimate of one frame alone (project_frame's frame.pipelined_frame_seconds) in the summary
// to compare with the simulated period. `setup_seconds` as Session::set_setup_seconds;
// `timeline_stream` as Session::stream_timeline.
RunSummary simulate_frames(const MachineConfig& config, std::shared_ptr<const Scene> scene,
                           std::shared_ptr<const Program> program, int threads, int count,
                           const std::function<void(int frame, FrameResult& result)>& on_frame,
                           bool pixels = true, nlohmann::json* timeline = nullptr,
                           double setup_seconds = 0, TimelineStream* timeline_stream = nullptr);

// The timing model alone, for projections over many configurations (pp5sim validate): the
// frame time and the statistics of simulate_frame, without executing the firmware on the
// pixel arrays, which no instruction's cost depends on. The image is not drawn, and what
// only execution counts (host.pixel_seconds) is 0.
FrameResult project_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                          SetupMemo* memo = nullptr);

// What every statistic of a run is (its name pattern, kind, unit and description), in
// registration order: the statistics a frame of the smallest machine registers, which are
// those of any run with the indices of gp, renderer, ring.channels and primitives_per_region
// written N.
// `program_path` is a firmware program (any: the statistics do not depend on it).
// `sets` are configuration assignments applied after the small default machine, e.g. the
// fidelity level whose statistics are wanted ({"fidelity.timing=analytic", ...}).
std::vector<StatisticInfo> describe_statistics(const std::string& program_path,
                                               const std::vector<std::string>& sets = {});
// Those of a run of overlapped frames: a frame's (Session::run_frames) and the run's
// (RunSummary::statistics), on the same small machine.
std::vector<StatisticInfo> describe_run_statistics(const std::string& program_path);

// The bit-budget table and the headline figures, as printed after a run.
std::string bit_budget_table(const Program& program, const TimingParams& timing);
std::string summary(const FrameResult& result, const Program& program, const TimingParams& timing);

}  // namespace pp5
