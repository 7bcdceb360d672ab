#pragma once
// The packing file (".pack"): one versioned text format that every subcommand reads and writes.
// Format version 1 (docs/files.md has the full description):
//
//   budjam-packing 1
//   L 15
//   shear 0
//   N 2
//   next_id 2
//   meta phase jammed            <- zero or more "meta <key> <value>" lines, free-form text values
//   cells id parent x y theta b gamma0
//   0 -1 7.5 7 0.3 0.01 0.00213
//   1 -1 7.5 8 -2.1 0.7245 0.00187
//   end
//
// Numbers are written as the shortest text that reads back bit-identically, so a packing
// survives any number of write/read cycles unchanged. Lines starting with '#' are allowed
// before the "cells" line. The "end" line makes any truncation detectable.
#include "budjam/errors.hpp"
#include "budjam/packing.hpp"
#include "io/atomic_file.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace budjam {
struct StateView;
}

namespace budjam::io {

inline constexpr int kPackingFormatVersion = 1;

// Free-form key/value metadata stored with a packing: phase, phi, P, step, seed, dphi, P0, ...
// Keys are [A-Za-z0-9_.-]+; values are one line of text (may be empty or contain spaces).
struct PackingMeta {
  std::map<std::string, std::string> values;  // sorted: files are deterministic

  void set(const std::string& key, std::string value);
  void set_number(const std::string& key, double value);  // round-trip text
  void set_integer(const std::string& key, std::int64_t value);

  bool has(const std::string& key) const { return values.count(key) != 0; }
  std::optional<std::string> get(const std::string& key) const;
  // InputError "meta.<key>: missing" / "meta.<key>: not a number (got ...)".
  double number(const std::string& key) const;
  std::int64_t integer(const std::string& key) const;
};

// The metadata of a growth run's packing (kind, phase, step, seed, φ, P, E/N, P0, φ_J, Δφ, N_nr, Z):
// what a run's saved packings and the packings of the Python module's growth events carry alike.
PackingMeta state_meta(const StateView& s, const std::string& kind, std::uint64_t seed,
                       std::optional<double> dphi = std::nullopt);

struct PackingFile {
  Packing packing;
  PackingMeta meta;
  std::filesystem::path source;  // the file read_packing read it from; empty for one made otherwise
};

// Why the packing and its metadata cannot be written as a packing file, naming the quantity as a
// Python Packing(...) names its arguments: "L: must be finite and > 0 (got nan)", "x[3]: not
// finite (got nan)", "b[0]: must be >= 0 (got -0.5)", "meta key \"a b\": ...", "meta[\"k\"]: ...";
// nothing if it can. The physical rules of a packing (include/budjam/packing_rules.hpp) are the
// reader's.
std::optional<std::string> unwritable_problem(const Packing& packing, const PackingMeta& meta);

// A meta key or value that a packing file cannot hold (a key outside [A-Za-z0-9_.-]+, a value with
// a line break or that is not UTF-8), as one line; nothing if it can.
std::optional<std::string> meta_problem(const std::string& key, std::string_view value);

// The file text. std::invalid_argument "format_packing: <unwritable_problem>" if the packing cannot
// be written (inconsistent arrays, non-finite numbers, a meta key or value that cannot be written):
// a programming error where budjam made the packing; Python's Packing(...) checks first.
std::string format_packing(const Packing& packing, const PackingMeta& meta = {});

// Parses file text; `source` names it in errors. Refuses anything not exactly in the format with
// InputError "<source>:<line>: <problem>": wrong magic, unsupported version, unknown/duplicate/
// missing header key, wrong column count, non-numeric or non-finite number, invalid L/b/γ0/ids,
// duplicate ids, fewer or more rows than N, missing "end" (truncation), text after "end".
PackingFile parse_packing(std::string_view text, const std::string& source = "<packing>");

// Atomic write (io/atomic_file.hpp) / read of a file.
void write_packing(const std::filesystem::path& path, const Packing& packing, const PackingMeta& meta = {});
// The same, as the file `name` of `dir` (io/atomic_file.hpp: a link is replaced, never followed).
void write_packing(const Directory& dir, std::string_view name, const Packing& packing, const PackingMeta& meta);
PackingFile read_packing(const std::filesystem::path& path);

// True if `text` starts like a packing file (its first line is "budjam-packing ...", after a UTF-8
// byte-order mark that the reader refuses, so that `validate` says so rather than read TOML).
bool looks_like_packing(std::string_view text);

}  // namespace budjam::io
