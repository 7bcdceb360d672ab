// `budjam`: builds the command line from the self-registered subcommands (command.hpp), runs the
// chosen one, and turns every failure into one line on stderr and an exit code.
#include "commands/command.hpp"
#include "commands/stop_signals.hpp"

#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/process_memory.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#ifndef BUDJAM_VERSION
#define BUDJAM_VERSION "0.1.0"  // keep equal to project(VERSION) in CMakeLists.txt
#endif

namespace {

int error(const std::string& message, int code) {
  // One short line, always, and no control bytes from a file reaching the terminal.
  std::cerr << "budjam: error: " << budjam::io::one_line(message) << std::endl;
  return code;
}

// An expected stop (a signal after a checkpoint) or a finding (a saddle): a notice, not an error.
int notice(const std::string& message, int code) {
  std::cerr << "budjam: " << budjam::io::one_line(message) << std::endl;
  return code;
}

// The help that documents what was mistyped: the subcommand's, once one was named.
std::string help_hint(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? "budjam --help" : "budjam " + chosen.front()->get_name() + " --help";
}

// A result printed on standard output is an output like a file: where it could not be written (a
// full disk, `> /dev/full`, a closed pipe), the command has not done its job. 0 if it was written,
// else the one error line's exit code.
int stdout_failure() {
  errno = 0;
  std::cout.flush();
  if (std::cout && std::fflush(stdout) == 0 && !std::ferror(stdout)) return 0;
  return error(std::string("standard output: cannot write: ") + (errno ? std::strerror(errno) : "write error"),
               budjam::cli::kExitInternal);
}

int with_stdout_written(int code) {
  const int failed = stdout_failure();
  return failed ? failed : code;
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  // A write past the file-size limit or into a pipe nobody reads fails (EFBIG, EPIPE) instead of
  // killing the process: it takes the path of every failed output (one line, exit 3, temporaries
  // removed, a half row taken back), and a run whose progress reader went away goes on. Helper
  // programs get the default dispositions back (io::run_program).
  std::signal(SIGXFSZ, SIG_IGN);
  std::signal(SIGPIPE, SIG_IGN);
  using namespace budjam::cli;
  CLI::App app{"budjam: growing packings of budding cells (yeast) in 2D, to jamming and beyond", "budjam"};
  app.set_version_flag("--version", std::string("budjam ") + BUDJAM_VERSION);
  app.require_subcommand(1);
  app.fallthrough(false);

  std::vector<Command> commands = registry();
  std::sort(commands.begin(), commands.end(), [](const Command& a, const Command& b) { return a.name < b.name; });
  std::set<std::string> seen;
  for (const Command& c : commands) {
    if (!seen.insert(c.name).second)
      return error("internal: subcommand \"" + c.name + "\" registered twice", kExitInternal);
    CLI::App* sub = app.add_subcommand(c.name, c.help);
    c.setup(*sub);
  }

  // CLI11 reads a mistyped subcommand as a stray argument and says only that one is required.
  if (argc > 1 && argv[1][0] != '-' && !seen.count(argv[1])) {
    std::string names;
    for (const std::string& n : seen) names += (names.empty() ? "" : ", ") + n;
    return error("unknown command '" + std::string(argv[1]) + "' (commands: " + names + "; see budjam --help)",
                 kExitBadInput);
  }
  // ... and a mistyped option before the subcommand (`budjam --versio`) the same way.
  if (const std::string first = argc > 1 ? argv[1] : "";
      first.starts_with("-") && first != "-h" && first != "--help" && first != "--version")
    return error("unknown option '" + first +
                     "': budjam's own options are --help and --version, a command's follow the command "
                     "(see budjam --help)",
                 kExitBadInput);

  remove_temporaries_on_fatal_signals();  // `grow` replaces them with its own while it runs
  try {
    app.parse(argc, argv);  // runs the chosen subcommand's callback
    return with_stdout_written(kExitOk);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))  // --help, --version
      return with_stdout_written(app.exit(e));
    return error(std::string(e.what()) + " (see " + help_hint(app) + ")", kExitBadInput);
  } catch (const Interrupted& e) {
    return notice(e.what(), 128 + e.signal);
  } catch (const RunFailure& e) {
    return error(e.what(), kExitRunFailed);
  } catch (const budjam::NoResultError& e) {  // cli::Finding included: the result, then the notice
    if (const int failed = stdout_failure()) return failed;
    return notice(e.what(), kExitRunFailed);
  } catch (const budjam::InputError& e) {
    return error(e.what(), kExitBadInput);
  } catch (const budjam::io::IoError& e) {
    return error(e.what(), kExitInternal);
  } catch (const nlohmann::json::exception& e) {
    // A JSON value of the wrong type or a missing key: always in a file the user gave.
    return error(std::string("input JSON: ") + e.what(), kExitBadInput);
  } catch (const std::filesystem::filesystem_error& e) {
    // Reading is checked where it happens (InputError); what is left is making outputs.
    return error((e.path1().empty() ? std::string("output") : e.path1().string()) + ": " + e.code().message(),
                 kExitInternal);
  } catch (const std::exception& e) {
    return error(std::string("internal: ") + e.what(), kExitInternal);
  }
}
