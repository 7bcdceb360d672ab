#pragma once
// Subcommands register themselves: each tools/commands/cmd_<name>.cpp holds
//
//   namespace {
//   const bool registered = budjam::cli::register_command({"grow", "Grow a packing from a scene",
//       [](CLI::App& sub) {
//         auto opts = std::make_shared<Options>();
//         sub.add_option("SCENE", opts->scene, "scene file")->required();
//         sub.callback([opts] { run(*opts); });
//       }});
//   }
//
// main.cpp creates one CLI11 subcommand per registered command, in name order, calls `setup` on
// it and runs the one the user chose. A callback reports failure by throwing (exit codes below);
// main prints exactly one line "budjam: error: <what()>" on stderr.
#include "budjam/errors.hpp"
#include "io/result_files.hpp"
#include "io/text.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace budjam::cli {

// Exit codes of `budjam` (docs/files.md).
enum ExitCode : int {
  kExitOk = 0,         // success
  kExitRunFailed = 1,  // the run ran and failed (step underflow, ...): RunFailure; a saddle, no result: NoResultError
  kExitBadInput = 2,   // invalid command line, scene or input file: CLI11 errors, budjam::InputError
  kExitInternal = 3,   // an output could not be written, or any other error: io::IoError, std::exception
  // 128 + N: stopped by signal N (SIGINT 130, SIGTERM 143) after writing a checkpoint: Interrupted
};

// Thrown by a subcommand after it has written its outputs (summary.json with the failure
// status) to make `budjam` exit with kExitRunFailed. what() is the one-line reason.
struct RunFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Thrown by a subcommand whose answer is not the one asked for but is a legitimate physical outcome
// (a packing that is a saddle has no relaxed moduli), after it has written that answer. `budjam`
// prints what() as a notice, `budjam: <what>`, not as an error, and exits with kExitRunFailed, so
// that a pipeline can record the outcome and go on. A budjam::NoResultError from the library (no
// answer at all: an unjammed packing's moduli, a solver that did not converge) is treated alike.
struct Finding : NoResultError {
  using NoResultError::NoResultError;
};

// A notice on stderr, `budjam: <text>`, one line (io::one_line): something the user should know about
// a result that is nevertheless given (exit 0), such as a negative shear modulus. The result goes out
// first: where standard output failed there is no result to speak of, and the failure is the one
// line (main: exit 3).
inline void notice(const std::string& text) {
  if (std::cout.flush()) std::cerr << "budjam: " << io::one_line(text) << std::endl;
}

// f(); a NoResultError from the library ("spectrum: …") is re-thrown as a Finding that names the
// command and its input first ("dos: p.pack: spectrum: …").
template <class F>
auto naming_input(const std::string& command, const std::string& input, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const NoResultError& e) {
    throw Finding(command + ": " + input + ": " + e.what());
  }
}

// Thrown by a subcommand that stopped on a signal after saving what it needs to continue; `budjam`
// exits with 128 + signal, the shell's code for a process ended by that signal.
struct Interrupted : std::runtime_error {
  Interrupted(int signal, const std::string& message) : std::runtime_error(message), signal(signal) {}
  int signal;
};

struct Command {
  std::string name;                          // the subcommand word: `budjam <name> ...`
  std::string help;                          // one line for `budjam --help`
  std::function<void(CLI::App& sub)> setup;  // adds options and sub.callback(...) to the subcommand
};

// Function-local static: safe to use from other translation units' static initialisers.
inline std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

// Returns true so that it can initialise a namespace-scope `const bool`.
inline bool register_command(Command command) {
  registry().push_back(std::move(command));
  return true;
}

// CLI11 2.1 reads "-2" into an unsigned option as 2^64 − 2, and its own range validators print
// their limits as full doubles. These validators run on the text before it is converted and fail
// with budjam's one-line message, "OPTION: must be ... (got TEXT)".
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const auto first = text.find_first_not_of(" \t");
        if (first != std::string::npos && text[first] == '-') return "must be ≥ 0 (got " + text + ")";
        return {};
      },
      "NONNEGATIVE");
}

// A floating option: a finite number in the interval from lo to hi (each end open or closed), checked
// on the text (so "nan", "inf" and out-of-range values fail alike): "must be a finite number in
// (0, 1] (got TEXT)". Every floating option of dos, moduli and survival goes through this one check.
inline CLI::Validator finite_in(double lo, double hi, bool lo_open = false, bool hi_open = false) {
  auto g = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", x);
    return std::string(buf);
  };
  const std::string range = (lo_open ? "(" : "[") + g(lo) + ", " + g(hi) + (hi_open ? ")" : "]");
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const auto first = text.find_first_not_of(" \t");
        const auto last = text.find_last_not_of(" \t");
        const auto v = first == std::string::npos
                           ? std::nullopt
                           : io::parse_double(std::string_view(text).substr(first, last - first + 1));
        const bool ok = v && std::isfinite(*v) && (lo_open ? *v > lo : *v >= lo) && (hi_open ? *v < hi : *v <= hi);
        return ok ? std::string() : "must be a finite number in " + range + " (got " + text + ")";
      },
      range);
}

// A seed is written into scene files as a TOML integer (signed 64 bit): 0 … 2^63 − 1.
inline CLI::Validator seed_range() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || end != text.data() + text.size() || v > static_cast<std::uint64_t>(INT64_MAX))
          return "must be an integer in [0, 2^63 − 1] (got " + text + ")";
        return {};
      },
      "0 ≤ N < 2^63");
}

// An output path given empty would be read as "not given" (a default name, or nothing written):
// a script whose variable is unset must hear of it.
inline CLI::Validator names_a_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return text.find_first_not_of(" \t") == std::string::npos ? "an empty name names no file or directory" : "";
      },
      "");
}

// --out BASE, --json and --quiet of the output convention (io/result_files.hpp). `files` names
// what --out writes, e.g. "BASE.json (summary) and BASE.csv (the curve)". `short_o` also accepts
// -o, for the commands that took it before the convention.
inline void add_output_options(CLI::App& sub, io::OutputRequest& request, const std::string& files,
                               bool short_o = false) {
  sub.add_option(short_o ? "-o,--out" : "--out", request.base,
                 "write " + files + ", atomically; a trailing .json or .csv of BASE is dropped")
      ->type_name("BASE")
      ->check(names_a_path());
  sub.add_flag("--json", request.json, "print the JSON on stdout (also with --out)");
  sub.add_flag("--quiet", request.quiet, "no summary line on stdout");
}

}  // namespace budjam::cli
