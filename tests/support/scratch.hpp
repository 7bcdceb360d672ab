#pragma once
// Scratch files for the tests: one directory per test process, and whole-file reads.
#include <filesystem>
#include <string>

namespace budjam::testing {

// A scratch directory for this process (tests run in parallel under ctest), removed at exit.
const std::filesystem::path& work_dir();

// The whole file as a string (empty if it cannot be read).
std::string slurp(const std::filesystem::path& p);

}  // namespace budjam::testing
