#pragma once
// The order of procedures a region runs, written once: the timing model (Renderer::run), the
// functional model (Renderer::execute, RendererBoard's empty regions), field readout
// (sim/analysis/field_render.cpp) and the tests all walk a region through RegionStream.
//
// A region's stream:
//   clear
//   for each of the frame's passes k = 0 .. passes - 1 (the program's `option passes`: a
//   number, or a frame parameter such as `layers` read from the FrameValues):
//     `pass` (before every pass but the first)
//     the region's packets, in display-list order, each running its own procedure
//   `light` once per scene light (only if the program defines it)
//   shade
// clear, pass and shade bind the frame's values; light k binds light k's; a packet binds its
// own expressions and the frame's parameters.
//
// With a pass plan (FrameValues::plan, made by the GP side from the scene: make_pass_plan in
// models/gp/pass_plan.hpp), the passes are the plan's: pass k opens with the procedures of
// plan[k].opening, in order (the first starts with clear), instead of `pass`, and a packet
// whose group or facing plan[k] does not draw runs nothing in it (its step runs an undefined
// procedure: no instruction, no cycle); one it draws runs plan[k].packets (a sphere's packet
// its sphere counterpart, planned_procedure in firmware/isa/interface.hpp), or its own
// procedure. After the last pass, FrameValues::closing's procedures run, then `light` and
// shade. The GPs still send every packet in every pass (the Renderer discards the others on
// reading the header).
//
// Contract:
//  - for_each yields every step of a region in the order above; before_pass, packet and
//    after_passes yield the same steps piecewise, for a caller that learns a region's packets
//    as they arrive (the event-driven timing loop): before_pass(0), then pass 0's packets,
//    before_pass(1), ..., then after_passes() gives exactly for_each's sequence.
//  - A step's values are a view into the packet and the FrameValues given to the constructor:
//    valid while both live.
//  - A step is yielded whether or not the program defines its procedure (an undefined one
//    runs nothing), except `light`, which is yielded only when defined.
#include <memory>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/isa.hpp"
#include "models/protocol/packet.hpp"

namespace pp5 {

// One procedure invocation of a region's stream.
struct RegionStep {
  Procedure procedure;
  const ProcedureCode& code;
  PacketValues values;
  const Packet* packet;  // the packet it runs, or null for clear, pass, light and shade
  int pass;              // the pass it belongs to (clear: 0, the `pass` before pass k: k,
                         // light and shade: the last)
  int index;             // the packet's index among the region's packets; -1 for steps
                         // without a packet, and in the timing loop, which meets packets in
                         // arrival order before their place is known
  int light;             // the scene light a `light` step runs for, else -1
};

class RegionStream {
 public:
  // Both are referred to, not copied: they must outlive the stream and its steps.
  RegionStream(const Program& program, const FrameValues& values)
      : program_(program), values_(values), passes_(pass_count(program, values)) {}

  // The frame's passes: the plan's, or the program's count (or its pass parameter's value).
  static int pass_count(const Program& program, const FrameValues& values) {
    return values.plan.empty() ? program.pass_count(values.frame.parameters)
                               : static_cast<int>(values.plan.size());
  }

  // The passes of this frame: the program's count, or its pass parameter's value.
  int passes() const { return passes_; }

  // What runs before pass k's packets: clear before the first, `pass` before the others; or
  // the plan's opening procedures.
  template <class Visit>
  void before_pass(int pass, Visit&& visit) const {
    auto region_wide = [&](Procedure p) {
      visit(RegionStep{p, program_.procedure(p), values_.frame, nullptr, pass, -1, -1});
    };
    if (values_.plan.empty()) {
      region_wide(pass == 0 ? Procedure::clear : Procedure::pass);
      return;
    }
    for (Procedure p : values_.plan[static_cast<std::size_t>(pass)].opening) region_wide(p);
  }

  // One packet of pass k, at `index` among the region's packets.
  RegionStep packet(const Packet& packet, int pass, int index) const {
    Procedure p = packet.procedure;
    if (!values_.plan.empty()) {
      const PlannedPass& planned = values_.plan[static_cast<std::size_t>(pass)];
      if (planned.packets != Procedure::count) p = planned_procedure(planned.packets, p);
      if (!planned.draws(packet.group, packet.back)) {
        return RegionStep{
            p,       skipped_, PacketValues(packet.values.expressions, values_.frame.parameters),
            &packet, pass,     index,
            -1};
      }
    }
    return RegionStep{p,
                      program_.procedure(p),
                      PacketValues(packet.values.expressions, values_.frame.parameters),
                      &packet,
                      pass,
                      index,
                      -1};
  }

  // What runs after the last pass: the plan's closing procedures, each light's `light`
  // procedure, then shade.
  template <class Visit>
  void after_passes(Visit&& visit) const {
    const int last = passes_ - 1;
    for (Procedure p : values_.closing) {
      visit(RegionStep{p, program_.procedure(p), values_.frame, nullptr, last, -1, -1});
    }
    const ProcedureCode& light = program_.procedure(Procedure::light);
    if (light.defined) {
      for (std::size_t k = 0; k < values_.lights.size(); ++k) {
        visit(RegionStep{Procedure::light, light, values_.lights[k], nullptr, last, -1,
                         static_cast<int>(k)});
      }
    }
    visit(RegionStep{Procedure::shade, program_.procedure(Procedure::shade), values_.frame, nullptr,
                     last, -1, -1});
  }

  // Every step after clear: the passes over `packets` and what follows them.
  template <class Packets, class Visit>
  void after_clear(const Packets& packets, Visit&& visit) const {
    for (int pass = 0; pass < passes_; ++pass) {
      if (pass > 0) before_pass(pass, visit);
      int index = 0;
      for (const auto& p : packets) visit(packet(deref(p), pass, index++));
    }
    after_passes(visit);
  }

  // The whole region over `packets` (a range of Packet, Packet pointers or shared pointers).
  template <class Packets, class Visit>
  void for_each(const Packets& packets, Visit&& visit) const {
    before_pass(0, visit);
    after_clear(packets, visit);
  }

  // A region with no packets.
  template <class Visit>
  void for_each_empty(Visit&& visit) const {
    for_each(std::vector<const Packet*>{}, visit);
  }

 private:
  static const Packet& deref(const Packet& p) { return p; }
  static const Packet& deref(const Packet* p) { return *p; }
  static const Packet& deref(const std::shared_ptr<const Packet>& p) { return *p; }

  const Program& program_;
  const FrameValues& values_;
  const ProcedureCode skipped_{};  // what a packet of a group the pass does not draw runs
  int passes_;
};

}  // namespace pp5
