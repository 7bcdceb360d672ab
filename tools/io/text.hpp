#pragma once
// Number <-> text for every file budjam writes. Doubles are written as the shortest text that
// reads back bit-identically (std::to_chars), so files round-trip exactly and are locale-free.
#include "budjam/number_text.hpp"

#include <charconv>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace budjam::io {

// Shortest round-trip text of a double (budjam::shortest_text): "0.002", "1e-16", "nan".
inline std::string format_double(double v) { return shortest_text(v); }

// The whole token must be a number (no leading/trailing junk, no leading '+'). Accepts "nan"
// and "inf" — callers that refuse non-finite values check std::isfinite themselves.
inline std::optional<double> parse_double(std::string_view s) {
  double v = 0;
  if (s.empty()) return std::nullopt;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

inline std::optional<std::int64_t> parse_int64(std::string_view s) {
  std::int64_t v = 0;
  if (s.empty()) return std::nullopt;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

// The length of the well-formed UTF-8 sequence that starts at text[i] (Unicode 15, Table 3-7: no
// overlong forms, no surrogates, nothing above U+10FFFF), 0 if none starts there.
inline std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto c = static_cast<unsigned char>(text[i]);
  std::size_t len = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (c < 0x80)
    len = 1;
  else if (c >= 0xC2 && c <= 0xDF)
    len = 2;
  else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;  // overlong
    if (c == 0xED) hi = 0x9F;  // surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;  // overlong
    if (c == 0xF4) hi = 0x8F;  // above U+10FFFF
  }
  if (len == 0 || i + len > text.size()) return 0;
  for (std::size_t k = 1; k < len; ++k) {
    const auto b = static_cast<unsigned char>(text[i + k]);
    if (k == 1 ? (b < lo || b > hi) : (b < 0x80 || b > 0xBF)) return 0;
  }
  return len;
}

// Where the first byte that is not well-formed UTF-8 sits, as "<line>:<column>" (column in
// bytes), or "".
inline std::string first_invalid_utf8(std::string_view text) {
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t len = utf8_sequence_length(text, i);
    if (len == 0) return std::to_string(line) + ":" + std::to_string(i - line_start + 1);
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
    i += len;
  }
  return "";
}

// `s` with every control byte (below 0x20, and 0x7f) and every byte that is not part of
// well-formed UTF-8 written as \xNN, so that text taken from a file or an exception cannot move
// the cursor, clear the terminal or break a one-line message, and is valid text (a Python str).
inline std::string escape_control(std::string_view s) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const auto u = static_cast<unsigned char>(s[i]);
    const std::size_t len = utf8_sequence_length(s, i);
    if (len > 0 && u >= 0x20 && u != 0x7f) {
      out.append(s.substr(i, len));
      i += len;
    } else {
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
      ++i;
    }
  }
  return out;
}

// A message as one short line: control bytes escaped as above, and a message longer than
// kMaxMessageBytes (one that quotes a whole input, such as a list of 10⁶ targets) cut in the middle,
// keeping its start (the file and key) and its end, with the number of bytes left out.
inline constexpr std::size_t kMaxMessageBytes = 1000;
inline std::string one_line(std::string_view s) {
  if (s.size() <= kMaxMessageBytes) return escape_control(s);
  // Cut on UTF-8 character boundaries (never before a continuation byte 10xxxxxx).
  const auto boundary = [s](std::size_t k) {
    while (k > 0 && k < s.size() && (static_cast<unsigned char>(s[k]) & 0xc0) == 0x80) --k;
    return k;
  };
  const std::size_t head = boundary(kMaxMessageBytes * 3 / 4), tail = boundary(s.size() - kMaxMessageBytes / 5);
  return escape_control(s.substr(0, head)) + " [... " + std::to_string(tail - head) + " bytes left out ...] " +
         escape_control(s.substr(tail));
}

// FNV-1a, 64 bit: the checksum of a checkpoint and the hashes of scenes and protocols. Stable across
// platforms: the hashes are written into files (checkpoints, runs.csv) and compared there.
inline std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

// A 64-bit hash as files write it: 16 lowercase hex digits.
inline std::string hex64(std::uint64_t v) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s(16, '0');
  for (int k = 15; k >= 0; --k, v >>= 4) s[static_cast<std::size_t>(k)] = kDigits[v & 0xf];
  return s;
}

}  // namespace budjam::io
