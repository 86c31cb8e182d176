#pragma once
// Reading a trace back: replay, and the reports of `pp5sim trace` (history, why, diff,
// bitmap, VCD). Each report is returned as text so that tests can check it.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim/trace/trace_file.hpp"

namespace pp5::trace {

// The state of one pixel's traced fields after replaying a trace (or a prefix of it).
struct PixelState {
  std::map<int, std::uint64_t> value;      // field -> raw value
  std::map<int, std::size_t> last_writer;  // field -> event index of its last change
};
using Pixel = std::pair<int, int>;  // screen x, y

// Applies every value record in order: the selected fields as they stood after the last
// recorded instruction.
std::map<Pixel, PixelState> replay(const Trace& trace);

// The selected pixel to report on: `requested` if given (it must be in the trace), else the
// trace's only pixel; otherwise an error listing how to choose.
Pixel choose_pixel(const Trace& trace, const std::optional<Pixel>& requested);

// A table of the pixel's fields over time: one row per instruction that changed one.
std::string history_report(const Trace& trace, Pixel pixel, const std::vector<std::string>& fields,
                           bool every_instruction);
// For each field: its final value and the primitive and instruction that last wrote it.
std::string why_report(const Trace& trace, Pixel pixel);
// Compares the fields two traces share, packet by packet, and reports the first packet
// after which they differ; `diverged` tells whether they did.
std::string diff_report(const Trace& a, const Trace& b, std::optional<Pixel> pixel, bool& diverged);
// Which bits each field occupies and which of them the trace saw change.
std::string bitmap_report(const Trace& trace);
// A VCD of the selected pixels' fields and of each Renderer's instruction stream.
std::string vcd(const Trace& trace);

std::string describe_event(const Trace& trace, const Event& e);

}  // namespace pp5::trace
