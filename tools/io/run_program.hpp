#pragma once
// Running a helper program (rsvg-convert, the Python interpreter) without a shell.
#include <string>
#include <vector>

namespace budjam::io {

// Runs argv[0] (looked up on PATH) with the arguments and waits for it; returns its exit status
// (128 if it was killed by a signal). IoError "<what>: cannot run <program>: <reason> (<hint>)"
// if it cannot be started: `what` names the caller's task, `hint` how to get the program.
// `stdout_to`: a descriptor for the program's standard output (-1: budjam's own), so that a program
// that can write there makes no temporary files of its own by name.
int run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint,
                int stdout_to = -1);

// For a handler of a signal that ends budjam (async-signal-safe: kill, waitpid): kills the program
// run_program is waiting for and reaps it, so that nothing of it writes after budjam has removed its
// temporaries (an orphan would finish the file, or create it anew by its name).
void stop_running_program() noexcept;

}  // namespace budjam::io
