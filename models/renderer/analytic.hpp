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
//  - The Machine must be built (its units exist) but its kernel never run: the model reads
//    the configuration, the program, the geometry and the ring's hop delays, and runs
//    geometry_pass for every GP's share of the display list, so its packets, set-up counts
//    and GP clocks are exactly the event model's.
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
#include "models/renderer/renderer.hpp"

namespace pp5 {

class Machine;

struct AnalyticTiming {
  // Per GP (all of them, idle ones with empty statistics).
  std::vector<GpStats> gps;
  std::vector<std::uint64_t> gp_send_clocks;  // starting its bin map and messages
  std::vector<std::uint64_t> gp_words;        // ring words it sends
  std::vector<std::uint64_t> gp_messages;
  // Per Renderer: its regions, in the order it renders them, each with its packets in
  // display-list order (what the event model records as RegionWork, without start cycles).
  std::vector<std::vector<RegionWork>> work;
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

AnalyticTiming analytic_timing(Machine& machine);

}  // namespace pp5
