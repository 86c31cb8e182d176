#include "sim/output/gif.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>

#if defined(__AVX512BW__) || defined(__AVX512VBMI__)
#include <immintrin.h>
#endif

namespace pp5 {

namespace {

constexpr int kGifMinCodeSize = 8;  // 256 palette entries
constexpr int kGifClear = 1 << kGifMinCodeSize;
constexpr int kGifEnd = kGifClear + 1;
constexpr int kGifMaxCodes = 4096;  // codes are at most 12 bits
constexpr int kGifRed = 6, kGifGreen = 7, kGifBlue = 6;

// The nearest of `levels` evenly spaced levels of 0..255 to v.
int gif_level(std::uint8_t v, int levels) { return (v * (levels - 1) + 127) / 255; }
std::uint8_t gif_level_value(int level, int levels) {
  return static_cast<std::uint8_t>((level * 255 + (levels - 1) / 2) / (levels - 1));
}

void put16(std::string& out, int v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>((v >> 8) & 0xff));
}

// Codes packed least significant bit first into sub-blocks of at most 255 bytes.
class GifBitWriter {
 public:
  explicit GifBitWriter(std::string& out) : out_(out) {}
  void code(int value, int bits) {
    acc_ |= static_cast<std::uint32_t>(value) << count_;
    count_ += bits;
    while (count_ >= 8) {
      byte(static_cast<std::uint8_t>(acc_ & 0xff));
      acc_ >>= 8;
      count_ -= 8;
    }
  }
  void finish() {
    if (count_ > 0) byte(static_cast<std::uint8_t>(acc_ & 0xff));
    acc_ = 0;
    count_ = 0;
    flush();
    out_.push_back('\0');  // the block terminator
  }

 private:
  void byte(std::uint8_t b) {
    block_[block_size_++] = b;
    if (block_size_ == 255) flush();
  }
  void flush() {
    if (block_size_ == 0) return;
    out_.push_back(static_cast<char>(block_size_));
    out_.append(reinterpret_cast<const char*>(block_), block_size_);
    block_size_ = 0;
  }
  std::string& out_;
  std::uint32_t acc_ = 0;
  int count_ = 0;
  std::uint8_t block_[255] = {};
  std::size_t block_size_ = 0;
};

// How many of the bytes from `px` on, at most `limit`, equal `value`: a frame's background
// is long runs of one index, compared 64 (AVX-512) or 8 bytes at a time.
std::size_t gif_run_length(const std::uint8_t* px, std::uint8_t value, std::size_t limit) {
  std::size_t k = 0;
#if defined(__AVX512BW__)
  const __m512i v = _mm512_set1_epi8(static_cast<char>(value));
  for (; k + 64 <= limit; k += 64) {
    const __mmask64 equal = _mm512_cmpeq_epi8_mask(_mm512_loadu_si512(px + k), v);
    if (~equal != 0) return k + static_cast<std::size_t>(__builtin_ctzll(~equal));
  }
#endif
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  const std::uint64_t word = value * 0x0101010101010101ull;
  for (; k + 8 <= limit; k += 8) {
    std::uint64_t w;
    std::memcpy(&w, px + k, 8);
    if (w != word) return k + static_cast<std::size_t>(__builtin_ctzll(w ^ word)) / 8;
  }
#endif
  while (k < limit && px[k] == value) ++k;
  return k;
}

}  // namespace

