#pragma once
// The functional half of a Renderer board, as plain C++: the pixel array, the expression
// evaluator and the controller that feeds a procedure's micro-instructions to them.
//
// Contract: every pixel value comes from executing instructions of the firmware's
// instruction table on the PixelArray; run() returns the cycles those instructions cost,
// the same figure the Renderer module charges in simulated time.
#include <cstdint>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/interface.hpp"
#include "firmware/isa/isa.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/pixel_array/pixel_array.hpp"

namespace pp5 {

class RendererBoard;

// Which packet the board is about to run, for observers (tracing); supplied by the
// Renderer, which knows the region, the primitive and when the timing pass started it.
struct PacketContext {
  Procedure procedure = Procedure::clear;
  int primitive = -1;  // scene triangle, or -1 for clear/shade
  int region = 0;
  std::uint64_t start_cycle = 0;  // simulated array cycle at which the packet starts
};

// An opt-in observer of a board's execution (see sim/trace/). Contract: the board calls
// begin_packet before each packet's first instruction, after_instruction after each
// instruction has executed (with its index in the procedure and its cost), and end_region
// after a region's shade procedure. With no observer the board's only extra work is one
// predictable branch per procedure run.
class BoardObserver {
 public:
  virtual ~BoardObserver() = default;
  virtual void begin_packet(const PacketContext& packet, const ProcedureCode& procedure,
                            const RendererBoard& board) = 0;
  virtual void after_instruction(int index, const Instruction& instruction, ArrayCycles cost,
                                 const RendererBoard& board) = 0;
  virtual void end_region(int region, const RendererBoard& board) = 0;
};

struct RendererBoardParams {
  PixelArrayGeometry array;
  EvaluatorParams evaluator;
  TimingParams timing;
};

class RendererBoard {
 public:
  explicit RendererBoard(const RendererBoardParams& params);

  // Points the evaluator at a region; pixel memory keeps whatever it held (as the hardware
  // would): the program's clear procedure is what initialises it.
  void begin_region(int x0, int y0);
  ArrayCycles run(const ProcedureCode& procedure, const PacketValues& values);
  // Observation (tracing): `observer` may be null; the board does not own it.
  void set_observer(BoardObserver* observer) { observer_ = observer; }
  void begin_packet(const PacketContext& packet) { packet_ = packet; }
  void end_region(int region) {
    if (observer_) observer_->end_region(region, *this);
  }
  // Reads the program's output fields of every pixel as 8-bit RGB, row-major.
  void read_outputs(const Program& program, std::vector<std::uint8_t>& rgb) const;

  PixelArray& array() { return array_; }
  const PixelArray& array() const { return array_; }
  ExpressionEvaluator& evaluator() { return evaluator_; }
  std::uint64_t instructions_executed() const { return instructions_; }
  ArrayCycles cycles_executed() const { return cycles_; }

 private:
  RendererBoardParams params_;
  PixelArray array_;
  ExpressionEvaluator evaluator_;
  std::vector<Word> scratch_;
  BoardObserver* observer_ = nullptr;
  PacketContext packet_;
  ArrayCycles run_observed(const ProcedureCode& procedure, const PacketValues& values);

  std::uint64_t instructions_ = 0;
  ArrayCycles cycles_{};
};

// The cost of one procedure for one packet, from the instruction table: the figure both
// the timing model and the board use.
ArrayCycles procedure_cost(const ProcedureCode& procedure, const TimingParams& timing,
                           const PacketValues& values);

}  // namespace pp5
