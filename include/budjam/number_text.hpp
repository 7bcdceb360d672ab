#pragma once
// Numbers as budjam writes them, in files and in messages: the shortest text that reads back as
// the same double (std::to_chars), so "(got 0.002)" rather than "0.0020000000000000001", files
// round-trip bit for bit, and nothing depends on the locale.
#include <charconv>
#include <cmath>
#include <string>

namespace budjam {

// "0.002", "1e-16", "-0"; non-finite values as "nan", "inf", "-inf".
inline std::string shortest_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

}  // namespace budjam
