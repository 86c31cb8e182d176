#include "sim/image/png_writer.hpp"

#include <fmt/format.h>
#include <png.h>
#include <zlib.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/output/output_set.hpp"

namespace pp5 {
namespace {

// Releases libpng's state on every exit path; png_image_free is a no-op once libpng has already
// freed it (after png_image_finish_read or a failed call).
class PngImageGuard {
 public:
  explicit PngImageGuard(png_image& image) : image_(image) {}
  ~PngImageGuard() { png_image_free(&image_); }
  PngImageGuard(const PngImageGuard&) = delete;
  PngImageGuard& operator=(const PngImageGuard&) = delete;

 private:
  png_image& image_;
};

[[noreturn]] void fail(const char* what, const std::string& path, const std::string& reason) {
  throw std::runtime_error(fmt::format("{} '{}': {}", what, path, reason));
}

// The longest IDAT chunk written (PNG allows 2^31 - 1 bytes).
constexpr std::size_t kMaxChunk = std::size_t{1} << 30;

void put_u32(std::string& out, std::uint32_t v) {
  const char bytes[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                         static_cast<char>(v >> 8), static_cast<char>(v)};
  out.append(bytes, 4);
}

// zlib's crc32 and adler32 take a uInt length: longer buffers go in pieces.
template <class F>
uLong png_checksum(F f, uLong start, const std::uint8_t* data, std::size_t size) {
  uLong sum = start;
  for (std::size_t done = 0; done < size;) {
    const auto n = static_cast<uInt>(std::min<std::size_t>(size - done, 1u << 30));
    sum = f(sum, data + done, n);
    done += n;
  }
  return sum;
}

// A PNG chunk: length, type, data, and the CRC of type and data.
void put_chunk(std::string& out, const char type[4], const char* data, std::size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t at = out.size();
  out.append(type, 4);
  out.append(data, size);
  const uLong crc = png_checksum(crc32, crc32(0L, Z_NULL, 0),
                                 reinterpret_cast<const std::uint8_t*>(out.data() + at), size + 4);
  put_u32(out, static_cast<std::uint32_t>(crc));
}

// The zlib stream of the filtered rows, made here: one dynamic-Huffman deflate block whose
// matches are runs, a byte repeating the one before it (distance 1: after the Up filter, a
// row like the one above is all 0) or the pixel before it (distance 3: a flat colour the row
// above does not share), found greedily, 8 bytes compared at a time. It is what zlib's
// run-length strategy (Z_RLE) makes of a rendered frame, plus the distance-3 runs, and several
// times quicker (bench/bench_png.cpp prints the ratio against zlib in one run); any inflater
// reads it (the tests decode it with libpng).
class PngDeflate {
 public:
  // The zlib stream of in[0, n) appended to out.
  void compress(const std::uint8_t* in, std::size_t n, std::string& out) {
    tokenize(in, n);
    build_codes();
    // At most 15 bits a literal, 5 + 5 + 1 + 15 a run of at least 3 bytes, the header's 300
    // symbols of at most 7 + 7 bits, and slack for the bit writer's 8-byte stores.
    bits_.resize(n * 2 + 1024);
    dst_ = bits_.data();
    acc_ = 0;
    count_ = 0;
    put(1, 1);  // BFINAL
    put(2, 2);  // BTYPE = dynamic Huffman
    write_header();
    // Per symbol: its code (bits 0..15), code length (16..23), extra bits (24..27) and
    // distance code bits after them (28..31: a run's, 0 for a literal).
    std::uint32_t sym_bits[kLitSymbols];
    for (int k = 0; k < kLitSymbols; ++k) {
      const bool run = k >= 257;
      sym_bits[k] = static_cast<std::uint32_t>(lit_code_[static_cast<std::size_t>(k)]) |
                    static_cast<std::uint32_t>(lit_len_[static_cast<std::size_t>(k)]) << 16 |
                    static_cast<std::uint32_t>(run ? kLengthExtra[k - 257] : 0) << 24 |
                    static_cast<std::uint32_t>(run ? dist_len_[0] : 0) << 28;
    }
    // Distance codes 0 (1) and 2 (3), each 1 bit (build_codes), no extra bits; a literal's
    // token has flag 0 and no distance bits, so what its shift brings in is 0.
    const std::uint64_t dist_code[2] = {dist_code_[0], dist_code_[2]};
    // A token's bits, LSB first: the symbol's code, a run's extra bits and its distance code.
    auto token_bits = [&sym_bits, &dist_code](std::uint16_t t, int& bits) {
      const std::uint32_t e = sym_bits[t & 0x1ff];
      const int len = static_cast<int>(e >> 16 & 0xff);
      const int extra = static_cast<int>(e >> 24 & 0xf);
      const std::uint64_t value = (e & 0xffff) | static_cast<std::uint64_t>(t >> 9 & 0x1f) << len |
                                  dist_code[t >> 14 & 1] << (len + extra);
      bits = len + extra + static_cast<int>(e >> 28);
      return value;
    };
    // The body's bits in locals (the member writer's state, stored through the byte pointer,
    // would be reloaded after every store).
    std::uint64_t acc = acc_;
    int count = count_;
    std::uint8_t* dst = dst_;
    // Two tokens (at most 15 + 5 + 1 bits each) as one put, one loop with no branch per
    // token: the writer's state is a chain of dependent operations, half as long this way.
    // At most 7 bits wait in acc between puts, and a put is at most 42 bits: on a
    // little-endian host the whole word is stored and the pointer advanced by the whole bytes,
    // with no branch (the stream has 1024 bytes of slack past its longest).
    const std::uint16_t* tok = tokens_.get();
    const std::size_t tokens = token_count_;
    std::size_t k = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    auto emit = [&acc, &count, &dst](std::uint64_t value, int bits) {
      acc |= value << count;
      count += bits;
      std::memcpy(dst, &acc, 8);
      dst += count >> 3;
      acc >>= count & ~7;
      count &= 7;
    };
    for (; k + 2 <= tokens; k += 2) {
      int la, lb;
      const std::uint64_t a = token_bits(tok[k], la);
      const std::uint64_t b = token_bits(tok[k + 1], lb);
      emit(a | b << la, la + lb);
    }
#endif
    for (; k < tokens; ++k) {
      int bits;
      const std::uint64_t value = token_bits(tok[k], bits);
      put_bits(acc, count, dst, static_cast<std::uint32_t>(value), bits);
    }
    acc_ = acc;
    count_ = count;
    dst_ = dst;
    put(lit_code_[256], lit_len_[256]);
    flush();
    out.push_back('\x78');  // zlib header: deflate, 32K window, no dictionary, FLEVEL 0
    out.push_back('\x01');
    out.append(reinterpret_cast<const char*>(bits_.data()),
               static_cast<std::size_t>(dst_ - bits_.data()));
    put_u32(out, adler_);
  }

