#include "models/renderer/analytic.hpp"

#include <algorithm>
#include <stdexcept>

#include "models/gp/primitive_kind.hpp"
#include "models/gp/setup_memo.hpp"

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

AnalyticTiming analytic_timing(const MachinePlan& plan) {
  const MachineConfig& config = plan.config();
  const Program& program = plan.program();
  const TimingParams& timing = plan.timing();
  const int gps = plan.gp_count();
  const int renderers = plan.renderer_count();
  const int regions = config.regions();
  const int passes = plan.passes();  // frame.layers for a program whose passes it sets
  const double gp_hz = config.gp.clock_hz;
  const double ring_hz = config.ring.clock_hz;
  const double array_hz = config.renderer.clock_hz;
  SetupMemo* memo = plan.setup_memo();
  if (memo == nullptr) {
    throw std::logic_error("analytic_timing: the plan has no set-up memo (use_setup_memo)");
  }
  AnalyticTiming a;

  // The set-up, once per memo key: the event model's geometry pass over the display list.
  const int n = static_cast<int>(plan.geometry().display_list().size());
  if (!memo->complete()) {
    GpStats scratch;
    geometry_pass(plan, 0, n, scratch, nullptr);
  }
  const SetupMemo::Summary& summary = memo->summary(regions);

  // GPs: each one's share of the display list summed from the summary, then the messages
  // its bins make (Machine and GraphicsProcessor::run split them alike).
  // A message carries a header word and as many of the bin's next packets as fit in a
  // Renderer's queue (GraphicsProcessor::run); packets of one kind all have the same words.
  const auto capacity = static_cast<std::uint64_t>(config.renderer.queue_words);
  const std::uint64_t uniform = summary.uniform_words;
  const std::uint64_t per_message = uniform > 0 ? (capacity - 1) / uniform : 0;
  const std::uint64_t send_clocks = plan.i860().clocks(I860Work::send_bin(), 0).count;
  a.gps.resize(static_cast<std::size_t>(gps));
  a.gp_send_clocks.assign(static_cast<std::size_t>(gps), 0);
  a.gp_words.assign(static_cast<std::size_t>(gps), 0);
  a.gp_messages.assign(static_cast<std::size_t>(gps), 0);
  // Each tally class's cost, from its kind's workload.
  std::vector<GpWorkload> workloads;
  for (const PrimitiveKind* k : primitive_kinds()) workloads.push_back(kind_workload(plan, *k));
  std::vector<PrimitiveCost> class_cost;
  for (const auto& c : summary.classes) {
    const auto kind = static_cast<std::size_t>(c.kind);
    class_cost.push_back(primitive_cost(plan, *primitive_kinds()[kind], workloads[kind], c.tally));
  }
  std::vector<std::uint32_t> in_class;
  std::size_t counted = 0;  // the next of summary.counted
  double geometry_end = 0;
  std::vector<int> block_end;  // per GP, the end of its block
  for (int k = 0; k < gps; ++k) {
    const auto [first, last] = plan.gp_block(k);
    block_end.push_back(last);
    if (last == first) continue;  // an idle GP sends nothing, not even a map
    GpStats& st = a.gps[static_cast<std::size_t>(k)];
    st.triangles_in = static_cast<std::uint64_t>(last - first);
    summary.count_classes(first, last, in_class);
    for (std::size_t c = 0; c < in_class.size(); ++c) {
      if (in_class[c] == 0) continue;
      const PrimitiveTally& t = summary.classes[c].tally;
      st.screen_triangles += static_cast<std::uint64_t>(t.pieces) * in_class[c];
      st.packets += static_cast<std::uint64_t>(t.regions) * in_class[c];
      st.ops += class_cost[c].ops * in_class[c];
      st.geometry += GpClocks(class_cost[c].clocks.count * in_class[c]);
    }
    for (; counted < summary.counted.size() && summary.counted[counted].first < last; ++counted) {
      st.setup += summary.counted[counted].second;
    }
    geometry_end = std::max(geometry_end, static_cast<double>(st.geometry.count) / gp_hz);
    a.gp_messages[static_cast<std::size_t>(k)] = 1;  // the bin map
    a.gp_words[static_cast<std::size_t>(k)] = plan.bin_map_words();
  }
  // Each GP's bin of each region: the region's packets from the GP's block, which follow
  // one another since the region's packets are in display-list order.
  for (int r = 0; r < regions; ++r) {
    const int* primitive = summary.region_primitive.data();
    std::uint32_t at = summary.region_first[static_cast<std::size_t>(r)];
    const std::uint32_t end = summary.region_first[static_cast<std::size_t>(r) + 1];
    for (int k = 0; k < gps && at < end; ++k) {
      const int last = block_end[static_cast<std::size_t>(k)];
      const std::uint32_t from = at;
      std::uint64_t m = 0, sent = 0;
      if (uniform > 0) {
        while (at < end && primitive[at] < last) ++at;
        const std::uint64_t bin = at - from;
        m = ceil_div(bin, per_message);
        sent = m + bin * uniform;  // a header word per message
      } else {  // packets of several kinds: filled one by one, as the GP fills them
        std::uint64_t used = capacity;
        for (; at < end && primitive[at] < last; ++at) {
          const std::uint64_t w = summary.region_words[at];
          if (used + w > capacity) ++m, used = 1, sent += 1;
          used += w;
          sent += w;
        }
      }
      a.gp_messages[static_cast<std::size_t>(k)] += m * passes;
      a.gp_words[static_cast<std::size_t>(k)] += sent * passes;
    }
  }
  for (int k = 0; k < gps; ++k) {
    const auto i = static_cast<std::size_t>(k);
    if (a.gp_messages[i] == 0) continue;
    GpStats& st = a.gps[i];
    a.gp_send_clocks[i] = a.gp_messages[i] * send_clocks;
    st.busy = st.geometry + GpClocks(a.gp_send_clocks[i]);
    st.messages = a.gp_messages[i];
    a.ring_words += a.gp_words[i];
    a.ring_messages += a.gp_messages[i];
  }
  a.geometry_seconds = geometry_end;

  // Renderers: each region's cycles from the instruction table, as Renderer::run charges
  // them. No cost formula reads a packet's expressions (only widths, literals and frame
  // parameters), so every packet running one procedure costs the same: one sum per
  // procedure, and one step per (procedure, solid, facing) of a region's packets.
  const RegionStream stream(program, plan.frame_values());
  std::uint64_t empty_cycles = 0;
  stream.for_each_empty([&](const RegionStep& step) {
    empty_cycles += busy_cycles(step.code, step.values, config, timing);
  });
  std::vector<std::pair<const ProcedureCode*, std::uint64_t>> code_cycles;
  auto cycles_of = [&](const RegionStep& step) {
    for (const auto& [code, cycles] : code_cycles) {
      if (code == &step.code) return cycles;
    }
    code_cycles.emplace_back(&step.code, busy_cycles(step.code, step.values, config, timing));
    return code_cycles.back().second;
  };
  // A packet's coefficients (its words after the header) move into the evaluator, unless
  // double buffering hides the move (Renderer::load_coefficients).
  auto load = [&config](const Packet& p) -> std::uint64_t {
    if (config.evaluator.double_buffered) return 0;
    return ceil_div(p.words > 0 ? p.words - 1 : 0,
                    static_cast<std::uint64_t>(config.evaluator.coefficient_words_per_cycle));
  };
  std::uint64_t copy_cycles = 0;
  if (config.renderer.overlap_shipping) {
    const int blocks = (config.frame_buffer.bits_per_pixel + config.renderer.block_bits - 1) /
                       config.renderer.block_bits;
    copy_cycles = static_cast<std::uint64_t>(blocks) *
                  static_cast<std::uint64_t>(config.renderer.backing_store_cycles_per_block);
  }
  a.regions.assign(static_cast<std::size_t>(renderers), {});
  a.region_cycles.assign(static_cast<std::size_t>(regions), 0);
  a.renderer_busy_cycles.assign(static_cast<std::size_t>(renderers), 0);
  a.renderer_packets.assign(static_cast<std::size_t>(renderers), 0);
  const bool dynamic = config.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic;
  const bool planned = !plan.frame_values().plan.empty();
  for (int r = 0; r < regions; ++r) {
    const auto i = static_cast<std::size_t>(r);
    std::uint64_t cycles = empty_cycles + copy_cycles;
    for (std::uint32_t g = summary.signature_first[i]; g < summary.signature_first[i + 1]; ++g) {
      const SetupMemo::Summary::Signature& sig = summary.signatures[g];
      if (planned) {
        // A pass plan: each pass runs the packet with its procedure, or not at all.
        for (int pass = 0; pass < passes; ++pass) {
          const RegionStep step = stream.packet(*sig.example, pass, 0);
          if (step.code.defined) cycles += (cycles_of(step) + load(*sig.example)) * sig.count;
        }
      } else {
        cycles += (cycles_of(stream.packet(*sig.example, 0, 0)) + load(*sig.example)) * passes *
                  sig.count;
      }
    }
    int owner = r % renderers;
    if (dynamic) {
      owner = static_cast<int>(
          std::min_element(a.renderer_busy_cycles.begin(), a.renderer_busy_cycles.end()) -
          a.renderer_busy_cycles.begin());
    }
    const std::uint64_t packets = summary.region_first[i + 1] - summary.region_first[i];
    a.renderer_busy_cycles[static_cast<std::size_t>(owner)] += cycles;
    a.renderer_packets[static_cast<std::size_t>(owner)] += packets * passes;
    a.region_cycles[i] = cycles;
    a.regions[static_cast<std::size_t>(owner)].push_back(r);
  }
  a.ring_words += static_cast<std::uint64_t>(regions) * plan.region_words();
  a.ring_messages += static_cast<std::uint64_t>(regions);

  // The closed form.
  double map_seconds = 0;
  for (int k = 0; k < gps; ++k) {
    if (a.gp_messages[static_cast<std::size_t>(k)] == 0) continue;
    double farthest = 0;
    for (int j = 0; j < renderers; ++j) {
      farthest =
          std::max(farthest, plan.hop_delay(plan.gp_stop(k), plan.renderer_stop(j)).to_seconds());
    }
    const double geometry =
        static_cast<double>(a.gps[static_cast<std::size_t>(k)].geometry.count) / gp_hz;
    map_seconds =
        std::max(map_seconds, geometry + static_cast<double>(send_clocks) / gp_hz +
                                  static_cast<double>(plan.bin_map_words()) / ring_hz + farthest);
  }
  a.fill_seconds = map_seconds;
  for (int k = 0; k < gps; ++k) {
    // After its map, a GP starts each message and holds its ring interface for its words.
    const auto i = static_cast<std::size_t>(k);
    if (a.gp_messages[i] == 0) continue;
    const double sending = static_cast<double>((a.gp_messages[i] - 1) * send_clocks) / gp_hz +
                           static_cast<double>(a.gp_words[i] - plan.bin_map_words()) / ring_hz;
    a.gp_busiest_seconds = std::max(a.gp_busiest_seconds, sending);
  }
  a.ring_seconds = static_cast<double>(a.ring_words) / (config.ring.channels * ring_hz);
  // Without overlapped shipping a Renderer also waits for each of its regions to cross.
  const double ship_wait =
      config.renderer.overlap_shipping ? 0 : static_cast<double>(plan.region_words()) / ring_hz;
  for (int j = 0; j < renderers; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const double t = static_cast<double>(a.renderer_busy_cycles[i]) / array_hz +
                     ship_wait * static_cast<double>(a.regions[i].size());
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
    drain = std::max(drain,
                     plan.hop_delay(plan.renderer_stop(j), plan.frame_buffer_stop()).to_seconds());
  }
  a.drain_seconds = static_cast<double>(plan.region_words()) / ring_hz + drain;
  a.frame_seconds = a.fill_seconds + a.busiest_seconds + a.drain_seconds;
  return a;
}

