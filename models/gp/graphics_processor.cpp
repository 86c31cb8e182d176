#include "models/gp/graphics_processor.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <stdexcept>
#include <string>

#include "common/parallel_for.hpp"
#include "models/gp/depth_sort.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/gp/region_bins.hpp"
#include "models/gp/setup_memo.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

GraphicsProcessor::GraphicsProcessor(sc_core::sc_module_name name, int index, int first, int last,
                                     const GpWiring& wiring)
    : sc_module(name),
      index_(index),
      first_(first),
      last_(last),
      wiring_(wiring),
      plan_(wiring.plan),
      clock_(1.0 / wiring.plan.config().gp.clock_hz, sc_core::SC_SEC) {
  for (int k = 0; k < plan_.renderer_count(); ++k)
    renderer_stops_.push_back(plan_.renderer_stop(k));
  clock_slot_ = wiring_.clock.enrol();
  SC_THREAD(run);
}

void GraphicsProcessor::begin(GpActivity a) {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  if (activity_.back().second == a) return;
  if (activity_.back().first == now) {
    activity_.back().second = a;
  } else {
    activity_.push_back({now, a});
  }
}

GpActivityTimes GraphicsProcessor::activity(sc_core::sc_time from, sc_core::sc_time to) const {
  GpActivityTimes t;
  if (!(from < to)) return t;
  auto it = std::upper_bound(activity_.begin(), activity_.end(), from,
                             [](sc_core::sc_time v, const auto& e) { return v < e.first; });
  if (it != activity_.begin()) --it;
  for (; it != activity_.end() && it->first < to; ++it) {
    const sc_core::sc_time a = std::max(from, it->first);
    const sc_core::sc_time b =
        std::next(it) == activity_.end() ? to : std::min(to, std::next(it)->first);
    if (!(a < b)) continue;
    const double d = (b - a).to_seconds();
    switch (it->second) {
      case GpActivity::compute:
        t.compute += d;
        break;
      case GpActivity::ring:
        t.ring += d;
        break;
      case GpActivity::renderer:
      case GpActivity::done:
        t.renderer += d;
        break;
    }
  }
  return t;
}

void GraphicsProcessor::spend(GpClocks clocks) {
  begin(GpActivity::compute);
  stats_.busy += clocks;
  wait(clock_ * static_cast<double>(clocks.count));
}

GpWorkload kind_workload(const MachinePlan& plan, const PrimitiveKind& kind) {
  GpWorkload w = plan.gp_workload();
  w.expressions = plan.program().procedure(kind.procedure()).expressions;
  w.packet_words = plan.packet_words(w.expressions);
  return w;
}

PrimitiveCost primitive_cost(const MachinePlan& plan, const PrimitiveKind& kind,
                             const GpWorkload& workload, const PrimitiveTally& tally) {
  PrimitiveCost c;
  c.ops = kind.operations(workload, tally);
  c.clocks = plan.i860().clocks(c.ops, 1);
  return c;
}

