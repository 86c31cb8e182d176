#pragma once
// In-code firmware that the analyses run beside the shipped programs: small programs whose
// pixel memory answers one question (which triangle is nearest, how many triangles own a
// pixel centre). Pixel values still come only from these micro-instruction streams.
//
// Contract: each function returns program text that assembles in the default 208 bits.
#include <string>
#include <vector>

namespace pp5 {

// Z-buffered on the expression `depth` (a field of `depth_bits`, cleared to its far end
// 2^depth_bits - 1): every pixel keeps the colour of the nearest triangle, loaded from the
// expressions COLOUR_red, COLOUR_green and COLOUR_blue (`base`: vertex colours; `flat`: one
// colour per triangle). `comment` becomes the first line.
std::string zbuffer_colour_firmware(const std::string& comment, int depth_bits,
                                    const std::string& depth, const std::string& colour);

// Coverage counter: every triangle adds 1 (modulo 256) to the `count` field of each pixel
// whose centre passes all of `tests` (expressions, each >= 0 inside); output count, 0, 0.
std::string coverage_firmware(const std::string& comment, const std::vector<std::string>& tests);

}  // namespace pp5
