#include "sim/simulation.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <exception>
#include <fstream>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <system_error>
#include <systemc>
#include <thread>

#include "common/serial_worker.hpp"
#include "firmware/assembler/program_statistics.hpp"
#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/graphics_processor.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/machine.hpp"
#include "models/renderer/analytic.hpp"
#include "models/renderer/execute_pixels.hpp"
#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"
#include "sim/kernel.hpp"
#include "sim/run_report.hpp"

namespace pp5 {

namespace {

// Chrome trace-event JSON: one process per kind of unit, one thread per unit, complete
// ("X") slices in microseconds. Slices of one track are recorded in time order and nest.
// The document's parts, each handed to `out` event by event (TimelineStream::Part order).
using TimelineOut = std::function<void(TimelineStream::Part, const nlohmann::json&)>;

void timeline_units(Machine& machine, const TimelineOut& out) {
  using nlohmann::json;
  constexpr auto part = TimelineStream::Part::units;
  const char* kinds[] = {"Graphics Processors", "Ring channels", "Renderers", "Frame buffer"};
  const int counts[] = {machine.gp_count(), machine.ring().params().channels,
                        machine.renderer_count(), 1};
  const char* names[] = {"gp", "channel ", "renderer", "frame buffer"};
  for (int k = 0; k < 4; ++k) {
    out(part, {{"ph", "M"},
               {"name", "process_name"},
               {"pid", k + 1},
               {"tid", 0},
               {"args", {{"name", kinds[k]}}}});
    out(part, {{"ph", "M"},
               {"name", "process_sort_index"},
               {"pid", k + 1},
               {"tid", 0},
               {"args", {{"sort_index", k}}}});
    for (int i = 0; i < counts[k]; ++i) {
      out(part,
          {{"ph", "M"},
           {"name", "thread_name"},
           {"pid", k + 1},
           {"tid", i},
           {"args", {{"name", k == 3 ? std::string(names[k]) : names[k] + std::to_string(i)}}}});
    }
  }
}

double timeline_us(sc_core::sc_time t) { return t.to_seconds() * 1e6; }

// The slices and ring messages recorded so far; with `drop`, they are then cleared from the
// machine (a run of frames hands them out frame by frame).
void timeline_records(Machine& machine, const TimelineOut& out, bool drop) {
  for (const TimelineSlice& sl : machine.slices()) {
    out(TimelineStream::Part::slices, {{"ph", "X"},
                                       {"name", sl.name},
                                       {"pid", static_cast<int>(sl.unit) + 1},
                                       {"tid", sl.index},
                                       {"ts", timeline_us(sl.start)},
                                       {"dur", timeline_us(sl.end - sl.start)}});
  }
  auto stop_name = [&](int stop) {
    if (stop < machine.gp_count()) return "gp" + std::to_string(stop);
    if (stop < machine.frame_buffer_stop())
      return "renderer" + std::to_string(stop - machine.gp_count());
    return std::string("frame buffer");
  };
  for (const RingMessage& m : machine.ring().messages_log()) {
    out(TimelineStream::Part::messages,
        {{"ph", "X"},
         {"name", stop_name(m.from) + " -> " + stop_name(m.to)},
         {"pid", 2},
         {"tid", m.channel},
         {"ts", timeline_us(m.start)},
         {"dur", timeline_us(m.end - m.start)},
         {"args", {{"words", m.words}, {"arrival_us", timeline_us(m.arrival)}}}});
  }
  if (drop) {
    machine.timeline().clear();
    machine.ring().clear_messages_log();
  }
}

void timeline_arrivals(Machine& machine, const TimelineOut& out) {
  const auto& arrivals = machine.frame_buffer().arrivals();
  for (std::size_t r = 0; r < arrivals.size(); ++r) {
    out(TimelineStream::Part::arrivals, {{"ph", "i"},
                                         {"s", "t"},
                                         {"name", "region " + std::to_string(r)},
                                         {"pid", 4},
                                         {"tid", 0},
                                         {"ts", timeline_us(arrivals[r])}});
  }
}

nlohmann::json timeline_document(Machine& machine) {
  nlohmann::json events = nlohmann::json::array();
  const TimelineOut into = [&events](TimelineStream::Part, const nlohmann::json& e) {
    events.push_back(e);
  };
  timeline_units(machine, into);
  timeline_records(machine, into, false);
  timeline_arrivals(machine, into);
  return {{"traceEvents", events}, {"displayTimeUnit", "ns"}};
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One frame's pixels in a run of frames, and the host time they took.
struct FramePixels {
  FrameImage image;
  double seconds = 0;
};

// The pixels of a run's frames, executed on one helper thread, job after job in the order
// submitted, while the caller goes on (the kernel simulating later frames): each job's result
// (or exception) through its future. Jobs run one at a time (they share one frame buffer).
// Dropping the worker drops the jobs not started (the caller has stopped waiting for them:
// on_frame threw, or the run was cancelled), so nothing a job uses goes before it.
using FramePixelsWorker = SerialWorker<FramePixels>;

}  // namespace

namespace {

double mean_of(const Statistics& s, const std::string& array, const char* key) {
  const std::size_t n = s.elements(array);
  double sum = 0;
  for (std::size_t k = 0; k < n; ++k) sum += s.real(fmt::format("{}.{}.{}", array, k, key));
  return n == 0 ? 0 : sum / static_cast<double>(n);
}
double max_of(const Statistics& s, const std::string& array, const char* key) {
  double m = 0;
  for (std::size_t k = 0; k < s.elements(array); ++k)
    m = std::max(m, s.real(fmt::format("{}.{}.{}", array, k, key)));
  return m;
}

// The frame time split along the critical path (timing.*).
struct FrameAttribution {
  int critical_renderer = 0;
  double gp_seconds = 0;
  double ring_seconds = 0;
  double renderer_seconds = 0;
  double unattributed_seconds = 0;
  std::string bottleneck;
};

// Splits the frame time along the critical path: the Renderer whose last region reaches the
// frame buffer last. Its time is its array's work (Renderers), its waits for messages no GP
// had asked for yet (GPs), its waits for messages still crossing the ring, its blocked
// shipping and the final region's trip to the frame buffer (ring).
// `renderers` are each Renderer's statistics for the frame, with `finished` and `computed`
// relative to `began` (its own start of the frame).
FrameAttribution frame_attribution(const std::vector<const RendererStats*>& renderers,
                                   const std::vector<sc_core::sc_time>& began, double array_hz,
                                   double frame_seconds) {
  FrameAttribution a;
  int critical = 0;
  for (std::size_t k = 1; k < renderers.size(); ++k) {
    if (began[k] + renderers[k]->finished > began[critical] + renderers[critical]->finished)
      critical = static_cast<int>(k);
  }
  const RendererStats& st = *renderers[static_cast<std::size_t>(critical)];
  a.critical_renderer = critical;
  a.renderer_seconds =
      (st.busy.count + st.stall.count) / array_hz + st.waiting_renderers.to_seconds();
  a.gp_seconds = st.waiting_gp.to_seconds();
  a.ring_seconds = st.waiting_ring.to_seconds() + st.waiting_ship.to_seconds() +
                   (st.finished - st.computed).to_seconds();
  a.unattributed_seconds =
      std::max(0.0, frame_seconds - a.renderer_seconds - a.gp_seconds - a.ring_seconds);
  a.bottleneck = "Renderers";
  double top = a.renderer_seconds;
  if (a.gp_seconds > top) a.bottleneck = "GPs", top = a.gp_seconds;
  if (a.ring_seconds > top) a.bottleneck = "ring", top = a.ring_seconds;
  return a;
}

FrameAttribution frame_attribution(Machine& machine, double frame_seconds) {
  std::vector<const RendererStats*> st;
  for (int k = 0; k < machine.renderer_count(); ++k) st.push_back(&machine.renderer(k).stats());
  return frame_attribution(st, std::vector<sc_core::sc_time>(st.size()),
                           machine.config().renderer.clock_hz, frame_seconds);
}

// Registers timing.*: the attribution `a` (which must outlive the reads) and the utilisation
// figures, which read the units' statistics already registered in `s`.
// `channels`: ring.channels.N.* are registered (a frame of an overlapped run has them only in
// the run's totals: timing.ring_channel_utilisation_max is then left out).
void register_timing_statistics(Statistics& s, const FrameAttribution& a,
                                const MachineConfig& config, bool channels = true) {
  namespace u = stat_unit;
  s.add_integer("timing.critical_renderer", u::index,
                "The Renderer whose last region reached the frame buffer last",
                [&a] { return std::int64_t{a.critical_renderer}; });
  s.add_real("timing.gp_seconds", u::seconds,
             "Of the frame time on the critical path: waiting for GPs that were computing",
             [&a] { return a.gp_seconds; });
  s.add_real("timing.ring_seconds", u::seconds,
             "Of the frame time on the critical path: waiting for the ring (messages crossing, "
             "blocked shipping, the last region's trip to the frame buffer)",
             [&a] { return a.ring_seconds; });
  s.add_real("timing.renderer_seconds", u::seconds,
             "Of the frame time on the critical path: the Renderer's own busy and stalled "
             "cycles, and waiting for other Renderers",
             [&a] { return a.renderer_seconds; });
  s.add_real("timing.unattributed_seconds", u::seconds,
             "Of the frame time on the critical path: what none of the above explains",
             [&a] { return a.unattributed_seconds; });
  s.add_text("timing.bottleneck", u::name,
             "The largest of gp_seconds, ring_seconds and renderer_seconds: GPs, ring or Renderers",
             [&a] { return a.bottleneck; });
  s.add_real("timing.gp_utilisation_mean", u::ratio, "Mean of gp.N.utilisation",
             [&s] { return mean_of(s, "gp", "utilisation"); });
  s.add_real("timing.gp_utilisation_max", u::ratio, "Largest gp.N.utilisation",
             [&s] { return max_of(s, "gp", "utilisation"); });
  s.add_real("timing.renderer_utilisation_mean", u::ratio, "Mean of renderer.N.utilisation",
             [&s] { return mean_of(s, "renderer", "utilisation"); });
  s.add_real("timing.renderer_utilisation_max", u::ratio, "Largest renderer.N.utilisation",
             [&s] { return max_of(s, "renderer", "utilisation"); });
  s.add_real("timing.ring_utilisation", u::ratio, "ring.utilisation, repeated here",
             [&s] { return s.real("ring.utilisation"); });
  if (channels) {
    s.add_real("timing.ring_channel_utilisation_max", u::ratio,
               "Largest ring.channels.N.utilisation",
               [&s] { return max_of(s, "ring.channels", "utilisation"); });
  }
  const std::string gp_code = name_of(config.gp.code);
  s.add_text("timing.gp_code", u::name, "gp.code of the run: assembly or compiled",
             [gp_code] { return gp_code; });
  const std::string balancing = name_of(config.renderer.balancing);
  s.add_text("timing.balancing", u::name, "renderer.balancing of the run: static or dynamic",
             [balancing] { return balancing; });
}

// Bytes the host can still give this process: the kernel's MemAvailable, and the address-space
// limit (ulimit -v) less what the process already maps, whichever is smaller.
double host_bytes_available() {
  double available = 0;
  {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    double kib = 0;
    std::string unit;
    while (meminfo >> key >> kib >> unit) {
      if (key == "MemAvailable:") available = kib * 1024;
    }
  }
  if (available <= 0) available = 1e18;  // unknown: no limit from here
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    double mapped = 0;
    std::ifstream status("/proc/self/status");
    std::string key;
    double kib = 0;
    std::string unit;
    while (status >> key) {
      if (key == "VmSize:" && status >> kib >> unit) mapped = kib * 1024;
    }
    available = std::min(available, static_cast<double>(limit.rlim_cur) - mapped);
  }
  return available;
}

// The memory a frame will need, estimated before anything is allocated, so that a run too
// large for the host is refused with what to reduce instead of dying in an allocation:
// each board in flight holds its pixel memory (and backing store, if the program uses it)
// three times (the array and the two kept states of an empty region); each triangle's packet
// holds every expression's coefficients; the frame is held as RGB, at most one block per
// region, and may be flattened once more (FrameImage::flat).
void check_memory(const MachineConfig& config, const Scene& scene, const Program& program,
                  int threads) {
  bool backing = false;
  for (const ProcedureCode& code : program.procedures) {
    for (const Instruction& ins : code.code) {
      backing = backing || ins.op == Opcode::bsld || ins.op == Opcode::bsst;
    }
  }
  const double pixels =
      static_cast<double>(config.renderer.region_width) * config.renderer.region_height;
  const double array_bits = std::max(1, program.bits_used()) + config.renderer.enable_stack_depth +
                            8 + (backing ? config.renderer.backing_store_bits : 0);
  const double board = 3 * array_bits * pixels / 8;
  const int boards = std::min(std::max(1, threads), config.renderer.count) + 1;
  // A packet is kept once for all passes (the GPs resend the same ones).
  const double packets = static_cast<double>(scene.mesh.triangles.size()) * (sizeof(Packet) + 64);
  const double frame = 2.0 * config.screen.width * config.screen.height * 3;
  const double need = board * boards + packets + frame;
  // Below this a host always has the memory, and asking it (reading /proc) would cost a
  // sweep point more than the analytic model's sums; an address-space limit (ulimit -v) is
  // always checked, since it can be smaller.
  struct rlimit limit {};
  const bool limited = ::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur != RLIM_INFINITY;
  if (need < 256.0 * 1024 * 1024 && !limited) return;
  const double available = host_bytes_available();
  if (need > 0.9 * available) {
    const double gib = 1024.0 * 1024 * 1024;
    throw std::runtime_error(fmt::format(
        "this frame needs about {:.1f} GiB ({} boards in flight x {:.2f} GiB of pixel memory{}, "
        "{:.2f} GiB of packets for {} triangles, {:.2f} GiB of frame) and the host can give "
        "{:.1f} GiB: use fewer --threads, a smaller renderer.region_width/height{} or a "
        "smaller scene",
        need / gib, boards, board / gib, backing ? " and backing store" : "", packets / gib,
        scene.mesh.triangles.size(), frame / gib, available / gib,
        backing ? ", a smaller renderer.backing_store_bits" : ""));
  }
}

// SystemC's time is a 64-bit count of picoseconds (about 213 days) whose sums wrap without a
// word. No unit can be busy for longer than the frame, so a Renderer or GP whose busy time
// exceeds the frame's end means that simulated time wrapped: the run is refused rather than
// reported with nonsense (a frame shorter than its work, utilisations in the millions).
void check_time_did_not_wrap(Machine& machine) {
  const MachineConfig& config = machine.config();
  const double end = machine.frame_buffer().frame_complete().to_seconds();
  const double limit = sc_core::sc_max_time().to_seconds();
  auto refuse = [&](const std::string& unit, double busy) {
    throw std::runtime_error(fmt::format(
        "simulated time ran past what SystemC can count ({:.3g} s, 2^64 ps): {} was busy for "
        "{:.3g} s of a frame that seems to end at {:.3g} s; make the frame shorter (fewer "
        "triangles, a faster renderer.clock_hz or backing store, larger renderer.block_bits)",
        limit, unit, busy, end));
  };
  for (int k = 0; k < machine.renderer_count(); ++k) {
    const RendererStats& st = machine.renderer(k).stats();
    const double busy =
        static_cast<double>(st.busy.count + st.stall.count) / config.renderer.clock_hz;
    if (busy > end * (1 + 1e-9) + 1e-12 || busy > limit) refuse(fmt::format("renderer{}", k), busy);
  }
  for (int k = 0; k < machine.gp_count(); ++k) {
    const double busy = machine.gp(k).stats().busy.seconds(config.gp.clock_hz);
    if (busy > end * (1 + 1e-9) + 1e-12 || busy > limit) refuse(fmt::format("gp{}", k), busy);
  }
}

// What every frame's statistics name first: the scene, the program and the display list.
void register_frame_identity(Statistics& s, const Scene& scene, const Program& program) {
  namespace u = stat_unit;
  const std::string scene_name = scene.name;
  const std::string program_name = program.name;
  const auto triangles = static_cast<std::int64_t>(scene.mesh.triangles.size());
  const auto spheres = static_cast<std::int64_t>(scene.spheres.size());
  s.add_text("frame.scene", u::name, "The scene's name", [scene_name] { return scene_name; });
  s.add_text("frame.firmware", u::name, "The firmware program (the path it was assembled from)",
             [program_name] { return program_name; });
  s.add_integer("frame.triangles", u::count, "Triangles in the display list",
                [triangles] { return triangles; });
  s.add_integer("frame.spheres", u::count, "Spheres in the display list (the sphere kind)",
                [spheres] { return spheres; });
}

struct HostTimes {
  double host_seconds, timing_seconds, pixel_seconds;
  int threads;
  double setup_seconds;  // the caller's, before the frame (Session::set_setup_seconds)
};

// The host's side of a frame (never in goldens): registered after renderers_total.*.
void register_host_statistics(Statistics& s, const HostTimes& t, const char* timing_meaning) {
  namespace u = stat_unit;
  s.add_real("host.seconds", u::host_seconds, "Host time of the whole frame (timing + pixels)",
             [t] { return t.host_seconds; });
  s.add_real("host.setup_seconds", u::host_seconds,
             "Host time before the run, not in host.seconds: making the scene and assembling the "
             "program (pp5sim render's, a Python session's first frame's; 0 in a later frame)",
             [t] { return t.setup_seconds; });
  s.add_real("host.timing_seconds", u::host_seconds, timing_meaning,
             [t] { return t.timing_seconds; });
  s.add_real("host.pixel_seconds", u::host_seconds,
             "Host time executing the firmware on the pixel arrays",
             [t] { return t.pixel_seconds; });
  s.add_integer("host.threads", u::count, "Host threads for the pixel arrays (--threads)",
                [t] { return std::int64_t{t.threads}; });
  s.add_real(
      "host.simulated_array_cycles_per_host_second", u::per_second,
      "renderers_total.busy_cycles per host second (per host second, not simulated)", [&s, t] {
        return t.host_seconds > 0
                   ? static_cast<double>(s.integer("renderers_total.busy_cycles")) / t.host_seconds
                   : 0;
      });
}

// Region r's place on the screen and the cycles Renderer `renderer` spent on it, for
// regions.png. Regions at the right and bottom edges may reach past the screen: clipped, as
// in the frame.
RegionLoad region_load(const MachineConfig& config, int r, int renderer, std::uint64_t cycles) {
  const int x0 = config.region_x0(r), y0 = config.region_y0(r);
  return {r,
          x0,
          y0,
          std::min(config.renderer.region_width, config.screen.width - x0),
          std::min(config.renderer.region_height, config.screen.height - y0),
          renderer,
          cycles};
}

// fidelity.timing=analytic: no kernel runs; the analytic model (models/renderer/analytic.hpp)
// gives every unit's work and the frame time from the MachinePlan alone, and, with pixels,
// the Machine is built for its boards, which execute the regions the model assigned. It
// registers the statistics the summary, sweeps and `pp5sim fidelity` read, under the event
// model's names, and its own terms as analytic.*.
// With `cancel`, it is checked after the set-up and the model, and between the boards' regions;
// once it is true the frame throws FrameCancelled. `setup_seconds` is host.setup_seconds.
FrameResult analytic_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                           int threads, SetupMemo* memo, const std::atomic<bool>* cancel = nullptr,
                           double setup_seconds = 0) {
  const auto cancelled = [cancel] { return cancel != nullptr && cancel->load(); };
  const auto t0 = std::chrono::steady_clock::now();
  check_memory(config, scene, program, threads);
  // Without a memo from the caller, one for this frame: the model sets up from a memo.
  std::unique_ptr<SetupMemo> own;
  if (memo == nullptr) memo = (own = std::make_unique<SetupMemo>(scene)).get();
  // Pixels need the Renderer boards and the frame buffer: only then is the Machine built,
  // and the model reads its plan; otherwise a plan alone.
  const bool pixels = config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
  std::optional<KernelContext> kernel;  // before the Machine, which must go first
  std::unique_ptr<Machine> machine;
  std::unique_ptr<MachinePlan> alone;
  if (pixels) {
    kernel.emplace();
    machine = std::make_unique<Machine>("pp5", config, scene, program);
    machine->use_setup_memo(*memo);
  } else {
    alone = std::make_unique<MachinePlan>(config, scene, program);
    alone->use_setup_memo(*memo);
  }
  const MachinePlan& plan = machine ? machine->plan() : *alone;
  plan.set_cancel(cancel);
  fill_setup_memo(plan, threads);
  if (cancelled()) throw FrameCancelled();
  auto a = std::make_shared<const AnalyticTiming>(analytic_timing(plan));
  if (cancelled()) throw FrameCancelled();
  const double timing_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  FrameResult result;
  if (machine) {
    const std::vector<std::vector<RegionWork>> regions = analytic_work(*a, plan);
    std::vector<const std::vector<RegionWork>*> work;
    for (const auto& w : regions) work.push_back(&w);
    execute_pixels(machine->plan(), machine->frame_buffer(), work, threads, {}, cancel);
    if (cancelled()) throw FrameCancelled();
    result.image = machine->frame_buffer().take_image();
  } else {
    result.image = FrameImage(config.screen.width, config.screen.height,
                              config.renderer.region_width, config.renderer.region_height, false);
  }
  for (std::size_t k = 0; k < a->regions.size(); ++k) {
    for (int r : a->regions[k]) {
      result.regions.push_back(region_load(config, r, static_cast<int>(k),
                                           a->region_cycles[static_cast<std::size_t>(r)]));
    }
  }
  const double pixel_seconds = seconds_since(t1);
  const double host_seconds = seconds_since(t0);

  const double T = a->frame_seconds;
  result.frame_seconds = T;
  const auto triangles = static_cast<std::int64_t>(scene.mesh.triangles.size());
  result.triangles_per_second = T > 0 ? static_cast<double>(triangles) / T : 0;

  namespace u = stat_unit;
  Statistics& s = result.stats;
  const std::string scene_name = scene.name;
  const std::string program_name = program.name;
  const double gp_hz = config.gp.clock_hz;
  const double array_hz = config.renderer.clock_hz;
  register_frame_identity(s, scene, program);
  s.add_real("frame.simulated_seconds", u::seconds,
             "The frame time: analytic.fill_seconds + analytic.busiest_seconds + "
             "analytic.drain_seconds",
             [T] { return T; });
  s.add_integer("frame.array_cycles", u::array_cycles,
                "The frame time in Renderer array cycles (rounded)",
                [T, array_hz] { return static_cast<std::int64_t>(std::llround(T * array_hz)); });
  const double tps = result.triangles_per_second;
  s.add_real("frame.projected_triangles_per_second", u::per_second,
             "Triangles per second the real machine would reach: triangles / frame time",
             [tps] { return tps; });
  s.add_real("frame.projected_frames_per_second", u::per_second, "1 / frame time",
             [T] { return T > 0 ? 1.0 / T : 0; });
  double gp_busy_max = 0, gp_busy_sum = 0, geometry_clocks = 0;
  for (const GpStats& g : a->gps) {
    gp_busy_max = std::max(gp_busy_max, static_cast<double>(g.busy.count) / gp_hz);
    gp_busy_sum += static_cast<double>(g.busy.count) / gp_hz;
    geometry_clocks += static_cast<double>(g.geometry.count);
  }
  const double pipelined = std::max(gp_busy_max, T - a->geometry_seconds);
  s.add_real("frame.pipelined_frame_seconds", u::seconds,
             "Frame period with frames pipelined: the longer of the GPs' busiest time and the "
             "frame time after the last GP's geometry",
             [pipelined] { return pipelined; });
  s.add_real("frame.pipelined_triangles_per_second", u::per_second,
             "triangles / pipelined_frame_seconds", [pipelined, triangles] {
               return pipelined > 0 ? static_cast<double>(triangles) / pipelined : 0;
             });
  s.add_real("frame.gp_clocks_per_triangle", u::gp_clocks,
             "geometry_clocks summed over the GPs per display-list triangle (rounded)",
             [geometry_clocks, triangles] {
               return triangles ? std::round(geometry_clocks / static_cast<double>(triangles))
                                : 0.0;
             });
  for (std::size_t k = 0; k < a->gps.size(); ++k) {
    const std::string p = fmt::format("gp.{}.", k);
    s.add_integer(p + "busy_clocks", u::gp_clocks, "Clocks computing: geometry and messages",
                  [a, k] { return static_cast<std::int64_t>(a->gps[k].busy.count); });
    s.add_integer(p + "geometry_clocks", u::gp_clocks, "Clocks of the geometry pass",
                  [a, k] { return static_cast<std::int64_t>(a->gps[k].geometry.count); });
    s.add_integer(p + "messages", u::count, "Ring messages it sends (its bin map included)",
                  [a, k] { return static_cast<std::int64_t>(a->gp_messages[k]); });
    s.add_real(p + "utilisation", u::ratio, "busy time / frame time", [a, k, gp_hz, T] {
      return T > 0 ? static_cast<double>(a->gps[k].busy.count) / gp_hz / T : 0;
    });
  }
  std::vector<const GpStats*> gp_stats;
  for (const GpStats& g : a->gps) gp_stats.push_back(&g);
  register_setup_statistics(s, gp_stats);
  std::uint64_t renderer_busy = 0;
  double renderer_util_max = 0;
  for (std::size_t k = 0; k < a->renderer_busy_cycles.size(); ++k) {
    const std::string p = fmt::format("renderer.{}.", k);
    renderer_busy += a->renderer_busy_cycles[k];
    const double util = T > 0 ? static_cast<double>(a->renderer_busy_cycles[k]) / array_hz / T : 0;
    renderer_util_max = std::max(renderer_util_max, util);
    s.add_integer(p + "busy_cycles", u::array_cycles,
                  "Cycles executing micro-instructions, decoding packets, copying out",
                  [a, k] { return static_cast<std::int64_t>(a->renderer_busy_cycles[k]); });
    s.add_integer(p + "regions", u::count, "Regions it rendered",
                  [a, k] { return static_cast<std::int64_t>(a->regions[k].size()); });
    s.add_real(p + "utilisation", u::ratio, "busy time / frame time", [util] { return util; });
  }
  s.add_integer("renderers_total.busy_cycles", u::array_cycles, "busy_cycles summed",
                [renderer_busy] { return static_cast<std::int64_t>(renderer_busy); });
  const double bandwidth =
      static_cast<double>(config.ring.channels) * config.ring.word_bits * config.ring.clock_hz;
  const double ring_util = T > 0 ? a->ring_seconds / T : 0;
  s.add_integer("ring.words", u::ring_words, "Words all messages carried",
                [a] { return static_cast<std::int64_t>(a->ring_words); });
  s.add_integer("ring.messages", u::count, "Messages",
                [a] { return static_cast<std::int64_t>(a->ring_messages); });
  s.add_real("ring.bandwidth_bits_per_second", u::bits_per_second,
             "channels x word_bits x clock_hz", [bandwidth] { return bandwidth; });
  s.add_real("ring.utilisation", u::ratio, "Words carried / (bandwidth x frame time)",
             [ring_util] { return ring_util; });

  // The critical path of the contention recurrence: the critical Renderer's array time, its
  // waits for computing GPs and for the ring (models/renderer/analytic.hpp).
  FrameAttribution at;
  at.critical_renderer = a->critical_renderer;
  at.gp_seconds = a->critical_gp_seconds;
  at.ring_seconds = a->critical_ring_seconds;
  at.renderer_seconds = a->critical_renderer_seconds;
  at.unattributed_seconds = 0;
  at.bottleneck = a->bottleneck;
  auto attribution = std::make_shared<const FrameAttribution>(at);
  s.add_integer("timing.critical_renderer", u::index, "The Renderer whose last region arrives last",
                [attribution] { return std::int64_t{attribution->critical_renderer}; });
  s.add_real("timing.gp_seconds", u::seconds,
             "Of the frame time on the critical path: waiting for GPs that were computing",
             [attribution] { return attribution->gp_seconds; });
  s.add_real("timing.ring_seconds", u::seconds,
             "Of the frame time on the critical path: waiting for the ring, and the last "
             "region's trip",
             [attribution] { return attribution->ring_seconds; });
  s.add_real("timing.renderer_seconds", u::seconds,
             "Of the frame time on the critical path: the Renderer's array cycles",
             [attribution] { return attribution->renderer_seconds; });
  s.add_real("timing.unattributed_seconds", u::seconds,
             "Always 0: the recurrence's critical path is all explained", [] { return 0.0; });
  s.add_text("timing.bottleneck", u::name,
             "The largest of gp_seconds, ring_seconds and renderer_seconds: GPs, ring or Renderers",
             [attribution] { return attribution->bottleneck; });
  const double gps = static_cast<double>(std::max<std::size_t>(1, a->gps.size()));
  const double renderers = static_cast<double>(std::max<std::size_t>(1, a->regions.size()));
  s.add_real("timing.gp_utilisation_mean", u::ratio, "Mean of gp.N.utilisation",
             [gp_busy_sum, gps, T] { return T > 0 ? gp_busy_sum / gps / T : 0; });
  s.add_real("timing.gp_utilisation_max", u::ratio, "Largest gp.N.utilisation",
             [gp_busy_max, T] { return T > 0 ? gp_busy_max / T : 0; });
  s.add_real("timing.renderer_utilisation_mean", u::ratio, "Mean of renderer.N.utilisation",
             [renderer_busy, array_hz, renderers, T] {
               return T > 0 ? static_cast<double>(renderer_busy) / array_hz / renderers / T : 0;
             });
  s.add_real("timing.renderer_utilisation_max", u::ratio, "Largest renderer.N.utilisation",
             [renderer_util_max] { return renderer_util_max; });
  s.add_real("timing.ring_utilisation", u::ratio, "ring.utilisation, repeated here",
             [ring_util] { return ring_util; });
  s.add_real("timing.ring_channel_utilisation_max", u::ratio,
             "The analytic model spreads words evenly over the channels: ring.utilisation",
             [ring_util] { return ring_util; });
  const std::string gp_code = name_of(config.gp.code);
  s.add_text("timing.gp_code", u::name, "gp.code of the run: assembly or compiled",
             [gp_code] { return gp_code; });
  const std::string balancing = name_of(config.renderer.balancing);
  s.add_text("timing.balancing", u::name, "renderer.balancing of the run: static or dynamic",
             [balancing] { return balancing; });
  s.add_real("analytic.geometry_seconds", u::seconds, "The slowest GP's geometry pass",
             [a] { return a->geometry_seconds; });
  s.add_real("analytic.fill_seconds", u::seconds, "Until the last bin map is in at every Renderer",
             [a] { return a->fill_seconds; });
  s.add_real("analytic.busiest_seconds", u::seconds,
             "What the contention recurrence adds between the fill and the drain",
             [a] { return a->busiest_seconds; });
  s.add_real("analytic.closed_form_seconds", u::seconds,
             "The closed form without contention: fill + the busiest unit's work + drain",
             [a] { return a->closed_form_seconds; });
  s.add_real("analytic.drain_seconds", u::seconds, "The last region's trip to the frame buffer",
             [a] { return a->drain_seconds; });
  s.add_text("analytic.busiest_unit", u::name,
             "Which unit the closed form names the busiest: GPs, ring or Renderers",
             [a] { return a->busiest_unit; });
  register_program_statistics(s, program);
  register_host_statistics(s, {host_seconds, timing_seconds, pixel_seconds, threads, setup_seconds},
                           "Host time of the timing model (the analytic model, with the GPs' "
                           "geometry)");
  s.freeze();
  result.stats_json = s.to_json();
  return result;
}

}  // namespace

