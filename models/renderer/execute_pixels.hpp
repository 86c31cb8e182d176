#pragma once
// The functional half of a frame, after its simulation: every Renderer's board executes the
// regions the timing pass recorded (Renderer::execute) and the frame buffer gets the colours.
//
// Contract:
//  - The level is the configuration's (fidelity.*): the boards' backend is fidelity.pixels
//    ("bit" or "word"); with "none" nothing executes and the frame holds no pixels; only the
//    regions inside the fidelity window execute.
//  - Deterministic: each board executes its own regions in order, whatever the thread count,
//    so the image never depends on `threads`.
//  - `observe`, if given, returns an observer (or null) for Renderer k's board; see
//    BoardObserver. Each board's observer is called from one host thread only.
//  - An exception thrown while a board executes (e.g. std::out_of_range from a backing-store
//    block) is rethrown here, on the caller's thread, once the other boards have stopped.
#include <atomic>
#include <functional>
#include <memory>
#include <vector>

namespace pp5 {

class MachinePlan;
struct FrameValues;
class FrameBuffer;
class BoardObserver;
struct RegionWork;

// Boards kept from one execute_pixels to the next (a run of frames): a call given them
// restarts the boards the call before made (RendererBoard::restart: what follows runs exactly
// as on new boards) instead of making new ones, when the boards' parameters are the same, so a
// frame pays neither their allocation nor the page faults of its first touches. Results are
// the same as without them. One call at a time.
class PixelBoards {
 public:
  PixelBoards();
  ~PixelBoards();
  PixelBoards(const PixelBoards&) = delete;
  PixelBoards& operator=(const PixelBoards&) = delete;

 private:
  friend void execute_pixels(const MachinePlan&, const FrameValues&, FrameBuffer&,
                             const std::vector<const std::vector<RegionWork>*>&, int,
                             const std::function<BoardObserver*(int)>&, const std::atomic<bool>*,
                             PixelBoards*);
  struct Kept;
  std::unique_ptr<Kept> kept_;
};

// work[k] is board k's regions, in order: the event model's Renderers' (Machine's
// execute_pixels, models/machine.hpp) or the analytic timing model's.
// With `cancel`, each board checks it before each region and executes no more regions once it
// is true (the frame is then incomplete: the caller discards it).
// With `boards`, the boards are kept there for the next call (see PixelBoards).
void execute_pixels(const MachinePlan& plan, FrameBuffer& frame_buffer,
                    const std::vector<const std::vector<RegionWork>*>& work, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe = {},
                    const std::atomic<bool>* cancel = nullptr, PixelBoards* boards = nullptr);
// The same with the frame's values given apart from the plan's: a frame of an animation run
// overlapped, whose own plan is gone by the time its pixels execute (FramePlans).
void execute_pixels(const MachinePlan& plan, const FrameValues& frame_values,
                    FrameBuffer& frame_buffer,
                    const std::vector<const std::vector<RegionWork>*>& work, int threads,
                    const std::function<BoardObserver*(int renderer)>& observe = {},
                    const std::atomic<bool>* cancel = nullptr, PixelBoards* boards = nullptr);

}  // namespace pp5
