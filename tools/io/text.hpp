#pragma once
// Number <-> text for every file budjam writes. Doubles are written as the shortest text that
// reads back bit-identically (std::to_chars), so files round-trip exactly and are locale-free.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace budjam::io {

// Shortest round-trip text of a double: "0.002", "1e-16", "-0"; non-finite as "nan", "inf", "-inf".
inline std::string format_double(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

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

// `s` with every control byte (below 0x20, and 0x7f) written as \xNN, so that text taken from a
// file or an exception cannot move the cursor, clear the terminal or break a one-line message.
inline std::string escape_control(std::string_view s) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
    } else {
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
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

}  // namespace budjam::io
