#pragma once
// Recording a per-pixel trace: which pixels, fields and window (Selection), and the
// observer attached to each Renderer board while it executes a frame (Recorder).
//
// Contract: recording is opt-in: a board without an observer pays one branch per
// procedure run. With one, for every micro-instruction executed in a region that holds
// selected pixels and inside the window, the recorder writes an instruction record and a
// value record for each selected (pixel, field) that the instruction wrote (its destination
// overlaps the field and the pixel was enabled) or whose value it changed; the
// first instruction of a window records the whole selected state, so that replaying any
// trace from its first record reconstructs the selected fields exactly.
#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/scene/scene.hpp"

namespace pp5::trace {

// A half-open range [first, last) of integers; the default is everything.
struct Range {
  std::int64_t first = 0;
  std::int64_t last = std::numeric_limits<std::int64_t>::max();
  bool all() const { return first == 0 && last == std::numeric_limits<std::int64_t>::max(); }
  bool contains(std::int64_t v) const { return v >= first && v < last; }
  std::string text() const;
};
// "A:B" (A to B-1), "A:" (from A), ":B" (before B) or "N" (N alone). `what` names the
// option in messages.
Range parse_range(const std::string& text, const std::string& what);

struct Rect {
  int x = 0, y = 0, width = 1, height = 1;
};

struct Selection {
  std::vector<Rect> rects;          // screen pixels: single pixels are 1 x 1 rectangles
  std::vector<int> regions;         // whole regions
  std::vector<std::string> fields;  // empty: every field resident in pixel memory
  Range instructions;               // micro-instruction numbers on the pixel's Renderer
  Range primitives;                 // scene triangles; if set, clear and shade are outside
  Range frames;                     // frame numbers (a pp5sim run renders frame 0)
  nlohmann::json to_json() const;
};

// "X,Y" -> 1 x 1; "X,Y,W,H" -> a rectangle.
Rect parse_rect(const std::string& text, const std::string& what);

class BoardRecorder;

class Recorder {
 public:
  // Throws std::runtime_error naming the option for pixels outside the screen, unknown
  // regions or fields, and fields spilled to the backing store.
  Recorder(const MachineConfig& config, const Scene& scene, const Program& program,
           const Selection& selection, int frame = 0);
  ~Recorder();

  // The observer for Renderer k's board (created on first use; call before the frame runs).
  BoardObserver* observer(int renderer);
  nlohmann::json header() const;
  // Records of all boards, in Renderer order (deterministic for any number of threads).
  std::vector<std::uint8_t> records(std::uint64_t& count) const;
  void write(const std::string& path) const;
  std::size_t pixel_count() const { return pixels_.size(); }

  struct PixelRef {
    int index;  // in the region's array
    int x, y;   // on the screen
  };
  struct TracedField {
    int index;  // in program.fields
    Field field;
  };

 private:
  friend class BoardRecorder;
  MachineConfig config_;
  const Program& program_;
  std::string scene_name_;
  std::size_t scene_triangles_;
  Selection selection_;
  int frame_;
  std::vector<std::pair<int, int>> pixels_;
  std::vector<std::vector<PixelRef>> by_region_;
  std::vector<TracedField> fields_;
  std::vector<std::unique_ptr<BoardRecorder>> boards_;
};

// The program's field map and instruction texts, as stored in trace and snapshot headers.
nlohmann::json firmware_json(const Program& program, const std::vector<bool>& traced);

}  // namespace pp5::trace
