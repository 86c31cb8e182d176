#include "sim/simulation.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <systemc>

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/graphics_processor.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

namespace {

// SystemC allows one elaboration per kernel; a new simulation context gives every frame a
// fresh kernel, so that one process can simulate many frames. The old context is left
// alive on purpose: objects of the previous run may still refer to it while they unwind.
void fresh_kernel() {
  static bool first = true;
  if (first) {
    setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0);
    first = false;
    return;
  }
  sc_core::sc_curr_simcontext = new sc_core::sc_simcontext();
  sc_core::sc_default_global_context = sc_core::sc_curr_simcontext;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

FrameResult simulate_frame(const MachineConfig& config, const Scene& scene, const Program& program,
                           int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  fresh_kernel();
  auto machine = std::make_unique<Machine>("pp5", config, scene, program);
  sc_core::sc_start();
  const double timing_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  machine->execute_pixels(threads);
  const double pixel_seconds = seconds_since(t1);
  const double host_seconds = seconds_since(t0);

  FrameResult result;
  FrameBuffer& fb = machine->frame_buffer();
  result.image = fb.image();
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
                   {"utilisation", g.busy.seconds(config.gp.clock_hz) / result.frame_seconds},
                   {"triangles_in", g.triangles_in},
                   {"packets", g.packets},
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
                         {"utilisation", st.busy.seconds(array_hz) / result.frame_seconds},
                         {"regions", st.regions},
                         {"packets", st.packets},
                         {"micro_instructions", st.instructions},
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
  s["ring"] = {{"messages", ring.messages()}, {"words", ring.words()}, {"channels", channels}};
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
