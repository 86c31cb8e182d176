#pragma once
// Untrusted text in messages: a name, a value or a line from a file echoed back to the user.
//
// Contract: escape_for_message(text, max_bytes) returns text safe to print on a terminal and
// in a log: printable ASCII and well-formed UTF-8 sequences are kept as they are; a backslash
// becomes "\\"; tab, newline and carriage return become "\t", "\n", "\r"; every other control
// byte, DEL, and every byte that is not part of well-formed UTF-8 (0xFF, a lone continuation
// byte, an overlong or surrogate form) becomes "\xHH". Text longer than max_bytes (counted in
// input bytes, cut at a character boundary) ends with "... (N bytes)", N the full length, so
// that a 1 MB name prints as a line. Pure function, no allocation beyond the result.
//
// sanitize_message(text) is the last guard before a message reaches the terminal (main's
// error printer): a message that is already escaped comes out unchanged (a backslash stays
// one backslash, a newline stays a line break), every other control byte and every byte that
// is not well-formed UTF-8 becomes "\xHH", and a word (a run without spaces or line breaks)
// longer than kMessageWordBytes is cut to kMessageTextBytes and "... (N bytes)". So text that
// a message took from an input without escaping it can neither drive the terminal nor run to
// a megabyte.
#include <cstddef>
#include <string>
#include <string_view>

namespace pp5 {

inline constexpr std::size_t kMessageTextBytes = 80;

// The length of the well-formed UTF-8 sequence starting at s[k], or 0 if there is none.
inline std::size_t utf8_sequence_length(std::string_view s, std::size_t k) {
  const auto b = [&](std::size_t i) { return static_cast<unsigned char>(s[i]); };
  const unsigned char c = b(k);
  const std::size_t left = s.size() - k;
  auto cont = [&](std::size_t i) { return (b(i) & 0xC0) == 0x80; };
  if (c >= 0xC2 && c <= 0xDF) return left >= 2 && cont(k + 1) ? 2 : 0;
  if (c >= 0xE0 && c <= 0xEF) {
    if (left < 3 || !cont(k + 1) || !cont(k + 2)) return 0;
    if (c == 0xE0 && b(k + 1) < 0xA0) return 0;   // overlong
    if (c == 0xED && b(k + 1) >= 0xA0) return 0;  // surrogate
    return 3;
  }
  if (c >= 0xF0 && c <= 0xF4) {
    if (left < 4 || !cont(k + 1) || !cont(k + 2) || !cont(k + 3)) return 0;
    if (c == 0xF0 && b(k + 1) < 0x90) return 0;   // overlong
    if (c == 0xF4 && b(k + 1) >= 0x90) return 0;  // beyond U+10FFFF
    return 4;
  }
  return 0;
}

inline std::string escape_for_message(std::string_view text,
                                      std::size_t max_bytes = kMessageTextBytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  std::size_t k = 0;
  while (k < text.size() && k < max_bytes) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c >= 0x20 && c < 0x7F) {
      if (c == '\\') out += '\\';
      out += static_cast<char>(c);
      ++k;
    } else if (c == '\t' || c == '\n' || c == '\r') {
      out += c == '\t' ? "\\t" : c == '\n' ? "\\n" : "\\r";
      ++k;
    } else if (const std::size_t n = c >= 0x80 ? utf8_sequence_length(text, k) : 0; n > 0) {
      if (k + n > max_bytes) break;
      out.append(text.substr(k, n));
      k += n;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
      ++k;
    }
  }
  if (k < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

// True if text prints as it is: printable ASCII, tabs and well-formed UTF-8 only (no control
// byte, no line break, nothing escape_for_message would rewrite but a backslash).
inline bool is_display_text(std::string_view text) {
  for (std::size_t k = 0; k < text.size();) {
    const auto c = static_cast<unsigned char>(text[k]);
    if ((c >= 0x20 && c < 0x7F) || c == '\t') {
      ++k;
    } else if (const std::size_t n = c >= 0x80 ? utf8_sequence_length(text, k) : 0; n > 0) {
      k += n;
    } else {
      return false;
    }
  }
  return true;
}

inline constexpr std::size_t kMessageWordBytes = 240;

inline std::string sanitize_message(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size() < 4096 ? text.size() : 4096);
  std::size_t k = 0;
  while (k < text.size()) {
    // One word at a time: its length decides whether it is cut.
    std::size_t end = k;
    while (end < text.size() && text[end] != ' ' && text[end] != '\n') ++end;
    const std::size_t length = end - k;
    const std::size_t keep = length > kMessageWordBytes ? kMessageTextBytes : length;
    std::size_t j = k;
    while (j < k + keep) {
      const auto c = static_cast<unsigned char>(text[j]);
      if ((c >= 0x20 && c < 0x7F) || c == '\t') {
        out += static_cast<char>(c);
        ++j;
      } else if (const std::size_t n = c >= 0x80 ? utf8_sequence_length(text, j) : 0; n > 0) {
        if (j + n > k + keep) break;
        out.append(text.substr(j, n));
        j += n;
      } else {
        out += "\\x";
        out += kHex[c >> 4];
        out += kHex[c & 15];
        ++j;
      }
    }
    if (length > keep) out += "... (" + std::to_string(length) + " bytes)";
    k = end;
    if (k < text.size()) out += text[k++];  // the space or line break
  }
  return out;
}

}  // namespace pp5
