#include "models/renderer/renderer.hpp"

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

Renderer::Renderer(sc_core::sc_module_name name, int index, Machine& machine)
    : sc_module(name),
      index_(index),
      machine_(machine),
      cycle_(1.0 / machine.config().renderer.clock_hz, sc_core::SC_SEC) {
  for (int r = index; r < machine.config().regions(); r += machine.config().renderer.count) {
    regions_.push_back(r);
    inbox_[r].assign(machine.program().passes,
                     std::vector<std::shared_ptr<const Bin>>(machine.config().gp.count));
  }
  SC_THREAD(run);
}

void Renderer::deliver(std::shared_ptr<const Bin> bin) {
  inbox_[bin->region][bin->pass][bin->gp] = std::move(bin);
  arrived_.notify(sc_core::SC_ZERO_TIME);
}

ArrayCycles Renderer::charge(const ProcedureCode& procedure, const PacketValues& values) {
  if (!procedure.defined) return ArrayCycles{};
  ++stats_.packets;
  stats_.instructions += procedure.code.size();
  return ArrayCycles(machine_.config().renderer.packet_overhead_cycles) +
         procedure_cost(procedure, machine_.timing(), values);
}

void Renderer::run() {
  const MachineConfig& config = machine_.config();
  const Program& program = machine_.program();
  PacketValues frame_values;
  frame_values.parameters = machine_.frame_parameters();
  for (int region : regions_) {
    RegionWork w;
    w.region = region;
    w.x0 = (region % config.regions_x()) * config.renderer.region_width;
    w.y0 = (region / config.regions_x()) * config.renderer.region_height;
    ArrayCycles cycles = charge(program.procedure(Procedure::clear), frame_values);
    for (int pass = 0; pass < program.passes; ++pass) {
      if (pass > 0) cycles += charge(program.procedure(Procedure::pass), frame_values);
      auto& bins = inbox_[region][pass];
      for (int g = 0; g < config.gp.count; ++g) {
        while (!bins[g]) wait(arrived_);
        for (const auto& packet : bins[g]->packets) {
          cycles += charge(program.procedure(Procedure::triangle), packet->values);
          if (pass == 0) w.triangles.push_back(packet);
        }
        // Time advances per bin, not per cycle: one kernel event for a whole stream.
        wait(cycle_ * static_cast<double>(cycles.count));
        stats_.busy += cycles;
        cycles = ArrayCycles{};
      }
    }
    cycles += charge(program.procedure(Procedure::shade), frame_values);
    wait(cycle_ * static_cast<double>(cycles.count));
    stats_.busy += cycles;
    inbox_.erase(region);
    machine_.ring().transfer(machine_.renderer_stop(index_), machine_.frame_buffer_stop(),
                             machine_.region_words());
    machine_.frame_buffer().region_arrived(region);
    ++stats_.regions;
    work_.push_back(std::move(w));
  }
  stats_.finished = sc_core::sc_time_stamp();
}

void Renderer::execute(RendererBoard& board, const Program& program, FrameBuffer& frame_buffer,
                       const PacketValues& frame_values) const {
  const auto& geometry = board.array().geometry();
  std::vector<std::uint8_t> rgb;
  for (const RegionWork& w : work_) {
    if (w.triangles.empty()) {  // the same stream every time: executed once, then reused
      board.run_empty_region(w.x0, w.y0, program, frame_values, rgb);
      frame_buffer.store_region(w.x0, w.y0, geometry.width, geometry.height, rgb);
      continue;
    }
    board.begin_region(w.x0, w.y0);
    board.run(program.procedure(Procedure::clear), frame_values);
    for (int pass = 0; pass < program.passes; ++pass) {
      if (pass > 0) board.run(program.procedure(Procedure::pass), frame_values);
      for (const auto& packet : w.triangles)
        board.run(program.procedure(Procedure::triangle), packet->values);
    }
    board.run(program.procedure(Procedure::shade), frame_values);
    board.read_outputs(program, rgb);
    frame_buffer.store_region(w.x0, w.y0, geometry.width, geometry.height, rgb);
  }
}

}  // namespace pp5