namespace {

// geometry_pass into `memo` (null for none).
void geometry_pass_with(const MachinePlan& machine, int first, int last, GpStats& stats,
                        RegionBins* bins, SetupMemo* memo,
                        std::vector<std::uint64_t>* done_after = nullptr) {
  const MachineConfig& config = machine.config();
  const GeometryEngine& geometry = machine.geometry();
  const DisplayList& display_list = geometry.display_list();
  // Per registered kind: this GP's worker, the expressions its procedure uses and the
  // workload the cost model charges (the machine's, with that procedure's expressions).
  struct KindState {
    const PrimitiveKind* kind;
    std::unique_ptr<PrimitiveWorker> worker;
    GpWorkload workload;
    // The operations and clocks of the tallies met so far: they depend on the workload and
    // the tally alone (PrimitiveKind's contract), and most primitives share a few tallies.
    std::vector<std::pair<PrimitiveTally, PrimitiveCost>> costs;
    const PrimitiveCost& cost(const PrimitiveTally& t, const MachinePlan& plan) {
      for (const auto& [tally, c] : costs) {
        if (tally.pieces == t.pieces && tally.setups == t.setups && tally.regions == t.regions)
          return c;
      }
      costs.emplace_back(t, primitive_cost(plan, *kind, workload, t));
      return costs.back().second;
    }
  };
  std::vector<KindState> kinds;
  for (const PrimitiveKind* k : primitive_kinds()) {
    kinds.push_back({k, k->start(geometry), kind_workload(machine, *k), {}});
  }

  // A bin per region: the packets this GP sends it, in display-list order. With a multipass
  // program the same packets go out once per pass.
  if (bins != nullptr) bins->reset(config.regions());
  std::vector<int> regions;
  SetupResult result;  // one for every set-up: its coefficient storage is reused
  if (done_after != nullptr) done_after->clear();
  const std::uint64_t clocks_before = stats.geometry.count;
  for (int i = first; i < last; ++i) {
    if ((i & 255) == 0 && machine.cancelled()) break;  // the frame is being cancelled
    const PrimitiveRef ref = display_list.at(i);
    KindState& k = kinds[static_cast<std::size_t>(ref.kind)];
    ++stats.triangles_in;
    PrimitiveTally tally;
    if (memo != nullptr && memo->record(i).filled) {
      // Set up at an earlier frame with the same key (models/gp/setup_memo.hpp).
      const SetupMemo::Record& r = memo->record(i);
      tally = r.tally;
      stats.screen_triangles += static_cast<std::uint64_t>(tally.pieces);
      stats.setup += memo->counts(r);
      for (std::uint32_t p = r.first; p < r.first + r.count; ++p) {
        const SetupMemo::Placed& placed = memo->placed(p);
        for (std::uint32_t q = placed.first; bins != nullptr && q < placed.first + placed.count;
             ++q) {
          bins->add(static_cast<int>(memo->region(q)), placed.packet);
        }
        stats.packets += placed.count;
      }
    } else {
      SetupCounts counts;
      if (memo != nullptr) memo->begin(i);
      tally.pieces = k.worker->transform(ref.index, counts);
      for (int piece = 0; piece < tally.pieces; ++piece) {
        ++stats.screen_triangles;
        ++tally.setups;
        result.clear();
        if (!k.worker->setup(piece, k.workload.expressions, result, counts)) continue;
        // From the bins' packet memory when there are bins (the GP's run), else its own.
        std::shared_ptr<Packet> packet =
            bins != nullptr ? bins->make_packet() : std::make_shared<Packet>();
        packet->procedure = k.kind->procedure();
        packet->kind = ref.kind;
        packet->primitive = i;
        packet->group = k.kind->solid(geometry.scene(), ref.index);
        packet->back = result.back;
        packet->words = k.workload.packet_words;
        regions.clear();
        k.worker->bin(result, regions);
        // The coefficients go in; the storage the packet's slot held comes back to `result`.
        std::swap(packet->values, result.values);
        stats.packets += regions.size();
        tally.regions += static_cast<int>(regions.size());
        if (bins != nullptr) {
          for (int r : regions) bins->add(r, packet);
        }
        if (memo != nullptr) memo->place(std::move(packet), regions);
      }
      stats.setup += counts;
      if (memo != nullptr) memo->end(i, ref.kind, tally, counts);
    }
    const PrimitiveCost& cost = k.cost(tally, machine);
    stats.ops += cost.ops;
    stats.geometry += cost.clocks;
    if (done_after != nullptr) done_after->push_back(stats.geometry.count - clocks_before);
  }
  if (bins != nullptr) bins->finish();
}

}  // namespace

void geometry_pass(const MachinePlan& machine, int first, int last, GpStats& stats,
                   RegionBins* bins, std::vector<std::uint64_t>* done_after) {
  geometry_pass_with(machine, first, last, stats, bins, machine.setup_memo(), done_after);
}

int setup_parts(const MachinePlan& plan, int threads, int least_part) {
  const int n = static_cast<int>(plan.geometry().display_list().size());
  return std::max(1, std::min(threads, n / std::max(1, least_part)));
}

void fill_setup_memo(const MachinePlan& plan, int threads, int least_part) {
  SetupMemo* memo = plan.setup_memo();
  if (memo == nullptr || !memo->empty()) return;
  const int n = static_cast<int>(plan.geometry().display_list().size());
  const int parts = setup_parts(plan, threads, least_part);
  if (parts <= 1) {
    GpStats scratch;
    geometry_pass_with(plan, 0, n, scratch, nullptr, memo);
    return;
  }
  std::vector<std::unique_ptr<SetupMemo>> filled(static_cast<std::size_t>(parts));
  auto block = [n, parts](int k) {
    return static_cast<int>(static_cast<long long>(n) * k / parts);
  };
  parallel_for(parts, threads, [&](int k) {
    auto part = std::make_unique<SetupMemo>(memo->scene());
    part->bind(memo->key(), static_cast<std::size_t>(n));
    GpStats scratch;
    geometry_pass_with(plan, block(k), block(k + 1), scratch, nullptr, part.get());
    filled[static_cast<std::size_t>(k)] = std::move(part);
  });
  if (plan.cancelled()) return;  // parts cut short: the memo stays empty
  for (int k = 0; k < parts; ++k)
    memo->absorb(std::move(*filled[static_cast<std::size_t>(k)]), block(k), block(k + 1));
}

