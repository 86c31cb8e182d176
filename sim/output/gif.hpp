#pragma once
// An animated GIF (GIF89a) of RGB frames, encoded here: every frame quantised to one fixed
// palette of 252 colours (6 levels of red, 7 of green, 6 of blue, each channel rounded to its
// nearest level), LZW-compressed with the variable-length codes of the GIF specification
// (clear code when the table reaches 4096 entries), looping forever (the NETSCAPE2.0
// application extension), each frame shown for `delay_centiseconds`.
//
// Contract:
//  - encode_gif reads only its arguments: the same frames give the same bytes.
//  - Every frame has the same size, 1 to 65535 pixels each way, and its pixels; else
//    std::invalid_argument naming the frame and what was wrong.
//  - decode_gif reads back what encode_gif writes (one global palette, no local ones,
//    no interlace): the frames as palette colours. For tests.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "models/frame_buffer/image.hpp"

namespace pp5 {

std::string encode_gif(const std::vector<const RgbImage*>& frames, int delay_centiseconds);

// The same, a frame at a time (pp5sim animate adds each frame as it is drawn, and keeps no
// image): add() checks and encodes a frame (std::invalid_argument as above), finish() returns
// the file and starts a new one. The bytes are encode_gif's for the same frames.
class GifLzw;
class GifWriter {
 public:
  explicit GifWriter(int delay_centiseconds);
  ~GifWriter();
  GifWriter(const GifWriter&) = delete;
  GifWriter& operator=(const GifWriter&) = delete;
  void add(const RgbImage& frame);
  // A frame buffer's frame, read a row at a time (no flat copy of it is made).
  void add(const FrameImage& frame);
  // The bytes encoded since the last take() (or the start), which then leave the writer: a
  // long animation writes its GIF out frame by frame (take after each add, then finish's
  // rest) and the writer holds one frame's bytes at most. Concatenated, the bytes of every
  // take() and finish() are the file.
  std::string take() { return std::exchange(out_, std::string()); }
  std::string finish();
  int frames() const { return frames_; }

 private:
  int delay_;
  int width_ = 0, height_ = 0;
  int frames_ = 0;
  template <class Rows>
  void add_rows(int width, int height, Rows rows);  // rows(y, out): row y's palette indices
  std::string out_;
  std::unique_ptr<GifLzw> lzw_;        // its code table, kept from frame to frame
  std::vector<std::uint8_t> indices_;  // a frame's palette indices
};

// The fixed palette's colour nearest `rgb` (what encode_gif draws a pixel as).
std::uint8_t gif_palette_index(const std::uint8_t rgb[3]);
void gif_palette_colour(std::uint8_t index, std::uint8_t rgb[3]);

struct DecodedGif {
  int width = 0, height = 0;
  std::vector<int> delays;                        // per frame, centiseconds
  std::vector<std::vector<std::uint8_t>> frames;  // per frame, width * height palette indices
};
DecodedGif decode_gif(const std::string& bytes);

}  // namespace pp5