// The event model's run: one SystemC context and one Machine, elaborated once, that run frame
// after frame (models/protocol/frame_clock.hpp). Declared in this order so that the Machine
// goes before the context it was elaborated in.
struct Session::Event {
  KernelContext kernel;
  std::unique_ptr<Machine> machine;
  std::unique_ptr<SetupMemo> own_memo;
  // run_frames': where a frame's pixels execute while the kernel goes on (the machine's frame
  // buffer receives the regions' arrivals meanwhile).
  std::unique_ptr<FrameBuffer> pixel_frame_buffer;
  // The pixel boards, kept from frame to frame (execute_pixels restarts them).
  PixelBoards boards;
};

Session::Session(const MachineConfig& config, std::shared_ptr<const Scene> scene,
                 std::shared_ptr<const Program> program, int threads, SetupMemo* memo,
                 const std::atomic<bool>* cancel)
    : config_(config),
      scene_(std::move(scene)),
      program_(std::move(program)),
      threads_(threads),
      memo_(memo),
      cancel_(cancel) {
  if (config_.fidelity.timing == MachineConfig::Fidelity::Timing::analytic) return;
  const auto t0 = std::chrono::steady_clock::now();
  check_memory(config_, *scene_, *program_, threads_);
  event_ = std::make_unique<Event>();
  event_->machine = std::make_unique<Machine>("pp5", config_, *scene_, *program_);
  Machine& machine = *event_->machine;
  // A display list large enough to split over the host threads is set up on them first,
  // into a memo the GPs replay (models/gp/setup_memo.hpp): the same packets and counts.
  if (memo_ == nullptr && setup_parts(machine.plan(), threads_) > 1)
    memo_ = (event_->own_memo = std::make_unique<SetupMemo>(*scene_)).get();
  if (memo_ != nullptr) {
    machine.use_setup_memo(*memo_);
    machine.plan().set_cancel(cancel_);
    fill_setup_memo(machine.plan(), threads_);
    if (cancel_ != nullptr && cancel_->load()) throw FrameCancelled();
  }
  startup_seconds_ = seconds_since(t0);
}

