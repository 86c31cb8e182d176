#include "models/renderer/renderer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

Renderer::Renderer(sc_core::sc_module_name name, int index, const RendererWiring& wiring)
    : sc_module(name),
      index_(index),
      wiring_(wiring),
      plan_(wiring.plan),
      cycle_(1.0 / wiring.plan.config().renderer.clock_hz, sc_core::SC_SEC),
      capacity_(static_cast<std::uint64_t>(wiring.plan.config().renderer.queue_words)) {
  clock_slot_ = wiring_.clock.enrol();
  SC_THREAD(run);
}

void Renderer::reserve_room(std::uint64_t words) {
  queued_words_ += words;
  stats_.queue_peak_words = std::max(stats_.queue_peak_words, queued_words_);
}

void Renderer::receive_bin(std::shared_ptr<const BinMessage> message) {
  const bool last = message->last;
  queue_.push_back(std::move(message));
  if (last) {
    ++lasts_delivered_;
    advance();
  }
  arrived_.notify(sc_core::SC_ZERO_TIME);
}

void Renderer::receive_bin_map(const BinMapArrival& map) {
  const int m = map.frame & 1;
  ++maps_delivered_[m];
  maps_requested_[m] = std::max(maps_requested_[m], map.requested);
  maps_arrival_[m] = std::max(maps_arrival_[m], map.arrival);
  // A map of the next frame waits until this Renderer is on it.
  if (map.frame == frame_ && maps_complete()) {
    maps_complete_.notify(sc_core::SC_ZERO_TIME);
    advance();
  }
}

void Renderer::advance() {
  if (open_region_ < 0 || !maps_complete()) return;
  const int senders = wiring_.scheduler.bin_senders(open_region_, frame_);
  if (lasts_delivered_ == senders && (senders > 0 || open_started_)) open_next_stage();
}

void Renderer::wait_for_bin_maps() {
  const sc_core::sc_time from = sc_core::sc_time_stamp();
  while (!maps_complete()) wait(maps_complete_);
  const sc_core::sc_time arrival = maps_arrival_[frame_ & 1];
  if (arrival > sc_core::sc_time_stamp()) wait(arrival - sc_core::sc_time_stamp());
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  const sc_core::sc_time gp_until = std::min(std::max(from, maps_requested_[frame_ & 1]), now);
  stats_.waiting_gp += gp_until - from;
  stats_.waiting_ring += now - gp_until;
  cursor_ = std::max(cursor_, now);
}

void Renderer::open_next_stage() {
  lasts_delivered_ = 0;
  open_started_ = false;
  if (open_region_ >= 0 && open_pass_ + 1 < wiring_.plans.of(frame_).passes()) {
    ++open_pass_;
  } else {
    // The last pass of the region is all in the queue: take the next region now, so that
    // its bins flow in while this one finishes.
    open_region_ = wiring_.scheduler.claim_region(index_, frame_);
    open_pass_ = open_region_ >= 0 ? 0 : -1;
  }
  if (open_region_ >= 0) stages_.push_back({open_region_, open_pass_});
  wiring_.scheduler.input_changed(index_, open_stage(plan_.config().regions()), frame_);
}

