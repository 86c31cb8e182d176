#pragma once
// An animated GIF as the GIF specification and sim/output/gif.hpp's contract describe it,
// written the textbook way and sharing no code with the encoder it checks: each channel's
// nearest level by division, greedy LZW over a hash map from (prefix code, index) to code,
// cleared when code 4095 has been assigned, codes LSB first in sub-blocks of 255 bytes. The
// yardstick of tests/test_animation.cpp (whole files compared) and bench/bench_gif.cpp (the
// encoder's speed against it).
#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "models/frame_buffer/image.hpp"

namespace pp5 {

inline std::string gif_textbook(const std::vector<const RgbImage*>& frames, int delay) {
  auto put16 = [](std::string& out, int v) {
    out.push_back(static_cast<char>(v & 0xff));
    out.push_back(static_cast<char>((v >> 8) & 0xff));
  };
  constexpr int kLevels[3] = {6, 7, 6};
  const int width = frames.front()->width, height = frames.front()->height;
  std::string out = "GIF89a";
  put16(out, width);
  put16(out, height);
  out += std::string("\xF7\x00\x00", 3);
  for (int i = 0; i < 256; ++i) {
    const int level[3] = {i / 42, i / 6 % 7, i % 6};
    for (int c = 0; c < 3; ++c) {
      const int l = kLevels[c] - 1;
      out.push_back(static_cast<char>(i < 252 ? (level[c] * 255 + l / 2) / l : 0));
    }
  }
  out += std::string("\x21\xFF\x0B", 3) + "NETSCAPE2.0" + std::string("\x03\x01\x00\x00\x00", 5);
  for (const RgbImage* image : frames) {
    out += std::string("\x21\xF9\x04\x04", 4);
    put16(out, delay);
    out += std::string("\x00\x00\x2C", 3);
    put16(out, 0);
    put16(out, 0);
    put16(out, width);
    put16(out, height);
    out += std::string("\x00\x08", 2);  // no local table; minimum code size 8
    // Palette indices: red * 42 + green * 6 + blue, each the nearest level.
    const std::size_t n = static_cast<std::size_t>(width) * height;
    std::vector<int> px(n);
    for (std::size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) {
        const int l = kLevels[c] - 1;
        px[i] = px[i] * kLevels[c] + (image->rgb[3 * i + c] * l + 127) / 255;
      }
    }
    std::string data;
    std::uint64_t acc = 0;
    int bits = 0;
    auto emit = [&](int code, int size) {
      acc |= static_cast<std::uint64_t>(code) << bits;
      for (bits += size; bits >= 8; bits -= 8, acc >>= 8) data.push_back(static_cast<char>(acc));
    };
    std::unordered_map<std::uint32_t, int> table;  // (prefix << 8 | index) -> code
    int size = 9, next = 258, current = px[0];
    emit(256, size);
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint32_t key =
          static_cast<std::uint32_t>(current) << 8 | static_cast<std::uint32_t>(px[i]);
      const auto it = table.find(key);
      if (it != table.end()) {
        current = it->second;
        continue;
      }
      emit(current, size);
      table.emplace(key, next);
      if (next >= (1 << size)) ++size;
      if (next == 4095) {
        emit(256, size);
        table.clear();
        size = 9;
        next = 257;
      }
      ++next;
      current = px[i];
    }
    emit(current, size);
    emit(257, size);
    if (bits > 0) data.push_back(static_cast<char>(acc));
    for (std::size_t at = 0; at < data.size(); at += 255) {
      const std::size_t k = std::min<std::size_t>(255, data.size() - at);
      out.push_back(static_cast<char>(k));
      out.append(data, at, k);
    }
    out.push_back('\0');
  }
  out.push_back('\x3B');
  return out;
}

}  // namespace pp5