void GraphicsProcessor::run() {
  if (wiring_.clock.overlapped()) {
    run_overlapped();
    return;
  }
  // Frame after frame: frame 0 as the kernel starts, each later one when the host begins it.
  for (;;) {
    run_frame();
    wait(wiring_.clock.started(clock_slot_));
  }
}

void GraphicsProcessor::reset_frame() {
  stats_ = GpStats{};
  sort_in_.clear();
  activity_.assign(1, {wiring_.clock.start(), GpActivity::compute});
}

bool GraphicsProcessor::sends_when_full() const {
  return plan_.config().frames.gp_send == MachineConfig::Frames::GpSend::when_full;
}

void GraphicsProcessor::geometry(RegionBins& bins, GpStats& stats, int frame, Growing* growing) {
  const sc_core::sc_time t0 = sc_core::sc_time_stamp();
  begin(GpActivity::compute);
  stats.geometry_started = t0;
  std::vector<std::uint64_t>* done_after = growing != nullptr ? &done_after_[frame & 1] : nullptr;
  geometry_pass(wiring_.plans.of(frame), first_, last_, stats, &bins, done_after);
  stats.busy += stats.geometry;
  if (growing != nullptr) {
    stats.geometry_done = t0 - wiring_.clock.start();  // until send_bins has spent it
    *growing = Growing{done_after, sc_core::SC_ZERO_TIME,
                       clock_ * static_cast<double>(stats.geometry.count)};
    return;
  }
  // Time advances once for the whole geometry phase: nothing leaves the GP before it ends.
  wait(clock_ * static_cast<double>(stats.geometry.count));
  stats.geometry_done = sc_core::sc_time_stamp() - wiring_.clock.start();
  if (wiring_.timeline.on()) {
    wiring_.timeline.add(Unit::gp, index_,
                         wiring_.clock.overlapped() ? "geometry of frame " + std::to_string(frame)
                                                    : std::string("geometry"),
                         t0, sc_core::sc_time_stamp());
  }
}

void GraphicsProcessor::run_frame() {
  const sc_core::sc_time base = wiring_.clock.start();
  const int frame = wiring_.clock.frame();
  // Painter's: the depth sort first (every GP takes part, even one with nothing to draw).
  for (const DepthSortWork* sort = wiring_.plans.of(frame).depth_sort(); sort != nullptr;
       sort = sort->next.get())
    depth_sort_phase(*sort, frame);
  // With fewer triangles than GPs, a GP may have none: it takes no part in the frame, and
  // the Renderers expect no bin map from it (Machine::busy_gp_count).
  if (first_ == last_) {
    begin(GpActivity::done);
    return;
  }
  RegionBins bins;
  Growing growing;
  geometry(bins, stats_, frame, sends_when_full() ? &growing : nullptr);
  send_bins(bins, frame, {}, sends_when_full() ? &growing : nullptr);
  begin(GpActivity::done);
  stats_.finished = sc_core::sc_time_stamp() - base;
}

bool GraphicsProcessor::may_start(int frame) const {
  const FrameClock& clock = wiring_.clock;
  // Two frames in flight at most: frame n's regions and bin senders take the slot frame n - 2
  // left, which every Renderer has finished. Set up after the frame before has been swapped
  // in (frames.gp_start=after_frame), the GPs do not overlap the Renderers.
  const bool overlap = plan_.config().frames.gp_start == MachineConfig::Frames::GpStart::overlap;
  return clock.released() > frame && clock.renderers_finished() >= frame - (overlap ? 1 : 0);
}

