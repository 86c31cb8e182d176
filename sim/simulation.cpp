#include "sim/simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <systemc>

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/graphics_processor.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"
#include "sim/kernel.hpp"

namespace pp5 {

namespace {

// Chrome trace-event JSON: one process per kind of unit, one thread per unit, complete
// ("X") slices in microseconds. Slices of one track are recorded in time order and nest.
nlohmann::json timeline_document(Machine& machine) {
  using nlohmann::json;
  json events = json::array();
  const char* kinds[] = {"Graphics Processors", "Ring channels", "Renderers", "Frame buffer"};
  const int counts[] = {machine.gp_count(), machine.ring().params().channels,
                        machine.renderer_count(), 1};
  const char* names[] = {"gp", "channel ", "renderer", "frame buffer"};
  for (int k = 0; k < 4; ++k) {
    events.push_back({{"ph", "M"},
                      {"name", "process_name"},
                      {"pid", k + 1},
                      {"tid", 0},
                      {"args", {{"name", kinds[k]}}}});
    events.push_back({{"ph", "M"},
                      {"name", "process_sort_index"},
                      {"pid", k + 1},
                      {"tid", 0},
                      {"args", {{"sort_index", k}}}});
    for (int i = 0; i < counts[k]; ++i) {
      events.push_back(
          {{"ph", "M"},
           {"name", "thread_name"},
           {"pid", k + 1},
           {"tid", i},
           {"args", {{"name", k == 3 ? std::string(names[k]) : names[k] + std::to_string(i)}}}});
    }
  }
  auto us = [](sc_core::sc_time t) { return t.to_seconds() * 1e6; };
  for (const TimelineSlice& sl : machine.slices()) {
    events.push_back({{"ph", "X"},
                      {"name", sl.name},
                      {"pid", static_cast<int>(sl.unit) + 1},
                      {"tid", sl.index},
                      {"ts", us(sl.start)},
                      {"dur", us(sl.end - sl.start)}});
  }
  auto stop_name = [&](int stop) {
    if (stop < machine.gp_count()) return "gp" + std::to_string(stop);
    if (stop < machine.frame_buffer_stop())
      return "renderer" + std::to_string(stop - machine.gp_count());
    return std::string("frame buffer");
  };
  for (const RingMessage& m : machine.ring().messages_log()) {
    events.push_back({{"ph", "X"},
                      {"name", stop_name(m.from) + " -> " + stop_name(m.to)},
                      {"pid", 2},
                      {"tid", m.channel},
                      {"ts", us(m.start)},
                      {"dur", us(m.end - m.start)},
                      {"args", {{"words", m.words}, {"arrival_us", us(m.arrival)}}}});
  }
  const auto& arrivals = machine.frame_buffer().arrivals();
  for (std::size_t r = 0; r < arrivals.size(); ++r) {
    events.push_back({{"ph", "i"},
                      {"s", "t"},
                      {"name", "region " + std::to_string(r)},
                      {"pid", 4},
                      {"tid", 0},
                      {"ts", us(arrivals[r])}});
  }
  return {{"traceEvents", events}, {"displayTimeUnit", "ns"}};
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

namespace {

double mean_of(const nlohmann::json& units, const char* key) {
  double sum = 0;
  for (const auto& u : units) sum += u[key].get<double>();
  return units.empty() ? 0 : sum / static_cast<double>(units.size());
}
double max_of(const nlohmann::json& units, const char* key) {
  double m = 0;
  for (const auto& u : units) m = std::max(m, u[key].get<double>());
  return m;
}

// Splits the frame time along the critical path: the Renderer whose last region reaches the
// frame buffer last. Its time is its array's work (Renderers), its waits for messages no GP
// had asked for yet (GPs), its waits for messages still crossing the ring, its blocked
// shipping and the final region's trip to the frame buffer (ring).
nlohmann::json frame_attribution(Machine& machine, double frame_seconds, const nlohmann::json& s) {
  const MachineConfig& config = machine.config();
  int critical = 0;
  for (int k = 1; k < machine.renderer_count(); ++k) {
    if (machine.renderer(k).stats().finished > machine.renderer(critical).stats().finished)
      critical = k;
  }
  const RendererStats& st = machine.renderer(critical).stats();
  const double renderer = (st.busy.count + st.stall.count) / config.renderer.clock_hz +
                          st.waiting_renderers.to_seconds();
  const double gps = st.waiting_gp.to_seconds();
  const double ring = st.waiting_ring.to_seconds() + st.waiting_ship.to_seconds() +
                      (st.finished - st.computed).to_seconds();
  const double other = std::max(0.0, frame_seconds - renderer - gps - ring);
  std::string bottleneck = "Renderers";
  double top = renderer;
  if (gps > top) bottleneck = "GPs", top = gps;
  if (ring > top) bottleneck = "ring", top = ring;
  return {{"critical_renderer", critical},
          {"gp_seconds", gps},
          {"ring_seconds", ring},
          {"renderer_seconds", renderer},
          {"unattributed_seconds", other},
          {"bottleneck", bottleneck},
          {"gp_utilisation_mean", mean_of(s["gp"], "utilisation")},
          {"gp_utilisation_max", max_of(s["gp"], "utilisation")},
          {"renderer_utilisation_mean", mean_of(s["renderer"], "utilisation")},
          {"renderer_utilisation_max", max_of(s["renderer"], "utilisation")},
          {"ring_utilisation", s["ring"]["utilisation"].get<double>()},
          {"ring_channel_utilisation_max", max_of(s["ring"]["channels"], "utilisation")},
          {"gp_code", name_of(config.gp.code)},
          {"balancing", name_of(config.renderer.balancing)}};
}

}  // namespace

FrameResult simulate_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                           int threads, const std::function<BoardObserver*(int renderer)>& observe,
                           nlohmann::json* timeline) {
  const auto t0 = std::chrono::steady_clock::now();
  fresh_kernel();
  auto machine = std::make_unique<Machine>("pp5", config, scene, program);
  machine->record_timeline(timeline != nullptr);
  run_kernel();
  if (timeline) *timeline = timeline_document(*machine);
  const double timing_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  machine->execute_pixels(threads, observe);
  const double pixel_seconds = seconds_since(t1);
  const double host_seconds = seconds_since(t0);

  FrameResult result;
  FrameBuffer& fb = machine->frame_buffer();
  result.image = fb.take_image();
  result.frame_seconds = fb.frame_complete().to_seconds();
  const auto triangles = scene.mesh.triangles.size();
  result.triangles_per_second =
      result.frame_seconds > 0 ? static_cast<double>(triangles) / result.frame_seconds : 0;

  using nlohmann::json;
  json& s = result.stats;
  const double array_hz = config.renderer.clock_hz;
  const auto frame_array_cycles =
      static_cast<std::uint64_t>(std::llround(result.frame_seconds * array_hz));
  s["frame"] = {
      {"scene", scene.name},
      {"firmware", program.name},
      {"triangles", triangles},
      {"simulated_seconds", result.frame_seconds},
      {"array_cycles", frame_array_cycles},
      {"projected_triangles_per_second", result.triangles_per_second},
      {"projected_frames_per_second", result.frame_seconds > 0 ? 1.0 / result.frame_seconds : 0},
  };
  SetupCounts setup;
  json gps = json::array();
  std::uint64_t packets = 0;
  for (int k = 0; k < machine->gp_count(); ++k) {
    const GpStats& g = machine->gp(k).stats();
    gps.push_back({{"busy_clocks", g.busy.count},
                   {"geometry_clocks", g.geometry.count},
                   {"utilisation", g.busy.seconds(config.gp.clock_hz) / result.frame_seconds},
                   {"triangles_in", g.triangles_in},
                   {"packets", g.packets},
                   {"messages", g.messages},
                   {"operations",
                    {{"fadd", g.ops.fadd},
                     {"fmul", g.ops.fmul},
                     {"load", g.ops.load},
                     {"store", g.ops.store},
                     {"integer", g.ops.integer},
                     {"branch", g.ops.branch},
                     {"chains", g.ops.chains}}},
                   {"waiting_for_stage_seconds", g.waiting_stage.to_seconds()},
                   {"waiting_for_queue_seconds", g.waiting_queue.to_seconds()},
                   {"sending_seconds", g.waiting_ring.to_seconds()},
                   {"geometry_done_seconds", g.geometry_done.to_seconds()},
                   {"finished_seconds", g.finished.to_seconds()}});
    packets += g.packets;
    setup.clipped_away += g.setup.clipped_away;
    setup.degenerate += g.setup.degenerate;
    setup.no_pixels += g.setup.no_pixels;
    setup.overflow += g.setup.overflow;
    setup.clip_splits += g.setup.clip_splits;
    setup.culled += g.setup.culled;
  }
  s["gp"] = gps;
  // With frames pipelined, as on the real machine, the GPs transform frame n + 1 while the
  // ring and Renderers finish frame n: the period is the longer of the two phases.
  double geometry_end = 0;
  double gp_busy = 0;
  for (int k = 0; k < machine->gp_count(); ++k) {
    const GpStats& g = machine->gp(k).stats();
    geometry_end = std::max(geometry_end, g.geometry_done.to_seconds());
    gp_busy = std::max(gp_busy, g.busy.seconds(config.gp.clock_hz));
  }
  const double pipelined = std::max(gp_busy, result.frame_seconds - geometry_end);
  s["frame"]["pipelined_frame_seconds"] = pipelined;
  s["frame"]["pipelined_triangles_per_second"] =
      pipelined > 0 ? static_cast<double>(triangles) / pipelined : 0;
  std::uint64_t geometry_clocks = 0;
  for (const auto& g : gps) geometry_clocks += g["geometry_clocks"].get<std::uint64_t>();
  s["frame"]["gp_clocks_per_triangle"] =
      triangles ? std::round(static_cast<double>(geometry_clocks) / triangles) : 0.0;
  s["setup"] = {{"packets", packets},
                {"clipped_away", setup.clipped_away},
                {"clip_splits", setup.clip_splits},
                {"culled", setup.culled},
                {"degenerate", setup.degenerate},
                {"no_pixel_centres", setup.no_pixels},
                {"coefficient_overflow", setup.overflow}};
  json renderers = json::array();
  std::uint64_t instructions = 0;
  std::uint64_t busy_cycles = 0;
  std::vector<std::uint64_t> per_region(config.regions(), 0);
  for (int k = 0; k < machine->renderer_count(); ++k) {
    const Renderer& r = machine->renderer(k);
    const RendererStats& st = r.stats();
    renderers.push_back({{"busy_cycles", st.busy.count},
                         {"backing_store_stall_cycles", st.stall.count},
                         {"utilisation", st.busy.seconds(array_hz) / result.frame_seconds},
                         {"waiting_for_gps_seconds", st.waiting_gp.to_seconds()},
                         {"waiting_for_ring_seconds", st.waiting_ring.to_seconds()},
                         {"waiting_for_other_renderers_seconds", st.waiting_renderers.to_seconds()},
                         {"blocked_shipping_seconds", st.waiting_ship.to_seconds()},
                         {"regions", st.regions},
                         {"packets", st.packets},
                         {"messages", st.messages},
                         {"queue_peak_words", st.queue_peak_words},
                         {"micro_instructions", st.instructions},
                         {"computed_seconds", st.computed.to_seconds()},
                         {"finished_seconds", st.finished.to_seconds()}});
    instructions += st.instructions;
    busy_cycles += st.busy.count;
    for (const RegionWork& w : r.work()) per_region[w.region] = w.triangles.size();
  }
  s["renderer"] = renderers;
  s["renderers_total"] = {{"busy_cycles", busy_cycles}, {"micro_instructions", instructions}};
  s["primitives_per_region"] = per_region;
  const Ring& ring = machine->ring();
  json channels = json::array();
  for (const RingCycles& c : ring.busy()) {
    channels.push_back({{"busy_cycles", c.count},
                        {"utilisation", c.seconds(config.ring.clock_hz) / result.frame_seconds}});
  }
  const double ring_capacity_words =
      config.ring.channels * config.ring.clock_hz * result.frame_seconds;
  s["ring"] = {
      {"messages", ring.messages()},
      {"words", ring.words()},
      {"bandwidth_bits_per_second", ring.bandwidth_bits_per_second()},
      {"utilisation",
       ring_capacity_words > 0 ? static_cast<double>(ring.words()) / ring_capacity_words : 0},
      {"contention_cycles", ring.contention().count},
      {"channels", channels}};
  s["timing"] = frame_attribution(*machine, result.frame_seconds, s);
  s["pixel_memory"] = {{"bits", program.memory_bits},
                       {"used", program.bits_used()},
                       {"resident", program.resident_bits},
                       {"staging", program.staging_bits}};
  s["host"] = {
      {"seconds", host_seconds},
      {"timing_seconds", timing_seconds},
      {"pixel_seconds", pixel_seconds},
      {"threads", threads},
      {"simulated_array_cycles_per_host_second",
       host_seconds > 0 ? static_cast<double>(busy_cycles) / host_seconds : 0},
  };
  machine.reset();
  return result;
}

std::string bit_budget_table(const Program& program, const TimingParams& timing) {
  std::string out = fmt::format("{:<16} {:>5}  {}\n", "field", "bits", "where");
  for (const FieldDecl& f : program.fields) {
    out += fmt::format("{:<16} {:>5}  {}\n", f.name, f.width,
                       f.spilled ? fmt::format("backing store, block {}", f.block)
                                 : fmt::format("pixel memory [{}:{}]", f.lo + f.width - 1, f.lo));
  }
  if (program.staging_bits) {
    out += fmt::format("{:<16} {:>5}  staging for spilled fields\n", "(staging)",
                       program.staging_bits);
  }
  out += fmt::format("{:<16} {:>5}  of {} bits ({:.0f}%)\n", "total", program.bits_used(),
                     program.memory_bits, 100.0 * program.bits_used() / program.memory_bits);
  const PacketValues none{};
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
  const auto& s = r.stats;
  std::string out = bit_budget_table(program, timing);
  out += fmt::format("\nframe: {} triangles, {} packets, simulated {:.3f} ms ({} array cycles)\n",
                     s["frame"]["triangles"].get<std::uint64_t>(),
                     s["setup"]["packets"].get<std::uint64_t>(), r.frame_seconds * 1e3,
                     s["frame"]["array_cycles"].get<std::uint64_t>());
  out += fmt::format("projected throughput: {:.0f} triangles/s, {:.1f} frames/s\n",
                     r.triangles_per_second, r.frame_seconds > 0 ? 1.0 / r.frame_seconds : 0.0);
  out += fmt::format(
      "pipelined (GPs on the next frame while the Renderers finish this one): {:.3f} ms, {:.0f} "
      "triangles/s\n",
      s["frame"]["pipelined_frame_seconds"].get<double>() * 1e3,
      s["frame"]["pipelined_triangles_per_second"].get<double>());
  const auto& t = s["timing"];
  const double f = r.frame_seconds > 0 ? r.frame_seconds : 1;
  out += fmt::format(
      "frame time on the critical path (renderer{}): GPs {:.3f} ms ({:.0f}%), ring {:.3f} ms "
      "({:.0f}%), Renderers {:.3f} ms ({:.0f}%)\n",
      t["critical_renderer"].get<int>(), t["gp_seconds"].get<double>() * 1e3,
      100 * t["gp_seconds"].get<double>() / f, t["ring_seconds"].get<double>() * 1e3,
      100 * t["ring_seconds"].get<double>() / f, t["renderer_seconds"].get<double>() * 1e3,
      100 * t["renderer_seconds"].get<double>() / f);
  out += fmt::format("bottleneck: {}\n", t["bottleneck"].get<std::string>());
  out += fmt::format(
      "utilisation: GPs {:.0f}% mean, {:.0f}% max ({} code, {} i860 clocks per triangle); ring "
      "{:.0f}% of {:.2f} Gb/s, busiest channel {:.0f}%; Renderers {:.0f}% mean, {:.0f}% max "
      "({} balancing)\n",
      100 * t["gp_utilisation_mean"].get<double>(), 100 * t["gp_utilisation_max"].get<double>(),
      t["gp_code"].get<std::string>(), s["frame"]["gp_clocks_per_triangle"].get<double>(),
      100 * t["ring_utilisation"].get<double>(),
      s["ring"]["bandwidth_bits_per_second"].get<double>() / 1e9,
      100 * t["ring_channel_utilisation_max"].get<double>(),
      100 * t["renderer_utilisation_mean"].get<double>(),
      100 * t["renderer_utilisation_max"].get<double>(), t["balancing"].get<std::string>());
  out += fmt::format("host: {:.2f} s ({:.2f} s timing, {:.2f} s pixels), {:.3g} array cycles/s\n",
                     s["host"]["seconds"].get<double>(), s["host"]["timing_seconds"].get<double>(),
                     s["host"]["pixel_seconds"].get<double>(),
                     s["host"]["simulated_array_cycles_per_host_second"].get<double>());
  return out;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", tmp));
    out << text;
    out.close();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error(fmt::format("{}: write failed", tmp));
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot rename into place", path));
  }
}

}  // namespace pp5

// libsystemc's own main() calls sc_main; pp5sim has its own main() and starts the kernel
// through simulate_frame(), but the shared library still needs the symbol to link.
int sc_main(int, char**) { return 1; }
