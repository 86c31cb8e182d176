#pragma once
// The analytic timing model (fidelity.timing=analytic): the frame time without a single
// SystemC event. Each unit's work is summed from the same cost tables the event model charges
// (the GPs' geometry pass and i860 clocks, the instruction table's cycles per procedure, the
// ring's words), and the frame time comes from a closed form, docs/timing.md "Analytic
// timing":
//
//   T = fill + busiest + drain
//   fill    = the slowest GP's geometry + starting and sending its bin map (nothing leaves a
//             GP before its geometry ends, and a Renderer waits for every map)
//   busiest = max(the busiest Renderer's cycles, all ring words over the ring's bandwidth,
//                 the busiest GP's sending: its i860 clocks per message and its words)
//   drain   = the last region's trip to the frame buffer
//
// Contract:
//  - It needs no Machine, only what the units share (MachinePlan: the configuration, the
//    program, the geometry, the ring's stops), with a set-up memo bound to it
//    (MachinePlan::use_setup_memo). It fills the memo by geometry_pass if the memo is not
//    complete, then sums each GP's share of the display list from the memo's summary
//    (SetupMemo::Summary), so its packets, set-up counts and GP clocks are exactly the event
//    model's, and a run of frames of one scene (a sweep) sets it up once.
//  - No contention: no unit waits for another beyond the closed form (no queue-full stalls,
//    no channel conflicts, no backing-store port stalls, coefficient loads overlapped when
//    double-buffered); the error this makes against the event model is measured, not assumed
//    (tests/test_analytic.cpp states the bound).
//  - Regions go to Renderers as the event model's static balancing does (r mod count); with
//    dynamic balancing, each region in order to the Renderer with the least work so far.
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
  // The closed form's terms, in simulated seconds, and which unit is the busiest.
  double geometry_seconds = 0;  // the slowest GP's geometry
  double fill_seconds = 0;
  double busiest_seconds = 0;
  double drain_seconds = 0;
  double frame_seconds = 0;
  std::string busiest_unit;  // "GPs", "ring" or "Renderers", as timing.bottleneck names them
  double gp_busiest_seconds = 0;
  double ring_seconds = 0;
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
