#include "models/machine.hpp"

#include <algorithm>
#include <string>

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/graphics_processor.hpp"
#include "models/renderer/execute_pixels.hpp"
#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

Machine::Machine(sc_core::sc_module_name name, const MachineConfig& config, const Scene& scene,
                 const Program& program)
    : sc_module(name),
      plan_(config, scene, program),
      scheduler_("scheduler", config.regions(), config.renderer.count, config.gp.count,
                 config.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic,
                 config.gp.send_order) {
  const int gps = config.gp.count;
  const int renderers = config.renderer.count;
  ring_ = std::make_unique<Ring>("ring", ring_params(config), plan_.ring_stops());
  // With fidelity.pixels=none no region's pixels arrive: the frame buffer holds none.
  frame_buffer_ = std::make_unique<FrameBuffer>(
      "frame_buffer", config.screen.width, config.screen.height, config.renderer.region_width,
      config.renderer.region_height, config.regions(),
      config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none);
  const RendererWiring renderer_wiring{plan_,       plans_,    *ring_, scheduler_,
                                       gp_reports_, timeline_, clock_};
  for (int k = 0; k < renderers; ++k) {
    renderers_.push_back(
        std::make_unique<Renderer>(fmt_name("renderer", k).c_str(), k, renderer_wiring));
    renderer_queues_.push_back(renderers_.back().get());
    clock_.enrol_renderer();
  }
  const GpWiring gp_wiring{plan_, plans_, *ring_, scheduler_, renderer_queues_, timeline_, clock_};
  for (int k = 0; k < gps; ++k) {
    const auto [first, last] = plan_.gp_block(k);
    gps_.push_back(
        std::make_unique<GraphicsProcessor>(fmt_name("gp", k).c_str(), k, first, last, gp_wiring));
    gp_reports_.push_back(gps_.back().get());
  }
  // The stops are numbered once every unit exists. GPs receive only the depth sort's
  // messages (painter's).
  for (int k = 0; k < gps; ++k) ring_->attach(gp_stop(k), *gps_[k]);
  for (int k = 0; k < renderers; ++k) {
    ring_->attach(renderer_stop(k), *renderers_[k]);
    renderer_stops_.push_back(renderer_stop(k));
  }
  ring_->attach(frame_buffer_stop(), *frame_buffer_);
  std::vector<std::vector<int>> hops(static_cast<std::size_t>(gps),
                                     std::vector<int>(static_cast<std::size_t>(renderers)));
  for (int g = 0; g < gps; ++g) {
    for (int k = 0; k < renderers; ++k) hops[g][k] = ring_->hops(gp_stop(g), renderer_stop(k));
  }
  scheduler_.set_ring(std::move(hops));
  scheduler_.wake_before_maps(config.frames.gp_send == MachineConfig::Frames::GpSend::when_full);
}

Machine::~Machine() = default;

sc_core::sc_time Machine::frame_end() const {
  return std::max(sc_core::sc_time_stamp(), clock_.start() + frame_buffer_->frame_complete());
}

void Machine::overlap(int frames, FramePlans::Source plans) {
  if (plans) plans_.set_source(std::move(plans));
  clock_.set_overlapped(true);
  clock_.release(frames);
}

void Machine::begin_frame(int frame) {
  clock_.begin(frame);
  timeline_.set_frame(frame);
  scheduler_.reset_frame();
  ring_->reset_frame(clock_.start());
  frame_buffer_->begin_frame(clock_.start());
  for (auto& r : renderers_) r->reset_frame();
  for (auto& g : gps_) g->reset_frame();
}

void Machine::record_timeline(bool on) {
  timeline_.record(on);
  ring_->record_messages(on);
}

void execute_pixels(Machine& machine, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe,
                    const std::atomic<bool>* cancel, PixelBoards* boards) {
  std::vector<const std::vector<RegionWork>*> work;
  for (int k = 0; k < machine.renderer_count(); ++k) work.push_back(&machine.renderer(k).work());
  execute_pixels(machine.plan(), machine.frame_buffer(), work, threads, observe, cancel, boards);
}

std::string Machine::fmt_name(const char* base, int k) {
  return std::string(base) + std::to_string(k);
}

}  // namespace pp5