Session::~Session() = default;

std::string RunSummary::text() const {
  return fmt::format(
      "run: {} frame{}, simulated {:.3f} ms a frame ({:.3f} .. {:.3f} ms), {:.3f} ms in all; "
      "host {:.3f} s a frame, {:.3g} host seconds per simulated second\n",
      frames, frames == 1 ? "" : "s", mean_frame_seconds() * 1e3, shortest_frame_seconds * 1e3,
      longest_frame_seconds * 1e3, simulated_seconds * 1e3, frames ? host_seconds / frames : 0.0,
      host_over_simulated());
}

FrameResult Session::counted(FrameResult r) {
  RunSummary& s = summary_;
  if (s.frames == 0) s.setup_seconds = setup_seconds_;
  s.shortest_frame_seconds =
      s.frames == 0 ? r.frame_seconds : std::min(s.shortest_frame_seconds, r.frame_seconds);
  s.longest_frame_seconds = std::max(s.longest_frame_seconds, r.frame_seconds);
  s.simulated_seconds += r.frame_seconds;
  s.host_seconds += r.stats.real("host.seconds");
  ++s.frames;
  return r;
}

const Machine* Session::machine() const { return event_ ? event_->machine.get() : nullptr; }

void Session::set_scene(std::shared_ptr<const Scene> scene) { next_scene_ = std::move(scene); }

