#pragma once
// SIGTERM and SIGINT during `budjam grow`: the handler only records the signal (nothing else is
// async-signal-safe); the run checks it between growth attempts and before every FIRE iteration of
// a relaxation, writes a checkpoint at the next growth attempt, accepted or not (or inside the
// relaxation under way), and exits with 128 + the signal number (docs/growth.md, "Checkpoints and
// resume"). A second signal of the same kind ends the process at once, as if no handler had been
// installed.
#include <csignal>

namespace budjam::cli {

class StopSignals {
 public:
  StopSignals();   // installs the handlers
  ~StopSignals();  // restores the previous ones
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // The signal received (SIGTERM or SIGINT), or 0.
  static int received();

 private:
  struct sigaction old_term_ {
  }, old_int_{};
};

// SIGINT, SIGTERM and SIGHUP in every other command (and a second signal in `grow`) end the process
// as they would without a handler, after removing the temporaries of outputs not yet committed
// (io::remove_open_temporaries): a render or export stopped half-way leaves no file behind.
void remove_temporaries_on_fatal_signals();

}  // namespace budjam::cli