// The image data of one frame of palette indices: LZW over a code table held as a hash table
// of (prefix code, byte) -> code, 16384 entries of 4 bytes (at most 4096 codes: a quarter full
// at most), so that it stays in the cache; a clear empties it. The codes are the table's,
// not the hash's: the same frames give the same bytes as any other form of the table.
//
// Runs of one index (a frame's background) take a shortcut with the same result. The table's
// strings that repeat one index c are c, cc, ..., c^K for some K (c^k enters only when c^(k-1)
// was sent and c followed), so while the string matched so far is c^L and the next r pixels
// are c, the greedy match goes on to c^min(L + r, K) with no lookup per pixel: those strings'
// codes are kept per index (run_codes_), not in the hash table, which holds the others.
class GifLzw {
 public:
  GifLzw() : slots_(kSlots, 0), run_codes_(256) {}
  void encode(const std::vector<std::uint8_t>& pixels, std::string& out) {
    out.push_back(static_cast<char>(kGifMinCodeSize));
    GifBitWriter w(out);
    int size = kGifMinCodeSize + 1;
    int max_code = kGifEnd;
    clear();
    w.code(kGifClear, size);
    int current = -1;
    int run = -1;     // the index the string so far repeats, else -1
    int run_len = 0;  // and how many times
    // A new code for the string so far and p: sent, the table grows, the string restarts at p.
    // (The writer is a parameter: a lambda holding a reference to a type of this file's
    // anonymous namespace, in a class outside it, draws -Wsubobject-linkage.)
    auto add = [&](GifBitWriter& writer, std::uint32_t slot, std::uint32_t key, int p,
                   bool extends_run) {
      writer.code(current, size);
      ++max_code;
      if (extends_run) {
        run_codes_[static_cast<std::size_t>(p)].push_back(static_cast<std::uint16_t>(max_code));
      } else {
        slots_[slot] = key << 12 | static_cast<std::uint32_t>(max_code);
      }
      if (max_code >= (1 << size)) ++size;
      if (max_code == kGifMaxCodes - 1) {
        writer.code(kGifClear, size);
        clear();
        size = kGifMinCodeSize + 1;
        max_code = kGifEnd;
      }
      current = p;
      run = p;
      run_len = 1;
    };
    const std::size_t n = pixels.size();
    const std::uint8_t* px = pixels.data();
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t p = px[i];
      if (current < 0) {
        current = p;
        run = p;
        run_len = 1;
        continue;
      }
      if (run == p) {
        // The pixels from i that repeat p, counted only as far as the string can grow (the
        // table holds runs of p up to `longest`) and one more, to see whether it stops there.
        const std::vector<std::uint16_t>& codes = run_codes_[p];
        const std::size_t longest = codes.size() + 1;  // c^k's code at codes[k - 2]
        const std::size_t room = longest - static_cast<std::size_t>(run_len);
        const std::size_t r = 1 + gif_run_length(px + i + 1, p, std::min(room, n - 1 - i));
        const std::size_t take = std::min(r, room);
        run_len += static_cast<int>(take);
        current = run_len == 1 ? p : codes[static_cast<std::size_t>(run_len) - 2];
        if (take < r) {
          // The next p cannot extend c^K (c^(K+1) is not in the table): c^K is sent, and the
          // string restarts at that p.
          i += take;
          add(w, 0, 0, p, true);
        } else {
          i += take - 1;
        }
        continue;
      }
      // An entry: key (prefix code << 8 | byte, 20 bits) << 12 | code (12 bits); 0 is empty
      // (every code in the table is above kGifEnd, so no entry is 0).
      const std::uint32_t key = static_cast<std::uint32_t>(current) << 8 | p;
      std::uint32_t at = (key * 2654435761u) >> (32 - kSlotBits);
      bool found = false;
      for (;;) {
        const std::uint32_t e = slots_[at];
        if (e == 0) break;
        if (e >> 12 == key) {
          current = static_cast<int>(e & 0xfff);
          found = true;
          break;
        }
        at = (at + 1) & (kSlots - 1);
      }
      if (found) {
        run = -1;  // the string no longer repeats one index
        continue;
      }
      add(w, at, key, p, false);
    }
    if (current >= 0) w.code(current, size);
    w.code(kGifEnd, size);
    w.finish();
  }

 private:
  static constexpr int kSlotBits = 14;
  static constexpr std::uint32_t kSlots = 1u << kSlotBits;
  void clear() {
    std::fill(slots_.begin(), slots_.end(), 0u);
    for (std::vector<std::uint16_t>& codes : run_codes_) codes.clear();
  }
  std::vector<std::uint32_t> slots_;
  // Per index c, the codes of cc, ccc, ... in the table.
  std::vector<std::vector<std::uint16_t>> run_codes_;
};

