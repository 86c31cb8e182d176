#pragma once
// What a GP sends a Renderer: one procedure invocation per packet (ring messages carry runs
// of them, see BinMessage in models/ring/ring.hpp).
//
// Contract:
//  - A packet names the procedure it runs and the primitive kind that made it; the Renderer
//    charges and executes `procedure`, whatever it is.
//  - A packet carries its expressions only. The frame's parameters are bound to them when
//    the packet is charged or executed (RegionStream), never copied into the packet.
#include <cstdint>

#include "firmware/isa/isa.hpp"

namespace pp5 {

struct Packet {
  Procedure procedure = Procedure::triangle;  // the procedure it runs: its kind's
  int kind = 0;        // the primitive kind that set it up: index in primitive_kinds() (models/gp)
  int primitive = -1;  // the display-list index of the primitive it came from
  int group = -1;      // the solid its primitive belongs to (Scene::solids), -1 for none
  bool back = false;   // a triangle facing away from the eye, or a solid sphere's far
                       // hemisphere (a header bit: the pass plan's front- and back-face
                       // passes, PlannedPass::faces)
  std::uint64_t words = 0;  // ring words: a header, then each expression's coefficients by form
  PacketExpressions values;
};

}  // namespace pp5
