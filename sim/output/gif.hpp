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
#include <string>
#include <vector>

#include "models/frame_buffer/image.hpp"

namespace pp5 {

std::string encode_gif(const std::vector<const RgbImage*>& frames, int delay_centiseconds);

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
