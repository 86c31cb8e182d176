#pragma once
// A run of frames' images encoded on a helper thread while the caller simulates the frames
// after them (pp5sim animate): each frame's PNG, and its part of the animated GIF. The bytes
// are those encode_png and GifWriter make on the calling thread; only where the work runs
// changes.
//
// Contract:
//  - add(k, image) queues frame k's image (frames added in increasing order). The encoded
//    frames come back through the sink, on the calling thread, in the order added, from
//    within add() (once more than `waiting` frames are queued) or finish().
//  - finish() waits for every frame, sinks it, and returns the GIF's last bytes (its
//    trailer): concatenated, the gif bytes of every sunk frame and finish()'s are the file.
//  - An encoding error (std::invalid_argument from the encoders) is thrown by the add() or
//    finish() that would have sunk that frame; frames after it are not sunk.
//  - Dropping the encoder unfinished (an error elsewhere) drops the frames not yet encoded.
#include <cstddef>
#include <deque>
#include <functional>
#include <future>
#include <string>

#include "common/serial_worker.hpp"
#include "models/frame_buffer/image.hpp"
#include "sim/output/gif.hpp"

namespace pp5 {

struct EncodedFrame {
  int frame = 0;
  std::string png;  // the frame's PNG file
  std::string gif;  // the frame's bytes of the animated GIF
};

class FrameEncoder {
 public:
  using Sink = std::function<void(EncodedFrame&)>;
  FrameEncoder(int gif_delay_centiseconds, Sink sink, std::size_t waiting = 2);
  void add(int frame, FrameImage image);
  std::string finish();

 private:
  void sink_front();
  GifWriter gif_;  // used by the helper thread only, until finish()
  Sink sink_;
  std::size_t waiting_;
  std::deque<std::future<EncodedFrame>> queued_;
  SerialWorker<EncodedFrame> worker_;  // last: joined before the rest goes
};

}  // namespace pp5
