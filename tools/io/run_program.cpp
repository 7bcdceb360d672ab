#include "io/run_program.hpp"

#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <fcntl.h>
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

// Of a program's standard error only the tail is kept: the last line is what is reported.
constexpr std::size_t kKeptErrorBytes = 64 * 1024;
// The longest quoted error line, in bytes (a program may write one huge line).
constexpr std::size_t kMaxQuotedLine = 300;

std::string last_nonempty_line(const std::string& text) {
  std::size_t end = text.size();
  while (end > 0) {
    const std::size_t nl = text.rfind('\n', end - 1);
    const std::size_t begin = nl == std::string::npos ? 0 : nl + 1;
    std::string line = text.substr(begin, end - begin);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    if (!line.empty()) return line;
    if (nl == std::string::npos) break;
    end = nl;
  }
  return {};
}

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};
}  // namespace

std::string ProgramResult::failure() const {
  if (signal != 0) {
    const char* name = ::strsignal(signal);
    return std::string("was killed (") + (name ? name : "signal " + std::to_string(signal)) + ")";
  }
  if (last_error_line.empty()) return "failed with exit status " + std::to_string(status);
  std::string line = last_error_line;
  if (line.size() > kMaxQuotedLine) {
    std::size_t cut = kMaxQuotedLine;  // on a UTF-8 character boundary
    while (cut > 0 && (static_cast<unsigned char>(line[cut]) & 0xc0) == 0x80) --cut;
    line = line.substr(0, cut) + " [...]";
  }
  return "failed: " + escape_control(line);
}

ProgramResult run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint,
                          int stdout_to) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw IoError(what + ": cannot run " + argv[0] + ": pipe: " + std::strerror(errno));
  Fd read_end{ends[0]}, write_end{ends[1]};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdout_to >= 0) posix_spawn_file_actions_adddup2(&actions, stdout_to, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, write_end.fd, STDERR_FILENO);
  pid_t pid = 0;
  int rc = 0;
  {
    // A fatal signal between the spawn and g_running would leave the program running after the
    // handler removed its output; the program starts with the caller's mask.
    const SignalsHeld held;
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setsigmask(&attributes, &held.before());
    // Ignored signals stay ignored across exec: the program gets the defaults budjam set aside.
    sigset_t defaults;
    sigemptyset(&defaults);
    for (const int sig : {SIGPIPE, SIGXFSZ}) sigaddset(&defaults, sig);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    rc = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
    posix_spawnattr_destroy(&attributes);
    if (rc == 0) g_running = static_cast<std::sig_atomic_t>(pid);
  }
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw IoError(what + ": cannot run " + argv[0] + ": " + std::strerror(rc) + " (" + hint + ")");
  ::close(write_end.fd);
  write_end.fd = -1;
  // Read until every writer has closed it (the program ends), keeping the tail.
  std::string err;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(read_end.fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    err.append(buf, static_cast<std::size_t>(n));
    if (err.size() > 2 * kKeptErrorBytes) err.erase(0, err.size() - kKeptErrorBytes);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      g_running = 0;
      throw IoError(what + ": waitpid failed");
    }
  g_running = 0;
  ProgramResult r;
  if (WIFEXITED(status))
    r.status = WEXITSTATUS(status);
  else if (WIFSIGNALED(status))
    r.signal = WTERMSIG(status);
  else
    r.status = 128;
  r.last_error_line = last_nonempty_line(err);
  return r;
}

void stop_running_program() noexcept {
  const pid_t pid = static_cast<pid_t>(g_running);
  if (pid <= 0) return;
  ::kill(pid, SIGKILL);
  while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {}
}

}  // namespace budjam::io
