#include "sim/frame_encoder.hpp"

#include <memory>
#include <utility>

#include "sim/image/png_writer.hpp"

namespace pp5 {

FrameEncoder::FrameEncoder(int gif_delay_centiseconds, Sink sink, std::size_t waiting)
    : gif_(gif_delay_centiseconds), sink_(std::move(sink)), waiting_(waiting) {}

void FrameEncoder::add(int frame, FrameImage image) {
  // The job owns the image (std::function needs a copyable callable: shared, not copied).
  auto held = std::make_shared<FrameImage>(std::move(image));
  queued_.push_back(worker_.submit([this, frame, held] {
    EncodedFrame e;
    e.frame = frame;
    e.png = encode_png(*held);
    gif_.add(*held);  // by rows: no flat copy of the frame
    e.gif = gif_.take();
    return e;
  }));
  while (queued_.size() > waiting_) sink_front();
}

void FrameEncoder::sink_front() {
  std::future<EncodedFrame> f = std::move(queued_.front());
  queued_.pop_front();
  EncodedFrame e = f.get();
  sink_(e);
}

std::string FrameEncoder::finish() {
  while (!queued_.empty()) sink_front();
  return gif_.finish();
}

}  // namespace pp5
