#pragma once
// The error a user can fix: bad input. Everything budjam reads — scene files, --set overrides,
// packing files, checkpoints, command-line choices — is refused with an InputError, and `budjam`
// exits with code 2 (docs/files.md, "Exit codes and errors").
#include <stdexcept>

namespace budjam {

// Thrown for invalid input; what() is one line that names the file (and line) or the key and the
// problem, e.g. "growth.P0: must be positive (got -0.001)".
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace budjam
