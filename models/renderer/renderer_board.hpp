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
#include "firmware/isa/isa.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/pixel_array/pixel_array.hpp"

namespace pp5 {

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
  std::uint64_t instructions_ = 0;
  ArrayCycles cycles_{};
};

// The cost of one procedure for one packet, from the instruction table: the figure both
// the timing model and the board use.
ArrayCycles procedure_cost(const ProcedureCode& procedure, const TimingParams& timing,
                           const PacketValues& values);

}  // namespace pp5
