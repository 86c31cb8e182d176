#include "models/renderer/analytic.hpp"

#include <algorithm>
#include <map>

#include "models/machine.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

namespace {

// The cycles Renderer::charge adds to the array's busy time for one step, without its waits:
// the packet overhead and every instruction's cost, a backing-store store costing only its
// issue cycle when transfers overlap the array (renderer.backing_store_overlap).
std::uint64_t busy_cycles(const ProcedureCode& code, const PacketValues& values,
                          const MachineConfig& config, const TimingParams& timing) {
  if (!code.defined) return 0;
  std::uint64_t cycles = static_cast<std::uint64_t>(config.renderer.packet_overhead_cycles);
  for (const Instruction& ins : code.code) {
    if (ins.op == Opcode::bsst && config.renderer.backing_store_overlap) {
      cycles += 1;
    } else {
      cycles += instruction_cost(ins, timing, values).count;
    }
  }
  return cycles;
}

std::uint64_t ceil_div(std::uint64_t a, std::uint64_t b) { return (a + b - 1) / b; }

}  // namespace

AnalyticTiming analytic_timing(Machine& machine) {
  const MachineConfig& config = machine.config();
  const Program& program = machine.program();
  const TimingParams& timing = machine.timing();
  const int gps = machine.gp_count();
  const int renderers = machine.renderer_count();
  const int regions = config.regions();
  const int passes = machine.passes();  // frame.layers for a program whose passes it sets
  const double gp_hz = config.gp.clock_hz;
  const double ring_hz = config.ring.clock_hz;
  const double array_hz = config.renderer.clock_hz;
  AnalyticTiming a;

  // GPs: the event model's geometry pass over the same blocks of the display list, then
  // the messages their bins make (Machine and GraphicsProcessor::run split them alike).
  const auto n = static_cast<long long>(machine.geometry().display_list().size());
  const std::uint64_t words = machine.gp_workload().packet_words;
  const std::uint64_t per_message =
      (static_cast<std::uint64_t>(config.renderer.queue_words) - 1) / words;
  const std::uint64_t send_clocks = machine.i860().clocks(I860Work::send_bin(), 0).count;
  a.gps.resize(static_cast<std::size_t>(gps));
  a.gp_send_clocks.assign(static_cast<std::size_t>(gps), 0);
  a.gp_words.assign(static_cast<std::size_t>(gps), 0);
  a.gp_messages.assign(static_cast<std::size_t>(gps), 0);
  // Each region's packets, GP after GP: display-list order.
  std::vector<std::vector<std::shared_ptr<const Packet>>> region_packets(
      static_cast<std::size_t>(regions));
  std::vector<std::vector<std::shared_ptr<const Packet>>> bins;
  double geometry_end = 0;
  for (int k = 0; k < gps; ++k) {
    const int first = static_cast<int>(n * k / gps);
    const int last = static_cast<int>(n * (k + 1) / gps);
    if (last == first) continue;  // an idle GP sends nothing, not even a map
    GpStats& st = a.gps[static_cast<std::size_t>(k)];
    geometry_pass(machine, first, last, st, bins);
    std::uint64_t messages = 1;  // the bin map
    std::uint64_t sent = machine.bin_map_words();
    for (int r = 0; r < regions; ++r) {
      const auto& bin = bins[static_cast<std::size_t>(r)];
      if (bin.empty()) continue;
      const std::uint64_t m = ceil_div(bin.size(), per_message);
      messages += m * passes;
      sent += (m + bin.size() * words) * passes;  // a header word per message
      auto& into = region_packets[static_cast<std::size_t>(r)];
      into.insert(into.end(), bin.begin(), bin.end());
    }
    a.gp_messages[static_cast<std::size_t>(k)] = messages;
    a.gp_words[static_cast<std::size_t>(k)] = sent;
    a.gp_send_clocks[static_cast<std::size_t>(k)] = messages * send_clocks;
    st.busy = st.geometry + GpClocks(messages * send_clocks);
    st.messages = messages;
    a.ring_words += sent;
    a.ring_messages += messages;
    geometry_end = std::max(geometry_end, static_cast<double>(st.geometry.count) / gp_hz);
  }
  a.geometry_seconds = geometry_end;

  // Renderers: each region's cycles from the instruction table, as Renderer::run charges
  // them. No cost formula reads a packet's expressions (only widths, literals and frame
  // parameters), so every packet of a procedure costs the same: one sum per procedure.
  const RegionStream stream(program, machine.frame_values());
  std::uint64_t empty_cycles = 0;
  stream.for_each_empty([&](const RegionStep& step) {
    empty_cycles += busy_cycles(step.code, step.values, config, timing);
  });
  std::map<Procedure, std::uint64_t> packet_cycles;
  const std::uint64_t load =
      config.evaluator.double_buffered
          ? 0
          : ceil_div(words > 0 ? words - 1 : 0,
                     static_cast<std::uint64_t>(config.evaluator.coefficient_words_per_cycle));
  std::uint64_t copy_cycles = 0;
  if (config.renderer.overlap_shipping) {
    const int blocks = (config.frame_buffer.bits_per_pixel + config.renderer.block_bits - 1) /
                       config.renderer.block_bits;
    copy_cycles = static_cast<std::uint64_t>(blocks) *
                  static_cast<std::uint64_t>(config.renderer.backing_store_cycles_per_block);
  }
  a.work.assign(static_cast<std::size_t>(renderers), {});
  a.renderer_busy_cycles.assign(static_cast<std::size_t>(renderers), 0);
  a.renderer_packets.assign(static_cast<std::size_t>(renderers), 0);
  const bool dynamic = config.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic;
  for (int r = 0; r < regions; ++r) {
    auto& packets = region_packets[static_cast<std::size_t>(r)];
    std::uint64_t cycles = empty_cycles + copy_cycles;
    for (const auto& p : packets) {
      if (!machine.frame_values().plan.empty()) {
        // A pass plan: each pass runs the packet with its procedure, or not at all.
        for (int pass = 0; pass < passes; ++pass) {
          const RegionStep step = stream.packet(*p, pass, 0);
          if (step.code.defined)
            cycles += busy_cycles(step.code, step.values, config, timing) + load;
        }
        continue;
      }
      auto it = packet_cycles.find(p->procedure);
      if (it == packet_cycles.end()) {
        const RegionStep step = stream.packet(*p, 0, 0);
        it =
            packet_cycles.emplace(p->procedure, busy_cycles(step.code, step.values, config, timing))
                .first;
      }
      cycles += (it->second + load) * passes;
    }
    int owner = r % renderers;
    if (dynamic) {
      owner = static_cast<int>(
          std::min_element(a.renderer_busy_cycles.begin(), a.renderer_busy_cycles.end()) -
          a.renderer_busy_cycles.begin());
    }
    a.renderer_busy_cycles[static_cast<std::size_t>(owner)] += cycles;
    a.renderer_packets[static_cast<std::size_t>(owner)] += packets.size() * passes;
    RegionWork w;
    w.region = r;
    w.x0 = (r % config.regions_x()) * config.renderer.region_width;
    w.y0 = (r / config.regions_x()) * config.renderer.region_height;
    w.triangles = std::move(packets);
    // Start cycles are for traces, which need the event model: zeros of the right size.
    std::uint64_t steps = 0;
    stream.for_each_empty([&](const RegionStep&) { ++steps; });
    w.step_start.assign(steps, 0);
    w.packet_start.assign(w.triangles.size() * static_cast<std::size_t>(passes), 0);
    a.work[static_cast<std::size_t>(owner)].push_back(std::move(w));
  }
  a.ring_words += static_cast<std::uint64_t>(regions) * machine.region_words();
  a.ring_messages += static_cast<std::uint64_t>(regions);

  // The closed form.
  Ring& ring = machine.ring();
  double map_seconds = 0;
  for (int k = 0; k < gps; ++k) {
    if (a.gp_messages[static_cast<std::size_t>(k)] == 0) continue;
    double farthest = 0;
    for (int j = 0; j < renderers; ++j) {
      farthest = std::max(
          farthest, ring.hop_delay(machine.gp_stop(k), machine.renderer_stop(j)).to_seconds());
    }
    const double geometry =
        static_cast<double>(a.gps[static_cast<std::size_t>(k)].geometry.count) / gp_hz;
    map_seconds = std::max(map_seconds, geometry + static_cast<double>(send_clocks) / gp_hz +
                                            static_cast<double>(machine.bin_map_words()) / ring_hz +
                                            farthest);
  }
  a.fill_seconds = map_seconds;
  for (int k = 0; k < gps; ++k) {
    // After its map, a GP starts each message and holds its ring interface for its words.
    const auto i = static_cast<std::size_t>(k);
    if (a.gp_messages[i] == 0) continue;
    const double sending = static_cast<double>((a.gp_messages[i] - 1) * send_clocks) / gp_hz +
                           static_cast<double>(a.gp_words[i] - machine.bin_map_words()) / ring_hz;
    a.gp_busiest_seconds = std::max(a.gp_busiest_seconds, sending);
  }
  a.ring_seconds = static_cast<double>(a.ring_words) / (config.ring.channels * ring_hz);
  // Without overlapped shipping a Renderer also waits for each of its regions to cross.
  const double ship_wait =
      config.renderer.overlap_shipping ? 0 : static_cast<double>(machine.region_words()) / ring_hz;
  for (int j = 0; j < renderers; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const double t = static_cast<double>(a.renderer_busy_cycles[i]) / array_hz +
                     ship_wait * static_cast<double>(a.work[i].size());
    if (t > a.renderer_busiest_seconds) {
      a.renderer_busiest_seconds = t;
      a.busiest_renderer = j;
    }
  }
  a.busiest_seconds = a.renderer_busiest_seconds;
  a.busiest_unit = "Renderers";
  if (a.ring_seconds > a.busiest_seconds)
    a.busiest_seconds = a.ring_seconds, a.busiest_unit = "ring";
  if (a.gp_busiest_seconds > a.busiest_seconds) {
    a.busiest_seconds = a.gp_busiest_seconds;
    a.busiest_unit = "GPs";
  }
  double drain = 0;
  for (int j = 0; j < renderers; ++j) {
    drain = std::max(
        drain, ring.hop_delay(machine.renderer_stop(j), machine.frame_buffer_stop()).to_seconds());
  }
  a.drain_seconds = static_cast<double>(machine.region_words()) / ring_hz + drain;
  a.frame_seconds = a.fill_seconds + a.busiest_seconds + a.drain_seconds;
  return a;
}

}  // namespace pp5
