#include "models/machine.hpp"

#include <fmt/format.h>

#include <atomic>
#include <stdexcept>
#include <thread>

#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/graphics_processor.hpp"
#include "models/renderer/renderer.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

GeometryParams geometry_params(const MachineConfig& c) {
  GeometryParams g;
  g.screen_width = c.screen.width;
  g.screen_height = c.screen.height;
  g.region_width = c.renderer.region_width;
  g.region_height = c.renderer.region_height;
  g.subpixel_bits = c.gp.subpixel_bits;
  g.depth_bits = c.gp.depth_bits;
  g.fraction_bits = c.evaluator.fraction_bits;
  g.coefficient_bits = c.evaluator.coefficient_bits;
  g.result_bits = c.evaluator.result_bits;
  g.cull_back_faces = c.gp.cull_back_faces != 0;
  g.frame = c.frame.set;
  return g;
}

TimingParams timing_params(const MachineConfig& c) {
  TimingParams t;
  t.fraction_bits = c.evaluator.fraction_bits;
  t.result_bits = c.evaluator.result_bits;
  t.evaluator_latency = c.evaluator.latency_cycles;
  t.block_bits = c.renderer.block_bits;
  t.backing_store_cycles_per_block = c.renderer.backing_store_cycles_per_block;
  return t;
}

I860Params i860_params(const MachineConfig& c) {
  I860Params p;
  p.code = parse_gp_code(name_of(c.gp.code));
  p.fp_latency_clocks = c.gp.fp_latency_clocks;
  p.load_use_clocks = c.gp.load_use_clocks;
  p.icache_bytes = c.gp.icache_bytes;
  p.icache_line_bytes = c.gp.icache_line_bytes;
  p.icache_miss_clocks = c.gp.icache_miss_clocks;
  p.assembly_code_bytes = c.gp.assembly_code_bytes;
  p.compiled_code_bytes = c.gp.compiled_code_bytes;
  p.overhead_factor = c.gp.overhead_factor;
  return p;
}

RendererBoardParams board_params(const MachineConfig& c) {
  RendererBoardParams p;
  p.array.width = c.renderer.region_width;
  p.array.height = c.renderer.region_height;
  p.array.memory_bits = c.renderer.memory_bits;
  p.array.enable_stack_depth = c.renderer.enable_stack_depth;
  p.array.backing_store_bits = c.renderer.backing_store_bits;
  p.array.block_bits = c.renderer.block_bits;
  p.evaluator.coefficient_bits = c.evaluator.coefficient_bits;
  p.evaluator.result_bits = c.evaluator.result_bits;
  p.timing = timing_params(c);
  return p;
}

AssemblerOptions assembler_options(const MachineConfig& c) {
  AssemblerOptions o;
  o.memory_bits = c.renderer.memory_bits;
  o.backing_store_bits = c.renderer.backing_store_bits;
  o.block_bits = c.renderer.block_bits;
  o.enable_stack_depth = c.renderer.enable_stack_depth;
  return o;
}

