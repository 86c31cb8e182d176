#pragma once
// The firmware assembler: turns a text program (see firmware/README.md) into the
// instruction streams the Renderer executes, and lays its fields out in pixel memory.
//
// Contract: a program that assembles fits the machine.
//  - `field`s keep their value from one procedure to the next; they are placed in
//    declaration order from bit 0.
//  - `scratch` fields hold a value only within one run of one procedure: they share one
//    overlay after the fields, where two scratch fields overlap only if no procedure uses
//    both. Every bit of a scratch field a procedure reads must have been written earlier in
//    that procedure (in program order), or the program is refused naming the line: so no
//    overlap is ever live across procedures.
//  - If the fields and the overlay do not fit in renderer.memory_bits the program is
//    rejected, unless it says `option spill`: then fields move to the backing store, those
//    marked `cold` first, then the least used (static uses weighted by how often their
//    procedure runs, kProcedureWeight), until the rest plus a staging area for the spilled
//    fields one instruction uses fit. Output fields and scratch fields never spill. Every use
//    of a spilled field is bracketed by real bsld/bsst instructions, whose cost the Renderer
//    charges like any other.
//  - Errors are AssemblyError with the message "FILE:LINE: what was expected".
#include <array>
#include <bitset>
#include <cstdint>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/isa/isa.hpp"

namespace pp5 {

struct AssemblyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct AssemblerOptions {
  int memory_bits = 208;
  int backing_store_bits = 4096;
  int block_bits = 32;
  int enable_stack_depth = 8;
};

// How often a procedure runs, relative to the others, for choosing what to spill: `triangle`
// and `sphere` run once per packet, the others once per region (light once per scene light). The
// 256 is assumed: a region of the built-in torus at 1280 x 1024 receives on the order of a hundred
// packets, and any weight well above the number of lights gives the same choices.
// clear triangle pass shade light sphere parity surface candidate keep_inside keep_outside merge
// next_layer sphere_surface sphere_parity
inline constexpr int kProcedureWeight[] = {1, 256, 1, 1, 1, 256, 256, 256, 1, 1, 1, 1, 1, 256, 256};
static_assert(std::size(kProcedureWeight) == static_cast<std::size_t>(Procedure::count));

struct FieldDecl {
  std::string name;
  int width = 0;
  bool is_signed = false;
  int line = 0;
  bool scratch = false;  // lives in the overlay: dead between procedure runs
  bool cold = false;     // the author asks that it spill first
  bool spilled = false;  // lives in the backing store
  int lo = -1;           // first bit in pixel memory (resident fields)
  int block = -1;        // first backing-store block (spilled fields)
  // Instructions of each procedure that name the field, and their weighted sum (the spill
  // order: cold first, then the lowest weight, then the last declared).
  std::array<int, static_cast<int>(Procedure::count)> uses{};
  std::uint64_t weight = 0;
};

struct ProcedureCode {
  bool defined = false;
  int line = 0;
  std::vector<Instruction> code;
  std::bitset<static_cast<int>(Expression::count)> expressions;  // what the GP must send
  std::bitset<static_cast<int>(Parameter::count)> parameters;
  int spill_transfers = 0;  // bsld/bsst the assembler inserted
};

// The most passes a program may ask for; each pass resends every triangle.
inline constexpr int kMaxPasses = 64;
// The largest program file read (16 MiB, some hundred thousand lines).
inline constexpr std::uint64_t kMaxProgramBytes = 16ull << 20;

struct Program {
  std::string name;  // file name or label, for messages and reports
  std::vector<FieldDecl> fields;
  std::array<ProcedureCode, static_cast<int>(Procedure::count)> procedures;
  std::array<Field, 3> outputs{};  // red, green, blue sent to the frame buffer
  bool spill_allowed = false;
  int passes = 1;             // times the GPs send each region's triangles (`option passes N`)
  int passes_parameter = -1;  // or a frame parameter's index (`option passes PARAMETER`)
  int memory_bits = 0;        // the budget
  int resident_bits = 0;      // bits of the fields kept in pixel memory, overlay included
  int overlay_bits = 0;       // bits of the scratch overlay (part of resident_bits)
  int overlay_lo = 0;         // its first bit
  int staging_bits = 0;       // bits reserved for spilled fields while an instruction uses them

  int bits_used() const { return resident_bits + staging_bits; }
  const ProcedureCode& procedure(Procedure p) const { return procedures[static_cast<int>(p)]; }
  const FieldDecl* find_field(const std::string& name) const;
  // The pass count of a frame with these parameters: `passes`, or the parameter's value.
  // Throws std::runtime_error naming the program if that value is outside 1..kMaxPasses.
  int pass_count(const ParameterValues& frame) const;
  // Whether the program may run more than one pass (a transparency program).
  bool multipass() const { return passes_parameter >= 0 || passes > 1; }
};

Program assemble(const std::string& source, const std::string& name,
                 const AssemblerOptions& options);
Program assemble_file(const std::string& path, const AssemblerOptions& options);

// A human-readable listing: the field map and every procedure's instructions with costs, each
// priced by the instruction table as the Renderer charges it for a packet whose frame
// parameters are `parameters` (a `mac` costs what its constant's set bits cost, so the price
// of `mac dst, a, epsilon_scale` depends on the frame). `priced_for` names where those
// values come from (a scene and configuration), printed in the listing's head.
std::string listing(const Program& program, const TimingParams& timing,
                    const ParameterValues& parameters, const std::string& priced_for);

}  // namespace pp5