 private:
  static constexpr int kLitSymbols = 286;  // literals, end of block, lengths 257..285
  static constexpr int kMaxMatch = 258;
  static constexpr int kLengthBase[29] = {3,  4,  5,  6,   7,   8,   9,   10,  11, 13,
                                          15, 17, 19, 23,  27,  31,  35,  43,  51, 59,
                                          67, 83, 99, 115, 131, 163, 195, 227, 258};
  static constexpr int kLengthExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                           2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
  static const std::array<std::uint16_t, kMaxMatch + 1> kLengthSymbol;

  // How many bytes from `at` on equal the ones `distance` before them (at most `limit`).
  static std::size_t run_length(const std::uint8_t* in, std::size_t at, std::size_t distance,
                                std::size_t limit) {
    std::size_t k = 0;
#if defined(__AVX2__)
    // 32 bytes compared at a time (a run of 258 bytes is 8 steps, not 32).
    for (; k + 32 <= limit; k += 32) {
      const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + at + k));
      const __m256i b =
          _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + at + k - distance));
      const auto equal = static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(a, b)));
      if (equal != 0xffffffffu) return k + static_cast<std::size_t>(__builtin_ctz(~equal));
    }
#endif
    while (k + 8 <= limit) {
      std::uint64_t a, b;
      std::memcpy(&a, in + at + k, 8);
      std::memcpy(&b, in + at + k - distance, 8);
      if (a != b) return k + static_cast<std::size_t>(__builtin_ctzll(a ^ b)) / 8;
      k += 8;
    }
    while (k < limit && in[at + k] == in[at + k - distance]) ++k;
    return k;
  }

  // Whether a run of at least 3 bytes (distance 1 or 3) starts at byte i.
  static bool run_starts(const std::uint8_t* in, std::size_t i, std::size_t n) {
    if (i + 3 > n) return false;
    if (i >= 1 && in[i] == in[i - 1] && in[i + 1] == in[i] && in[i + 2] == in[i + 1]) return true;
    return i >= 3 && in[i] == in[i - 3] && in[i + 1] == in[i - 2] && in[i + 2] == in[i - 1];
  }

  // The first byte at or after i where a run starts (run_starts), else n. Sixteen bytes are
  // compared with the one before and the pixel before at once where SSE2 is there.
  static std::size_t next_run(const std::uint8_t* in, std::size_t i, std::size_t n) {
    while (i < 3 && i < n) {
      if (run_starts(in, i, n)) return i;
      ++i;
    }
#if defined(__SSE2__)
    // Bit k of m1 (m3): byte i + k equals the one 1 (3) before it; a run starts at k when
    // bits k, k + 1 and k + 2 are set, which 16 bytes decide for k up to 13.
    for (; i + 16 <= n; i += 14) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
      const auto m1 = static_cast<unsigned>(_mm_movemask_epi8(
          _mm_cmpeq_epi8(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i - 1)))));
      const auto m3 = static_cast<unsigned>(_mm_movemask_epi8(
          _mm_cmpeq_epi8(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i - 3)))));
      const unsigned r = ((m1 & m1 >> 1 & m1 >> 2) | (m3 & m3 >> 1 & m3 >> 2)) & 0x3fffu;
      if (r != 0) return i + static_cast<std::size_t>(__builtin_ctz(r));
    }
