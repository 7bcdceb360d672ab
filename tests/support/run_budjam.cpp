#include "run_budjam.hpp"

#include "scratch.hpp"

#include <sys/wait.h>
#include <cstdlib>
#include <stdexcept>

namespace budjam::testing {
namespace {

std::string environment(const char* name) {
  const char* value = std::getenv(name);
  if (value == nullptr) throw std::runtime_error(std::string(name) + " is not set (run the tests through ctest)");
  return value;
}

// `budjam <args>` through the shell, from `dir` when it is not empty; returns the exit code.
int run_from(const std::filesystem::path& dir, const std::string& args, const std::filesystem::path& out,
             const std::filesystem::path& err) {
  const std::string cd = dir.empty() ? "" : "cd " + shell_quoted(dir) + " && ";
  const std::string cmd =
      cd + shell_quoted(environment("BUDJAM_EXE")) + " " + args + " >" + shell_quoted(out) + " 2>" + shell_quoted(err);
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status)) throw std::runtime_error("budjam " + args + ": did not exit normally");
  return WEXITSTATUS(status);
}

BudjamRun captured(const std::filesystem::path& dir, const std::string& args) {
  const std::filesystem::path out = work_dir() / "stdout", err = work_dir() / "stderr";
  BudjamRun r;
  r.code = run_from(dir, args, out, err);
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace

int run_budjam_redirected(const std::string& args, const std::filesystem::path& out, const std::filesystem::path& err) {
  return run_from({}, args, out, err);
}

BudjamRun run_budjam(const std::string& args) { return captured({}, args); }

BudjamRun run_budjam_in(const std::filesystem::path& dir, const std::string& args) { return captured(dir, args); }

std::string shell_quoted(const std::filesystem::path& p) {
  std::string quoted = "'";
  quoted += p.string();
  return quoted + "'";
}

std::filesystem::path source_file(const std::filesystem::path& relative) {
  return std::filesystem::path(environment("BUDJAM_SOURCE_DIR")) / relative;
}

}  // namespace budjam::testing
