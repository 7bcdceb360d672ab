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

}  // namespace

int run_budjam_redirected(const std::string& args, const std::filesystem::path& out, const std::filesystem::path& err) {
  const std::string cmd =
      shell_quoted(environment("BUDJAM_EXE")) + " " + args + " >" + shell_quoted(out) + " 2>" + shell_quoted(err);
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status)) throw std::runtime_error("budjam " + args + ": did not exit normally");
  return WEXITSTATUS(status);
}

BudjamRun run_budjam(const std::string& args) {
  const std::filesystem::path out = work_dir() / "stdout", err = work_dir() / "stderr";
  BudjamRun r;
  r.code = run_budjam_redirected(args, out, err);
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

std::string shell_quoted(const std::filesystem::path& p) {
  std::string quoted = "'";
  quoted += p.string();
  return quoted + "'";
}

std::filesystem::path source_file(const std::filesystem::path& relative) {
  return std::filesystem::path(environment("BUDJAM_SOURCE_DIR")) / relative;
}

}  // namespace budjam::testing