#endif
    for (; i < n; ++i) {
      if (run_starts(in, i, n)) return i;
    }
    return n;
  }

  // Greedy: at each byte the longer run (distance 1 or 3) if it is at least 3 bytes long,
  // else the byte as a literal; the bytes between runs are found a block at a time
  // (next_run). The zlib stream's Adler-32 is summed as it goes: a run of one byte in closed
  // form, so that the long runs of 0 cost nothing per byte.
  void tokenize(const std::uint8_t* in, std::size_t n) {
    // At most one token a byte; kept from image to image, and not zeroed (only the tokens
    // written are read).
    if (token_capacity_ < n) {
      tokens_.reset(new std::uint16_t[n]);
      token_capacity_ = n;
    }
    std::uint16_t* tok = tokens_.get();
    std::size_t t = 0;
    // Counted in two tables on the stack, alternate literals in each: a store to a member
    // (or to the thread's scratch) could alias `in` and would force every byte to be loaded
    // again, and a byte repeating the one before it would wait on its own count's store.
    std::uint32_t freq[2][kLitSymbols] = {};
    constexpr std::uint64_t kBase = 65521;
    std::uint64_t s1 = 1, s2 = 0;
    std::size_t i = 0;
    // Bytes summed since the last reduction, at most 4096: s1 stays below 2^21, s2 below 2^33.
    std::size_t since = 0;
    auto reduce = [&] {
      s1 %= kBase;
      s2 %= kBase;
      since = 0;
    };
    while (i < n) {
      const std::size_t at = next_run(in, i, n);
      // Literals [i, at), in pieces that keep at most 4096 bytes between reductions.
      for (std::size_t k = i; k < at;) {
        const std::size_t end = std::min(at, k + (4096 - since));
        since += end - k;
        for (; k + 2 <= end; k += 2) {
          const std::uint8_t a = in[k], b = in[k + 1];
          tok[t] = a;
          tok[t + 1] = b;
          t += 2;
          ++freq[0][a];
          ++freq[1][b];
          s1 += a;
          s2 += s1;
          s1 += b;
          s2 += s1;
        }
        if (k < end) {
          const std::uint8_t a = in[k++];
          tok[t++] = a;
          ++freq[0][a];
          s1 += a;
          s2 += s1;
        }
        if (since == 4096) reduce();
      }
      if (at == n) break;
      const std::size_t limit = std::min<std::size_t>(kMaxMatch, n - at);
      const std::size_t r1 = at >= 1 ? run_length(in, at, 1, limit) : 0;
      const std::size_t r3 = at >= 3 && r1 < limit ? run_length(in, at, 3, limit) : 0;
      const std::size_t best = r3 > r1 ? r3 : r1;
      const int distance = r3 > r1 ? 3 : 1;
      const int sym = kLengthSymbol[best];
      tok[t++] = static_cast<std::uint16_t>(
          sym | static_cast<int>(best - static_cast<std::size_t>(kLengthBase[sym - 257])) << 9 |
          (distance == 3) << 14);
      ++freq[0][sym];
      // A run of at most 258 bytes: reduced before when it could take the count past 4096.
      if (since + best > 4096) reduce();
      since += best;
      if (distance == 1) {  // best copies of b: s2 gains best s1 + b (1 + 2 + ... + best)
        const std::uint64_t b = in[at];
        s2 += best * s1 + b * (best * (best + 1) / 2);
        s1 += best * b;
      } else {
        for (std::size_t k = 0; k < best; ++k) {
          s1 += in[at + k];
          s2 += s1;
        }
      }
      i = at + best;
    }
    token_count_ = t;
    for (int k = 0; k < kLitSymbols; ++k) lit_freq_[k] = freq[0][k] + freq[1][k];
    lit_freq_[256] = 1;
    adler_ = static_cast<std::uint32_t>((s2 % kBase) << 16 | (s1 % kBase));
  }

  // Code lengths for `freq` (n symbols), none longer than `limit`: Huffman's construction,
  // over frequencies halved (a used symbol keeps at least 1) until it fits. Unused symbols
  // get 0; a lone used symbol gets 1.
  static void huffman_lengths(const std::uint32_t* freq, int n, int limit, std::uint8_t* len) {
    // On the stack: n is at most kLitSymbols (a frame's encoding makes no allocation here).
    std::array<std::uint32_t, kLitSymbols> f{};
    std::copy(freq, freq + n, f.begin());
    std::array<std::pair<std::uint64_t, int>, kLitSymbols> heap_store;  // (weight, node)
    std::array<int, 2 * kLitSymbols> parent;
    for (;;) {
      std::fill(len, len + n, std::uint8_t{0});
      // Nodes: leaves 0..n-1, inner nodes after; parent links give the depths. A min-heap
      // of (weight, node) in heap_store[0, size).
      std::fill(parent.begin(), parent.begin() + 2 * n, -1);
      const auto heap = heap_store.begin();
      std::ptrdiff_t size = 0;
      for (int s = 0; s < n; ++s) {
        if (f[static_cast<std::size_t>(s)] != 0) heap[size++] = {f[static_cast<std::size_t>(s)], s};
      }
      if (size == 0) return;
      if (size == 1) {
        len[heap[0].second] = 1;
        return;
      }
      auto greater = [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second > b.second;
      };
      std::make_heap(heap, heap + size, greater);
      int next = n;
      while (size > 1) {
        std::pop_heap(heap, heap + size, greater);
        const auto a = heap[--size];
        std::pop_heap(heap, heap + size, greater);
        const auto b = heap[--size];
        parent[static_cast<std::size_t>(a.second)] = next;
        parent[static_cast<std::size_t>(b.second)] = next;
        heap[size++] = {a.first + b.first, next};
        std::push_heap(heap, heap + size, greater);
        ++next;
      }
      int longest = 0;
      for (int s = 0; s < n; ++s) {
        if (f[static_cast<std::size_t>(s)] == 0) continue;
        int depth = 0;
        for (int v = s; parent[static_cast<std::size_t>(v)] >= 0;
             v = parent[static_cast<std::size_t>(v)])
          ++depth;
        len[s] = static_cast<std::uint8_t>(std::min(depth, 255));
        longest = std::max(longest, depth);
      }
      if (longest <= limit) return;
      for (std::uint32_t& x : f) {
        if (x != 0) x = std::max<std::uint32_t>(1, x >> 1);
      }
    }
  }

  // Canonical codes (RFC 1951 3.2.2) for the lengths, bit-reversed for the LSB-first stream.
  static void canonical_codes(const std::uint8_t* len, int n, std::uint16_t* code) {
    int count[16] = {};
    for (int s = 0; s < n; ++s) ++count[len[s]];
    count[0] = 0;
    int next[16] = {};
    int c = 0;
    for (int b = 1; b < 16; ++b) {
      c = (c + count[b - 1]) << 1;
      next[b] = c;
    }
    for (int s = 0; s < n; ++s) {
      const int l = len[s];
      if (l == 0) continue;
      int v = next[l]++;
      int r = 0;
      for (int b = 0; b < l; ++b, v >>= 1) r = (r << 1) | (v & 1);
      code[s] = static_cast<std::uint16_t>(r);
    }
  }

  void build_codes() {
    huffman_lengths(lit_freq_.data(), kLitSymbols, 15, lit_len_.data());
    canonical_codes(lit_len_.data(), kLitSymbols, lit_code_.data());
    // Distance codes 0 and 2 one bit each, whichever are used: a complete code.
    dist_len_ = {1, 0, 1};
    canonical_codes(dist_len_.data(), 3, dist_code_.data());
  }

  // HLIT, HDIST, HCLEN and the code lengths, each sent as its own code-length symbol (0-15).
  void write_header() {
    int hlit = kLitSymbols;
    while (hlit > 257 && lit_len_[static_cast<std::size_t>(hlit - 1)] == 0) --hlit;
    std::array<std::uint8_t, kLitSymbols + 3> lengths{};
    std::copy_n(lit_len_.begin(), hlit, lengths.begin());
    std::copy_n(dist_len_.begin(), 3, lengths.begin() + hlit);
    const int total = hlit + 3;
    std::array<std::uint32_t, 19> freq{};
    for (int k = 0; k < total; ++k) ++freq[lengths[static_cast<std::size_t>(k)]];
    std::array<std::uint8_t, 19> cl_len{};
    std::array<std::uint16_t, 19> cl_code{};
    huffman_lengths(freq.data(), 19, 7, cl_len.data());
    canonical_codes(cl_len.data(), 19, cl_code.data());
    static constexpr int kOrder[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                       11, 4,  12, 3, 13, 2, 14, 1, 15};
    int hclen = 19;
    while (hclen > 4 && cl_len[static_cast<std::size_t>(kOrder[hclen - 1])] == 0) --hclen;
    put(static_cast<std::uint32_t>(hlit - 257), 5);
    put(3 - 1, 5);  // HDIST: distance codes 0..2
    put(static_cast<std::uint32_t>(hclen - 4), 4);
    for (int k = 0; k < hclen; ++k) put(cl_len[static_cast<std::size_t>(kOrder[k])], 3);
    for (int k = 0; k < total; ++k) {
      const std::size_t l = lengths[static_cast<std::size_t>(k)];
      put(cl_code[l], cl_len[l]);
    }
  }

  // `bits` bits of `value` after the `count` in `acc`, LSB first; 32 at a time to dst.
  static void put_bits(std::uint64_t& acc, int& count, std::uint8_t*& dst, std::uint32_t value,
                       int bits) {
    acc |= static_cast<std::uint64_t>(value) << count;
    count += bits;
    if (count >= 32) {
      const auto word = static_cast<std::uint32_t>(acc);
      dst[0] = static_cast<std::uint8_t>(word);
      dst[1] = static_cast<std::uint8_t>(word >> 8);
      dst[2] = static_cast<std::uint8_t>(word >> 16);
      dst[3] = static_cast<std::uint8_t>(word >> 24);
      dst += 4;
      acc >>= 32;
      count -= 32;
    }
  }
  void put(std::uint32_t value, int bits) { put_bits(acc_, count_, dst_, value, bits); }
  void flush() {
    while (count_ > 0) {
      *dst_++ = static_cast<std::uint8_t>(acc_);
      acc_ >>= 8;
      count_ -= 8;
    }
    count_ = 0;
  }

  // The tokens in order: a literal byte (0..255), or a run: its length symbol (bits 0..8),
  // the length less the symbol's base (9..13) and whether its distance is 3 (bit 14).
  std::unique_ptr<std::uint16_t[]> tokens_;
  std::size_t token_capacity_ = 0;
  std::size_t token_count_ = 0;
  std::array<std::uint32_t, kLitSymbols> lit_freq_{};
  std::array<std::uint8_t, kLitSymbols> lit_len_{};
  std::array<std::uint16_t, kLitSymbols> lit_code_{};
  std::array<std::uint8_t, 3> dist_len_{};
  std::array<std::uint16_t, 3> dist_code_{};
  std::vector<std::uint8_t> bits_;  // the deflate stream, written at dst_
  std::uint8_t* dst_ = nullptr;
  std::uint64_t acc_ = 0;
  int count_ = 0;
  std::uint32_t adler_ = 1;
};