void GraphicsProcessor::run_overlapped() {
  // Frames overlap (Machine::overlap): frame after frame with no host between them. The GP
  // keeps frames.gp_bins bin buffers. With two it sets up frame n + 1 into the second while
  // the Renderers still take frame n's bins from the first, whenever it has nothing of frame n
  // it can send, and stalls only when both are full; that set-up yields to frame n's bins: a
  // Renderer opening a stage it owes, or freeing room, interrupts it (it resumes when the GP
  // again has nothing to send). With one buffer it sets up frame n + 1 once the last of frame
  // n's bins has gone.
  if (first_ == last_) {
    begin(GpActivity::done);
    return;
  }
  const MachineConfig& config = plan_.config();
  const bool double_buffered = config.frames.gp_bins >= 2 &&
                               config.frames.gp_start == MachineConfig::Frames::GpStart::overlap;
  RegionBins(&bins)[2] = overlap_bins_;
  Ahead ahead;
  const bool when_full = sends_when_full();
  for (frame_ = 0;; ++frame_) {
    Growing growing;
    if (!ahead.started) {
      stats_ = GpStats{};
      if (!may_start(frame_)) {
        const sc_core::sc_time t0 = sc_core::sc_time_stamp();
        begin(GpActivity::renderer);
        while (!may_start(frame_)) wait(wiring_.clock.progress());
        stats_.waiting_start = sc_core::sc_time_stamp() - t0;
      }
      for (const DepthSortWork* sort = wiring_.plans.of(frame_).depth_sort(); sort != nullptr;
           sort = sort->next.get())
        depth_sort_phase(*sort, frame_);
      geometry(bins[frame_ & 1], stats_, frame_, when_full ? &growing : nullptr);
    } else if (when_full) {
      // The rest of a set-up begun ahead, spent while its full messages go.
      stats_ = ahead_;
      const sc_core::sc_time total = clock_ * static_cast<double>(ahead_.geometry.count);
      growing = Growing{&done_after_[frame_ & 1], total - ahead.remaining, total};
    } else {
      // The rest of a set-up begun ahead.
      if (!ahead.done) {
        const sc_core::sc_time t0 = sc_core::sc_time_stamp();
        begin(GpActivity::compute);
        wait(ahead.remaining);
        finish_ahead_piece(ahead, t0);
      }
      stats_ = ahead_;
    }
    ahead = Ahead{};
    ahead.possible = double_buffered;
    ahead.frame = frame_ + 1;
    ahead.bins = &bins[(frame_ + 1) & 1];
    send_bins(bins[frame_ & 1], frame_, double_buffered ? &ahead : nullptr,
              when_full ? &growing : nullptr);
    begin(GpActivity::done);
    stats_.finished = sc_core::sc_time_stamp();
    history_.push_back({frame_, stats_});
  }
}

GpFrameRecord GraphicsProcessor::release_frame(int frame, sc_core::sc_time before) {
  if (history_.empty() || history_.front().frame != frame) {
    throw std::logic_error(fmt::format(
        "{}: frame {} released, but its oldest record is {}", name(), frame,
        history_.empty() ? std::string("none") : std::to_string(history_.front().frame)));
  }
  GpFrameRecord out = std::move(history_.front());
  history_.erase(history_.begin());
  // The activity in force at `before` stays (activity() looks back to it).
  auto it = std::upper_bound(activity_.begin(), activity_.end(), before,
                             [](sc_core::sc_time v, const auto& e) { return v < e.first; });
  if (it != activity_.begin()) activity_.erase(activity_.begin(), std::prev(it));
  return out;
}

void GraphicsProcessor::start_ahead(Ahead& ahead) {
  // The set-up itself is plain C++ (geometry_pass); its time is spent piece by piece.
  ahead_ = GpStats{};
  ahead_.geometry_started = sc_core::sc_time_stamp();
  geometry_pass(wiring_.plans.of(ahead.frame), first_, last_, ahead_, ahead.bins,
                sends_when_full() ? &done_after_[ahead.frame & 1] : nullptr);
  ahead_.busy += ahead_.geometry;
  ahead.started = true;
  ahead.remaining = clock_ * static_cast<double>(ahead_.geometry.count);
  if (ahead.remaining == sc_core::SC_ZERO_TIME) ahead.done = true;
}

void GraphicsProcessor::finish_ahead_piece(Ahead& ahead, sc_core::sc_time t0) {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  const sc_core::sc_time spent = now - t0;
  ahead.remaining = spent < ahead.remaining ? ahead.remaining - spent : sc_core::SC_ZERO_TIME;
  if (wiring_.timeline.on() && t0 < now) {
    wiring_.timeline.add(Unit::gp, index_, "geometry of frame " + std::to_string(ahead.frame), t0,
                         now);
  }
  if (ahead.remaining == sc_core::SC_ZERO_TIME) {
    ahead.done = true;
    ahead_.geometry_done = now;
  }
}

