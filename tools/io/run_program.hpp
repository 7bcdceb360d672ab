#pragma once
// Running a helper program (rsvg-convert, the Python interpreter) without a shell.
#include <string>
#include <vector>

namespace budjam::io {

// How a program ended: its exit status, or the signal that killed it, and the last non-empty line it
// wrote to its standard error (which run_program keeps to itself: budjam says what went wrong, in
// one line of its own).
struct ProgramResult {
  int status = 0;  // the exit status (meaningful when signal == 0)
  int signal = 0;  // the signal that killed it, or 0
  std::string last_error_line;
  bool ok() const { return signal == 0 && status == 0; }
  // Why it failed, for an error message after "<program> ": "was killed (Killed)", or
  // "failed: <its last error line, escaped and shortened>", or "failed with exit status N".
  std::string failure() const;
};

// Runs argv[0] (looked up on PATH) with the arguments and waits for it. Its standard error is read
// through a pipe and not shown; the last non-empty line is in the result. IoError "<what>: cannot run
// <program>: <reason> (<hint>)" if it cannot be started: `what` names the caller's task, `hint` how
// to get the program. `stdout_to`: a descriptor for the program's standard output (-1: budjam's
// own), so that a program that can write there makes no temporary files of its own by name.
ProgramResult run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint,
                          int stdout_to = -1);

// For a handler of a signal that ends budjam (async-signal-safe: kill, waitpid): kills the program
// run_program is waiting for and reaps it, so that nothing of it writes after budjam has removed its
// temporaries (an orphan would finish the file, or create it anew by its name).
void stop_running_program() noexcept;

}  // namespace budjam::io
