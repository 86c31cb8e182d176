#pragma once
// The functional half of a Renderer board, as plain C++: a pixel backend (the pixel array
// and its expression evaluator, firmware/isa/backend.hpp) and the controller that feeds a
// procedure's micro-instructions to it.
//
// Contract: every pixel value comes from executing instructions of the firmware's
// instruction table on the board's pixel backend, built by name from the registry
// (models/pixel_array/backends.hpp); run() returns the cycles those instructions cost, the
// same figure the Renderer module charges in simulated time, whatever the backend.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "firmware/isa/interface.hpp"
#include "firmware/isa/isa.hpp"
#include "firmware/isa/types.hpp"
#include "models/config/machine_config.hpp"
#include "models/frame_buffer/image.hpp"
#include "models/protocol/region_stream.hpp"

namespace pp5 {

class RendererBoard;

// Which packet the board is about to run, for observers (tracing); supplied by the
// Renderer, which knows the region, the primitive and when the timing pass started it.
struct PacketContext {
  Procedure procedure = Procedure::clear;
  int primitive = -1;  // scene triangle, or -1 for clear, pass, light and shade
  int region = 0;
  std::uint64_t start_cycle = 0;  // simulated array cycle at which the packet starts
  int light = -1;                 // the scene light a `light` packet runs for, else -1
};

// An opt-in observer of a board's execution (see sim/trace/). Contract: the board calls
// begin_packet before each packet's first instruction, after_instruction after each
// instruction has executed (with its index in the procedure and its cost), and end_region
// after a region's shade procedure. Observers see the board's pixels through the
// PixelBackend interface (board.array()), whatever the backend. With no observer the
// board's only extra work is one predictable branch per instruction.
class BoardObserver {
 public:
  virtual ~BoardObserver() = default;
  virtual void begin_packet(const PacketContext& packet, const ProcedureCode& procedure,
                            const RendererBoard& board) = 0;
  virtual void after_instruction(int index, const Instruction& instruction, ArrayCycles cost,
                                 const RendererBoard& board) = 0;
  virtual void end_region(int region, const RendererBoard& board) = 0;
};

struct RendererBoardParams {
  PixelArrayGeometry array;
  EvaluatorParams evaluator;
  TimingParams timing;
  std::string backend = "bit";  // a name in pixel_backends()
};

// A board's parameters from the configuration (the array, the evaluator, the timing).
RendererBoardParams board_params(const MachineConfig& config);
// Every field the same (boards of equal parameters are interchangeable).
inline bool operator==(const RendererBoardParams& a, const RendererBoardParams& b) {
  const TimingParams& s = a.timing;
  const TimingParams& t = b.timing;
  return a.array == b.array && a.evaluator.coefficient_bits == b.evaluator.coefficient_bits &&
         a.evaluator.result_bits == b.evaluator.result_bits && s.fraction_bits == t.fraction_bits &&
         s.result_bits == t.result_bits && s.evaluator_latency == t.evaluator_latency &&
         s.block_bits == t.block_bits &&
         s.backing_store_cycles_per_block == t.backing_store_cycles_per_block &&
         s.multiply_window == t.multiply_window && s.msb_first == t.msb_first &&
         a.backend == b.backend;
}

class RendererBoard {
 public:
  // Throws std::invalid_argument for an unknown backend name.
  explicit RendererBoard(const RendererBoardParams& params);

  // Points the evaluator at a region; pixel memory keeps whatever it held (as the hardware
  // would): the program's clear procedure is what initialises it.
  void begin_region(int x0, int y0);
  ArrayCycles run(const ProcedureCode& procedure, const PacketValues& values);
  // Back to the state of a newly made board: `fresh` is one of the same parameters that has
  // executed nothing (its state is copied, not assumed). What follows runs exactly as on a
  // new board; only the host memory is reused (execute_pixels keeps one board per host
  // thread, made on the calling thread, instead of one per Renderer).
  void restart(const RendererBoard& fresh);
  // Observation (tracing): `observer` may be null; the board does not own it.
  void set_observer(BoardObserver* observer) { observer_ = observer; }
  bool observed() const { return observer_ != nullptr; }
  void begin_packet(const PacketContext& packet) { packet_ = packet; }
  void end_region(int region) {
    after_drawn_ = true;
    if (observer_) observer_->end_region(region, *this);
  }
  // Reads the program's output fields of every pixel as 8-bit RGB, row-major.
  void read_outputs(const Program& program, std::vector<std::uint8_t>& rgb) const;
  // The same into pixels() * 3 bytes at rgb.
  void read_outputs(const Program& program, std::uint8_t* rgb) const;