std::vector<std::vector<RegionWork>> analytic_work(const AnalyticTiming& timing,
                                                   const MachinePlan& plan) {
  const MachineConfig& config = plan.config();
  const SetupMemo::Summary& summary = plan.setup_memo()->summary(config.regions());
  const RegionStream stream(plan.program(), plan.frame_values());
  std::uint64_t steps = 0;
  stream.for_each_empty([&](const RegionStep&) { ++steps; });
  const auto passes = static_cast<std::size_t>(plan.passes());
  std::vector<std::vector<RegionWork>> work(timing.regions.size());
  for (std::size_t k = 0; k < timing.regions.size(); ++k) {
    for (int r : timing.regions[k]) {
      const auto i = static_cast<std::size_t>(r);
      RegionWork w;
      w.region = r;
      w.x0 = config.region_x0(r);
      w.y0 = config.region_y0(r);
      for (std::uint32_t p = summary.region_first[i]; p < summary.region_first[i + 1]; ++p) {
        w.triangles.push_back(*summary.region_packets[p]);
      }
      w.step_start.assign(steps, 0);
      w.packet_start.assign(w.triangles.size() * passes, 0);
      w.busy_cycles = timing.region_cycles[i];
      work[k].push_back(std::move(w));
    }
  }
  return work;
}

}  // namespace pp5
