#pragma once
// Running a helper program (rsvg-convert, the Python interpreter) without a shell.
#include <string>
#include <vector>

namespace budjam::io {

// Runs argv[0] (looked up on PATH) with the arguments and waits for it; returns its exit status
// (128 if it was killed by a signal). IoError "<what>: cannot run <program>: <reason> (<hint>)"
// if it cannot be started: `what` names the caller's task, `hint` how to get the program.
int run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint);

}  // namespace budjam::io