namespace {

// Each channel's share of the palette index, by byte value (the nearest level, scaled).
struct GifLevelTables {
  std::array<std::uint8_t, 256> red{}, green{}, blue{};
  GifLevelTables() {
    for (int v = 0; v < 256; ++v) {
      const auto b = static_cast<std::uint8_t>(v);
      red[static_cast<std::size_t>(v)] =
          static_cast<std::uint8_t>(gif_level(b, kGifRed) * kGifGreen * kGifBlue);
      green[static_cast<std::size_t>(v)] =
          static_cast<std::uint8_t>(gif_level(b, kGifGreen) * kGifBlue);
      blue[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(gif_level(b, kGifBlue));
    }
  }
};

const GifLevelTables& gif_level_tables() {
  static const GifLevelTables tables;
  return tables;
}

#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
// 32 pixels (96 bytes, `mask` the bytes to read, pixels the bytes to write) at a time: each
// channel's bytes gathered into 16-bit lanes (one two-source byte permute each), the nearest
// level as gif_level's (v (L - 1) + 127) / 255 by a multiply: (v (L - 1) + 128) 257 >> 16,
// which equals it for every byte v and L - 1 = 5 or 6 (tests/test_animation.cpp checks all
// 256 values of each channel against the tables).
void gif_quantise_32(const std::uint8_t* rgb, std::uint8_t* out, __mmask64 bytes_lo,
                     __mmask64 bytes_hi, __mmask32 pixels) {
  // Byte 3k + c of the 128 loaded is pixel k's channel c; odd bytes of each lane are 0.
  alignas(64) static constexpr struct Index {
    std::uint8_t at[3][64];
    constexpr Index() : at() {
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 32; ++k) at[c][2 * k] = static_cast<std::uint8_t>(3 * k + c);
    }
  } kIndex{};
  const __m512i lo = _mm512_maskz_loadu_epi8(bytes_lo, rgb);
  const __m512i hi = _mm512_maskz_loadu_epi8(bytes_hi, rgb + 64);
  constexpr __mmask64 kEven = 0x5555555555555555ull;
  auto channel = [&](int c) {
    return _mm512_maskz_permutex2var_epi8(kEven, lo, _mm512_load_si512(kIndex.at[c]), hi);
  };
  const __m512i k128 = _mm512_set1_epi16(128), k257 = _mm512_set1_epi16(257);
  auto level = [&](__m512i v, int steps) {
    return _mm512_mulhi_epu16(
        _mm512_add_epi16(_mm512_mullo_epi16(v, _mm512_set1_epi16(static_cast<short>(steps))), k128),
        k257);
  };
  const __m512i r = level(channel(0), kGifRed - 1);
  const __m512i g = level(channel(1), kGifGreen - 1);
  const __m512i b = level(channel(2), kGifBlue - 1);
  const __m512i index = _mm512_add_epi16(
      _mm512_add_epi16(_mm512_mullo_epi16(r, _mm512_set1_epi16(kGifGreen * kGifBlue)),
                       _mm512_mullo_epi16(g, _mm512_set1_epi16(kGifBlue))),
      b);
  _mm512_mask_cvtepi16_storeu_epi8(out, pixels, index);
}
#endif

// n pixels of RGB as palette indices.
void gif_quantise(const std::uint8_t* rgb, int n, std::uint8_t* out) {
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
  int x = 0;
  for (; x + 32 <= n; x += 32) gif_quantise_32(rgb + 3 * x, out + x, ~0ull, ~0ull >> 32, ~0u);
  if (x < n) {
    const int bytes = 3 * (n - x);  // 3 to 93
    const __mmask64 lo = bytes >= 64 ? ~0ull : (1ull << bytes) - 1;
    const __mmask64 hi = bytes > 64 ? (1ull << (bytes - 64)) - 1 : 0;
    gif_quantise_32(rgb + 3 * x, out + x, lo, hi, (1u << (n - x)) - 1);
  }
#else
  const GifLevelTables& t = gif_level_tables();
  for (int x = 0; x < n; ++x) {
    out[x] = static_cast<std::uint8_t>(t.red[rgb[3 * x]] + t.green[rgb[3 * x + 1]] +
                                       t.blue[rgb[3 * x + 2]]);
  }
#endif
}

}  // namespace

std::uint8_t gif_palette_index(const std::uint8_t rgb[3]) {
  const GifLevelTables& t = gif_level_tables();
  return static_cast<std::uint8_t>(t.red[rgb[0]] + t.green[rgb[1]] + t.blue[rgb[2]]);
}

void gif_palette_colour(std::uint8_t index, std::uint8_t rgb[3]) {
  if (index >= kGifRed * kGifGreen * kGifBlue) {
    rgb[0] = rgb[1] = rgb[2] = 0;
    return;
  }
  rgb[0] = gif_level_value(index / (kGifGreen * kGifBlue), kGifRed);
  rgb[1] = gif_level_value((index / kGifBlue) % kGifGreen, kGifGreen);
  rgb[2] = gif_level_value(index % kGifBlue, kGifBlue);
}

GifWriter::GifWriter(int delay_centiseconds) : delay_(delay_centiseconds) {}
GifWriter::~GifWriter() = default;