void GraphicsProcessor::send_bins(const RegionBins& bins, int frame, Ahead* ahead,
                                  Growing* growing) {
  const MachineConfig& config = plan_.config();
  // The bin map goes first, in one message that passes every Renderer: which regions this
  // GP has packets for. While the set-up goes on (frames.gp_send=when_full) the GP does not
  // know them yet: the map goes when it ends.
  const auto finish_geometry = [&] {
    growing = nullptr;
    wiring_.scheduler.add_bin_senders(bins.regions(), frame);
    send_bin_map(frame);
  };
  if (growing != nullptr && !growing->done()) {
    // The set-up's time is spent piece by piece below.
  } else {
    finish_geometry();
  }
  // A piece [t0, now) of the set-up, spent between messages.
  const auto geometry_piece = [&](sc_core::sc_time t0) {
    const sc_core::sc_time now = sc_core::sc_time_stamp();
    growing->spent += now - t0;
    if (wiring_.timeline.on() && t0 < now) {
      wiring_.timeline.add(Unit::gp, index_,
                           wiring_.clock.overlapped() ? "geometry of frame " + std::to_string(frame)
                                                      : std::string("geometry"),
                           t0, now);
    }
    if (growing->done()) {
      stats_.geometry_done = now - wiring_.clock.start();
      finish_geometry();
    }
  };
  // When the packet is set up (growing): the end of its primitive's set-up.
  const auto packet_ready_at = [&](const Packet& p) {
    return clock_ * static_cast<double>(
                        (*growing->done_after)[static_cast<std::size_t>(p.primitive - first_)]);
  };

  // Bins go out as their Renderers open (pass, region) stages: each message goes to the
  // lowest open stage whose Renderer's queue has room for it, so a full queue holds up only
  // the bins bound for it. A multipass program gets the same packets again for every pass.
  // gp.multipass=resend: the GP keeps its set-up packets, so only the sending repeats.
  // gp.multipass=retraverse: pass k's packets exist only once the GP has traversed and
  // transformed its share k more times, each costing what the first traversal cost; it
  // does the next traversal whenever it has nothing it can send (functionally the packets
  // are the same, so the first traversal's are sent).
  const int passes = wiring_.plans.of(frame).passes();
  const bool retraverse = config.gp.multipass == MachineConfig::Gp::Multipass::retraverse;
  const GpClocks traversal = stats_.geometry;
  const OpCounts traversal_ops = stats_.ops;
  int ready_passes = retraverse ? 1 : passes;
  const int n = config.regions();
  const auto capacity = static_cast<std::uint64_t>(config.renderer.queue_words);
  // An empty bin is not sent: the map has told its Renderer not to wait for it. So the
  // stages this GP owes are (pass, region) for the regions it has packets for, and what it
  // keeps per stage is kept per owed stage, at its slot: pass * (those regions) + the
  // region's index among them (a large screen's other regions cost it nothing).
  const std::vector<int>& held = bins.regions();
  const auto slot = [&bins, n, h = static_cast<int>(held.size())](int s) {
    return static_cast<std::size_t>((s / n) * h + bins.slot(s % n));
  };
  std::vector<std::size_t> next(static_cast<std::size_t>(passes) * held.size(), 0);
  std::vector<bool> done(next.size(), false);
  // The stages this GP still owes, ascending.
  std::vector<int> owed;
  owed.reserve(next.size());
  for (int pass = 0; pass < passes; ++pass) {
    for (const int r : held) owed.push_back(pass * n + r);
  }
  // A message carries a header word and as many of the bin's next packets as fit in a queue
  // (packets of different kinds differ in size; each fits, checked by the Machine): its size
  // is known before it is built. Worked out once per message, when the stage's next packet
  // changes.
  std::vector<std::size_t> chunk_packets(next.size(), 0);
  std::vector<std::uint64_t> chunk_words(next.size(), 0);
  std::vector<std::size_t> chunk_from(next.size(), SIZE_MAX);
  auto chunk = [&](int s) {
    const std::size_t k = slot(s);
    if (chunk_from[k] != next[k]) {
      const RegionBins::Bin& bin = bins.bin(s % n);
      std::uint64_t used = 1;
      std::size_t i = next[k];
      for (; i < bin.size() && used + bin[i]->words <= capacity; ++i) used += bin[i]->words;
      chunk_packets[k] = i - next[k];
      chunk_words[k] = used;
      chunk_from[k] = next[k];
    }
    return k;
  };
  auto packets_for = [&](int s) { return chunk_packets[chunk(s)]; };
  auto words_for = [&](int s) { return chunk_words[chunk(s)]; };
  // Each Renderer has at most one stage open, so the candidates are those stages, tried in
  // stage order: the lowest open stage this GP still owes something, whose queue has room.
  // Found from whichever list is shorter: the Renderers' open stages, or the stages owed
  // (the stage of a region is open only at the Renderer that claimed the region). A GP
  // with nothing it can send waits until a stage it owes opens or frees room
  // (RegionScheduler::wait_for_input, which says in what order waiting GPs go).
  std::vector<int> open_stages;
  open_stages.reserve(static_cast<std::size_t>(plan_.renderer_count()));
  const auto renderers = static_cast<std::size_t>(plan_.renderer_count());
  // While the set-up goes on, a message goes only when it is full: the packet after it is
  // set up (and does not fit). Only first passes: a later pass's stage opens once every bin
  // map is in.
  const auto full_and_ready = [&](int s) {
    const std::size_t k = chunk(s);
    const RegionBins::Bin& bin = bins.bin(s % n);
    const std::size_t end = next[k] + chunk_packets[k];
    return end < bin.size() && !(growing->spent < packet_ready_at(*bin[end]));
  };
  while (!owed.empty()) {
    const bool setting_up = growing != nullptr;
    const int sendable_passes = setting_up ? 1 : ready_passes;
    open_stages.clear();
    if (owed.size() <= renderers) {
      for (const int s : owed) {
        if (s / n >= sendable_passes) break;
        const int owner = wiring_.scheduler.owner_of_region(s % n, frame);
        if (owner >= 0 && queue(owner).open_frame() == frame && queue(owner).open_stage(n) == s)
          open_stages.push_back(s);
      }
    } else {
      for (int k = 0; k < plan_.renderer_count(); ++k) {
        if (queue(k).open_frame() != frame) continue;
        const int s = queue(k).open_stage(n);
        // A region it claimed (its owner), of a pass whose packets exist.
        if (s >= 0 && bins.slot(s % n) >= 0 && !done[slot(s)] && s / n < sendable_passes)
          open_stages.push_back(s);
      }
      std::sort(open_stages.begin(), open_stages.end());
    }
    int pick = -1;
    for (int s : open_stages) {
      if (setting_up && !full_and_ready(s)) continue;
      if (queue(wiring_.scheduler.owner_of_region(s % n, frame)).has_room(words_for(s))) {
        pick = s;
        break;
      }
    }
    if (pick < 0 && setting_up) {
      // Nothing it can send yet: the set-up goes on until the next message fills, the set-up
      // ends, or a Renderer opens a stage it owes or frees room.
      sc_core::sc_time until = growing->total;
      for (const int s : owed) {
        if (s / n >= 1) break;
        const std::size_t k = chunk(s);
        const RegionBins::Bin& bin = bins.bin(s % n);
        const std::size_t end = next[k] + chunk_packets[k];
        if (end >= bin.size()) continue;
        const sc_core::sc_time at = packet_ready_at(*bin[end]);
        if (growing->spent < at && at < until) until = at;
      }
      const sc_core::sc_time t0 = sc_core::sc_time_stamp();
      begin(GpActivity::compute);
      const sc_core::sc_time timeout = until - growing->spent;
      wiring_.scheduler.wait_for_input(index_, owed, frame, nullptr, &timeout);
      geometry_piece(t0);
      continue;
    }
    if (pick < 0 && ready_passes < passes) {
      const sc_core::sc_time t0 = sc_core::sc_time_stamp();
      spend(traversal);
      stats_.geometry += traversal;
      stats_.ops += traversal_ops;
      if (wiring_.timeline.on()) {
        wiring_.timeline.add(Unit::gp, index_,
                             "retraverse for pass " + std::to_string(ready_passes), t0,
                             sc_core::sc_time_stamp());
      }
      ++ready_passes;
      continue;
    }
    // Nothing of this frame it can send: the next frame's set-up, if it may start it, until
    // a stage it owes opens or frees room.
    if (pick < 0 && ahead != nullptr && !ahead->done) {
      // A frame that sorts first (painter's) is not set up ahead: its sort comes before.
      if (!ahead->started && may_start(ahead->frame) &&
          wiring_.plans.of(ahead->frame).depth_sort() == nullptr)
        start_ahead(*ahead);
      if (ahead->started && !ahead->done) {
        const sc_core::sc_time t0 = sc_core::sc_time_stamp();
        begin(GpActivity::compute);
        wiring_.scheduler.wait_for_input(index_, owed, frame, nullptr, &ahead->remaining);
        finish_ahead_piece(*ahead, t0);
        continue;
      }
    }
    if (pick < 0) {
      const sc_core::sc_time t0 = sc_core::sc_time_stamp();
      begin(GpActivity::renderer);
      // A GP that may start its next frame's set-up later waits for that too.
      const bool may_later =
          ahead != nullptr && !ahead->started && wiring_.clock.released() > ahead->frame;
      wiring_.scheduler.wait_for_input(index_, owed, frame,
                                       may_later ? &wiring_.clock.progress() : nullptr);
      (open_stages.empty() ? stats_.waiting_stage : stats_.waiting_queue) +=
          sc_core::sc_time_stamp() - t0;
      continue;
    }
    const RegionBins::Bin& bin = bins.bin(pick % n);
    const std::size_t k = slot(pick);
    auto m = std::make_shared<BinMessage>();
    m->region = pick % n;
    m->pass = pick / n;
    m->gp = index_;
    m->words = words_for(pick);
    const std::size_t first = next[k];
    next[k] += packets_for(pick);
    m->packets.assign(bin.begin() + static_cast<std::ptrdiff_t>(first),
                      bin.begin() + static_cast<std::ptrdiff_t>(next[k]));
    m->last = next[k] == bin.size();
    queue(wiring_.scheduler.owner_of_region(pick % n, frame)).reserve_room(m->words);
    if (m->last) {
      done[k] = true;
      owed.erase(std::lower_bound(owed.begin(), owed.end(), pick));
    }
    send(std::move(m), frame);
  }
  // A GP with no packet at all still spends its set-up, then sends its (empty) bin map.
  if (growing != nullptr) {
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    begin(GpActivity::compute);
    wait(growing->total - growing->spent);
    geometry_piece(t0);
  }
}

