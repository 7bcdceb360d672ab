#pragma once
// The end-to-end tests run the `budjam` executable that ctest names in BUDJAM_EXE, through the
// shell: arguments are passed as written, so quote paths with shell_quoted().
#include <filesystem>
#include <string>

namespace budjam::testing {

struct BudjamRun {
  int code = -1;    // exit code
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `budjam <args>` and captures its exit code, stdout and stderr. Throws std::runtime_error
// if BUDJAM_EXE is not set or budjam did not exit normally (killed by a signal).
BudjamRun run_budjam(const std::string& args);

// The same, run from the directory `dir`, so that relative file names in `args` (and in budjam's
// messages) are relative to it.
BudjamRun run_budjam_in(const std::filesystem::path& dir, const std::string& args);

// Runs `budjam <args>` with stdout and stderr sent to the given files; returns the exit code.
int run_budjam_redirected(const std::string& args, const std::filesystem::path& out,
                          const std::filesystem::path& err = "/dev/null");

// A path in single quotes, for a shell command line.
std::string shell_quoted(const std::filesystem::path& p);

// A file of the source tree (BUDJAM_SOURCE_DIR, set by ctest), e.g. "data/scenes/demo.toml".
std::filesystem::path source_file(const std::filesystem::path& relative);

}  // namespace budjam::testing
