#include "models/renderer/renderer_board.hpp"

#include "models/gp/machine_plan.hpp"
#include "models/pixel_array/backends.hpp"

namespace pp5 {

RendererBoard::RendererBoard(const RendererBoardParams& params)
    : params_(params),
      array_(make_pixel_backend(params.backend, PixelBackendParams{params.array, params.evaluator,
                                                                   params.timing.fraction_bits})) {}

void RendererBoard::begin_region(int x0, int y0) {
  materialise();
  untouched_ = false;
  array_->set_origin(x0, y0);
}

// Logically const: the board's state is the same before and after, only where it is held
// changes (the backend object itself is not const-qualified through the unique_ptr).
void RendererBoard::materialise() const {
  if (!lazy_) return;
  array_->copy_state_from(*empty_after_shade_);
  lazy_ = false;
  untouched_ = false;
}

ArrayCycles RendererBoard::run_step(const RegionStep& step, int region, std::uint64_t start_cycle) {
  begin_packet(
      {step.procedure, step.packet ? step.packet->primitive : -1, region, start_cycle, step.light});
  return run(step.code, step.values);
}

void RendererBoard::run_rest_of_empty(const RegionStream& stream, const Program& program,
                                      std::vector<std::uint8_t>& rgb) {
  stream.after_clear(std::vector<const Packet*>{}, [&](const RegionStep& step) { run_step(step); });
  read_outputs(program, rgb);
}

RegionPixels RendererBoard::run_empty_region(int x0, int y0, const Program& program,
                                             const FrameValues& frame_values) {
  const RegionStream stream(program, frame_values);
  auto clear = [&] { stream.before_pass(0, [&](const RegionStep& step) { run_step(step); }); };
  auto executed = [&] {
    std::vector<std::uint8_t> rgb;
    run_rest_of_empty(stream, program, rgb);
    return region_pixels(std::move(rgb));
  };
  if (observer_) {  // a traced board shows every instruction: nothing is reused
    begin_region(x0, y0);
    clear();
    return executed();
  }
  // The region's origin matters only if a step binds a non-zero expression (checked once
  // per frame's values).
  if (origin_free_for_ != &frame_values) {
    origin_free_ = true;
    stream.for_each_empty([&](const RegionStep& step) {
      for (const QuadraticCoefficients& c : step.values.expressions) {
        origin_free_ = origin_free_ && c.A == 0 && c.B == 0 && c.C == 0 && c.D == 0 && c.E == 0;
      }
    });
    origin_free_for_ = &frame_values;
  }
  const bool origin_free = origin_free_;
  const bool after_drawn = std::exchange(after_drawn_, false);
  if (after_drawn && misses_after_drawn_ >= 2 && ++unchecked_after_drawn_ % 8 != 0) {
    begin_region(x0, y0);
    clear();
    return executed();
  }
  if (origin_free && ((lazy_ && clear_restores_.value_or(false)) ||
                      (fresh_ && clear_from_fresh_ && empty_after_clear_))) {
    fresh_ = false;
    lazy_ = true;
    ++empty_reused_;
    return empty_rgb_;
  }
  const bool was_fresh = fresh_;
  begin_region(x0, y0);
  const bool was_kept_state = empty_after_shade_ && array_->same_state(*empty_after_shade_);
  clear();
  if (!origin_free) return executed();
  if (empty_after_clear_ && array_->same_state(*empty_after_clear_)) {
    if (was_kept_state) clear_restores_ = true;
    if (was_fresh) clear_from_fresh_ = true;
    lazy_ = true;
    ++empty_reused_;
    if (after_drawn) misses_after_drawn_ = 0;
    return empty_rgb_;
  }
  if (after_drawn) {
    // What the drawn region left in the fields clear does not set makes this state unlike
    // any a later empty region starts from, unless it follows this one: keeping it (two
    // copies of the array) would serve only that case, which the next miss keeps instead.
    ++misses_after_drawn_;
    return executed();
  }
  // Nothing kept, or a different state (fields the clear procedure leaves alone hold what an
  // earlier region put there): execute, and keep this region's states instead, since the
  // next empty region on this board will most likely start from them.
  keep_state(empty_after_clear_);
  empty_rgb_ = executed();
  keep_state(empty_after_shade_);
  clear_restores_.reset();
  clear_from_fresh_ = was_fresh;
  return empty_rgb_;
}

void RendererBoard::probe_clear_after_shade(const Program& program,
                                            const FrameValues& frame_values) {
  if (!empty_after_clear_ || !empty_after_shade_ || clear_restores_.has_value()) return;
  materialise();
  array_->copy_state_from(*empty_after_shade_);
  lazy_ = fresh_ = untouched_ = false;
  const RegionStream stream(program, frame_values);
  stream.before_pass(0, [&](const RegionStep& step) { run_step(step); });
  clear_restores_ = array_->same_state(*empty_after_clear_);
}

void RendererBoard::keep_state(std::shared_ptr<PixelBackend>& slot) const {
  // In place when this board alone holds the copy: no allocation and no fresh pages (a
  // clone per kept state was about 8% of a word-level frame's host time, perf on the Banks
  // configuration). A copy shared with other boards is never written: a board's first keep
  // clones.
  if (slot && slot.use_count() == 1) {
    slot->copy_state_from(*array_);
  } else if (!spare_states_.empty()) {  // a copy the board kept before restart
    slot = std::move(spare_states_.back());
    spare_states_.pop_back();
    slot->copy_state_from(*array_);
  } else {
    slot = array_->clone();
  }
}

void RendererBoard::restart(const RendererBoard& fresh) {
  // A board whose array nothing has changed since it was new (its empty regions all reused)
  // holds a new board's state already.
  if (!untouched_) array_->copy_state_from(fresh.array());
  untouched_ = true;
  origin_free_for_ = nullptr;
  lazy_ = false;
  // The kept states' copies that this board alone holds stay, as spares for the next keep.
  for (std::shared_ptr<PixelBackend>* slot : {&empty_after_clear_, &empty_after_shade_}) {
    if (*slot && slot->use_count() == 1) spare_states_.push_back(std::move(*slot));
    slot->reset();
  }
  empty_rgb_.reset();
  clear_restores_.reset();
  clear_from_fresh_ = false;
  fresh_ = true;
  empty_reused_ = 0;
  after_drawn_ = false;  // what a drawn region left goes now (misses_after_drawn_ stays)
  observer_ = nullptr;
  packet_ = PacketContext{};
  instructions_ = 0;
  cycles_ = ArrayCycles{};
}

void RendererBoard::share_empty_region(const RendererBoard& other) {
  if (!other.empty_after_clear_ || empty_after_clear_) return;
  empty_after_clear_ = other.empty_after_clear_;
  empty_after_shade_ = other.empty_after_shade_;
  empty_rgb_ = other.empty_rgb_;
  clear_restores_ = other.clear_restores_;
  clear_from_fresh_ = other.clear_from_fresh_;
}

ArrayCycles RendererBoard::run(const ProcedureCode& procedure, const PacketValues& values) {
  materialise();
  fresh_ = untouched_ = false;
  ExecutionContext ctx{*array_, values, params_.timing.fraction_bits,
                       params_.timing.multiply_window};
  if (observer_) observer_->begin_packet(packet_, procedure, *this);
  ArrayCycles cycles{};
  int index = 0;
  for (const Instruction& ins : procedure.code) {
    const InstructionInfo& info = instruction_info(ins.op);
    info.execute(ins, ctx);
    const ArrayCycles cost = info.cost(ins, params_.timing, values);
    cycles += cost;
    // One predictable branch per instruction when nobody observes: nothing measurable
    // beside an instruction's walk over the array (bench/bench_trace.cpp).
    if (observer_) observer_->after_instruction(index, ins, cost, *this);
    ++index;
  }
  instructions_ += procedure.code.size();
  cycles_ += cycles;
  return cycles;
}

void RendererBoard::read_outputs(const Program& program, std::vector<std::uint8_t>& rgb) const {
  rgb.resize(static_cast<std::size_t>(array().pixels()) * 3);
  read_outputs(program, rgb.data());
}

void RendererBoard::read_outputs(const Program& program, std::uint8_t* rgb) const {
  materialise();
  array_->read_bytes(program.outputs.data(), 3, rgb);
}

ArrayCycles procedure_cost(const ProcedureCode& procedure, const TimingParams& timing,
                           const PacketValues& values) {
  ArrayCycles cycles{};
  for (const Instruction& ins : procedure.code) cycles += instruction_cost(ins, timing, values);
  return cycles;
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

}  // namespace pp5
