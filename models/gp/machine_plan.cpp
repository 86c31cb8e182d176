#include "models/gp/machine_plan.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "models/gp/depth_sort.hpp"
#include "models/gp/expressions.hpp"
#include "models/gp/pass_plan.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/gp/setup_memo.hpp"

namespace pp5 {

GeometryParams geometry_params(const MachineConfig& c) {
  GeometryParams g;
  g.screen_width = c.screen.width;
  g.screen_height = c.screen.height;
  g.region_width = c.renderer.region_width;
  g.region_height = c.renderer.region_height;
  g.subpixel_bits = c.gp.subpixel_bits;
  g.significand_bits = c.gp.significand_bits;
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
  t.multiply_window =
      c.renderer.multiply_microcode == MachineConfig::Renderer::MultiplyMicrocode::window;
  t.msb_first = c.evaluator.bit_order == MachineConfig::Evaluator::BitOrder::msb_first;
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
  p.overhead_form = c.gp.overhead_form == MachineConfig::Gp::OverheadForm::add
                        ? I860Params::OverheadForm::add
                        : I860Params::OverheadForm::multiply;
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

RingParams ring_params(const MachineConfig& c) {
  RingParams p;
  p.channels = c.ring.channels;
  p.word_bits = c.ring.word_bits;
  p.clock_hz = c.ring.clock_hz;
  p.hop_latency_cycles = c.ring.hop_latency_cycles;
  return p;
}

MachinePlan::MachinePlan(const MachineConfig& config, const Scene& scene, const Program& program)
    : config_(config),
      scene_(&scene),
      program_(program),
      geometry_(std::in_place, geometry_params(config), scene),
      timing_(timing_params(config)),
      i860_(i860_params(config)),
      ring_(ring_params(config)),
      ring_cycle_(1.0 / ring_.clock_hz, sc_core::SC_SEC) {
  check_pass_plan(program);
  derive_from_scene();
}

void MachinePlan::set_scene(const Scene& scene) {
  check_same_primitives(scene);
  scene_ = &scene;
  geometry_.emplace(geometry_params(config_), scene);
  setup_memo_ = nullptr;
  busy_gps_ = 0;
  derive_from_scene();
}

void MachinePlan::check_same_primitives(const Scene& scene) const {
  const std::vector<int> before = primitive_counts(*scene_);
  const std::vector<int> after = primitive_counts(scene);
  for (std::size_t k = 0; k < before.size(); ++k) {
    if (before[k] != after[k]) {
      throw std::runtime_error(fmt::format(
          "scene '{}' has {} {}s where the machine's scene '{}' has {}: a scene changed between "
          "frames keeps its primitives (only their positions, colours, the camera and the "
          "lights change)",
          scene.name, after[k], primitive_kinds()[k]->name(), scene_->name, before[k]));
    }
  }
}

const MachinePlan& FramePlans::of(int frame) {
  if (!source_) return *base_;
  for (; made_ <= frame; ++made_) {
    slots_[made_ & 1] = source_(made_);
    slot_frame_[made_ & 1] = made_;
  }
  const int slot = frame & 1;
  if (frame < 0 || slot_frame_[slot] != frame || !slots_[slot]) {
    throw std::logic_error(
        fmt::format("FramePlans: the plan of frame {} was asked for after frame {}'s took its "
                    "place (more than two frames in flight)",
                    frame, slot_frame_[slot]));
  }
  return *slots_[slot];
}

std::vector<int> MachinePlan::primitive_counts(const Scene& scene) {
  std::vector<int> counts;
  for (const PrimitiveKind* kind : primitive_kinds()) counts.push_back(kind->count(scene));
  return counts;
}

void MachinePlan::derive_from_scene() {
  const Program& program = program_;
  const Scene& scene = *scene_;
  const MachineConfig& config = config_;
  if (scene.depth_sort && scene.depth_sort->gps() != config.gp.count) {
    throw std::runtime_error(
        fmt::format("scene '{}': its depth sort was made for {} GPs, but key 'gp.count' = {}",
                    scene.name, scene.depth_sort->gps(), config.gp.count));
  }
  frame_values_ = geometry_->frame_values();
  set_pass_plan(program, scene, frame_values_);
  const ProcedureCode& triangle = program.procedure(Procedure::triangle);
  workload_.expressions = triangle.expressions;
  workload_.lights = geometry_->lights();
  workload_.packet_words = packet_words(triangle.expressions);
  if (workload_.packet_words + 1 > static_cast<std::uint64_t>(config.renderer.queue_words)) {
    throw std::runtime_error(fmt::format(
        "key 'renderer.queue_words' = {} is too small: one triangle packet of '{}' takes {} "
        "words plus a header word",
        config.renderer.queue_words, program.name, workload_.packet_words));
  }
  // Every other kind (the sphere): its procedure may use only what its set-up computes, its
  // packet must fit a queue, and a scene with such primitives needs the procedure.
  for (std::size_t k = 0; k < primitive_kinds().size(); ++k) {
    const PrimitiveKind& kind = *primitive_kinds()[k];
    const ProcedureCode& code = program.procedure(kind.procedure());
    for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
      if (code.expressions.test(e) && !kind.supplies(static_cast<Expression>(e))) {
        throw std::runtime_error(fmt::format(
            "program '{}': procedure '{}' uses expression '{}', which the {} kind does not supply",
            program.name, kProcedureNames[static_cast<int>(kind.procedure())], kExpressions[e].name,
            kind.name()));
      }
    }
    if (k == kTriangleKind) continue;
    const int n = kind.count(scene);
    if (n > 0 && !code.defined) {
      throw std::runtime_error(
          fmt::format("scene '{}' has {} {}s, but program '{}' defines no '{}' procedure (phong "
                      "and threshold draw them)",
                      scene.name, n, kind.name(), program.name,
                      kProcedureNames[static_cast<int>(kind.procedure())]));
    }
    if (packet_words(code.expressions) + 1 >
        static_cast<std::uint64_t>(config.renderer.queue_words)) {
      throw std::runtime_error(fmt::format(
          "key 'renderer.queue_words' = {} is too small: one {} packet of '{}' takes {} words "
          "plus a header word",
          config.renderer.queue_words, kind.name(), program.name, packet_words(code.expressions)));
    }
  }
  for (int k = 0; k < gp_count(); ++k) {
    const auto [first, last] = gp_block(k);
    if (last > first) ++busy_gps_;
  }
}

std::pair<int, int> MachinePlan::gp_block(int k) const {
  const auto n = static_cast<long long>(geometry_->display_list().size());
  const long long gps = gp_count();
  return {static_cast<int>(n * k / gps), static_cast<int>(n * (k + 1) / gps)};
}

sc_core::sc_time MachinePlan::hop_delay(int from, int to) const {
  return ring_hop_delay(ring_, ring_cycle_, from, to, ring_stops());
}

void MachinePlan::use_setup_memo(SetupMemo& memo) {
  if (&memo.scene() != scene_) {
    throw std::invalid_argument(
        fmt::format("a set-up memo of scene '{}' given to a machine of scene '{}'",
                    memo.scene().name, scene_->name));
  }
  SetupMemo::Key key;
  key.params = geometry_->params();
  for (const PrimitiveKind* k : primitive_kinds()) {
    key.expressions.push_back(program_.procedure(k->procedure()).expressions);
    key.words.push_back(packet_words(key.expressions.back()));
  }
  memo.bind(key, geometry_->display_list().size());
  setup_memo_ = &memo;
}

std::uint64_t MachinePlan::bin_map_words() const {
  const auto bits = static_cast<std::uint64_t>(config_.regions());
  const auto word = static_cast<std::uint64_t>(config_.ring.word_bits);
  return 1 + (bits + word - 1) / word;
}

std::uint64_t MachinePlan::packet_words(const ExpressionSet& expressions) const {
  return pp5::packet_words(
      expressions, coefficient_words(config_.evaluator.coefficient_bits, config_.ring.word_bits));
}

std::uint64_t MachinePlan::region_words() const {
  const std::uint64_t bits = static_cast<std::uint64_t>(config_.renderer.region_width) *
                             config_.renderer.region_height * config_.frame_buffer.bits_per_pixel;
  return (bits + config_.ring.word_bits - 1) / config_.ring.word_bits;
}

}  // namespace pp5
