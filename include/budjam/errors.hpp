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

// Valid input whose asked-for quantity has no value, or that a numerical method could not compute:
// an unjammed packing has no elastic moduli, an eigensolver did not converge. what() is one line
// that says why and what to try. `budjam` prints it as a notice and exits with code 1 (the outcome
// is a finding about the input, not an error of budjam); Python raises budjam.NoResultError.
struct NoResultError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace budjam