  // One step of a region's stream (models/protocol/region_stream.hpp); an observer sees it
  // as a packet of `region` starting at simulated array cycle `start_cycle`.
  ArrayCycles run_step(const RegionStep& step, int region = 0, std::uint64_t start_cycle = 0);
  // A region no primitive touches: its stream (RegionStream::for_each_empty) and its outputs,
  // as executing it step by step would give them; see "Empty regions" below. Returns the
  // outputs: new ones when the region was executed, the kept ones (shared, not copied) when
  // it was reused.
  RegionPixels run_empty_region(int x0, int y0, const Program& program,
                                const FrameValues& frame_values);
  // After a first empty region: executes clear on the kept after-shade state and records
  // whether it gives the kept after-clear state, without replacing what is kept (which a
  // new board's first empty region needs). Boards sharing from this one then reuse a run of
  // empty regions without executing any.
  void probe_clear_after_shade(const Program& program, const FrameValues& frame_values);
  // Empty regions whose result was reused rather than executed again.
  std::uint64_t empty_regions_reused() const { return empty_reused_; }
  // Starts from another board's kept empty region (if it has one) instead of executing a
  // first one here: boards of one frame run the same program, so one board's result serves
  // all whose state after clear matches (checked, as for the board's own).
  void share_empty_region(const RendererBoard& other);

  // The board's pixel array, as the backend that models it.
  PixelBackend& array() {
    materialise();
    fresh_ = untouched_ = false;  // the caller may change it
    return *array_;
  }
  const PixelBackend& array() const {
    materialise();
    return *array_;
  }
  std::uint64_t instructions_executed() const { return instructions_; }
  ArrayCycles cycles_executed() const { return cycles_; }

 private:
  // Keeps the array's state in `slot` (see the members below).
  void keep_state(std::shared_ptr<PixelBackend>& slot) const;
  // Empty regions. Their stream is the same every time (clear, the passes' procedures, the
  // lights, shade, all with the frame's values, whose expressions are zero, so the region's origin
  // does not matter): its result depends only on the array's state before it. So the first empty
  // region is executed for real and its states after clear and after shade and its outputs
  // are kept; a later empty region whose state after clear is the same (the clear procedure
  // initialises every field that matters, as real firmware does) takes the kept outputs, and
  // the array is left "lazily" in the kept after-shade state, copied in only when something
  // else runs. A run of empty regions then costs nothing once clear is known to map the
  // after-shade state onto the kept after-clear state. Exact: nothing is assumed that is not
  // checked on the array's full state; the simulated timing still charges every region.
  // A board that has executed nothing (new, or restarted) starts from the one state every
  // new board has, so when the kept after-clear state is what clear gave a new board (on
  // the board that kept it: clear_from_fresh_), a new board's first empty region takes the
  // kept outputs without executing either.
  void materialise() const;
  void run_rest_of_empty(const RegionStream& stream, const Program& program,
                         std::vector<std::uint8_t>& rgb);

  RendererBoardParams params_;
  std::unique_ptr<PixelBackend> array_;
  mutable bool lazy_ = false;  // array_'s true state is *empty_after_shade_
  // Shared with the boards share_empty_region gave them to; a board rewrites one in place
  // only while it alone holds it (keep_state).
  std::shared_ptr<PixelBackend> empty_after_clear_;
  std::shared_ptr<PixelBackend> empty_after_shade_;
  RegionPixels empty_rgb_;
  // Copies of the array (kept states before a restart) that nothing holds, reused by
  // keep_state rather than cloned: at most two.
  mutable std::vector<std::shared_ptr<PixelBackend>> spare_states_;
  std::optional<bool> clear_restores_;  // clear(after shade) == after clear
  bool clear_from_fresh_ = false;       // clear(a new board's state) == after clear
  bool fresh_ = true;                   // the board's state is a new board's
  mutable bool untouched_ = true;       // array_ itself holds a new board's state
  // run_empty_region's check of the frame values it last saw (`origin_free_for_`): whether
  // the empty stream binds no expression that depends on the region's origin.
  const FrameValues* origin_free_for_ = nullptr;
  bool origin_free_ = false;
  std::uint64_t empty_reused_ = 0;
  // Empty regions right after a drawn one (after_drawn_) start from what the drawn region
  // left in the fields clear does not set: they match no kept state unless clear sets every
  // field, and their own states are not kept. After two such misses in a row (counted
  // across restarts: a program's clear either sets every field or not), the board executes
  // those regions without comparing states (each comparison reads two whole arrays),
  // looking again at every eighth. The results are the same either way: host speed only.
  bool after_drawn_ = false;
  int misses_after_drawn_ = 0;
  int unchecked_after_drawn_ = 0;
  BoardObserver* observer_ = nullptr;
  PacketContext packet_;

  std::uint64_t instructions_ = 0;
  ArrayCycles cycles_{};
};

// The cost of one procedure for one packet, from the instruction table: the figure both
// the timing model and the board use.
ArrayCycles procedure_cost(const ProcedureCode& procedure, const TimingParams& timing,
                           const PacketValues& values);

}  // namespace pp5
