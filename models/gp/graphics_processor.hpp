#pragma once
// A Graphics Processor (Intel i860) as a SystemC module: transforms, clips, lights and sets
// up its share of the display list, bins the packets by region, then sends each region's
// bin over the ring to the Renderer that owns the region. The arithmetic is
// GeometryEngine's; this module charges its time in i860 clocks.
#include <memory>
#include <systemc>
#include <vector>

#include "models/common/units.hpp"
#include "models/machine.hpp"

namespace pp5 {

struct GpStats {
  GpClocks busy{};
  std::uint64_t triangles_in = 0;      // scene triangles it transformed
  std::uint64_t packets = 0;           // triangle packets it sent (one per region touched)
  std::uint64_t screen_triangles = 0;  // triangles after clipping that reached set-up
  SetupCounts setup;
  sc_core::sc_time finished;
};

class GraphicsProcessor : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(GraphicsProcessor);
  GraphicsProcessor(sc_core::sc_module_name name, int index, int first, int last, Machine& machine);

  const GpStats& stats() const { return stats_; }

 private:
  void run();
  void spend(GpClocks clocks);

  int index_;
  int first_;  // display-list range [first_, last_)
  int last_;
  Machine& machine_;
  sc_core::sc_time clock_;
  GpStats stats_;
};

}  // namespace pp5