void GraphicsProcessor::receive_sort(const SortArrival& message) {
  sort_in_.push_back(message);
  sort_arrived_.notify(sc_core::SC_ZERO_TIME);
}

void GraphicsProcessor::await_sort(SortArrival::Kind kind, int frame, int count) {
  const auto mine = [kind, frame](const SortArrival& m) {
    return m.kind == kind && m.frame == frame;
  };
  begin(GpActivity::ring);
  while (std::count_if(sort_in_.begin(), sort_in_.end(), mine) < count) wait(sort_arrived_);
  // Every message is booked: the last of them arrives at a known time.
  sc_core::sc_time last = sc_core::sc_time_stamp();
  for (const SortArrival& m : sort_in_) {
    if (mine(m) && last < m.arrival) last = m.arrival;
  }
  if (sc_core::sc_time_stamp() < last) wait(last - sc_core::sc_time_stamp());
  sort_in_.erase(std::remove_if(sort_in_.begin(), sort_in_.end(), mine), sort_in_.end());
}

void GraphicsProcessor::send_sort(const std::vector<int>& to_gps, SortArrival::Kind kind,
                                  std::uint64_t words, int frame) {
  // Starting the message costs what starting a bin's does.
  spend(plan_.i860().clocks(I860Work::send_bin(), 0));
  std::vector<int> stops;
  for (const int g : to_gps) stops.push_back(plan_.gp_stop(g));
  SortArrival m;
  m.kind = kind;
  m.from_gp = index_;
  m.frame = frame;
  m.words = words;
  const RingBooking b = wiring_.ring.send_sort(plan_.gp_stop(index_), stops, m);
  ++stats_.messages;
  ++stats_.sort_messages;
  stats_.ring_words += words;
  stats_.sort_words += words;
  begin(GpActivity::ring);
  stats_.waiting_ring += b.end - sc_core::sc_time_stamp();
  wait(b.end - sc_core::sc_time_stamp());
}