FrameResult Session::frame(const std::function<BoardObserver*(int renderer)>& observe,
                           nlohmann::json* timeline, bool pixels) {
  // set_scene's scene takes over once the last frame has ended (the machine's units are idle).
  if (event_ && frames_ > 0 && next_scene_) event_->kernel.run_until(event_->machine->frame_end());
  if (next_scene_) {
    std::shared_ptr<const Scene> next = std::move(next_scene_);
    next_scene_.reset();
    if (event_) {
      check_memory(config_, *next, *program_, threads_);
      event_->machine->set_scene(*next);  // drops the machine's set-up memo
    }
    if (!event_ || memo_ != event_->own_memo.get()) memo_ = nullptr;
    if (event_) {
      event_->own_memo.reset();
      Machine& machine = *event_->machine;
      if (setup_parts(machine.plan(), threads_) > 1) {
        memo_ = (event_->own_memo = std::make_unique<SetupMemo>(*next)).get();
        machine.use_setup_memo(*memo_);
        fill_setup_memo(machine.plan(), threads_);
      } else {
        memo_ = nullptr;
      }
    }
    scene_ = std::move(next);
  }
  const MachineConfig& config = config_;
  const Scene& scene = *scene_;
  const Program& program = *program_;
  const int threads = threads_;
  if (!event_) {
    MachineConfig c = config;
    if (!pixels) c.fidelity.pixels = MachineConfig::Fidelity::Pixels::none;
    const double setup = frames_ == 0 ? setup_seconds_ : 0;
    FrameResult r = analytic_frame(c, scene, program, pixels ? threads : 1, memo_, cancel_, setup);
    ++frames_;
    return counted(std::move(r));
  }
  const auto t0 = std::chrono::steady_clock::now();
  Machine* machine = event_->machine.get();
  // Frame 0 runs as the kernel first starts; a later frame begins where the last ended.
  if (frames_ > 0) {
    event_->kernel.run_until(machine->frame_end());
    machine->begin_frame(frames_);
  }
  machine->record_timeline(timeline != nullptr);
  machine->plan().set_cancel(cancel_);
  if (!event_->kernel.run(cancel_) || (cancel_ != nullptr && cancel_->load()))
    throw FrameCancelled();
  check_time_did_not_wrap(*machine);
  if (timeline) *timeline = timeline_document(*machine);
  // The first frame's host time includes elaborating the machine, as a single frame's always
  // has; a later frame's does not.
  const double startup = frames_ == 0 ? startup_seconds_ : 0;
  const double setup = frames_ == 0 ? setup_seconds_ : 0;
  const double timing_seconds = seconds_since(t0) + startup;
  const auto t1 = std::chrono::steady_clock::now();
  if (pixels) execute_pixels(*machine, threads, observe, cancel_, &event_->boards);
  if (cancel_ != nullptr && cancel_->load()) throw FrameCancelled();
  const double pixel_seconds = seconds_since(t1);
  const double host_seconds = seconds_since(t0) + startup;
  ++frames_;
  FrameResult result;
  FrameBuffer& fb = machine->frame_buffer();
  result.image = fb.take_image();
  for (int k = 0; k < machine->renderer_count(); ++k) {
    for (const RegionWork& w : machine->renderer(k).work()) {
      result.regions.push_back(region_load(config, w.region, k, w.busy_cycles));
    }
  }
  result.frame_seconds = fb.frame_complete().to_seconds();
  const double frame_seconds = result.frame_seconds;
  const auto triangles = static_cast<std::int64_t>(scene.mesh.triangles.size());
  result.triangles_per_second =
      frame_seconds > 0 ? static_cast<double>(triangles) / frame_seconds : 0;

  // Each unit registers its own statistics; the frame-level figures below are registered here,
  // where they are computed. Everything is read once, by freeze(), before the machine goes.
  namespace u = stat_unit;
  Statistics& s = result.stats;
  const std::string scene_name = scene.name;
  const std::string program_name = program.name;
  register_frame_identity(s, scene, program);
  fb.register_statistics(s);
  const double array_hz = config.renderer.clock_hz;
  s.add_integer("frame.array_cycles", u::array_cycles,
                "The frame time in Renderer array cycles (rounded)", [frame_seconds, array_hz] {
                  return static_cast<std::int64_t>(
                      static_cast<std::uint64_t>(std::llround(frame_seconds * array_hz)));
                });
  const double triangles_per_second = result.triangles_per_second;
  s.add_real("frame.projected_triangles_per_second", u::per_second,
             "Triangles per second the real machine would reach: triangles / frame time",
             [triangles_per_second] { return triangles_per_second; });
  s.add_real("frame.projected_frames_per_second", u::per_second, "1 / frame time",
             [frame_seconds] { return frame_seconds > 0 ? 1.0 / frame_seconds : 0; });

  std::vector<const GraphicsProcessor*> gps;
  for (int k = 0; k < machine->gp_count(); ++k) {
    machine->gp(k).register_statistics(s, frame_seconds);
    gps.push_back(&machine->gp(k));
  }
  // With frames pipelined, as on the real machine, the GPs transform frame n + 1 while the
  // ring and Renderers finish frame n: the period is the longer of the two phases.
  const double gp_hz = config.gp.clock_hz;
  auto pipelined = [&s, frame_seconds, gp_hz] {
    double geometry_end = 0;
    double gp_busy = 0;
    for (std::size_t k = 0; k < s.elements("gp"); ++k) {
      const std::string p = fmt::format("gp.{}.", k);
      geometry_end = std::max(geometry_end, s.real(p + "geometry_done_seconds"));
      gp_busy = std::max(gp_busy, static_cast<double>(s.integer(p + "busy_clocks")) / gp_hz);
    }
    return std::max(gp_busy, frame_seconds - geometry_end);
  };
  s.add_real("frame.pipelined_frame_seconds", u::seconds,
             "Frame period with frames pipelined (the GPs on frame n + 1 while the ring and "
             "Renderers finish frame n): the longer of the GPs' busiest time and the frame "
             "time after the last GP's geometry",
             pipelined);
  s.add_real("frame.pipelined_triangles_per_second", u::per_second,
             "triangles / pipelined_frame_seconds", [pipelined, triangles] {
               const double period = pipelined();
               return period > 0 ? static_cast<double>(triangles) / period : 0;
             });
  s.add_real("frame.gp_clocks_per_triangle", u::gp_clocks,
             "geometry_clocks summed over the GPs per display-list triangle (rounded)",
             [&s, triangles] {
               std::int64_t geometry_clocks = 0;
               for (std::size_t k = 0; k < s.elements("gp"); ++k)
                 geometry_clocks += s.integer(fmt::format("gp.{}.geometry_clocks", k));
               return triangles ? std::round(static_cast<double>(geometry_clocks) /
                                             static_cast<double>(triangles))
                                : 0.0;
             });
  register_setup_statistics(s, gps);

  std::vector<const Renderer*> renderers;
  for (int k = 0; k < machine->renderer_count(); ++k) {
    machine->renderer(k).register_statistics(s, frame_seconds);
    renderers.push_back(&machine->renderer(k));
  }
  register_renderer_totals(s, renderers, config.regions());
  machine->ring().register_statistics(s, frame_seconds);
  const FrameAttribution attribution = frame_attribution(*machine, frame_seconds);
  register_timing_statistics(s, attribution, config);
  register_program_statistics(s, program);

  register_host_statistics(s, {host_seconds, timing_seconds, pixel_seconds, threads, setup},
                           "Host time of the timing model (the SystemC run)");
  s.freeze();
  result.stats_json = s.to_json();
  return counted(std::move(result));
}

