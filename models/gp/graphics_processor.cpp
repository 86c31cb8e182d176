#include "models/gp/graphics_processor.hpp"

#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

GraphicsProcessor::GraphicsProcessor(sc_core::sc_module_name name, int index, int first, int last,
                                     Machine& machine)
    : sc_module(name),
      index_(index),
      first_(first),
      last_(last),
      machine_(machine),
      clock_(1.0 / machine.config().gp.clock_hz, sc_core::SC_SEC) {
  SC_THREAD(run);
}

void GraphicsProcessor::spend(GpClocks clocks) {
  stats_.busy += clocks;
  wait(clock_ * static_cast<double>(clocks.count));
}

void GraphicsProcessor::run() {
  const MachineConfig& config = machine_.config();
  const GeometryEngine& geometry = machine_.geometry();
  const ProcedureCode& triangle = machine_.program().procedure(Procedure::triangle);
  const int expressions = static_cast<int>(triangle.expressions.count());
  const std::uint64_t words = machine_.packet_words(expressions);
  const GpClocks per_triangle(config.gp.clocks_per_triangle);
  const GpClocks per_setup(static_cast<std::uint64_t>(config.gp.clocks_per_expression) *
                           expressions);

  std::vector<std::shared_ptr<Bin>> bins(config.regions());
  for (int r = 0; r < config.regions(); ++r) {
    bins[r] = std::make_shared<Bin>();
    bins[r]->region = r;
    bins[r]->gp = index_;
  }
  std::vector<ScreenTriangle> screen;
  std::vector<int> regions;
  for (int i = first_; i < last_; ++i) {
    screen.clear();
    geometry.transform(i, screen, stats_.setup);
    ++stats_.triangles_in;
    GpClocks clocks = per_triangle;
    for (const ScreenTriangle& t : screen) {
      ++stats_.screen_triangles;
      clocks += per_setup;
      SetupResult result;
      if (!geometry.setup(t, triangle.expressions, result, stats_.setup)) continue;
      auto packet = std::make_shared<Packet>();
      packet->primitive = i;
      packet->words = words;
      packet->values = result.values;
      packet->values.parameters = machine_.frame_parameters();
      regions.clear();
      geometry.bin(result, regions);
      for (int r : regions) {
        bins[r]->packets.push_back(packet);
        bins[r]->words += words;
        ++stats_.packets;
      }
    }
    spend(clocks);
  }
  // One header word per bin, so an empty bin still tells its Renderer this GP is done. A
  // multipass program gets the same packets again for every pass, after the previous pass's
  // bins have all gone: the GP keeps its set-up packets, so only the sending repeats.
  const int passes = machine_.program().passes;
  for (int r = 0; r < config.regions(); ++r) bins[r]->words += 1;
  for (int pass = 0; pass < passes; ++pass) {
    for (int r = 0; r < config.regions(); ++r) {
      spend(GpClocks(config.gp.clocks_per_bin));
      auto bin = pass + 1 < passes ? std::make_shared<Bin>(*bins[r]) : std::move(bins[r]);
      bin->pass = pass;
      const int renderer = machine_.renderer_of_region(r);
      machine_.ring().transfer(machine_.gp_stop(index_), machine_.renderer_stop(renderer),
                               bin->words);
      machine_.renderer(renderer).deliver(std::move(bin));
    }
  }
  stats_.finished = sc_core::sc_time_stamp();
}

}  // namespace pp5