void GraphicsProcessor::depth_sort_phase(const DepthSortWork& work, int frame) {
  // The sort's clocks come from its own counts unless the work says x gp.overhead_factor
  // (docs/timing.md "Depth sort").
  I860Params params = plan_.i860().params();
  if (!work.overhead_factor) params.overhead_factor = 1;
  const I860Model i860(params);
  const auto k = static_cast<std::size_t>(index_);
  const int gps = work.gps();
  const auto phase = [&](const OpCounts& ops, const char* name) {
    const GpClocks clocks = i860.clocks(ops, 0);
    if (clocks.count == 0) return;
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    spend(clocks);
    stats_.sort += clocks;
    if (wiring_.timeline.on())
      wiring_.timeline.add(Unit::gp, index_, name, t0, sc_core::sc_time_stamp());
  };
  const auto slice = [&](const char* name, sc_core::sc_time t0) {
    if (wiring_.timeline.on() && t0 < sc_core::sc_time_stamp())
      wiring_.timeline.add(Unit::gp, index_, name, t0, sc_core::sc_time_stamp());
  };
  // 1. Its share's records and sort; the run to GP 0.
  phase(work.prepare[k], "depth sort: prepare");
  if (index_ != 0 && work.run_words[k] > 0) {
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    send_sort({0}, SortArrival::Kind::run, work.run_words[k], frame);
    slice("depth sort: send run to gp0", t0);
  }
  // 2. GP 0 merges the runs and sends the order past every GP.
  std::vector<int> others;
  for (int g = 0; g < gps; ++g)
    if (g != index_) others.push_back(g);
  if (index_ == 0) {
    int runs = 0;
    for (int g = 1; g < gps; ++g) runs += work.run_words[static_cast<std::size_t>(g)] > 0 ? 1 : 0;
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    await_sort(SortArrival::Kind::run, frame, runs);
    slice("depth sort: await runs", t0);
    phase(work.merge, "depth sort: merge");
    if (work.order_words > 0 && !others.empty()) {
      const sc_core::sc_time t1 = sc_core::sc_time_stamp();
      send_sort(others, SortArrival::Kind::order, work.order_words, frame);
      slice("depth sort: send order", t1);
    }
  } else if (work.order_words > 0) {
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    await_sort(SortArrival::Kind::order, frame, 1);
    slice("depth sort: await order", t0);
  }
  // 3. Each polygon's record to the GP that checks it.
  for (const int g : others) {
    const std::uint64_t words = work.record_words[k][static_cast<std::size_t>(g)];
    if (words == 0) continue;
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    send_sort({g}, SortArrival::Kind::records, words, frame);
    slice(("depth sort: send records to gp" + std::to_string(g)).c_str(), t0);
  }
  int senders = 0;
  for (const int g : others)
    senders += work.record_words[static_cast<std::size_t>(g)][k] > 0 ? 1 : 0;
  {
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    await_sort(SortArrival::Kind::records, frame, senders);
    slice("depth sort: await records", t0);
  }
  // 4. The checks of its slice, then the split pieces inserted into it.
  phase(work.check[k], "depth sort: check");
  if (k < work.insert.size()) phase(work.insert[k], "depth sort: split and insert");
  stats_.sort_done = sc_core::sc_time_stamp() - wiring_.clock.start();
}

