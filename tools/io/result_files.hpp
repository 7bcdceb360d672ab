#pragma once
// The output convention of the commands that analyse one packing or a set of runs (moduli,
// rigidity, dos, survival; docs/files.md "Outputs"):
//   --out BASE   writes BASE.json, and BASE.csv where the result has a table, each atomically;
//   --json       prints the JSON on stdout;
//   neither      prints a one-line summary on stdout.
// Growth observers write the same pair of files beside a run's packings (write_result_files).
#include "io/json.hpp"

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

struct CommandResult {
  Json json;
  std::function<void(std::ostream&)> csv;  // the table, header line first; empty: the result has none
  std::string summary;                     // one line for a terminal, without the newline
};

struct OutputRequest {
  std::string base;    // --out BASE; empty: no files
  bool json = false;   // --json: the JSON on stdout
  bool quiet = false;  // --quiet: no summary line
};

// BASE as given, less a trailing ".json" or ".csv": `--out survival.csv` writes survival.csv
// and survival.json, not survival.csv.csv.
std::filesystem::path result_base(const std::string& base);

// InputError naming --out unless BASE (without a trailing .json or .csv) names files budjam may
// write: BASE.json, and BASE.csv if the result has a `table` (check_output_base). Call it before the
// work, so that a bad name costs nothing; without --out it checks nothing. Neither file may be one of
// the command's `inputs` (check_not_an_input).
void check_output_request(const OutputRequest& request, bool table,
                          const std::vector<std::filesystem::path>& inputs = {});

// InputError "<option>: <output>: is the input file <input> ..." when `output` exists and is the
// same file as one of the command's `inputs` (same device and inode: also through a link, a hard
// link or another spelling), which writing it would replace.
void check_not_an_input(std::string_view option, const std::filesystem::path& output,
                        const std::vector<std::filesystem::path>& inputs);

// Writes BASE.csv (if the result has a table) and BASE.json as one (write_atomically of both: both
// contents are complete before the first rename, and a SIGINT, SIGTERM or SIGHUP never falls
// between the renames), BASE.json last. Returns the paths written, JSON first.
std::vector<std::filesystem::path> write_result_files(const std::filesystem::path& base, const CommandResult& result);
// The same in `dir`: files `<base_name>.json` and `<base_name>.csv`.
std::vector<std::filesystem::path> write_result_files(const Directory& dir, const std::string& base_name,
                                                      const CommandResult& result);

// What the request asks for: the files, the JSON on `out`, or the summary line on `out` (also
// after the files, naming them, unless quiet).
void emit(const OutputRequest& request, const CommandResult& result, std::ostream& out);

}  // namespace budjam::io
