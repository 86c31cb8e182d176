#include "models/renderer/analytic.hpp"

#include <algorithm>
#include <deque>
#include <functional>
#include <iterator>
#include <limits>
#include <queue>
#include <stdexcept>
#include <tuple>

#include "models/gp/primitive_kind.hpp"
#include "models/gp/setup_memo.hpp"
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

struct ContentionResult {
  std::vector<std::vector<int>> regions;  // per Renderer, the regions it rendered, in order
  double maps_seconds = 0;                // the last bin map in at every Renderer
  double frame_seconds = 0;               // the last region at the frame buffer
  double drain_seconds = 0;               // the last region's trip
  int critical_renderer = 0;
  // The critical Renderer's time, split as the event model splits its critical path.
  double gp_seconds = 0, ring_seconds = 0, renderer_seconds = 0;
};

// One message of a Renderer's stage: from GP `gp`, `words` ring words, `cycles` of the
// Renderer's array to consume.
struct AnalyticMessage {
  int gp = 0;
  std::uint64_t words = 0;
  std::uint64_t cycles = 0;
  // With evaluator.double_buffered, the cycles its first drawn packet's coefficients take to
  // load: the array stalls for them when it has waited for the message (below).
  std::uint64_t first_load = 0;
};

ContentionResult contention_recurrence(const MachinePlan& plan, const SetupMemo::Summary& summary,
                                       const AnalyticTiming& a, const std::vector<int>& block_end,
                                       std::uint64_t send_clocks) {
  const MachineConfig& config = plan.config();
  const TimingParams& timing = plan.timing();
  const int gps = plan.gp_count();
  const int renderers = plan.renderer_count();
  const int passes = plan.passes();
  const double gp_hz = config.gp.clock_hz;
  const double ring_hz = config.ring.clock_hz;
  const double cycle = 1.0 / config.renderer.clock_hz;
  const double start_s = static_cast<double>(send_clocks) / gp_hz;
  const auto capacity = static_cast<std::uint64_t>(config.renderer.queue_words);
  const bool retraverse = config.gp.multipass == MachineConfig::Gp::Multipass::retraverse;
  const RegionStream stream(plan.program(), plan.frame_values());

  // Region-wide cycles: before each pass (clear, pass), after the last (closing, lights,
  // shade) and the copy-out; each packet's cycles per pass, one sum per procedure.
  std::vector<std::uint64_t> before(static_cast<std::size_t>(passes), 0);
  for (int pass = 0; pass < passes; ++pass) {
    stream.before_pass(pass, [&](const RegionStep& step) {
      before[static_cast<std::size_t>(pass)] += busy_cycles(step.code, step.values, config, timing);
    });
  }
  std::uint64_t after = 0;
  stream.after_passes([&](const RegionStep& step) {
    after += busy_cycles(step.code, step.values, config, timing);
  });
  if (config.renderer.overlap_shipping) {
    const int blocks = (config.frame_buffer.bits_per_pixel + config.renderer.block_bits - 1) /
                       config.renderer.block_bits;
    after += static_cast<std::uint64_t>(blocks) *
             static_cast<std::uint64_t>(config.renderer.backing_store_cycles_per_block);
  }
  std::vector<std::pair<const ProcedureCode*, std::uint64_t>> memo;
  auto packet_cycles = [&](const Packet& p, int pass) -> std::uint64_t {
    const RegionStep step = stream.packet(p, pass, 0);
    if (!step.code.defined) return 0;
    std::uint64_t load = 0;
    if (!config.evaluator.double_buffered) {
      load = ceil_div(p.words > 0 ? p.words - 1 : 0,
                      static_cast<std::uint64_t>(config.evaluator.coefficient_words_per_cycle));
    }
    for (const auto& [code, cycles] : memo) {
      if (code == &step.code) return cycles + load;
    }
    memo.emplace_back(&step.code, busy_cycles(step.code, step.values, config, timing));
    return memo.back().second + load;
  };
  // The messages of a stage (region r, pass): each GP's bin cut as GraphicsProcessor::run
  // cuts it, a header word and as many of the bin's next packets as fit in the queue.
  auto stage_messages = [&](int r, int pass, std::vector<AnalyticMessage>& out) {
    out.clear();
    const auto i = static_cast<std::size_t>(r);
    std::uint32_t at = summary.region_first[i];
    const std::uint32_t end = summary.region_first[i + 1];
    for (int k = 0; k < gps && at < end; ++k) {
      const int last = block_end[static_cast<std::size_t>(k)];
      AnalyticMessage m{k, 0, 0, 0};
      bool loaded = false;  // a packet of the message drawn in this pass
      for (; at < end && summary.region_primitive[at] < last; ++at) {
        const Packet& p = **summary.region_packets[at];
        if (m.words > 0 && m.words + p.words > capacity) {
          out.push_back(m);
          m = AnalyticMessage{k, 0, 0, 0};
          loaded = false;
        }
        if (m.words == 0) m.words = 1;
        m.words += p.words;
        m.cycles += packet_cycles(p, pass);
        if (!loaded && config.evaluator.double_buffered && stream.packet(p, pass, 0).code.defined) {
          loaded = true;
          m.first_load =
              ceil_div(p.words > 0 ? p.words - 1 : 0,
                       static_cast<std::uint64_t>(config.evaluator.coefficient_words_per_cycle));
        }
      }
      if (m.words > 0) out.push_back(m);
    }
  };

  // The ring's channels. Every booking is made in the order of the time it is asked for
  // (messages through the heap below, finished regions when their copy-out is done or, without
  // overlapped shipping, when the array finishes them), so the channels book as Ring::reserve
  // does: the channel whose last booking ends first (ties to the lowest), held from then, or
  // from the request, until the message's last word. A finished region may start only when
  // its Renderer's interface has sent the region before (`not_before`): the channel is held,
  // idle, until then, as in the event model, where the Renderers that finish empty regions
  // quickly book their next ones far ahead.
  std::vector<double> channel_free(static_cast<std::size_t>(config.ring.channels), 0.0);
  auto book = [&](double at, std::uint64_t words, double not_before = 0) {
    const double length = static_cast<double>(words) / ring_hz;
    std::size_t c = 0;
    for (std::size_t k = 1; k < channel_free.size(); ++k) {
      if (channel_free[k] < channel_free[c]) c = k;
    }
    const double start = std::max({at, channel_free[c], not_before});
    channel_free[c] = start + length;
    return start + length;  // the end of its last word
  };
  std::vector<double> geometry_end(static_cast<std::size_t>(gps), 0.0);
  std::vector<double> gp_free(static_cast<std::size_t>(gps), 0.0);
  ContentionResult out;
  // The bin maps, in the order the GPs finish their geometry.
  std::vector<int> order;
  for (int k = 0; k < gps; ++k) {
    if (a.gp_messages[static_cast<std::size_t>(k)] > 0) order.push_back(k);
  }
  for (int k : order) {
    geometry_end[static_cast<std::size_t>(k)] =
        static_cast<double>(a.gps[static_cast<std::size_t>(k)].geometry.count) / gp_hz;
  }
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return geometry_end[static_cast<std::size_t>(x)] < geometry_end[static_cast<std::size_t>(y)];
  });
  std::vector<double> maps_in(static_cast<std::size_t>(renderers), 0.0);
  std::vector<double> maps_requested(static_cast<std::size_t>(renderers), 0.0);
  for (int k : order) {
    const auto i = static_cast<std::size_t>(k);
    const double requested = geometry_end[i] + start_s;
    const double end = book(requested, plan.bin_map_words());
    gp_free[i] = end;
    for (int j = 0; j < renderers; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      maps_in[jj] = std::max(
          maps_in[jj], end + plan.hop_delay(plan.gp_stop(k), plan.renderer_stop(j)).to_seconds());
      maps_requested[jj] = std::max(maps_requested[jj], requested);
    }
  }
  for (double t : maps_in) out.maps_seconds = std::max(out.maps_seconds, t);

  // Each Renderer's progress through its stages.
  struct Queued {
    double consumed;
    std::uint64_t words;
  };
  // A message of the stage the Renderer has open: sent, consumed once the stage's order is
  // known (consume_stage).
  struct StageMessage {
    double requested = 0;  // when it reached the Renderer's queue (the ring booked it)
    double arrival = 0;    // its last word in
    double gp_from = 0;    // the GPs' part of a wait for it ends here (attribute_wait)
    std::uint64_t cycles = 0;
    std::uint64_t words = 0;
    double load = 0;            // its first packet's coefficients (AnalyticMessage::first_load)
    double begin = 0, end = 0;  // the array's, from consume_stage (begin after any stall)
    bool freed = false;         // its room counted free (consumed before a later send)
  };
  struct Parked {
    int pass = 0;
    std::vector<StageMessage> stage;
  };
  struct RendererState {
    std::size_t region = 0;  // static balancing: the next of a.regions[j]
    int current = -1;        // the region it renders, -1 before it has one
    int pass = 0;
    bool entered = false;  // the stage's region-wide steps and messages are made
    std::vector<AnalyticMessage> messages;
    std::size_t next = 0;             // the stage's messages sent
    std::vector<char> sent;           // by message of the stage
    double stage_open = 0;            // when the stage opened for input
    double started = 0;               // when the array started on the stage
    double last_sent = 0;             // the latest booking of the stage's messages
    double room = 0;                  // when the queue has room for the next message
    double array = 0;                 // when the array is free
    double ship_free = 0;             // the video-RAM port's next free time
    double finished = 0;              // its last region at the frame buffer
    std::deque<Queued> queue;         // messages of earlier stages, not yet consumed, in order
    std::vector<StageMessage> stage;  // the open stage's messages sent, in the order sent
    std::vector<std::size_t> order;   // ... in the order the array consumes them
    double stage_base = 0;            // when the array is ready for the stage's messages
    bool shipping = false;            // without overlapped shipping: its array waits for the
                                      // trip of its finished region, not yet booked
    bool array_entered = false;       // the array has started on the entered stage
    std::deque<Parked> parked;        // stages all sent, waiting for the array, in order
    std::deque<double> ships;         // finished regions whose copy-out is done, not yet booked
    std::uint64_t queued = 0;
    double gp_s = 0, ring_s = 0, renderer_s = 0;  // its time, attributed
    bool maps_waited = false;
    bool done = false;
  };
  std::vector<RendererState> rs(static_cast<std::size_t>(renderers));
  // A wait of the array from `from` to `to`: the GPs' while the GP computed (from `gp_from`
  // until `gp_until`), the ring's for the rest, as the event model attributes its critical
  // path.
  auto attribute_wait = [](RendererState& st, double from, double to, double gp_from,
                           double gp_until) {
    if (to <= from) return;
    const double gp_part = std::max(0.0, std::min(to, gp_until) - std::max(from, gp_from));
    st.gp_s += gp_part;
    st.ring_s += to - from - gp_part;
  };
  auto run_array = [&](RendererState& st, std::uint64_t cycles) {
    const double t = static_cast<double>(cycles) * cycle;
    st.array += t;
    st.renderer_s += t;
  };
  // The order in which the array consumes the open stage's messages, as Renderer::run_frame
  // takes them: whenever it is free, of the stage's messages in its queue (delivered when the
  // ring booked them) the one whose last word arrives first (ties to the one delivered
  // first), waiting for its arrival; with none in the queue, the first delivered next. The
  // messages sent so far are all those delivered before any later send's request, so the
  // order up to the time of the latest send is final.
  // Kept sorted by request (a heap of the delivered by arrival, then by index): the same
  // choice as scanning every message each time, in n log n.
  std::vector<std::size_t> by_request;
  std::vector<std::size_t> delivered_heap;
  auto consume_stage = [&](RendererState& st) {
    st.order.clear();
    const std::size_t n = st.stage.size();
    by_request.resize(n);
    for (std::size_t i = 0; i < n; ++i) by_request[i] = i;
    std::stable_sort(by_request.begin(), by_request.end(), [&](std::size_t x, std::size_t y) {
      return st.stage[x].requested < st.stage[y].requested;
    });
    // The heap's top: the earliest arrival, ties to the one sent first.
    auto later = [&](std::size_t x, std::size_t y) {
      const double ax = st.stage[x].arrival, ay = st.stage[y].arrival;
      return ax > ay || (ax == ay && x > y);
    };
    delivered_heap.clear();
    std::size_t next = 0;
    auto deliver_until = [&](double until) {
      while (next < n && st.stage[by_request[next]].requested <= until) {
        delivered_heap.push_back(by_request[next++]);
        std::push_heap(delivered_heap.begin(), delivered_heap.end(), later);
      }
    };
    double t = st.stage_base;
    for (std::size_t k = 0; k < n; ++k) {
      // Those delivered by now; with none, the first delivered next (and any delivered at
      // that instant). A message arrives after it is delivered, so every one in the heap
      // stays delivered as t moves on.
      deliver_until(t);
      if (delivered_heap.empty()) deliver_until(st.stage[by_request[next]].requested);
      std::pop_heap(delivered_heap.begin(), delivered_heap.end(), later);
      const std::size_t pick = delivered_heap.back();
      delivered_heap.pop_back();
      StageMessage& m = st.stage[pick];
      // Double-buffered, a packet's coefficients load while the packet before it runs; the
      // first packet's start only once it has arrived, so the array stalls for that load
      // as far as it waited (Renderer::load_coefficients).
      m.begin = std::max(t, m.arrival + m.load);
      m.end = m.begin + static_cast<double>(m.cycles) * cycle;
      t = m.end;
      st.order.push_back(pick);
    }
    return t;
  };
  // The stage is all sent: its messages consumed in that order, the array's waits
  // attributed, and those not yet counted free kept in the queue for the stages after it.
  auto close_stage = [&](RendererState& st) {
    consume_stage(st);
    for (const std::size_t i : st.order) {
      const StageMessage& m = st.stage[i];
      const double in = std::max(st.array, std::min(m.begin, m.arrival));
      attribute_wait(st, st.array, in, m.gp_from, m.requested);
      st.renderer_s += m.begin - in;  // the stall for its coefficients
      st.array = m.begin;
      run_array(st, m.cycles);
      if (!m.freed) st.queue.push_back({m.end, m.words});
    }
    st.stage.clear();
    st.order.clear();
  };
  // Static balancing: Renderer j renders a.regions[j] in order. Dynamic: a Renderer claims
  // the next unclaimed region when it opens its next stage (RegionScheduler::claim_region),
  // in time order among the Renderers (claims go through the heap below).
  const bool dynamic = config.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic;
  const int regions = config.regions();
  int unclaimed = 0;
  out.regions.assign(static_cast<std::size_t>(renderers), {});
  // The last entry pushed for each Renderer (kinds 0 and 1); an older one is stale.
  std::vector<std::uint64_t> token(static_cast<std::size_t>(renderers), 0);
  using Candidate = std::tuple<double, int, int, int, std::uint64_t>;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> heap;
  enum class Next { message, claim, wait, done };
  // The array starts on the entered stage: its region-wide steps, the wait for the bin maps.
  auto enter_array = [&](RendererState& st, int j, int pass) {
    st.array_entered = true;
    st.started = st.array;
    run_array(st, before[static_cast<std::size_t>(pass)]);
    if (!st.maps_waited) {
      // The array waits for every GP's bin map before its first message.
      st.maps_waited = true;
      const double in = std::max(st.array, maps_in[static_cast<std::size_t>(j)]);
      attribute_wait(st, st.array, in, 0.0, maps_requested[static_cast<std::size_t>(j)]);
      st.array = in;
    }
    st.stage_base = st.array;
    if (!st.stage.empty()) consume_stage(st);  // its messages' times, now known
  };
  // The region is finished (its last pass consumed): its closing steps, then its trip,
  // booked when the copy-out is done (Renderer::ship) or, without overlapped shipping, when
  // the array finishes the region, in time order with the other bookings (through the heap).
  // Without overlapped shipping the array waits for the region's arrival before it starts on
  // its next stage (that stage may open and take messages meanwhile, as in the event model).
  auto ship_region = [&](RendererState& st, int j) {
    run_array(st, after);
    st.ships.push_back(st.array);
    st.shipping = !config.renderer.overlap_shipping;
    heap.emplace(st.array - start_s, 2, 0, j, 0);
  };
  // The trip is booked: the array takes the stages that opened meanwhile, all sent, in order
  // (until another region is finished and waits for its trip), then the open stage.
  auto drain = [&](RendererState& st, int j) {
    while (!st.shipping && !st.parked.empty()) {
      Parked p = std::move(st.parked.front());
      st.parked.pop_front();
      std::vector<StageMessage> open = std::move(st.stage);
      std::vector<std::size_t> open_order = std::move(st.order);
      const double open_base = st.stage_base;
      st.stage = std::move(p.stage);
      st.order.clear();
      enter_array(st, j, p.pass);
      close_stage(st);
      st.stage = std::move(open);
      st.order = std::move(open_order);
      st.stage_base = open_base;
      st.array_entered = false;  // the open stage's array is not yet on it
      if (p.pass + 1 == passes) ship_region(st, j);
    }
    if (!st.shipping && st.parked.empty() && st.entered && !st.array_entered) {
      enter_array(st, j, st.pass);
    }
  };
  // Moves Renderer j to a stage with a message to send, running the region-wide steps and
  // empty stages on the way: Next::message, or Next::claim when it needs its next region
  // (dynamic balancing), or Next::done.
  auto advance = [&](int j) -> Next {
    RendererState& st = rs[static_cast<std::size_t>(j)];
    for (;;) {
      if (st.entered && st.next < st.messages.size()) return Next::message;
      if (st.entered && !st.array_entered) {
        // Its array waits for the last region's trip, not yet booked. An empty stage opens the
        // next when the array starts on it: wait. Otherwise the next stage opens now, and the
        // array takes this one once the trip is booked (drain).
        if (st.messages.empty()) return Next::wait;
        st.parked.push_back({st.pass, std::move(st.stage)});
        st.stage.clear();
        st.order.clear();
        st.stage_open = std::max(st.last_sent, maps_requested[static_cast<std::size_t>(j)]);
        st.entered = false;
        if (st.pass + 1 < passes) {
          ++st.pass;
        } else {
          st.current = -1;
          st.pass = 0;
        }
      } else if (st.entered) {
        close_stage(st);
        // The stage is all sent (its messages consumed as they came): the next one opens
        // when its last message was sent, or, for an empty stage, when the Renderer
        // started on it (before its region-wide steps, Renderer::run_frame); either once
        // every bin map is in, which says who sends (Renderer::advance).
        st.stage_open =
            std::max(st.messages.empty() ? std::max(st.stage_open, st.started) : st.last_sent,
                     maps_requested[static_cast<std::size_t>(j)]);
        st.entered = false;
        if (st.pass + 1 < passes) {
          ++st.pass;
        } else {
          ship_region(st, j);
          st.current = -1;
          st.pass = 0;
        }
      }
      if (st.current < 0) {
        if (dynamic) return Next::claim;
        const auto& mine = a.regions[static_cast<std::size_t>(j)];
        if (st.region >= mine.size()) return Next::done;
        st.current = mine[st.region++];
        out.regions[static_cast<std::size_t>(j)].push_back(st.current);
      }
      st.entered = true;
      stage_messages(st.current, st.pass, st.messages);
      st.sent.assign(st.messages.size(), 0);
      st.next = 0;
      st.last_sent = st.stage_open;
      st.array_entered = false;
      // While its last region's trip is not booked, the array's times are not known: its
      // messages cannot yet be consumed (no room freed by them).
      st.stage_base = std::numeric_limits<double>::infinity();
      if (!st.shipping && st.parked.empty()) enter_array(st, j, st.pass);
    }
  };
  // Retraversal: a GP's packets of pass k exist after k more traversals of its share.
  auto pass_ready = [&](int k, int pass) {
    const double g = geometry_end[static_cast<std::size_t>(k)];
    return retraverse ? g * (1 + pass) : g;
  };
  // When Renderer j's next message can go: its stage open, room in the queue, its GP free.
  // When Renderer j's next message can go, and which: of each GP's next message of the
  // stage (a GP's messages of one bin go in order), the one that can go first (its stage
  // open, room in the queue for it, its GP free), ties in the scheduler's order (gp_rank
  // below); as the event model's GPs each send to an open stage they owe whenever they can.
  // The queue's room: the earlier stages' messages go first, then the open stage's in the
  // order the array consumes them (consume_stage, kept up to date as messages are sent).
  auto room_for = [&](const RendererState& st, std::uint64_t words) {
    double t = st.room;
    std::uint64_t queued = st.queued;
    for (auto it = st.queue.begin(); it != st.queue.end() && queued + words > capacity; ++it) {
      t = std::max(t, it->consumed);
      queued -= it->words;
    }
    // The parked stages' messages go next, at times not known until the array takes them.
    if (queued + words > capacity && !st.parked.empty()) {
      return std::numeric_limits<double>::infinity();
    }
    for (auto it = st.order.begin(); it != st.order.end() && queued + words > capacity; ++it) {
      const StageMessage& m = st.stage[*it];
      if (m.freed) continue;
      t = std::max(t, m.end);
      queued -= m.words;
    }
    return t;
  };
  // Of GPs that could go at one instant, which goes first: RegionScheduler::arbitrate's
  // order (gp.send_order): the fewest hops to the Renderer, then the lower GP; the lower GP;
  // or round-robin from the GP after the one that sent last.
  const MachineConfig::Gp::SendOrder send_order = config.gp.send_order;
  int next_turn = 0;
  auto gp_rank = [&](int gp, int j) -> long {
    switch (send_order) {
      case MachineConfig::Gp::SendOrder::nearest:
        return static_cast<long>(
                   ring_hops(plan.gp_stop(gp), plan.renderer_stop(j), plan.ring_stops())) *
                   gps +
               gp;
      case MachineConfig::Gp::SendOrder::lowest:
        return gp;
      case MachineConfig::Gp::SendOrder::round_robin:
        return (gp - next_turn + gps) % gps;
    }
    return gp;
  };
  constexpr double kTie = 1e-12;  // one picosecond, SystemC's time resolution
  auto pick_message = [&](int j) {
    RendererState& st = rs[static_cast<std::size_t>(j)];
    double best = 0;
    long best_rank = 0;
    std::size_t pick = st.messages.size();
    int previous_gp = -1;
    for (std::size_t i = 0; i < st.messages.size(); ++i) {
      const AnalyticMessage& m = st.messages[i];
      if (st.sent[i] || m.gp == previous_gp) {
        if (!st.sent[i]) previous_gp = m.gp;
        continue;
      }
      previous_gp = m.gp;
      const double t =
          std::max({st.stage_open, room_for(st, m.words), gp_free[static_cast<std::size_t>(m.gp)],
                    pass_ready(m.gp, st.pass)});
      const long rank = gp_rank(m.gp, j);
      if (pick == st.messages.size() || t < best - kTie || (t <= best + kTie && rank < best_rank)) {
        best = t, best_rank = rank, pick = i;
      }
    }
    return std::make_pair(best, pick);
  };
  auto ready_time = [&](int j) { return pick_message(j).first; };
  // (time, kind, stage, Renderer): kind 0 a region to claim, 1 a message to send, 2 a finished
  // region to book (at its request time less the send clocks, the scale of kind 1); earliest
  // first, claims before messages at one instant, then the lower stage (pass * regions +
  // region: a GP free for several open stages sends to the lowest, as
  // GraphicsProcessor::run picks), then the lower Renderer.
  auto stage_of = [&](int j) {
    const RendererState& st = rs[static_cast<std::size_t>(j)];
    return st.pass * regions + st.current;
  };
  auto schedule = [&](int j) {
    switch (advance(j)) {
      case Next::message: {
        const double ready = ready_time(j);
        // Not before its array's times are known (its trip booked: it schedules it then).
        if (ready < std::numeric_limits<double>::infinity()) {
          heap.emplace(ready, 1, stage_of(j), j, ++token[static_cast<std::size_t>(j)]);
        }
        break;
      }
      case Next::claim:
        heap.emplace(rs[static_cast<std::size_t>(j)].stage_open, 0, 0, j,
                     ++token[static_cast<std::size_t>(j)]);
        break;
      case Next::wait:
      case Next::done:
        break;
    }
  };
  for (int j = 0; j < renderers; ++j) schedule(j);
  while (!heap.empty()) {
    const auto [when, kind, stage, j, tok] = heap.top();
    heap.pop();
    RendererState& st = rs[static_cast<std::size_t>(j)];
    if (kind == 2) {
      const double requested = st.ships.front();
      st.ships.pop_front();
      const double trip =
          plan.hop_delay(plan.renderer_stop(j), plan.frame_buffer_stop()).to_seconds();
      const double end = book(requested, plan.region_words(), st.ship_free);
      st.ship_free = end;
      st.finished = std::max(st.finished, end + trip);
      if (st.shipping) {
        // The array waited for the region's arrival (Renderer::ship).
        st.ring_s += end + trip - st.array;
        st.array = end + trip;
        st.shipping = false;
        drain(st, j);
        schedule(j);
      }
      continue;
    }
    if (tok != token[static_cast<std::size_t>(j)]) continue;  // stale
    if (kind == 0) {
      if (unclaimed < regions) {
        st.current = unclaimed++;
        out.regions[static_cast<std::size_t>(j)].push_back(st.current);
        schedule(j);
      }
      continue;
    }
    const double ready = ready_time(j);
    if (ready > when) {  // its GP was taken meanwhile
      if (ready < std::numeric_limits<double>::infinity()) {
        heap.emplace(ready, 1, stage, j, ++token[static_cast<std::size_t>(j)]);
      }
      continue;
    }
    const std::size_t picked = pick_message(j).second;
    const AnalyticMessage m = st.messages[picked];
    st.sent[picked] = 1;
    ++st.next;
    next_turn = (m.gp + 1) % gps;
    // The queue's room for it: messages consumed by the time it could go are out.
    while (!st.queue.empty() && st.queued + m.words > capacity) {
      st.room = std::max(st.room, st.queue.front().consumed);
      st.queued -= st.queue.front().words;
      st.queue.pop_front();
    }
    for (auto it = st.order.begin(); it != st.order.end() && st.queued + m.words > capacity; ++it) {
      StageMessage& q = st.stage[*it];
      if (q.freed) continue;
      st.room = std::max(st.room, q.end);
      st.queued -= q.words;
      q.freed = true;
    }
    const auto g = static_cast<std::size_t>(m.gp);
    // The GP starts the message (i860 clocks), then holds its interface for the words.
    const double requested = ready + start_s;
    const double end = book(requested, m.words);
    gp_free[g] = end;
    st.last_sent = std::max(st.last_sent, requested);
    const double arrival =
        end + plan.hop_delay(plan.gp_stop(m.gp), plan.renderer_stop(j)).to_seconds();
    // The array consumes it in the stage's order (consume_stage). A wait for it is the GPs'
    // while the GP computed, if its geometry (or a traversal) held it, otherwise only while
    // it started the message; the ring's after.
    StageMessage q;
    q.requested = requested;
    q.arrival = arrival;
    q.gp_from = pass_ready(m.gp, st.pass) >= ready ? 0.0 : ready;
    q.cycles = m.cycles;
    q.words = m.words;
    q.load = static_cast<double>(m.first_load) * cycle;
    st.stage.push_back(q);
    consume_stage(st);
    st.queued += m.words;
    schedule(j);
  }
  for (int j = 0; j < renderers; ++j) {
    const RendererState& st = rs[static_cast<std::size_t>(j)];
    const double finished = std::max(st.finished, st.array);
    if (finished > out.frame_seconds || j == 0) {
      out.frame_seconds = finished;
      out.critical_renderer = j;
      out.gp_seconds = st.gp_s;
      out.renderer_seconds = st.renderer_s;
      out.ring_seconds = st.ring_s + (finished - st.array);  // the last region's trip
      out.drain_seconds = finished - st.array;
    }
  }
  return out;
}

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

  // The closed form without contention: each unit's work, overlapped perfectly after the
  // fill. A lower bound, kept beside the recurrence below (analytic.closed_form_seconds).
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
  double unit_seconds = a.renderer_busiest_seconds;
  a.busiest_unit = "Renderers";
  if (a.ring_seconds > unit_seconds) unit_seconds = a.ring_seconds, a.busiest_unit = "ring";
  if (a.gp_busiest_seconds > unit_seconds)
    unit_seconds = a.gp_busiest_seconds, a.busiest_unit = "GPs";
  double drain = 0;
  for (int j = 0; j < renderers; ++j) {
    drain = std::max(drain,
                     plan.hop_delay(plan.renderer_stop(j), plan.frame_buffer_stop()).to_seconds());
  }
  a.closed_form_seconds =
      map_seconds + unit_seconds + static_cast<double>(plan.region_words()) / ring_hz + drain;

  // The contention recurrence (docs/timing.md "Analytic timing"): every message of every
  // Renderer's stages, booked in order of the time it could go, on servers shared as the
  // machine shares them: each GP's ring interface (one message at a time, after starting it),
  // the ring's channels (the one that frees first), each Renderer's queue (a message needs
  // room for all its words, freed when the Renderer has consumed it) and its array (one
  // message after another, after its arrival). A stage opens when the last message of the
  // stage before was sent. No process and no event: a max-plus recurrence over messages.
  const ContentionResult c = contention_recurrence(plan, summary, a, block_end, send_clocks);
  if (dynamic) {
    // Dynamic balancing: the regions go where the recurrence's Renderers claimed them.
    a.regions = c.regions;
    std::fill(a.renderer_busy_cycles.begin(), a.renderer_busy_cycles.end(), 0);
    std::fill(a.renderer_packets.begin(), a.renderer_packets.end(), 0);
    for (std::size_t j = 0; j < a.regions.size(); ++j) {
      for (int r : a.regions[j]) {
        const auto i = static_cast<std::size_t>(r);
        a.renderer_busy_cycles[j] += a.region_cycles[i];
        a.renderer_packets[j] += (summary.region_first[i + 1] - summary.region_first[i]) *
                                 static_cast<std::uint64_t>(passes);
      }
    }
  }
  a.fill_seconds = c.maps_seconds;
  a.frame_seconds = c.frame_seconds;
  a.drain_seconds = c.drain_seconds;
  a.busiest_seconds = a.frame_seconds - a.fill_seconds - a.drain_seconds;
  a.critical_renderer = c.critical_renderer;
  a.critical_gp_seconds = c.gp_seconds;
  a.critical_ring_seconds = c.ring_seconds;
  a.critical_renderer_seconds = c.renderer_seconds;
  a.bottleneck = "Renderers";
  double top = c.renderer_seconds;
  if (c.gp_seconds > top) a.bottleneck = "GPs", top = c.gp_seconds;
  if (c.ring_seconds > top) a.bottleneck = "ring";
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