void Renderer::charge(const ProcedureCode& procedure, const PacketValues& values,
                      bool region_wide) {
  if (!procedure.defined) return;
  const MachineConfig& config = plan_.config();
  const TimingParams& timing = plan_.timing();
  ++stats_.packets;
  stats_.instructions += procedure.code.size();
  RegionWideCost* memo = nullptr;
  if (region_wide) {
    for (RegionWideCost& c : region_wide_costs_) {
      if (c.code == &procedure && c.expressions_begin == values.expressions.begin() &&
          c.expressions_end == values.expressions.end() && c.parameters == &values.parameters) {
        cursor_ += cycle_ * static_cast<double>(c.cycles.count);
        stats_.busy += c.cycles;
        return;
      }
    }
    const bool port = config.renderer.backing_store_overlap &&
                      std::any_of(procedure.code.begin(), procedure.code.end(), [](const auto& i) {
                        return i.op == Opcode::bsld || i.op == Opcode::bsst;
                      });
    if (!port) {
      memo = &region_wide_costs_.emplace_back(RegionWideCost{&procedure,
                                                             values.expressions.begin(),
                                                             values.expressions.end(),
                                                             &values.parameters,
                                                             {}});
    }
  }
  ArrayCycles cycles(config.renderer.packet_overhead_cycles);
  for (const Instruction& ins : procedure.code) {
    const ArrayCycles cost = instruction_cost(ins, timing, values);
    const bool transfer = ins.op == Opcode::bsld || ins.op == Opcode::bsst;
    if (!transfer || !config.renderer.backing_store_overlap) {
      cycles += cost;
      continue;
    }
    cursor_ += cycle_ * static_cast<double>(cycles.count);
    stats_.busy += cycles;
    cycles = ArrayCycles{};
    const sc_core::sc_time length = cycle_ * static_cast<double>(cost.count);
    if (ins.op == Opcode::bsst) {
      // The array issues the store in one cycle; the port moves the blocks while the array
      // goes on (a later write to the field is the firmware's to order after a load).
      const ArrayCycles issue(1);
      cursor_ += cycle_ * static_cast<double>(issue.count);
      stats_.busy += issue;
      port_free_ = std::max(cursor_, port_free_) + length;
    } else {
      // A load's data must be in pixel memory before the next instruction can use it.
      if (port_free_ > cursor_) {
        stats_.stall +=
            ArrayCycles(static_cast<std::uint64_t>((port_free_ - cursor_) / cycle_ + 0.5));
        cursor_ = port_free_;
      }
      cursor_ += length;
      port_free_ = cursor_;
      stats_.busy += cost;
    }
  }
  cursor_ += cycle_ * static_cast<double>(cycles.count);
  stats_.busy += cycles;
  if (memo != nullptr) memo->cycles = cycles;
}

void Renderer::load_coefficients(const Packet& packet, sc_core::sc_time arrival) {
  const MachineConfig& config = plan_.config();
  // The packet's words after its header are coefficients, moved from the queue into the
  // evaluator's input registers.
  const std::uint64_t words = packet.words > 0 ? packet.words - 1 : 0;
  const auto per_cycle = static_cast<std::uint64_t>(config.evaluator.coefficient_words_per_cycle);
  const ArrayCycles load((words + per_cycle - 1) / per_cycle);
  if (!config.evaluator.double_buffered) {
    cursor_ += cycle_ * static_cast<double>(load.count);
    stats_.busy += load;
    return;
  }
  // Double-buffered: the next packet's coefficients load while the current packet executes;
  // the array waits only if they are not in yet.
  const sc_core::sc_time ready =
      std::max(arrival, coefficients_free_) + cycle_ * static_cast<double>(load.count);
  if (ready > cursor_) {
    stats_.stall += ArrayCycles(static_cast<std::uint64_t>((ready - cursor_) / cycle_ + 0.5));
    cursor_ = ready;
  }
  coefficients_free_ = cursor_;
}

void Renderer::catch_up() {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  if (cursor_ > now) wait(cursor_ - now);
  cursor_ = sc_core::sc_time_stamp();
}

void Renderer::ship(int region) {
  const MachineConfig& config = plan_.config();
  Ring& ring = wiring_.ring;
  const int from = plan_.renderer_stop(index_);
  const int to = plan_.frame_buffer_stop();
  const std::uint64_t words = plan_.region_words();
  if (config.renderer.overlap_shipping) {
    // Colours go to the backing store (before the next region's clear overwrites them); its
    // video-RAM port then streams them onto the ring while the array works on.
    const int blocks = (config.frame_buffer.bits_per_pixel + config.renderer.block_bits - 1) /
                       config.renderer.block_bits;
    const ArrayCycles copy(static_cast<std::uint64_t>(blocks) *
                           config.renderer.backing_store_cycles_per_block);
    if (port_free_ > cursor_) {
      stats_.stall +=
          ArrayCycles(static_cast<std::uint64_t>((port_free_ - cursor_) / cycle_ + 0.5));
      cursor_ = port_free_;
    }
    const sc_core::sc_time t0 = cursor_;
    cursor_ += cycle_ * static_cast<double>(copy.count);
    port_free_ = cursor_;
    stats_.busy += copy;
    catch_up();
    wiring_.timeline.add(Unit::renderer, index_, "copy out", t0, cursor_);
    const RingBooking b = ring.send_region(from, to, words, region, ship_free_);
    ship_free_ = b.end;
    stats_.finished = std::max(stats_.finished, b.arrival);
  } else {
    catch_up();
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    // The region is handed to the frame buffer at booking; the array waits for its arrival.
    const RingBooking b = ring.send_region(from, to, words, region);
    wait(b.arrival - sc_core::sc_time_stamp());
    stats_.waiting_ship += sc_core::sc_time_stamp() - t0;
    cursor_ = sc_core::sc_time_stamp();
    stats_.finished = std::max(stats_.finished, cursor_);
  }
}

