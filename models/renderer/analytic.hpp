#pragma once
// The analytic timing model (fidelity.timing=analytic): the frame time without a single
// SystemC event. Each unit's work is summed from the same cost tables the event model charges
// (the GPs' geometry pass and i860 clocks, the instruction table's cycles per procedure, the
// ring's words), and the frame time comes from a contention recurrence, docs/timing.md
// "Analytic timing": every Renderer's messages, stage by stage, booked in order of the time
// each could go on servers shared as the machine shares them (each GP's ring interface, the
// ring's channels, each Renderer's queue of renderer.queue_words and its array), a stage
// opening when the stage before it was all sent. It is a max-plus recurrence over messages:
// no process, no event, one pass in time order.
//
// Contract:
//  - It needs no Machine, only what the units share (MachinePlan: the configuration, the
//    program, the geometry, the ring's stops), with a set-up memo bound to it
//    (MachinePlan::use_setup_memo). It fills the memo by geometry_pass if the memo is not
//    complete, then sums each GP's share of the display list from the memo's summary
//    (SetupMemo::Summary), so its packets, set-up counts and GP clocks are exactly the event
//    model's, and a run of frames of one scene (a sweep) sets it up once.
//  - It follows the event model's rules: of a stage's messages, the one whose GP can go
//    first goes first, ties in the scheduler's order (gp.send_order; round-robin's turn
//    advanced per message rather than per wake-up); the array takes a stage's messages in
//    the order of their arrival among those delivered (Renderer::run_frame); an empty
//    stage lets the next open when the Renderer starts on it; double-buffered, the array
//    stalls for a message's first packet's coefficients when it waited for the message
//    (Renderer::load_coefficients). What it leaves out: backing-store port stalls, a
//    double-buffered load's stall on a later packet shorter than its successor's load, and,
//    at one instant, the order in which GPs woken for several Renderers book the ring. With
//    renderer.overlap_shipping its ring books as Ring::reserve does, in request order;
//    without it, finished regions are booked when they finish, ahead of messages asked for
//    earlier, on channel calendars that fill the gaps before them. The error this makes is
//    measured on held-out machines (sim/analysis/analytic_validation.hpp, `pp5sim
//    fidelity`), not assumed.
//  - Regions go to Renderers as the event model's static balancing does (r mod count); with
//    dynamic balancing, as the recurrence's Renderers claim them, each taking the next
//    region when it opens its next stage, in time order (the closed form kept beside it
//    gives each region to the Renderer with the least work so far).
//  - Deterministic, and a pure function of the machine's inputs.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "models/gp/graphics_processor.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/renderer/renderer.hpp"

namespace pp5 {

struct AnalyticTiming {
  // Per GP (all of them, idle ones with empty statistics).
  std::vector<GpStats> gps;
  std::vector<std::uint64_t> gp_send_clocks;  // starting its bin map and messages
  std::vector<std::uint64_t> gp_words;        // ring words it sends
  std::vector<std::uint64_t> gp_messages;
  // Per Renderer: its regions, in the order it renders them (analytic_work gives their
  // packets); per region, its busy cycles.
  std::vector<std::vector<int>> regions;
  std::vector<std::uint64_t> region_cycles;
  std::vector<std::uint64_t> renderer_busy_cycles;
  std::vector<std::uint64_t> renderer_packets;
  std::uint64_t ring_words = 0;
  std::uint64_t ring_messages = 0;
  // The frame time from the contention recurrence, in simulated seconds, split as
  // fill (until every bin map is in) + busiest (the span the recurrence adds) + drain (the
  // last region's trip).
  double geometry_seconds = 0;  // the slowest GP's geometry
  double fill_seconds = 0;
  double busiest_seconds = 0;
  double drain_seconds = 0;
  double frame_seconds = 0;
  // The critical Renderer (whose last region arrives last) and its time split as the event
  // model splits its critical path; the bottleneck is the largest part.
  int critical_renderer = 0;
  double critical_gp_seconds = 0;
  double critical_ring_seconds = 0;
  double critical_renderer_seconds = 0;
  std::string bottleneck;  // "GPs", "ring" or "Renderers", as timing.bottleneck names them
  // The closed form without contention (fill + the busiest unit's work + drain): a lower
  // bound the recurrence refines, and which unit it names the busiest.
  double closed_form_seconds = 0;
  std::string busiest_unit;
  double gp_busiest_seconds = 0;
  double ring_seconds = 0;  // all ring words over the ring's bandwidth
  double renderer_busiest_seconds = 0;
  int busiest_renderer = 0;
};

AnalyticTiming analytic_timing(const MachinePlan& plan);

// The regions of `timing`, each with its packets in display-list order, per Renderer: what
// the event model records as RegionWork (start cycles zero: traces need the event model),
// for the boards to execute. `plan` is the one `timing` was made from, its memo unchanged.
std::vector<std::vector<RegionWork>> analytic_work(const AnalyticTiming& timing,
                                                   const MachinePlan& plan);

}  // namespace pp5
