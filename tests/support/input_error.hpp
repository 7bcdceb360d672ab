#pragma once
// budjam's promise for bad input (docs/files.md "Exit codes and errors"): exit 2 and one line on stderr,
// "budjam: error: <what is wrong>", never an internal error. Catch2 assertions: tests only.
#include "run_budjam.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <string>

namespace budjam::testing {

// Checks that `r` is that one-line input error and that its message starts with `start`.
inline void check_input_error(const BudjamRun& r, const std::string& start) {
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.rfind("budjam: error: " + start, 0) == 0);
  CHECK(r.err.find("internal") == std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

}  // namespace budjam::testing
