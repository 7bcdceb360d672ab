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

}  // namespace budjam::io
