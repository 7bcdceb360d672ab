#include "commands/stop_signals.hpp"

#include "io/atomic_file.hpp"

namespace budjam::cli {

namespace {

volatile std::sig_atomic_t g_received = 0;

extern "C" void on_stop_signal(int sig) {
  if (g_received == sig) {  // asked twice: stop now
    io::end_process_without_temporaries(sig);
    return;
  }
  g_received = sig;
}

void install(int sig, struct sigaction& old) {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // system calls in progress (writes, fsync) complete normally
  sigaction(sig, &sa, &old);
}

}  // namespace

StopSignals::StopSignals() {
  g_received = 0;
  install(SIGTERM, old_term_);
  install(SIGINT, old_int_);
}

StopSignals::~StopSignals() {
  sigaction(SIGTERM, &old_term_, nullptr);
  sigaction(SIGINT, &old_int_, nullptr);
}

int StopSignals::received() { return g_received; }

void remove_temporaries_on_fatal_signals() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction sa {};
    sa.sa_handler = io::end_process_without_temporaries;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
  }
}

}  // namespace budjam::cli