Machine::Machine(sc_core::sc_module_name name, const MachineConfig& config, const Scene& scene,
                 const Program& program)
    : sc_module(name),
      config_(config),
      scene_(scene),
      program_(program),
      geometry_(geometry_params(config), scene),
      timing_(timing_params(config)),
      frame_values_(geometry_.frame_values()),
      i860_(i860_params(config)),
      dynamic_(config.renderer.balancing == MachineConfig::Renderer::Balancing::dynamic),
      owner_(config.regions(), -1),
      bin_senders_(config.regions(), 0),
      claimed_(config.renderer.count, 0) {
  const int gps = config.gp.count;
  const int renderers = config.renderer.count;
  const ProcedureCode& triangle = program.procedure(Procedure::triangle);
  workload_.expressions = triangle.expressions;
  workload_.lights = geometry_.lights();
  workload_.packet_words = packet_words(static_cast<int>(triangle.expressions.count()));
  if (workload_.packet_words + 1 > static_cast<std::uint64_t>(config.renderer.queue_words)) {
    throw std::runtime_error(fmt::format(
        "key 'renderer.queue_words' = {} is too small: one triangle packet of '{}' takes {} "
        "words plus a header word",
        config.renderer.queue_words, program.name, workload_.packet_words));
  }
  RingParams rp;
  rp.channels = config.ring.channels;
  rp.word_bits = config.ring.word_bits;
  rp.clock_hz = config.ring.clock_hz;
  rp.hop_latency_cycles = config.ring.hop_latency_cycles;
  ring_ = std::make_unique<Ring>("ring", rp, gps + renderers + 1);
  frame_buffer_ = std::make_unique<FrameBuffer>("frame_buffer", config.screen.width,
                                                config.screen.height, config.regions());
  for (int k = 0; k < renderers; ++k) {
    renderers_.push_back(std::make_unique<Renderer>(fmt_name("renderer", k).c_str(), k, *this));
  }
  // The host spreads the display list over the GPs in contiguous blocks, so that the
  // concatenation of the GPs' bins is in display-list order.
  const auto n = static_cast<long long>(scene.mesh.triangles.size());
  for (int k = 0; k < gps; ++k) {
    const int first = static_cast<int>(n * k / gps);
    const int last = static_cast<int>(n * (k + 1) / gps);
    if (last > first) ++busy_gps_;
    gps_.push_back(
        std::make_unique<GraphicsProcessor>(fmt_name("gp", k).c_str(), k, first, last, *this));
  }
}

Machine::~Machine() = default;

int Machine::claim_region(int renderer) {
  int region = -1;
  if (dynamic_) {
    if (next_region_ < config_.regions()) region = next_region_++;
  } else {
    const int r = renderer + claimed_[renderer] * renderer_count();
    if (r < config_.regions()) {
      region = r;
      ++claimed_[renderer];
    }
  }
  if (region >= 0) owner_[region] = renderer;
  return region;
}

void Machine::add_bin_senders(const std::vector<int>& regions) {
  for (int r : regions) ++bin_senders_[r];
}

std::uint64_t Machine::bin_map_words() const {
  const auto bits = static_cast<std::uint64_t>(config_.regions());
  const auto word = static_cast<std::uint64_t>(config_.ring.word_bits);
  return 1 + (bits + word - 1) / word;
}

void Machine::record_timeline(bool on) {
  timeline_on_ = on;
  ring_->record_messages(on);
}

std::string Machine::fmt_name(const char* base, int k) {
  return std::string(base) + std::to_string(k);
}

std::uint64_t Machine::packet_words(int expressions) const {
  const int per_coefficient =
      (config_.evaluator.coefficient_bits + config_.ring.word_bits - 1) / config_.ring.word_bits;
  // A header word naming the procedure, then three coefficients per linear expression.
  return 1 + static_cast<std::uint64_t>(expressions) * 3 * per_coefficient;
}

std::uint64_t Machine::region_words() const {
  const std::uint64_t bits = static_cast<std::uint64_t>(config_.renderer.region_width) *
                             config_.renderer.region_height * config_.frame_buffer.bits_per_pixel;
  return (bits + config_.ring.word_bits - 1) / config_.ring.word_bits;
}

void Machine::execute_pixels(int threads,
                             const std::function<BoardObserver*(int renderer)>& observe) {
  RendererBoardParams params = board_params(config_);
  // Only the bits the program declares are allocated and processed: fields beyond them would
  // be refused by the pixel array's bounds checks, never silently dropped.
  params.array.memory_bits = std::max(1, program_.bits_used());
  // One empty region, executed before the boards start, serves every board whose state
  // after clear matches it (RendererBoard::run_empty_region checks); the rest of the boards'
  // regions run as recorded.
  RendererBoard first(params);
  std::vector<std::uint8_t> empty_rgb;
  first.run_empty_region(0, 0, program_, frame_values_, empty_rgb);
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int k = next++; k < renderer_count(); k = next++) {
      if (renderers_[k]->work().empty()) continue;  // a Renderer the frame did not use
      RendererBoard board(params);
      if (observe) board.set_observer(observe(k));
      board.share_empty_region(first);
      renderers_[k]->execute(board, program_, *frame_buffer_, frame_values_);
    }
  };
  const int n = std::max(1, std::min(threads, renderer_count()));
  std::vector<std::thread> pool;
  for (int t = 1; t < n; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace pp5