std::string RunSummary::sustained_text() const {
  if (frames == 0) return {};
  std::string rate = fmt::format("{:.0f} triangles/s", sustained_triangles_per_second);
  if (sustained_spheres_per_second > 0)
    rate += fmt::format(", {:.0f} spheres/s", sustained_spheres_per_second);
  if (!overlapped) {
    return fmt::format(
        "sustained (closed-form estimate, frames not simulated overlapped): {:.3f} ms a frame, "
        "{:.1f} frames/s, {}\n",
        sustained_frame_seconds * 1e3,
        sustained_frame_seconds > 0 ? 1 / sustained_frame_seconds : 0.0, rate);
  }
  std::string out = fmt::format(
      "sustained (simulated, {} frames overlapped): {:.3f} ms a frame, {:.1f} frames/s, {}; "
      "latency {:.3f} ms mean, {:.3f} ms longest; GPs busy {:.1f}%, waiting for Renderers "
      "{:.1f}%; Renderers idle between frames {:.1f}%; {} of {} frames overlapped "
      "the one before\n",
      frames, sustained_frame_seconds * 1e3,
      sustained_frame_seconds > 0 ? 1 / sustained_frame_seconds : 0.0, rate,
      mean_latency_seconds * 1e3, longest_latency_seconds * 1e3, 100 * gp_busy_share,
      100 * gp_wait_share, 100 * renderer_wait_share, overlapped_frames,
      frames > 1 ? frames - 1 : 0);
  if (estimate_frame_seconds > 0) {
    out += fmt::format(
        "closed-form estimate (frame.pipelined_frame_seconds of one frame alone): {:.3f} ms, "
        "{:+.1f}% against the simulated period\n",
        estimate_frame_seconds * 1e3, 100 * estimate_error());
  }
  return out;
}

Statistics RunSummary::statistics() const {
  namespace u = stat_unit;
  Statistics s;
  const RunSummary r = *this;
  s.add_integer("run.frames", u::count, "Frames in the run",
                [r] { return std::int64_t{r.frames}; });
  s.add_text("run.timing", u::name,
             "How the sustained figures were found: 'simulated' (frames overlapped in the event "
             "model) or 'estimate' (the closed form, fidelity.timing=analytic)",
             [r] { return std::string(r.overlapped ? "simulated" : "estimate"); });
  s.add_real("run.sustained_frame_seconds", u::seconds,
             "Sustained frame period: from the end of the first frame to the end of the last, "
             "over the frames between (one frame: its time)",
             [r] { return r.sustained_frame_seconds; });
  s.add_real("run.sustained_frames_per_second", u::per_second, "1 / sustained_frame_seconds",
             [r] { return r.sustained_frame_seconds > 0 ? 1 / r.sustained_frame_seconds : 0; });
  s.add_real("run.sustained_triangles_per_second", u::per_second,
             "Display-list triangles / sustained_frame_seconds",
             [r] { return r.sustained_triangles_per_second; });
  s.add_real("run.sustained_spheres_per_second", u::per_second,
             "Display-list spheres / sustained_frame_seconds",
             [r] { return r.sustained_spheres_per_second; });
  s.add_real("run.mean_latency_seconds", u::seconds,
             "Frame latency, mean: from the first GP starting a frame's set-up to its last "
             "region reaching the frame buffer",
             [r] { return r.mean_latency_seconds; });
  s.add_real("run.longest_latency_seconds", u::seconds, "Frame latency, longest",
             [r] { return r.longest_latency_seconds; });
  s.add_real("run.gp_busy_share", u::ratio,
             "The busy GPs' busy time (geometry, starting messages) over their number x the GPs' "
             "part of the run (first set-up to the last GP's last message)",
             [r] { return r.gp_busy_share; });
  s.add_real("run.gp_wait_share", u::ratio,
             "The busy GPs' time waiting for the Renderers (a stage to open, room in a queue, "
             "the frame before to let them start) over their number x the GPs' part of the run",
             [r] { return r.gp_wait_share; });
  s.add_real("run.renderer_wait_share", u::ratio,
             "Time the Renderers stood idle between frames (in each frame after the first, "
             "their waits before its first message: the bin maps, the first bin) over their "
             "number x the run after the first frame",
             [r] { return r.renderer_wait_share; });
  s.add_integer("run.overlapped_frames", u::count,
                "Frames whose set-up began on a GP before the frame before had finished on "
                "every Renderer",
                [r] { return std::int64_t{r.overlapped_frames}; });
  s.add_integer("run.gp_busy_clocks", u::gp_clocks,
                "gp.N.busy_clocks summed over the GPs and the frames",
                [r] { return stat_count(r.gp_busy_clocks); });
  s.add_integer("run.renderer_busy_cycles", u::array_cycles,
                "renderer.N.busy_cycles summed over the Renderers and the frames",
                [r] { return stat_count(r.renderer_busy_cycles); });
  s.add_integer("run.ring_messages", u::count, "Messages the ring carried over the run",
                [r] { return stat_count(r.ring_messages); });
  s.add_integer("run.ring_words", u::ring_words,
                "Words the ring carried over the run: ring.words summed over the frames",
                [r] { return stat_count(r.ring_words); });
  s.add_integer("run.ring_contention_cycles", u::ring_cycles,
                "Cycles messages waited for a free channel, over the run (when frames overlap, "
                "a run total only: a wait is not split between frames)",
                [r] { return stat_count(r.ring_contention_cycles); });
  s.add_real("run.ring_channel_utilisation_max", u::ratio,
             "The busiest ring channel's busy time over the run's time (a run total only when "
             "frames overlap)",
             [r] { return r.ring_channel_utilisation_max; });
  s.add_real("run.estimate_frame_seconds", u::seconds,
             "The closed-form estimate of the period, frame.pipelined_frame_seconds of one frame "
             "alone (0: not computed)",
             [r] { return r.estimate_frame_seconds; });
  s.add_real("run.estimate_error", u::ratio,
             "estimate_frame_seconds / sustained_frame_seconds - 1 (0: not computed)",
             [r] { return r.estimate_error(); });
  s.add_real("run.host_seconds_per_frame", u::host_seconds,
             "Host time per frame (timing and pixels, start-up included)",
             [r] { return r.frames ? r.host_seconds / r.frames : 0; });
  s.add_real("run.host_setup_seconds", u::host_seconds,
             "Host time before the run, not in the figures above: making the scene and "
             "assembling the program (the first frame's host.setup_seconds)",
             [r] { return r.setup_seconds; });
  s.add_real("run.host_over_simulated", u::ratio,
             "Host seconds per simulated second of the run's frames (below 1: real time)",
             [r] { return r.host_over_simulated(); });
  s.freeze();
  return s;
}

