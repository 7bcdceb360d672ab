#include "io/run_program.hpp"

#include "io/atomic_file.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

extern char** environ;

namespace budjam::io {

namespace {
// The program being waited for (0: none), for stop_running_program.
volatile std::sig_atomic_t g_running = 0;
}  // namespace

int run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint, int stdout_to) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdout_to >= 0) posix_spawn_file_actions_adddup2(&actions, stdout_to, STDOUT_FILENO);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw IoError(what + ": cannot run " + argv[0] + ": " + std::strerror(rc) + " (" + hint + ")");
  g_running = static_cast<std::sig_atomic_t>(pid);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      g_running = 0;
      throw IoError(what + ": waitpid failed");
    }
  g_running = 0;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

void stop_running_program() noexcept {
  const pid_t pid = static_cast<pid_t>(g_running);
  if (pid <= 0) return;
  ::kill(pid, SIGKILL);
  while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {}
}

}  // namespace budjam::io