void GifWriter::add(const RgbImage& f) {
  if (f.width >= 1 && f.height >= 1 && f.width <= 65535 && f.height <= 65535 &&
      f.rgb.size() != static_cast<std::size_t>(f.width) * f.height * 3) {
    throw std::invalid_argument(fmt::format("GIF frame {} is {}x{} with {} bytes of pixels",
                                            frames_, f.width, f.height, f.rgb.size()));
  }
  const std::size_t stride = static_cast<std::size_t>(std::max(f.width, 0)) * 3;
  add_rows(f.width, f.height, [&f, stride](int y, std::uint8_t* out) {
    gif_quantise(f.rgb.data() + stride * static_cast<std::size_t>(y), f.width, out);
  });
}

void GifWriter::add(const FrameImage& f) {
  if (!f.has_pixels()) {
    throw std::invalid_argument(fmt::format("GIF frame {} holds no pixels", frames_));
  }
  // Region by region along the row, where the pixels lie (a black region's part is index 0's
  // colour, black).
  const int width = f.width();
  const int region_width = f.region_width();
  add_rows(width, f.height(), [&f, width, region_width](int y, std::uint8_t* out) {
    for (int c = 0; c < f.columns(); ++c) {
      const int x0 = c * region_width;
      const int n = std::min(region_width, width - x0);
      if (const std::uint8_t* rgb = f.region_row(c, y)) {
        gif_quantise(rgb, n, out + x0);
      } else {
        const std::uint8_t black[3] = {0, 0, 0};
        std::memset(out + x0, gif_palette_index(black), static_cast<std::size_t>(n));
      }
    }
  });
}

template <class Rows>
void GifWriter::add_rows(int width, int height, Rows rows) {
  const int k = frames_;
  if (k > 0 && (width != width_ || height != height_)) {
    throw std::invalid_argument(
        fmt::format("GIF frame {} is {}x{}, frame 0 {}x{}", k, width, height, width_, height_));
  }
  if (width < 1 || height < 1 || width > 65535 || height > 65535) {
    throw std::invalid_argument(fmt::format("GIF frame {} is {}x{}", k, width, height));
  }
  if (k == 0) {
    width_ = width;
    height_ = height;
    out_ = "GIF89a";
    put16(out_, width_);
    put16(out_, height_);
    out_.push_back(static_cast<char>(0xF7));  // a global table of 256 colours, 8 bits each
    out_.push_back('\0');                     // background colour index
    out_.push_back('\0');                     // square pixels
    for (int i = 0; i < 256; ++i) {
      std::uint8_t rgb[3];
      gif_palette_colour(static_cast<std::uint8_t>(i), rgb);
      out_.append(reinterpret_cast<const char*>(rgb), 3);
    }
    // Loop forever.
    out_ += std::string("\x21\xFF\x0B", 3) + "NETSCAPE2.0" + std::string("\x03\x01\x00\x00\x00", 5);
  }
  // The frame's palette indices, a row at a time (kept from frame to frame).
  indices_.resize(static_cast<std::size_t>(width_) * height_);
  for (int y = 0; y < height_; ++y) rows(y, indices_.data() + static_cast<std::size_t>(y) * width_);
  // Graphic control: no disposal, the delay, no transparent colour.
  out_ += std::string("\x21\xF9\x04\x04", 4);
  put16(out_, delay_);
  out_ += std::string("\x00\x00", 2);
  out_.push_back(static_cast<char>(0x2C));
  put16(out_, 0);
  put16(out_, 0);
  put16(out_, width_);
  put16(out_, height_);
  out_.push_back('\0');  // no local table, not interlaced
  if (!lzw_) lzw_ = std::make_unique<GifLzw>();
  lzw_->encode(indices_, out_);
  ++frames_;
}

std::string GifWriter::finish() {
  if (frames_ == 0) throw std::invalid_argument("an animated GIF needs at least one frame");
  std::string out = std::move(out_);
  out.push_back(static_cast<char>(0x3B));
  out_.clear();
  frames_ = 0;
  return out;
}

std::string encode_gif(const std::vector<const RgbImage*>& frames, int delay_centiseconds) {
  if (frames.empty()) throw std::invalid_argument("an animated GIF needs at least one frame");
  GifWriter gif(delay_centiseconds);
  for (const RgbImage* f : frames) gif.add(*f);
  return gif.finish();
}