void Renderer::run() {
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

void Renderer::reset_frame() {
  const sc_core::sc_time base = wiring_.clock.start();
  open_region_ = -1;
  open_pass_ = -1;
  lasts_delivered_ = 0;
  open_started_ = false;
  frame_ = wiring_.clock.frame();
  forget_maps(0, base);
  forget_maps(1, base);
  stages_.clear();
  queue_.clear();
  queued_words_ = 0;
  cursor_ = base;
  port_free_ = base;
  ship_free_ = base;
  coefficients_free_ = base;
  stats_ = RendererStats{};
  work_.clear();
}

void Renderer::forget_maps(int frame, sc_core::sc_time base) {
  maps_delivered_[frame & 1] = 0;
  maps_requested_[frame & 1] = base;
  maps_arrival_[frame & 1] = base;
}

void Renderer::run_overlapped() {
  // Frames overlap: the Renderer takes frame n + 1's regions as soon as it has finished
  // frame n's, with its array, backing-store port and ring interface as frame n left them.
  for (frame_ = 0;; ++frame_) {
    // Two frames in flight at most (as for the GPs): a Renderer with no region of frame n
    // (a small screen) waits for every other to finish frame n - 1 before taking up n + 1.
    while (wiring_.clock.released() <= frame_ || wiring_.clock.renderers_finished() < frame_ - 1)
      wait(wiring_.clock.progress());
    const sc_core::sc_time began = sc_core::sc_time_stamp();
    open_region_ = -1;
    open_pass_ = -1;
    lasts_delivered_ = 0;
    open_started_ = false;
    stats_ = RendererStats{};
    work_.clear();
    run_frame();
    history_.push_back({frame_, began, stats_, std::move(work_)});
    work_.clear();
    // Frame n + 2's maps come only once every Renderer has finished n + 1.
    forget_maps(frame_, sc_core::SC_ZERO_TIME);
    wiring_.clock.renderer_finished(index_);
  }
}

Renderer::FrameRecord Renderer::release_frame(int frame) {
  if (history_.empty() || history_.front().frame != frame) {
    throw std::logic_error(fmt::format(
        "{}: frame {} released, but its oldest record is {}", name(), frame,
        history_.empty() ? std::string("none") : std::to_string(history_.front().frame)));
  }
  FrameRecord out = std::move(history_.front());
  history_.erase(history_.begin());
  return out;
}

void Renderer::run_frame() {
  // A frame's times are relative to its start: the frame clock's, or where an overlapped
  // Renderer took the frame up.
  const sc_core::sc_time base =
      wiring_.clock.overlapped() ? sc_core::sc_time_stamp() : wiring_.clock.start();
  const MachineConfig& config = plan_.config();
  const Program& program = plan_.program();
  const int gps = plan_.gp_count();
  // The frame's own values (an animation's frames in flight each have theirs); the costs of
  // region-wide steps are kept per frame, since they bind the frame's values.
  const RegionStream stream(program, wiring_.plans.of(frame_).frame_values());
  region_wide_costs_.clear();
  cursor_ = base;
  open_next_stage();
  std::vector<std::vector<std::shared_ptr<const Packet>>> by_gp(gps);
  // The array cycle at which each packet started, by pass and GP (for traces): a GP's
  // packets come in the same order in every pass.
  std::vector<std::vector<std::vector<std::uint64_t>>> starts(
      stream.passes(), std::vector<std::vector<std::uint64_t>>(gps));
  auto cycle_now = [&] {
    return static_cast<std::uint64_t>(std::llround((cursor_ - base) / cycle_));
  };
  std::vector<std::uint64_t> step_start;
  auto charge_step = [&](const RegionStep& step) {
    step_start.push_back(cycle_now());
    charge(step.code, step.values, true);
  };
  sc_core::sc_time region_start;
  std::uint64_t region_busy_start = 0;
  while (!stages_.empty()) {
    const Stage stage = stages_.front();
    stages_.pop_front();
    if (stage.region == open_region_ && stage.pass == open_pass_) {
      open_started_ = true;
      advance();
    }
    if (stage.pass == 0) {
      for (auto& v : by_gp) v.clear();
      for (auto& pass : starts)
        for (auto& v : pass) v.clear();
      step_start.clear();
      region_start = cursor_;
      region_busy_start = stats_.busy.count;
    }
    stream.before_pass(stage.pass, charge_step);
    catch_up();
    // How many GPs send the stage is known once every bin map is in. GPs that send a full
    // message before their set-up ends (frames.gp_send=when_full) send it before their map:
    // the Renderer then takes the stage's messages as they come and waits for the maps only
    // to know when the stage is complete.
    const bool early = config.frames.gp_send == MachineConfig::Frames::GpSend::when_full;
    const auto maps_in = [&] {
      return maps_complete() && !(maps_arrival_[frame_ & 1] > sc_core::sc_time_stamp());
    };
    if (!early && !maps_in()) wait_for_bin_maps();
    int lasts = 0;
    while (!maps_in() || lasts < wiring_.scheduler.bin_senders(stage.region, frame_)) {
      catch_up();
      const sc_core::sc_time waiting_from = sc_core::sc_time_stamp();
      std::size_t pick = queue_.size();
      bool complete = false;  // early: the maps came in and said the stage has all it gets
      for (;;) {
        // Scanned afresh after every wait: the queue may have grown by messages of the next
        // stage (early, while the maps are still coming).
        pick = queue_.size();
        for (std::size_t k = 0; k < queue_.size(); ++k) {
          const BinMessage& m = *queue_[k];
          if (m.region != stage.region || m.pass != stage.pass) continue;
          if (pick == queue_.size() || m.arrival < queue_[pick]->arrival) pick = k;
        }
        if (pick < queue_.size()) break;
        if (!maps_in()) {
          if (maps_complete()) {
            wait(maps_arrival_[frame_ & 1] - sc_core::sc_time_stamp(), arrived_);
          } else {
            wait(arrived_ | maps_complete_);
          }
          if (maps_in() && lasts >= wiring_.scheduler.bin_senders(stage.region, frame_)) {
            complete = true;
            break;
          }
          continue;
        }
        wait(arrived_);
      }
      if (complete) {
        // The wait was for the maps: the GPs' while they had not asked for them, the ring's
        // after (as wait_for_bin_maps).
        const sc_core::sc_time now = sc_core::sc_time_stamp();
        const sc_core::sc_time gp_until =
            std::min(std::max(waiting_from, maps_requested_[frame_ & 1]), now);
        stats_.waiting_gp += gp_until - waiting_from;
        stats_.waiting_ring += now - gp_until;
        cursor_ = std::max(cursor_, now);
        break;
      }
      const std::shared_ptr<const BinMessage> m = queue_[pick];
      queue_.erase(queue_.begin() + static_cast<std::ptrdiff_t>(pick));
      if (m->arrival > sc_core::sc_time_stamp()) wait(m->arrival - sc_core::sc_time_stamp());
      // Whatever of the wait came after the GP asked for the message was the ring's.
      const sc_core::sc_time now = sc_core::sc_time_stamp();
      const sc_core::sc_time ring_from = std::max(waiting_from, m->requested);
      const sc_core::sc_time ring_part = now > ring_from ? now - ring_from : sc_core::SC_ZERO_TIME;
      stats_.waiting_ring += ring_part;
      // Before that, it was whatever the sending GP was doing: computing (the GPs' time),
      // sending earlier messages (the ring's) or waiting for other Renderers (theirs).
      const GpActivityTimes before = wiring_.gps[static_cast<std::size_t>(m->gp)]->activity(
          waiting_from, std::min(m->requested, now));
      stats_.waiting_gp += sc_core::sc_time(before.compute, sc_core::SC_SEC);
      stats_.waiting_ring += sc_core::sc_time(before.ring, sc_core::SC_SEC);
      stats_.waiting_renderers += sc_core::sc_time(before.renderer, sc_core::SC_SEC);
      if (stats_.messages == 0)
        stats_.waiting_first = stats_.waiting_gp + stats_.waiting_ring + stats_.waiting_renderers;
      cursor_ = now;
      const sc_core::sc_time t0 = cursor_;
      for (const auto& packet : m->packets) {
        // Its place among the region's packets is known only once all have arrived.
        const RegionStep step = stream.packet(*packet, stage.pass, -1);
        // A packet the pass plan does not draw in this pass is discarded on its header.
        if (step.code.defined) load_coefficients(*packet, m->arrival);
        starts[stage.pass][m->gp].push_back(cycle_now());
        charge(step.code, step.values);
        if (stage.pass == 0) by_gp[m->gp].push_back(packet);
      }
      // Time advances per message, not per cycle: one kernel event for a whole stream.
      catch_up();
      ++stats_.messages;
      if (wiring_.timeline.on() && cursor_ > t0) {
        wiring_.timeline.add(
            Unit::renderer, index_,
            "gp" + std::to_string(m->gp) + ": " + std::to_string(m->packets.size()) + " triangles",
            t0, cursor_);
      }
      queued_words_ -= m->words;
      wiring_.scheduler.input_changed(index_, open_stage(plan_.config().regions()), frame_);
      if (m->last) ++lasts;
    }
    if (stage.pass + 1 < stream.passes()) continue;
    stream.after_passes(charge_step);
    catch_up();
    wiring_.timeline.add(Unit::renderer, index_, "region " + std::to_string(stage.region),
                         region_start, cursor_);
    RegionWork w;
    w.region = stage.region;
    w.x0 = config.region_x0(stage.region);
    w.y0 = config.region_y0(stage.region);
    // Moved, not copied (each copy of a packet's pointer is an atomic count): by_gp and
    // step_start are cleared before the next region's first pass.
    for (auto& v : by_gp) {
      w.triangles.insert(w.triangles.end(), std::make_move_iterator(v.begin()),
                         std::make_move_iterator(v.end()));
    }
    w.step_start = std::move(step_start);
    for (const auto& pass : starts)
      for (const auto& v : pass) w.packet_start.insert(w.packet_start.end(), v.begin(), v.end());
    ship(stage.region);
    w.busy_cycles = stats_.busy.count - region_busy_start;
    ++stats_.regions;
    work_.push_back(std::move(w));
  }
  catch_up();
  // The frame's times are the frame's own (FrameClock's contract).
  stats_.computed = sc_core::sc_time_stamp() - base;
  stats_.finished = std::max(stats_.finished, sc_core::sc_time_stamp()) - base;
}

void Renderer::execute(RendererBoard& board, const Program& program, FrameBuffer& frame_buffer,
                       const FrameValues& values,
                       const std::function<bool(const RegionWork&)>& executes) const {
  execute_regions(work_, board, program, frame_buffer, values, executes);
}

void execute_regions(const std::vector<RegionWork>& work, RendererBoard& board,
                     const Program& program, FrameBuffer& frame_buffer, const FrameValues& values,
                     const std::function<bool(const RegionWork&)>& executes) {
  const RegionStream stream(program, values);
  for (const RegionWork& w : work) {
    if (executes && !executes(w)) continue;
    // An empty region's stream is the same every time: executed once, then reused (a traced
    // board runs every instruction, so that the trace shows them).
    if (w.triangles.empty() && !board.observed()) {
      frame_buffer.store_region(w.x0, w.y0, board.run_empty_region(w.x0, w.y0, program, values));
      continue;
    }
    board.begin_region(w.x0, w.y0);
    const std::size_t n = w.triangles.size();
    std::size_t next_step = 0;
    stream.for_each(w.triangles, [&](const RegionStep& step) {
      const std::uint64_t start =
          step.packet ? w.packet_start[step.pass * n + step.index] : w.step_start[next_step++];
      board.run_step(step, w.region, start);
    });
    board.end_region(w.region);
    board.read_outputs(program, frame_buffer.region_bytes(w.x0, w.y0));
    frame_buffer.store_region(w.x0, w.y0);
  }
}

}  // namespace pp5