const RunSummary& Session::run_frames(
    int count, const std::function<void(int frame, FrameResult& result)>& on_frame, bool pixels,
    const SceneSource& scenes, nlohmann::json* timeline, const ObservedFrame& observed) {
  if (count < 1) throw std::invalid_argument("a run of frames needs at least one frame");
  if (frames_ > 0)
    throw std::logic_error("Session::run_frames: the session has simulated frames already");
  summary_.setup_seconds = setup_seconds_;
  const auto triangles = static_cast<double>(scene_->mesh.triangles.size());
  const auto spheres = static_cast<double>(scene_->spheres.size());
  // The scene of frame f: the source's, or the session's when it gives none.
  auto scene_of = [&](int f) {
    std::shared_ptr<const Scene> given = scenes ? scenes(f) : nullptr;
    return given ? given : scene_;
  };
  if (!event_) {
    // The analytic level: each frame alone; the sustained period is the closed form's.
    if (observed.frame >= 0) {
      throw std::invalid_argument(
          "traces and snapshots need fidelity.timing=event (the analytic model runs no events "
          "and records no start cycles)");
    }
    double estimate = 0;
    for (int f = 0; f < count; ++f) {
      const std::shared_ptr<const Scene> given = scene_of(f);
      if (given != scene_) set_scene(given);
      FrameResult r = frame({}, nullptr, pixels);
      estimate = r.stats.real("frame.pipelined_frame_seconds");
      if (on_frame) on_frame(f, r);
    }
    summary_.overlapped = false;
    summary_.sustained_frame_seconds = estimate;
    summary_.estimate_frame_seconds = estimate;
    summary_.sustained_triangles_per_second = estimate > 0 ? triangles / estimate : 0;
    summary_.sustained_spheres_per_second = estimate > 0 ? spheres / estimate : 0;
    return summary_;
  }
  Machine& machine = *event_->machine;
  // A scene that changes from frame to frame (an animation): each frame in flight works from
  // its own plan (FramePlans), made inside the kernel when a unit first asks for the frame,
  // with the GPs' set-up memo of its scene when the display list is large. Only its frame
  // values outlive it, for the frame's pixels.
  std::map<int, FrameValues> values;  // each frame's, until it is handed over
  std::exception_ptr source_error;
  FramePlans::Source plans;
  if (scenes) {
    struct FramePlan {
      std::shared_ptr<const Scene> scene;
      std::unique_ptr<SetupMemo> memo;
      std::unique_ptr<MachinePlan> plan;  // goes before the memo and scene it refers to
    };
    plans = [&, base = &machine.plan()](int f) -> std::shared_ptr<const MachinePlan> {
      const std::shared_ptr<const MachinePlan> same(std::shared_ptr<void>(), base);
      if (source_error) return same;
      try {
        const std::shared_ptr<const Scene> given = scene_of(f);
        if (given == scene_) return same;
        base->check_same_primitives(*given);
        check_memory(config_, *given, *program_, threads_);
        auto p = std::make_shared<FramePlan>();
        p->scene = given;
        p->plan = std::make_unique<MachinePlan>(config_, *given, *program_);
        p->plan->set_cancel(cancel_);
        if (setup_parts(*p->plan, threads_) > 1) {
          p->memo = std::make_unique<SetupMemo>(*given);
          p->plan->use_setup_memo(*p->memo);
          fill_setup_memo(*p->plan, threads_);
        }
        values.emplace(f, p->plan->frame_values());
        return std::shared_ptr<const MachinePlan>(p, p->plan.get());
      } catch (...) {
        // Not through the kernel: stop it, and throw once it has returned.
        source_error = std::current_exception();
        // (quietly: the error says what happened)
        sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                                sc_core::SC_DO_NOTHING);
        sc_core::sc_stop();
        return same;
      }
    };
  }
  machine.record_timeline(timeline != nullptr || timeline_stream_ != nullptr);
  // A streamed timeline: the units' tracks now, each frame's records once it is handed over.
  const TimelineOut stream_out = [this](TimelineStream::Part part, const nlohmann::json& e) {
    timeline_stream_->add(part, e);
  };
  if (timeline_stream_ && !timeline) timeline_units(machine, stream_out);
  machine.overlap(count, plans);
  // With a cancel flag (Ctrl-C from Python), the GPs' set-up passes stop short too.
  machine.plan().set_cancel(cancel_);
  // However the run ends: the source refers to this call's locals, the flag may go.
  struct RunEnd {
    Machine& machine;
    ~RunEnd() {
      machine.plan().set_cancel(nullptr);
      machine.frame_plans().set_source({});
    }
  } run_end{machine};

  // The streaming pipeline. The calling thread runs the kernel in slices until every unit has
  // finished the next frame, hands that frame over (its records, released from the units),
  // and runs on; a helper thread executes the handed-over frames' pixels, in order, on a
  // frame buffer of its own; once a frame's pixels are done, the calling thread builds its
  // statistics and result, calls on_frame and frees the frame. At most kFramesWaiting frames
  // are handed over and not yet delivered, so memory stays flat whatever the count.
  constexpr std::size_t kFramesWaiting = 3;
  std::vector<const GraphicsProcessor*> gps;
  std::vector<int> gp_index;
  for (int k = 0; k < machine.gp_count(); ++k) {
    if (machine.gp(k).takes_part()) {
      gps.push_back(&machine.gp(k));
      gp_index.push_back(k);
    }
  }
  auto frame_done = [&](int f) {
    for (const GraphicsProcessor* g : gps) {
      if (g->history().empty() || g->history().front().frame != f) return false;
    }
    for (int k = 0; k < machine.renderer_count(); ++k) {
      const auto& h = machine.renderer(k).history();
      if (h.empty() || h.front().frame != f) return false;
    }
    return true;
  };
  const double gp_hz = config_.gp.clock_hz;
  const double array_hz = config_.renderer.clock_hz;
  const RingParams& ring = machine.ring().params();
  const std::uint64_t region_words = machine.plan().region_words();
  const bool execute = pixels && config_.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
  // The pixels' frame buffer: the machine's receives the regions' arrivals as the kernel runs.
  // A module, made before the kernel first starts (run_frames runs on a new session only).
  if (!event_->pixel_frame_buffer) {
    event_->kernel.make_current();
    event_->pixel_frame_buffer = std::make_unique<FrameBuffer>(
        "pixel_frame_buffer", config_.screen.width, config_.screen.height,
        config_.renderer.region_width, config_.renderer.region_height, config_.regions(),
        config_.fidelity.pixels != MachineConfig::Fidelity::Pixels::none);
  }
  FrameBuffer& pixel_fb = *event_->pixel_frame_buffer;

  // The run summary, summed frame by frame as frames are handed over.
  RunSummary& sum = summary_;
  sum.overlapped = true;
  sum.gp_busy_clocks = 0;
  sum.renderer_busy_cycles = 0;
  // Sums kept exact (clocks, picoseconds) and converted once at the end: the same whatever
  // the order frames and units are visited in.
  sc_core::sc_time gp_wait, renderer_wait;
  double gp_end = 0;
  double first_start = 0, first_end = 0, last_end = 0, previous_computed = 0;
  double previous_end = 0;  // the frame delivered last's end
  double latency_sum = 0;
  sum.longest_latency_seconds = 0;
  sum.overlapped_frames = 0;

  // A frame handed over: its records, and its pixels in flight.
  struct Pending {
    int frame = 0;
    double start = 0, end = 0;    // in the run's time
    double timing_seconds = 0;    // the kernel's host time since the frame before
    std::vector<GpStats> gstats;  // per GP (those taking part), times from the frame's start
    std::vector<Renderer::FrameRecord> renderers;
    std::vector<RegionLoad> regions;
    std::future<FramePixels> pixels;
  };
  std::deque<std::unique_ptr<Pending>> pending;  // before the worker, which refers to them
  // Delivered frames' images that on_frame left, whose bytes the next frames' images reuse
  // (FrameBuffer::begin_frame): taken on the helper thread, given back on this one.
  std::mutex spare_mutex;
  std::vector<FrameImage> spare_images;
  FramePixelsWorker worker;

  double kernel_seconds = startup_seconds_;  // host time in the kernel not yet handed over
  auto run_kernel = [&](const std::function<bool()>& done) {
    const auto k0 = std::chrono::steady_clock::now();
    const bool ran = event_->kernel.run(cancel_, done);
    kernel_seconds += seconds_since(k0);
    if (source_error) {
      frames_ = count;  // the machine stopped mid-run: no frame can follow
      std::rethrow_exception(source_error);
    }
    if (!ran || (cancel_ != nullptr && cancel_->load())) {
      frames_ = count;  // likewise: the caller frees the machine
      throw FrameCancelled();
    }
  };

  auto hand_over = [&](int f) {
    auto p = std::make_unique<Pending>();
    p->frame = f;
    // Every Renderer is past frame f: no GP's activity before its start of f is asked for.
    sc_core::sc_time renderers_began = sc_core::sc_max_time();
    for (int k = 0; k < machine.renderer_count(); ++k)
      renderers_began = std::min(renderers_began, machine.renderer(k).history().front().began);
    // Its span: from the first GP starting its set-up to its last region reaching the frame
    // buffer.
    double start = -1;
    std::vector<GpFrameRecord> grec;
    grec.reserve(gps.size());
    for (std::size_t i = 0; i < gps.size(); ++i) {
      grec.push_back(machine.gp(gp_index[i]).release_frame(f, renderers_began));
      const GpStats& st = grec.back().stats;
      const double t = st.geometry_started.to_seconds();
      start = start < 0 ? t : std::min(start, t);
      gp_wait += st.waiting_stage + st.waiting_queue + st.waiting_start;
      gp_end = std::max(gp_end, st.finished.to_seconds());
      sum.gp_busy_clocks += st.busy.count;
    }
    double end = 0, computed = 0;
    // Reserved: a record's move may throw (sc_time's), so growing would copy each record's
    // regions and packet pointers.
    p->renderers.reserve(static_cast<std::size_t>(machine.renderer_count()));
    for (int k = 0; k < machine.renderer_count(); ++k) {
      p->renderers.push_back(machine.renderer(k).release_frame(f));
      const Renderer::FrameRecord& rec = p->renderers.back();
      end = std::max(end, (rec.began + rec.stats.finished).to_seconds());
      computed = std::max(computed, (rec.began + rec.stats.computed).to_seconds());
      if (f > 0) renderer_wait += rec.stats.waiting_first;
      sum.renderer_busy_cycles += rec.stats.busy.count;
    }
    if (f == 0) {
      first_start = start < 0 ? 0 : start;
      first_end = end;
    }
    last_end = end;
    const double latency = end - std::max(0.0, start);
    latency_sum += latency;
    sum.longest_latency_seconds = std::max(sum.longest_latency_seconds, latency);
    if (f > 0 && start >= 0 && start < previous_computed) ++sum.overlapped_frames;
    previous_computed = computed;
    p->start = std::max(0.0, start);
    p->end = end;
    p->timing_seconds = kernel_seconds;
    kernel_seconds = 0;
    // Times relative to the frame's start, as a frame alone reports them.
    const sc_core::sc_time start_time(p->start, sc_core::SC_SEC);
    auto since_start = [start_time](sc_core::sc_time t) {
      return t > start_time ? t - start_time : sc_core::SC_ZERO_TIME;
    };
    p->gstats.resize(static_cast<std::size_t>(machine.gp_count()));
    for (std::size_t i = 0; i < gps.size(); ++i) {
      GpStats st = grec[i].stats;
      st.geometry_done = since_start(st.geometry_done);
      st.finished = since_start(st.finished);
      p->gstats[static_cast<std::size_t>(gp_index[i])] = st;
    }
    std::vector<const std::vector<RegionWork>*> work;
    for (int k = 0; k < machine.renderer_count(); ++k) {
      Renderer::FrameRecord& rec = p->renderers[static_cast<std::size_t>(k)];
      work.push_back(&rec.work);
      for (const RegionWork& w : rec.work)
        p->regions.push_back(region_load(config_, w.region, k, w.busy_cycles));
      rec.stats.computed = since_start(rec.began + rec.stats.computed);
      rec.stats.finished = since_start(rec.began + rec.stats.finished);
    }
    // Its pixels, on the helper thread: from its frame values (an animation frame's, made with
    // its plan; that plan may be gone by now).
    std::shared_ptr<const FrameValues> v;
    if (auto it = values.find(f); it != values.end()) {
      v = std::make_shared<const FrameValues>(std::move(it->second));
      values.erase(it);
    }
    const MachinePlan& plan = machine.plan();
    const int threads = threads_;
    const std::atomic<bool>* cancel = cancel_;
    const bool executes = execute && (observed.frame < 0 || f == observed.frame);
    std::function<BoardObserver*(int)> observe =
        f == observed.frame ? observed.observe : std::function<BoardObserver*(int)>();
    PixelBoards* boards = &event_->boards;
    p->pixels = worker.submit([&pixel_fb, &plan, work, v, threads, cancel, executes, observe,
                               boards, &spare_mutex, &spare_images] {
      const auto t1 = std::chrono::steady_clock::now();
      FrameImage storage;
      {
        const std::lock_guard<std::mutex> lock(spare_mutex);
        if (!spare_images.empty()) {
          storage = std::move(spare_images.back());
          spare_images.pop_back();
        }
      }
      pixel_fb.begin_frame(sc_core::SC_ZERO_TIME, std::move(storage));
      if (executes)
        execute_pixels(plan, v ? *v : plan.frame_values(), pixel_fb, work, threads, observe, cancel,
                       boards);
      FramePixels out;
      out.image = pixel_fb.take_image();
      out.seconds = seconds_since(t1);
      return out;
    });
    pending.push_back(std::move(p));
  };

  // Frame p's result once its pixels are done: its statistics from its own records (the GPs'
  // set-up and sending of that frame, the Renderers' regions of it); what the units do not
  // record per frame (the ring's channels) is the run's. Then on_frame, and the frame goes.
  // The statistics registered for the frame before (names, kinds, units, descriptions): each
  // frame's registry follows them (Statistics::follow), so that a frame that registers what
  // the one before did only fills in its getters.
  std::shared_ptr<const Statistics::Layout> stats_layout;
  auto deliver = [&] {
    std::unique_ptr<Pending> p = std::move(pending.front());
    pending.pop_front();
    FramePixels executed = p->pixels.get();
    if (cancel_ != nullptr && cancel_->load()) {
      frames_ = count;
      throw FrameCancelled();
    }
    const int f = p->frame;
    FrameResult result;
    result.image = std::move(executed.image);
    result.regions = std::move(p->regions);
    const double pixel_seconds = executed.seconds;
    const double frame_start = p->start;
    const double frame_end = p->end;
    result.frame_seconds = frame_end - previous_end;
    previous_end = frame_end;
    result.triangles_per_second = result.frame_seconds > 0 ? triangles / result.frame_seconds : 0;
    namespace u = stat_unit;
    Statistics& s = result.stats;
    s.follow(stats_layout);
    register_frame_identity(s, *scene_, *program_);
    const double frame_seconds = result.frame_seconds;
    s.add_integer("frame.index", u::index, "The frame's place in a run of frames (from 0)",
                  [f] { return std::int64_t{f}; });
    s.add_real("frame.simulated_seconds", u::seconds,
               "Frame time: when the last region reached the frame buffer (in a run of "
               "overlapped frames: since the frame before ended, the first since the run began)",
               [frame_seconds] { return frame_seconds; });
    s.add_integer("frame.array_cycles", u::array_cycles,
                  "The frame time in Renderer array cycles (rounded)", [frame_seconds, array_hz] {
                    return static_cast<std::int64_t>(
                        static_cast<std::uint64_t>(std::llround(frame_seconds * array_hz)));
                  });
    s.add_real("frame.start_seconds", u::seconds,
               "In the run's time: when the first GP started the frame's set-up",
               [frame_start] { return frame_start; });
    s.add_real("frame.end_seconds", u::seconds,
               "In the run's time: when the frame's last region reached the frame buffer (the "
               "frame buffer swaps)",
               [frame_end] { return frame_end; });
    s.add_real("frame.latency_seconds", u::seconds, "end_seconds - start_seconds",
               [frame_start, frame_end] { return frame_end - frame_start; });
    const double tps = result.triangles_per_second;
    s.add_real("frame.projected_triangles_per_second", u::per_second,
               "Triangles per second the real machine would reach: triangles / frame time",
               [tps] { return tps; });
    s.add_real("frame.projected_frames_per_second", u::per_second, "1 / frame time",
               [frame_seconds] { return frame_seconds > 0 ? 1.0 / frame_seconds : 0; });
    // The units' figures of this frame: busy times over the frame time (its period), which a
    // frame's work may exceed when it began in the period before (set-up ahead).
    std::vector<const GpStats*> gp_of;
    std::uint64_t words = 0, messages = 0;
    for (int k = 0; k < machine.gp_count(); ++k) {
      const GpStats& g = p->gstats[static_cast<std::size_t>(k)];
      register_gp_statistics(s, k, g, gp_hz, frame_seconds);
      if (machine.gp(k).takes_part()) gp_of.push_back(&g);
      words += g.ring_words;
      messages += g.messages;
    }
    std::uint64_t geometry_clocks = 0;
    for (const GpStats* g : gp_of) geometry_clocks += g->geometry.count;
    s.add_real("frame.gp_clocks_per_triangle", u::gp_clocks,
               "geometry_clocks summed over the GPs per display-list triangle (rounded)",
               [geometry_clocks, triangles] {
                 return triangles > 0 ? std::round(static_cast<double>(geometry_clocks) / triangles)
                                      : 0.0;
               });
    register_setup_statistics(s, gp_of);
    std::vector<const RendererStats*> renderer_of;
    std::vector<const std::vector<RegionWork>*> work;
    std::vector<sc_core::sc_time> began;
    const sc_core::sc_time start_time(frame_start, sc_core::SC_SEC);
    for (int k = 0; k < machine.renderer_count(); ++k) {
      const Renderer::FrameRecord& rec = p->renderers[static_cast<std::size_t>(k)];
      register_renderer_statistics(s, k, rec.stats, array_hz, frame_seconds);
      renderer_of.push_back(&rec.stats);
      work.push_back(&rec.work);
      began.push_back(start_time);
      words += rec.stats.regions * region_words;
      messages += rec.stats.regions;
    }
    register_renderer_totals(s, renderer_of, work, config_.regions());
    s.add_integer("ring.messages", u::count,
                  "Messages of the frame: the GPs' bin maps and bins, the Renderers' regions",
                  [messages] { return stat_count(messages); });
    s.add_integer("ring.words", u::ring_words, "Words of those messages",
                  [words] { return stat_count(words); });
    const double bandwidth = static_cast<double>(ring.channels) * ring.word_bits * ring.clock_hz;
    s.add_real("ring.bandwidth_bits_per_second", u::bits_per_second,
               "Capacity: channels x word_bits x clock", [bandwidth] { return bandwidth; });
    const double capacity = ring.channels * ring.clock_hz * frame_seconds;
    s.add_real(
        "ring.utilisation", u::ratio,
        "words as a fraction of what all channels could carry in the frame time",
        [words, capacity] { return capacity > 0 ? static_cast<double>(words) / capacity : 0; });
    const FrameAttribution attribution =
        frame_attribution(renderer_of, began, array_hz, frame_seconds);
    register_timing_statistics(s, attribution, config_, false);
    register_program_statistics(s, *program_);
    const double timing_seconds = p->timing_seconds;
    const double host = timing_seconds + pixel_seconds;
    s.add_real("host.seconds", u::host_seconds,
               "Host time of the frame: the timing model's host time since the frame before "
               "was handed over, and its pixels",
               [host] { return host; });
    const double setup = f == 0 ? setup_seconds_ : 0;
    s.add_real("host.setup_seconds", u::host_seconds,
               "Host time before the run, not in host.seconds: making the scene and assembling the "
               "program (pp5sim render's, a Python session's first frame's; 0 in a later frame)",
               [setup] { return setup; });
    s.add_real("host.timing_seconds", u::host_seconds,
               "Host time of the timing model (the SystemC run) from the frame before's hand-over "
               "to this frame's (the first frame's: from elaborating the machine)",
               [timing_seconds] { return timing_seconds; });
    s.add_real("host.pixel_seconds", u::host_seconds,
               "Host time executing the firmware on the pixel arrays",
               [pixel_seconds] { return pixel_seconds; });
    const int threads = threads_;
    s.add_integer("host.threads", u::count, "Host threads for the pixel arrays (--threads)",
                  [threads] { return std::int64_t{threads}; });
    s.freeze();
    stats_layout = s.layout();
    result.stats_json = s.to_json();
    p.reset();  // the frame's records and packets go
    ++frames_;
    RunSummary& rs = summary_;
    rs.shortest_frame_seconds =
        rs.frames == 0 ? frame_seconds : std::min(rs.shortest_frame_seconds, frame_seconds);
    rs.longest_frame_seconds = std::max(rs.longest_frame_seconds, frame_seconds);
    rs.simulated_seconds += frame_seconds;
    rs.host_seconds += host;
    ++rs.frames;
    if (!on_frame) return;
    try {
      on_frame(f, result);
      if (result.image.has_pixels()) {
        const std::lock_guard<std::mutex> lock(spare_mutex);
        if (spare_images.size() < 2) spare_images.push_back(std::move(result.image));
      }
    } catch (...) {
      // The units finish the frames they are on and start none after them (at most two are in
      // flight: none beyond the frame after the one every Renderer is on), so that no unit's
      // thread is left in the middle of a frame: what it holds there is never unwound.
      if (!source_error && (cancel_ == nullptr || !cancel_->load())) {
        machine.overlap(std::min(count, machine.clock().renderers_finished() + 2));
        event_->kernel.run(cancel_);
      }
      frames_ = count;  // no frame can follow
      throw;
    }
  };

  int handed = 0;
  while (handed < count || !pending.empty()) {
    if (cancel_ != nullptr && cancel_->load()) {  // between frames
      frames_ = count;
      throw FrameCancelled();
    }
    // What the helper thread has done, in frame order.
    while (!pending.empty() &&
           pending.front()->pixels.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
      deliver();
    if (handed < count && pending.size() < kFramesWaiting) {
      run_kernel([&] { return frame_done(handed); });
      if (handed == count - 1) {
        // The last frame: the kernel runs on until no event is left (the ring's last
        // bookings, for the ring's totals and the timeline).
        run_kernel({});
      }
      if (!frame_done(handed))
        throw std::logic_error(
            fmt::format("run_frames: the units did not finish frame {} of {} (no event was left)",
                        handed, count));
      hand_over(handed++);
      if (timeline_stream_ && !timeline) timeline_records(machine, stream_out, true);
    } else if (!pending.empty()) {
      deliver();
    }
  }
  if (timeline) *timeline = timeline_document(machine);
  if (timeline_stream_ && !timeline) {
    timeline_records(machine, stream_out, true);  // none left, unless the last frame's
    timeline_arrivals(machine, stream_out);
  }

  {
    const Ring& r = machine.ring();
    sum.ring_messages = r.messages();
    sum.ring_words = r.words();
    sum.ring_contention_cycles = r.contention().count;
    const double run_seconds = last_end;
    double busiest = 0;
    for (const RingCycles& c : r.busy())
      busiest = std::max(busiest, c.seconds(r.params().clock_hz));
    sum.ring_channel_utilisation_max = run_seconds > 0 ? busiest / run_seconds : 0;
  }
  sum.sustained_frame_seconds = count > 1 ? (last_end - first_end) / (count - 1) : first_end;
  const double period = sum.sustained_frame_seconds;
  sum.sustained_triangles_per_second = period > 0 ? triangles / period : 0;
  sum.sustained_spheres_per_second = period > 0 ? spheres / period : 0;
  const double gp_span = (gp_end - first_start) * static_cast<double>(gps.size());
  const double gp_busy = static_cast<double>(sum.gp_busy_clocks) / gp_hz;
  sum.gp_busy_share = gp_span > 0 ? gp_busy / gp_span : 0;
  sum.gp_wait_share = gp_span > 0 ? gp_wait.to_seconds() / gp_span : 0;
  const double later = last_end - first_end;
  sum.renderer_wait_share =
      later > 0 ? renderer_wait.to_seconds() / (later * machine.renderer_count()) : 0;
  sum.mean_latency_seconds = latency_sum / count;
  return summary_;
}