// The length symbol (257..285) of each match length 3..258.
const std::array<std::uint16_t, PngDeflate::kMaxMatch + 1> PngDeflate::kLengthSymbol = [] {
  std::array<std::uint16_t, kMaxMatch + 1> table{};
  for (int sym = 0; sym < 29; ++sym) {
    const int end = sym + 1 < 29 ? kLengthBase[sym + 1] : kMaxMatch + 1;
    for (int l = kLengthBase[sym]; l < end && l <= kMaxMatch; ++l)
      table[static_cast<std::size_t>(l)] = static_cast<std::uint16_t>(257 + sym);
  }
  table[kMaxMatch] = 285;  // 258 has its own symbol, not 284 with 31 extra
  return table;
}();

// Per host thread, kept between images: the filtered rows and the encoder's tokens and
// output, so that a run of frames allocates (and the kernel zeroes) them once, not per image.
struct PngScratch {
  std::vector<std::uint8_t> filtered;
  std::string stream;  // the zlib stream, before it is cut into IDAT chunks
  PngDeflate deflate;
};

PngScratch& png_scratch() {
  thread_local PngScratch scratch;
  return scratch;
}

}  // namespace

namespace {

// Up-filtered bytes: each byte of `row` less the byte above it (`above` null: the first row,
// whose bytes are its own).
void png_up(const std::uint8_t* row, const std::uint8_t* above, std::size_t n, std::uint8_t* out) {
  if (above == nullptr) {
    std::memcpy(out, row, n);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(row[i] - above[i]);
}

// The PNG of a width x height image whose rows filter(y, out) writes Up-filtered (width * 3
// bytes, after the filter byte), for y = 0 .. height - 1 in order: the rows are filtered where
// they lie, not copied first.
template <class Filter>
std::string encode_filtered_png(int width, int height, const std::string& what, Filter&& filter) {
  constexpr const char* kWhat = "cannot write PNG";
  if (width <= 0 || height <= 0) {
    fail(kWhat, what, fmt::format("invalid size {}x{}", width, height));
  }
  // The PNG container written here, its zlib stream made here (PngDeflate) over the whole
  // filtered image; libpng reads it.
  const std::size_t stride = static_cast<std::size_t>(width) * 3u;
  const std::size_t line = stride + 1;
  if (line > std::numeric_limits<std::size_t>::max() / 4 / static_cast<std::size_t>(height)) {
    fail(kWhat, what, fmt::format("a {}x{} image is too large to compress", width, height));
  }
  PngScratch& scratch = png_scratch();
  std::vector<std::uint8_t>& filtered = scratch.filtered;
  filtered.resize(line * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    std::uint8_t* out = filtered.data() + line * static_cast<std::size_t>(y);
    out[0] = 2;  // the Up filter: each byte less the byte above it
    filter(y, out + 1);
  }
  std::string& stream = scratch.stream;
  stream.clear();
  scratch.deflate.compress(filtered.data(), filtered.size(), stream);
  const std::size_t written = stream.size();
  std::string png;
  png.reserve(written + 64 + written / kMaxChunk * 12);
  png.append("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  put_u32(header, static_cast<std::uint32_t>(width));
  put_u32(header, static_cast<std::uint32_t>(height));
  header.append("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, filters 0, no interlace
  put_chunk(png, "IHDR", header.data(), header.size());
  for (std::size_t at = 0; at < written; at += kMaxChunk) {
    put_chunk(png, "IDAT", stream.data() + at, std::min(kMaxChunk, written - at));
  }
  put_chunk(png, "IEND", "", 0);
  return png;
}

}  // namespace

std::string encode_png(const RgbImage& image, const std::string& what) {
  // Computed in size_t, where the product of two positive ints cannot overflow.
  const auto expected = static_cast<std::size_t>(std::max(image.width, 0)) *
                        static_cast<std::size_t>(std::max(image.height, 0)) * 3u;
  if (image.width > 0 && image.height > 0 && image.rgb.size() != expected) {
    fail("cannot write PNG", what,
         fmt::format("pixel buffer holds {} bytes, a {}x{} RGB image needs {}", image.rgb.size(),
                     image.width, image.height, expected));
  }
  const std::size_t stride = static_cast<std::size_t>(std::max(image.width, 0)) * 3u;
  return encode_filtered_png(image.width, image.height, what, [&](int y, std::uint8_t* out) {
    const std::uint8_t* row = image.rgb.data() + stride * static_cast<std::size_t>(y);
    png_up(row, y > 0 ? row - stride : nullptr, stride, out);
  });
}

std::string encode_png(const FrameImage& frame, const std::string& what) {
  if (!frame.has_pixels()) fail("cannot write PNG", what, "the frame holds no pixels");
  // Region by region along the row: a black region's part of a row is 0s.
  const int width = frame.width();
  const int region_width = frame.region_width();
  return encode_filtered_png(width, frame.height(), what, [&](int y, std::uint8_t* out) {
    for (int c = 0; c < frame.columns(); ++c) {
      const int x0 = c * region_width;
      const std::size_t bytes = static_cast<std::size_t>(std::min(region_width, width - x0)) * 3;
      std::uint8_t* to = out + static_cast<std::size_t>(x0) * 3;
      const std::uint8_t* row = frame.region_row(c, y);
      const std::uint8_t* above = y > 0 ? frame.region_row(c, y - 1) : nullptr;
      if (row != nullptr) {
        png_up(row, above, bytes, to);
      } else if (above != nullptr) {
        for (std::size_t i = 0; i < bytes; ++i) to[i] = static_cast<std::uint8_t>(0 - above[i]);
      } else {
        std::memset(to, 0, bytes);
      }
    }
  });
}

std::string encode_png(int width, int height,
                       const std::function<void(int y, std::uint8_t* row)>& rows,
                       const std::string& what) {
  const std::size_t stride = static_cast<std::size_t>(std::max(width, 0)) * 3u;
  std::vector<std::uint8_t> row, above;
  return encode_filtered_png(width, height, what, [&](int y, std::uint8_t* out) {
    if (y == 0) {
      row.resize(stride);
      above.resize(stride);
    }
    rows(y, row.data());
    png_up(row.data(), y > 0 ? above.data() : nullptr, stride, out);
    row.swap(above);
  });
}

void write_png(const std::string& path, const RgbImage& image) {
  const std::string bytes = encode_png(image, path);
  try {
    write_file_atomically(path, bytes);
  } catch (const OutputError& e) {
    throw std::runtime_error(std::string("cannot write PNG: ") + e.what());
  }
}

RgbImage read_png(const std::string& path) {
  constexpr const char* kWhat = "cannot read PNG";
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  PngImageGuard guard(png);
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    fail(kWhat, path, png.message);
  }
  png.format = PNG_FORMAT_RGB;
  if (png.width > static_cast<png_uint_32>(std::numeric_limits<int>::max()) ||
      png.height > static_cast<png_uint_32>(std::numeric_limits<int>::max())) {
    fail(kWhat, path, "image too large");
  }
  RgbImage out;
  out.width = static_cast<int>(png.width);
  out.height = static_cast<int>(png.height);
  // Sized in size_t rather than with PNG_IMAGE_SIZE, whose 32-bit arithmetic can wrap; libpng
  // itself rejects images whose rows do not fit its own limits.
  out.rgb.resize(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 3u);
  const png_color black{0, 0, 0};
  if (png_image_finish_read(&png, &black, out.rgb.data(), /*row_stride=*/0,
                            /*colormap=*/nullptr) == 0) {
    fail(kWhat, path, png.message);
  }
  return out;
}

}  // namespace pp5
