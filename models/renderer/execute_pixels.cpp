#include "models/renderer/execute_pixels.hpp"

#include <algorithm>

#include "common/parallel_for.hpp"
#include "models/frame_buffer/frame_buffer.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer.hpp"

namespace pp5 {

void execute_pixels(Machine& machine, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe) {
  const Program& program = machine.program();
  RendererBoardParams params = board_params(machine.config());
  // Only the bits the program declares are allocated and processed: fields beyond them would
  // be refused by the pixel array's bounds checks, never silently dropped.
  params.array.memory_bits = std::max(1, program.bits_used());
  // One empty region, executed before the boards start, serves every board whose state
  // after clear matches it (RendererBoard::run_empty_region checks); the rest of the boards'
  // regions run as recorded.
  RendererBoard first(params);
  std::vector<std::uint8_t> empty_rgb;
  first.run_empty_region(0, 0, program, machine.frame_values(), empty_rgb);
  parallel_for(machine.renderer_count(), threads, [&](int k) {
    const Renderer& renderer = machine.renderer(k);
    if (renderer.work().empty()) return;  // a Renderer the frame did not use
    RendererBoard board(params);
    if (observe) board.set_observer(observe(k));
    board.share_empty_region(first);
    renderer.execute(board, program, machine.frame_buffer(), machine.frame_values());
  });
}

}  // namespace pp5