RunSummary simulate_frames(const MachineConfig& config, std::shared_ptr<const Scene> scene,
                           std::shared_ptr<const Program> program, int threads, int count,
                           const std::function<void(int frame, FrameResult& result)>& on_frame,
                           bool pixels, nlohmann::json* timeline, double setup_seconds,
                           TimelineStream* timeline_stream) {
  // The closed form first: its own SystemC context, freed before the session's is made.
  const double estimate =
      project_frame(config, *scene, *program).stats.real("frame.pipelined_frame_seconds");
  Session session(config, std::move(scene), std::move(program), threads);
  session.set_setup_seconds(setup_seconds);
  session.stream_timeline(timeline_stream);
  RunSummary summary = session.run_frames(count, on_frame, pixels, {}, timeline);
  summary.estimate_frame_seconds = estimate;
  return summary;
}

namespace {

// simulate_frame, or with `pixels` false project_frame: the one-frame case of a Session.
FrameResult run_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                      int threads, const std::function<BoardObserver*(int renderer)>& observe,
                      nlohmann::json* timeline, bool pixels, SetupMemo* memo,
                      double setup_seconds = 0) {
  // The caller owns the scene and the program: the session only refers to them.
  Session session(config, std::shared_ptr<const Scene>(&scene, [](const Scene*) {}),
                  std::shared_ptr<const Program>(&program, [](const Program*) {}), threads, memo);
  session.set_setup_seconds(setup_seconds);
  return session.frame(observe, timeline, pixels);
}

}  // namespace

