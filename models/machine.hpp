#pragma once
// The whole Pixel-Planes 5 as a SystemC top level: Graphics Processors, the ring, the
// Renderer boards and the frame buffer, and what they share for one frame.
//
// A triangle's path: the host's display list (the Scene) is split into contiguous blocks,
// one per GP; each GraphicsProcessor transforms, clips, lights and sets up its triangles
// (models/gp/geometry.hpp) and bins the packets by region; then, region by region, it sends
// each bin over the Ring to the Renderer that owns the region; each Renderer charges the
// firmware's cycles for its bins in GP order (so ties resolve in display-list order) and
// ships the finished region over the ring to the FrameBuffer.
//
// Timing and function are separated: no instruction's cost depends on pixel data, so the
// modules advance simulated time from the instruction table alone, and record each
// region's packets; after the simulation each Renderer's board executes its regions'
// instruction streams on its pixel array (execute_pixels), in parallel across boards.
#include <memory>
#include <systemc>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/gp/geometry.hpp"
#include "sim/config/machine_config.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

class GraphicsProcessor;
class Renderer;
class Ring;
class FrameBuffer;

// One procedure invocation sent from a GP to a Renderer.
struct Packet {
  int primitive = -1;  // scene triangle, or -1 for clear/shade
  std::uint64_t words = 0;
  PacketValues values;
};

// Everything one GP sends one region.
// With a multipass program the GP sends the same packets once per pass.
struct Bin {
  int region = 0;
  int gp = 0;
  int pass = 0;
  std::vector<std::shared_ptr<const Packet>> packets;
  std::uint64_t words = 0;
};

// The machine configuration seen by each plain-C++ part.
GeometryParams geometry_params(const MachineConfig& config);
TimingParams timing_params(const MachineConfig& config);
struct RendererBoardParams;
RendererBoardParams board_params(const MachineConfig& config);
AssemblerOptions assembler_options(const MachineConfig& config);

class Machine : public sc_core::sc_module {
 public:
  Machine(sc_core::sc_module_name name, const MachineConfig& config, const Scene& scene,
          const Program& program);
  ~Machine() override;

  const MachineConfig& config() const { return config_; }
  const Program& program() const { return program_; }
  const Scene& scene() const { return scene_; }
  const GeometryEngine& geometry() const { return geometry_; }
  const TimingParams& timing() const { return timing_; }
  const std::array<std::int64_t, static_cast<int>(Parameter::count)>& frame_parameters() const {
    return frame_parameters_;
  }

  Ring& ring() { return *ring_; }
  FrameBuffer& frame_buffer() { return *frame_buffer_; }
  Renderer& renderer(int k) { return *renderers_[k]; }
  GraphicsProcessor& gp(int k) { return *gps_[k]; }
  int gp_count() const { return static_cast<int>(gps_.size()); }
  int renderer_count() const { return static_cast<int>(renderers_.size()); }

  // Ring stops: GPs first, then Renderers, then the frame buffer.
  int gp_stop(int k) const { return k; }
  int renderer_stop(int k) const { return gp_count() + k; }
  int frame_buffer_stop() const { return gp_count() + renderer_count(); }
  int ring_stops() const { return frame_buffer_stop() + 1; }

  // Static assignment: region r belongs to Renderer r mod count.
  int renderer_of_region(int region) const { return region % renderer_count(); }
  // Ring words of a packet carrying `expressions` linear expressions.
  std::uint64_t packet_words(int expressions) const;
  std::uint64_t region_words() const;

  // Runs every board's recorded instruction streams on its pixel array, on `threads` host
  // threads, and stores the results in the frame buffer's image. Deterministic: each
  // board executes its own regions in order, whatever the thread count.
  void execute_pixels(int threads);

 private:
  static std::string fmt_name(const char* base, int k);

  MachineConfig config_;
  const Scene& scene_;
  const Program& program_;
  GeometryEngine geometry_;
  TimingParams timing_;
  std::array<std::int64_t, static_cast<int>(Parameter::count)> frame_parameters_{};
  std::unique_ptr<Ring> ring_;
  std::unique_ptr<FrameBuffer> frame_buffer_;
  std::vector<std::unique_ptr<Renderer>> renderers_;
  std::vector<std::unique_ptr<GraphicsProcessor>> gps_;
};

}  // namespace pp5
