#include "models/renderer/renderer_board.hpp"

namespace pp5 {

RendererBoard::RendererBoard(const RendererBoardParams& params)
    : params_(params),
      array_(params.array),
      evaluator_(params.evaluator, params.array.width, params.array.height),
      scratch_(static_cast<std::size_t>(Bits::kMaxBits) * array_.words(), 0) {}

void RendererBoard::begin_region(int x0, int y0) { evaluator_.set_origin(x0, y0); }

ArrayCycles RendererBoard::run(const ProcedureCode& procedure, const PacketValues& values) {
  if (observer_) return run_observed(procedure, values);
  ExecutionContext ctx{array_, evaluator_, values, params_.timing.fraction_bits, scratch_};
  ArrayCycles cycles{};
  for (const Instruction& ins : procedure.code) {
    const InstructionInfo& info = instruction_info(ins.op);
    info.execute(ins, ctx);
    cycles += info.cost(ins, params_.timing, values);
  }
  instructions_ += procedure.code.size();
  cycles_ += cycles;
  return cycles;
}

// The same loop as run(), with the observer told about every instruction.
ArrayCycles RendererBoard::run_observed(const ProcedureCode& procedure,
                                        const PacketValues& values) {
  ExecutionContext ctx{array_, evaluator_, values, params_.timing.fraction_bits, scratch_};
  observer_->begin_packet(packet_, procedure, *this);
  ArrayCycles cycles{};
  int index = 0;
  for (const Instruction& ins : procedure.code) {
    const InstructionInfo& info = instruction_info(ins.op);
    info.execute(ins, ctx);
    const ArrayCycles cost = info.cost(ins, params_.timing, values);
    cycles += cost;
    observer_->after_instruction(index++, ins, cost, *this);
  }
  instructions_ += procedure.code.size();
  cycles_ += cycles;
  return cycles;
}

void RendererBoard::read_outputs(const Program& program, std::vector<std::uint8_t>& rgb) const {
  const int n = array_.pixels();
  rgb.resize(static_cast<std::size_t>(n) * 3);
  for (int c = 0; c < 3; ++c) {
    const Field& f = program.outputs[c];
    for (int p = 0; p < n; ++p) {
      rgb[static_cast<std::size_t>(p) * 3 + c] = static_cast<std::uint8_t>(array_.read(p, f));
    }
  }
}

ArrayCycles procedure_cost(const ProcedureCode& procedure, const TimingParams& timing,
                           const PacketValues& values) {
  ArrayCycles cycles{};
  for (const Instruction& ins : procedure.code) cycles += instruction_cost(ins, timing, values);
  return cycles;
}

}  // namespace pp5
