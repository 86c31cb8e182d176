// The frame buffer's statistic: the frame time (see common/statistics.hpp for the registry).
#include "common/statistics.hpp"
#include "models/frame_buffer/frame_buffer.hpp"

namespace pp5 {

void FrameBuffer::register_statistics(Statistics& stats) const {
  stats.add_real("frame.simulated_seconds", stat_unit::seconds,
                 "Frame time: when the last region reached the frame buffer",
                 [this] { return frame_complete().to_seconds(); });
}

}  // namespace pp5
