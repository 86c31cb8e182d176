#pragma once
// Snapshots of a region's whole pixel memory (memory_bits x width x height bits) at a chosen
// point of a frame: after micro-instruction number N of the Renderer that owns the region,
// or when the region is finished. Written as a .pp5m file (see traces/README.md), and
// selected fields as PNG images.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/image/png_writer.hpp"

namespace pp5::trace {

struct Snapshot {
  nlohmann::json header;  // config, firmware field map, region, point
  std::string point;      // where it was taken ("after micro-instruction N ..."), checked text
  int region = 0;
  int width = 0, height = 0, memory_bits = 0;
  std::vector<std::uint64_t> planes;  // memory_bits planes of width * height / 64 words

  int words() const { return width * height / 64; }
  std::uint64_t read(int pixel, int lo, int width) const;  // raw bits of one field
};

// Captures one region: attach observer(k) to every board k; after the frame, taken() says
// whether the point was reached, and snapshot() holds the memory.
class SnapshotTaker {
 public:
  // `after` is the micro-instruction number on the region's Renderer; none = region's end.
  SnapshotTaker(const MachineConfig& config, const Program& program, int region,
                std::optional<std::uint64_t> after);
  ~SnapshotTaker();
  BoardObserver* observer(int renderer);
  bool taken() const { return taken_; }
  // Throws with the range of instruction numbers the region ran if the point was missed.
  const Snapshot& snapshot() const;

 private:
  class Board;
  friend class Board;
  MachineConfig config_;
  const Program& program_;
  int region_;
  std::optional<std::uint64_t> after_;
  bool taken_ = false;
  std::uint64_t first_seq_ = 0, last_seq_ = 0;
  bool ran_ = false;
  Snapshot snap_;
  std::unique_ptr<Board> board_;
};

void write_snapshot(const std::string& path, const Snapshot& s);
// The bytes write_snapshot writes.
std::string encode_snapshot(const Snapshot& s);
Snapshot read_snapshot(const std::string& path);
// The same from a file's bytes; `path` names it in messages.
Snapshot parse_snapshot(const std::string& bytes, const std::string& path);

// One field of every pixel as an image: 1-bit fields as a mask (0 black, 1 white), wider
// ones as a grey ramp from the region's smallest value (black) to its largest (white).
RgbImage field_image(const Snapshot& s, const std::string& field);

}  // namespace pp5::trace
