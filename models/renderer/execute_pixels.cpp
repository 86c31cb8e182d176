#include "models/renderer/execute_pixels.hpp"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/parallel_for.hpp"
#include "models/frame_buffer/frame_buffer.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/renderer/renderer.hpp"

namespace pp5 {

struct PixelBoards::Kept {
  RendererBoardParams params;
  RendererBoard fresh;  // executes nothing: the state every board restarts from
  RendererBoard first;  // the frame's first empty region, shared with the others
  std::vector<std::unique_ptr<RendererBoard>> boards;  // one per host worker
  explicit Kept(const RendererBoardParams& p) : params(p), fresh(p), first(p) {}
};

PixelBoards::PixelBoards() = default;
PixelBoards::~PixelBoards() = default;

void execute_pixels(const MachinePlan& plan, FrameBuffer& frame_buffer,
                    const std::vector<const std::vector<RegionWork>*>& work, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe,
                    const std::atomic<bool>* cancel, PixelBoards* boards) {
  execute_pixels(plan, plan.frame_values(), frame_buffer, work, threads, observe, cancel, boards);
}

void execute_pixels(const MachinePlan& plan, const FrameValues& frame_values,
                    FrameBuffer& frame_buffer,
                    const std::vector<const std::vector<RegionWork>*>& work, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe,
                    const std::atomic<bool>* cancel, PixelBoards* kept_boards) {
  const Program& program = plan.program();
  const MachineConfig& config = plan.config();
  using Pixels = MachineConfig::Fidelity::Pixels;
  if (config.fidelity.pixels == Pixels::none) return;  // timing only: the frame holds no pixels
  RendererBoardParams params = board_params(config);
  params.backend = name_of(config.fidelity.pixels);
  // Only the bits the program declares are allocated and processed: fields beyond them would
  // be refused by the pixel array's bounds checks, never silently dropped.
  params.array.memory_bits = std::max(1, program.bits_used());
  // The boards: kept from the call before when their parameters are the same (restarted, so
  // each runs as a new board would), else made here, on the calling thread.
  PixelBoards local;
  PixelBoards& kept = kept_boards != nullptr ? *kept_boards : local;
  if (!kept.kept_ || !(kept.kept_->params == params)) {
    kept.kept_ = std::make_unique<PixelBoards::Kept>(params);
  } else {
    // The boards first, so that they no longer share the first board's kept states, which
    // its restart then keeps for reuse (RendererBoard::keep_state).
    for (auto& board : kept.kept_->boards) board->restart(kept.kept_->fresh);
    kept.kept_->first.restart(kept.kept_->fresh);
  }
  const RendererBoard& fresh = kept.kept_->fresh;
  // An empty region executed on a new board before the boards start serves every board whose
  // state after clear matches it (RendererBoard::run_empty_region checks), a new board's
  // without a check; the rest of the boards' regions run as recorded. Where clear after
  // shade gives the same state again (the probe), no board executes an empty region at all.
  RendererBoard& first = kept.kept_->first;
  first.run_empty_region(0, 0, program, frame_values);
  first.probe_clear_after_shade(program, frame_values);
  // One board per host worker, restarted for each Renderer in the state of a newly made board
  // (`fresh`): the same results as a new board per Renderer, whatever the thread count,
  // without a worker thread's first allocations, whose page faults in a new malloc arena cost
  // more than the copy.
  const int count = static_cast<int>(work.size());
  const int workers = parallel_workers(count, threads);
  std::vector<std::unique_ptr<RendererBoard>>& boards = kept.kept_->boards;
  while (static_cast<int>(boards.size()) < workers)
    boards.push_back(std::make_unique<RendererBoard>(params));
  // The Renderers with the most packets first, so that the last one a host thread takes is a
  // short one and the threads finish together (host speed only: each Renderer's board
  // restarts as a new one, whichever thread runs it and whenever).
  std::vector<int> order(static_cast<std::size_t>(count));
  std::vector<std::size_t> packets(static_cast<std::size_t>(count), 0);
  for (int k = 0; k < count; ++k) {
    order[static_cast<std::size_t>(k)] = k;
    for (const RegionWork& w : *work[static_cast<std::size_t>(k)])
      packets[static_cast<std::size_t>(k)] += w.triangles.size() + 1;
  }
  std::stable_sort(order.begin(), order.end(), [&packets](int a, int b) {
    return packets[static_cast<std::size_t>(a)] > packets[static_cast<std::size_t>(b)];
  });
  parallel_for(count, threads, [&](int i, int worker) {
    const int k = order[static_cast<std::size_t>(i)];
    const std::vector<RegionWork>& regions = *work[static_cast<std::size_t>(k)];
    if (regions.empty()) return;  // a Renderer the frame did not use
    RendererBoard& board = *boards[static_cast<std::size_t>(worker)];
    board.restart(fresh);  // on a board that has executed nothing, no copy
    if (observe) board.set_observer(observe(k));
    board.share_empty_region(first);
    const int columns = config.regions_x();
    execute_regions(regions, board, program, frame_buffer, frame_values, [&](const RegionWork& w) {
      if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return false;
      return config.fidelity.executes(w.region % columns, w.region / columns);
    });
  });
}

}  // namespace pp5