FrameResult simulate_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                           int threads, const std::function<BoardObserver*(int renderer)>& observe,
                           nlohmann::json* timeline, SetupMemo* memo, double setup_seconds) {
  if (config.fidelity.timing == MachineConfig::Fidelity::Timing::analytic) {
    if (observe || timeline) {
      throw std::invalid_argument(
          "traces, snapshots and timelines need fidelity.timing=event (the analytic model runs "
          "no events and records no start cycles)");
    }
    return analytic_frame(config, scene, program, threads, memo, nullptr, setup_seconds);
  }
  if (observe && config.fidelity.pixels == MachineConfig::Fidelity::Pixels::none) {
    throw std::invalid_argument("an observer of the boards needs fidelity.pixels=bit or word");
  }
  return run_frame(config, scene, program, threads, observe, timeline, true, memo, setup_seconds);
}

FrameResult project_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                          SetupMemo* memo) {
  if (config.fidelity.timing == MachineConfig::Fidelity::Timing::analytic) {
    MachineConfig timing_only = config;
    timing_only.fidelity.pixels = MachineConfig::Fidelity::Pixels::none;
    return analytic_frame(timing_only, scene, program, 1, memo);
  }
  return run_frame(config, scene, program, 1, {}, nullptr, false, memo);
}

std::vector<StatisticInfo> describe_statistics(const std::string& program_path,
                                               const std::vector<std::string>& sets) {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "gp.count=1", "renderer.count=1"});
  config.set(sets);
  const Program program = assemble_file(program_path, assembler_options(config));
  return simulate_frame(config, make_builtin_scene("two-triangles"), program, 1).stats.describe();
}

std::vector<StatisticInfo> describe_run_statistics(const std::string& program_path) {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "gp.count=1", "renderer.count=1",
              "fidelity.pixels=none"});
  auto program =
      std::make_shared<const Program>(assemble_file(program_path, assembler_options(config)));
  auto scene = std::make_shared<const Scene>(make_builtin_scene("two-triangles"));
  std::vector<StatisticInfo> out;
  Session session(config, scene, program, 1);
  session.run_frames(
      1, [&out](int, FrameResult& r) { out = r.stats.describe(); }, false);
  for (StatisticInfo& i : session.summary().statistics().describe()) out.push_back(std::move(i));
  return out;
}

std::string bit_budget_table(const Program& program, const TimingParams& timing) {
  // The table itself comes from the report model (sim/run_report.hpp).
  std::string out = report::text(bit_budget(program));
  const OwnedValues none{};
  for (int k = 0; k < static_cast<int>(Procedure::count); ++k) {
    const ProcedureCode& code = program.procedures[k];
    if (code.spill_transfers == 0) continue;
    std::uint64_t cycles = 0;
    for (const Instruction& ins : code.code) {
      if (ins.line == 0) cycles += instruction_cost(ins, timing, none).count;
    }
    out += fmt::format("spilling adds {} backing-store transfers, {} array cycles, to each '{}'\n",
                       code.spill_transfers, cycles, kProcedureNames[k]);
  }
  return out;
}

std::string summary(const FrameResult& r, const Program& program, const TimingParams& timing) {
  const Statistics& s = r.stats;
  std::string out = bit_budget_table(program, timing);
  // A scene of spheres counts them beside its triangles (a sphere is one primitive, drawn
  // with the evaluator's quadratic terms, not a tessellation).
  const std::int64_t spheres = s.integer("frame.spheres");
  out += fmt::format("\nframe: {} triangles{}, {} packets, simulated {:.3f} ms ({} array cycles)\n",
                     s.integer("frame.triangles"),
                     spheres > 0 ? fmt::format(", {} spheres", spheres) : std::string(),
                     s.integer("setup.packets"), r.frame_seconds * 1e3,
                     s.integer("frame.array_cycles"));
  out += fmt::format(
      "projected throughput: {:.0f} triangles/s{}, {:.1f} frames/s\n", r.triangles_per_second,
      spheres > 0 && r.frame_seconds > 0
          ? fmt::format(", {:.0f} spheres/s", static_cast<double>(spheres) / r.frame_seconds)
          : std::string(),
      r.frame_seconds > 0 ? 1.0 / r.frame_seconds : 0.0);
  // A closed-form estimate: `render --frames N` simulates the overlap.
  const double pipelined = s.real("frame.pipelined_frame_seconds");
  out += fmt::format(
      "pipelined estimate (GPs on the next frame while the Renderers finish this one; closed "
      "form): {:.3f} ms, {:.0f} triangles/s{}\n",
      pipelined * 1e3, s.real("frame.pipelined_triangles_per_second"),
      spheres > 0 && pipelined > 0
          ? fmt::format(", {:.0f} spheres/s", static_cast<double>(spheres) / pipelined)
          : std::string());
  const double f = r.frame_seconds > 0 ? r.frame_seconds : 1;
  const double gp = s.real("timing.gp_seconds");
  const double ring = s.real("timing.ring_seconds");
  const double renderer = s.real("timing.renderer_seconds");
  out += fmt::format(
      "frame time on the critical path (renderer{}): GPs {:.3f} ms ({:.0f}%), ring {:.3f} ms "
      "({:.0f}%), Renderers {:.3f} ms ({:.0f}%)\n",
      s.integer("timing.critical_renderer"), gp * 1e3, 100 * gp / f, ring * 1e3, 100 * ring / f,
      renderer * 1e3, 100 * renderer / f);
  out += fmt::format("bottleneck: {}\n", s.text("timing.bottleneck"));
  out += fmt::format(
      "utilisation: GPs {:.0f}% mean, {:.0f}% max ({} code, {} i860 clocks per triangle); ring "
      "{:.0f}% of {:.2f} Gb/s, busiest channel {:.0f}%; Renderers {:.0f}% mean, {:.0f}% max "
      "({} balancing)\n",
      100 * s.real("timing.gp_utilisation_mean"), 100 * s.real("timing.gp_utilisation_max"),
      s.text("timing.gp_code"), s.real("frame.gp_clocks_per_triangle"),
      100 * s.real("timing.ring_utilisation"), s.real("ring.bandwidth_bits_per_second") / 1e9,
      100 * s.real("timing.ring_channel_utilisation_max"),
      100 * s.real("timing.renderer_utilisation_mean"),
      100 * s.real("timing.renderer_utilisation_max"), s.text("timing.balancing"));
  out += fmt::format("host: {:.3f} s ({:.3f} s timing, {:.3f} s pixels), {:.3g} array cycles/s\n",
                     s.real("host.seconds"), s.real("host.timing_seconds"),
                     s.real("host.pixel_seconds"),
                     s.real("host.simulated_array_cycles_per_host_second"));
  return out;
}

}  // namespace pp5

// libsystemc's own main() calls sc_main; pp5sim has its own main() and starts the kernel
// through simulate_frame(), but the shared library still needs the symbol to link.
int sc_main(int, char**) { return 1; }
