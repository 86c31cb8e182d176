#pragma once
// A Renderer board as a SystemC module: the timing half. It receives bins over the ring,
// charges the firmware's cycles for each in GP order, and ships finished regions to the
// frame buffer. The functional half is RendererBoard (renderer_board.hpp), which executes
// the same streams on the pixel array; see models/machine.hpp for how the two meet.
#include <map>
#include <memory>
#include <systemc>
#include <vector>

#include "models/common/units.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer_board.hpp"

namespace pp5 {

// The instruction stream of one region: clear, then for each of the program's passes the
// triangles in this order (with `pass` between passes), then shade.
struct RegionWork {
  int region = 0;
  int x0 = 0;
  int y0 = 0;
  std::vector<std::shared_ptr<const Packet>> triangles;
};

struct RendererStats {
  ArrayCycles busy{};  // cycles executing micro-instructions and decoding packets
  std::uint64_t regions = 0;
  std::uint64_t packets = 0;
  std::uint64_t instructions = 0;  // micro-instructions issued to the array
  sc_core::sc_time finished;       // when its last region left for the frame buffer
};

class Renderer : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(Renderer);
  Renderer(sc_core::sc_module_name name, int index, Machine& machine);

  // A GP's bin has arrived over the ring.
  void deliver(std::shared_ptr<const Bin> bin);

  const RendererStats& stats() const { return stats_; }
  const std::vector<RegionWork>& work() const { return work_; }
  // The functional model: runs this board's regions on its pixel array.
  void execute(RendererBoard& board, const Program& program, FrameBuffer& frame_buffer,
               const PacketValues& frame_values) const;

 private:
  void run();
  ArrayCycles charge(const ProcedureCode& procedure, const PacketValues& values);

  int index_;
  Machine& machine_;
  std::vector<int> regions_;
  // region -> pass -> bins by GP
  std::map<int, std::vector<std::vector<std::shared_ptr<const Bin>>>> inbox_;
  sc_core::sc_event arrived_;
  sc_core::sc_time cycle_;
  RendererStats stats_;
  std::vector<RegionWork> work_;
};

}  // namespace pp5