void GraphicsProcessor::send_bin_map(int frame) {
  spend(plan_.i860().clocks(I860Work::send_bin(), 0));
  const sc_core::sc_time requested = sc_core::sc_time_stamp();
  const RingBooking b = wiring_.ring.send_bin_map(plan_.gp_stop(index_), renderer_stops_,
                                                  plan_.bin_map_words(), index_, frame);
  ++stats_.messages;
  stats_.ring_words += plan_.bin_map_words();
  if (wiring_.timeline.on()) wiring_.timeline.add(Unit::gp, index_, "bin map", requested, b.end);
  begin(GpActivity::ring);
  stats_.waiting_ring += b.end - sc_core::sc_time_stamp();
  wait(b.end - sc_core::sc_time_stamp());
}

void GraphicsProcessor::send(std::shared_ptr<BinMessage> m, int frame) {
  const int renderer_index = wiring_.scheduler.owner_of_region(m->region, frame);
  // Starting the message costs i860 clocks; its room in the queue is already reserved.
  spend(plan_.i860().clocks(I860Work::send_bin(), 0));
  const sc_core::sc_time requested = sc_core::sc_time_stamp();
  m->requested = requested;
  const int region = m->region;
  stats_.ring_words += m->words;
  const RingBooking b = wiring_.ring.send_bin(plan_.gp_stop(index_),
                                              plan_.renderer_stop(renderer_index), std::move(m));
  ++stats_.messages;
  if (wiring_.timeline.on()) {
    wiring_.timeline.add(
        Unit::gp, index_,
        "send region " + std::to_string(region) + " to renderer" + std::to_string(renderer_index),
        requested, b.end);
  }
  // The GP's ring interface sends one message at a time.
  begin(GpActivity::ring);
  stats_.waiting_ring += b.end - sc_core::sc_time_stamp();
  wait(b.end - sc_core::sc_time_stamp());
}

}  // namespace pp5