DecodedGif decode_gif(const std::string& bytes) {
  std::size_t pos = 0;
  auto need = [&](std::size_t n) {
    if (pos + n > bytes.size()) throw std::runtime_error("GIF: truncated");
  };
  auto u8 = [&]() {
    need(1);
    return static_cast<std::uint8_t>(bytes[pos++]);
  };
  auto u16 = [&]() {
    const int lo = u8();
    return lo | (u8() << 8);
  };
  need(6);
  if (bytes.compare(0, 6, "GIF89a") != 0) throw std::runtime_error("GIF: not GIF89a");
  pos = 6;
  DecodedGif gif;
  gif.width = u16();
  gif.height = u16();
  const std::uint8_t packed = u8();
  pos += 2;
  if (packed & 0x80) pos += 3u * (2u << (packed & 7));
  int delay = 0;
  for (;;) {
    const std::uint8_t tag = u8();
    if (tag == 0x3B) break;
    if (tag == 0x21) {
      const std::uint8_t label = u8();
      std::string data;
      for (std::uint8_t n = u8(); n != 0; n = u8()) {
        need(n);
        data.append(bytes, pos, n);
        pos += n;
      }
      if (label == 0xF9 && data.size() == 4) {
        delay = static_cast<std::uint8_t>(data[1]) | (static_cast<std::uint8_t>(data[2]) << 8);
      }
      continue;
    }
    if (tag != 0x2C) throw std::runtime_error(fmt::format("GIF: unexpected block {:#x}", tag));
    pos += 8;
    if (u8() != 0) throw std::runtime_error("GIF: local tables and interlace are not read");
    const int min_size = u8();
    std::string data;
    for (std::uint8_t n = u8(); n != 0; n = u8()) {
      need(n);
      data.append(bytes, pos, n);
      pos += n;
    }
    const int clear = 1 << min_size, end = clear + 1;
    // The code table as prefix code + last byte, with each string's first byte and length.
    std::vector<int> prefix(kGifMaxCodes, -1), first(kGifMaxCodes, 0), length(kGifMaxCodes, 0);
    std::vector<std::uint8_t> last(kGifMaxCodes, 0);
    for (int i = 0; i < clear; ++i) {
      last[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i);
      first[static_cast<std::size_t>(i)] = i;
      length[static_cast<std::size_t>(i)] = 1;
    }
    std::vector<std::uint8_t> pixels;
    auto emit = [&](int code) {
      const std::size_t n = static_cast<std::size_t>(length[static_cast<std::size_t>(code)]);
      pixels.resize(pixels.size() + n);
      std::size_t at = pixels.size();
      for (int c = code; c >= 0; c = prefix[static_cast<std::size_t>(c)]) {
        pixels[--at] = last[static_cast<std::size_t>(c)];
      }
    };
    int size = min_size + 1, prev = -1, next = end + 1;
    std::size_t bit = 0;
    for (;;) {
      if (bit + static_cast<std::size_t>(size) > data.size() * 8) {
        throw std::runtime_error("GIF: image data ends without an end code");
      }
      int code = 0;
      for (int b = 0; b < size; ++b, ++bit) {
        code |= ((static_cast<std::uint8_t>(data[bit / 8]) >> (bit % 8)) & 1) << b;
      }
      if (code == clear) {
        size = min_size + 1;
        next = end + 1;
        prev = -1;
        continue;
      }
      if (code == end) break;
      if (prev < 0) {
        if (code >= clear) throw std::runtime_error("GIF: bad first code");
        emit(code);
        prev = code;
        continue;
      }
      if (code > next || (code >= clear && code <= end)) {
        throw std::runtime_error("GIF: code beyond the table");
      }
      const int head = code < next ? first[static_cast<std::size_t>(code)]
                                   : first[static_cast<std::size_t>(prev)];
      if (next < kGifMaxCodes) {
        const auto e = static_cast<std::size_t>(next);
        prefix[e] = prev;
        last[e] = static_cast<std::uint8_t>(head);
        first[e] = first[static_cast<std::size_t>(prev)];
        length[e] = length[static_cast<std::size_t>(prev)] + 1;
        ++next;
      }
      emit(code);
      if (next == (1 << size) && size < 12) ++size;
      prev = code;
    }
    if (pixels.size() != static_cast<std::size_t>(gif.width) * gif.height) {
      throw std::runtime_error(fmt::format("GIF: frame {} has {} pixels, not {}", gif.frames.size(),
                                           pixels.size(), gif.width * gif.height));
    }
    gif.frames.push_back(std::move(pixels));
    gif.delays.push_back(delay);
  }
  return gif;
}

}  // namespace pp5
