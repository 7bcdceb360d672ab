#include "io/run_program.hpp"

#include "io/atomic_file.hpp"

#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>

extern char** environ;

namespace budjam::io {

int run_program(const std::vector<std::string>& argv, const std::string& what, const std::string& hint) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ);
  if (rc != 0) throw IoError(what + ": cannot run " + argv[0] + ": " + std::strerror(rc) + " (" + hint + ")");
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw IoError(what + ": waitpid failed");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

}  // namespace budjam::io
