#pragma once
// Reading finished growth-run directories for the analysis subcommands (survival, analyse):
// summary.json, steps.csv, divisions.csv, bud_events.csv and the per-packing results of
// `budjam moduli` / `budjam dos` stored beside the packings (docs/analysis.md, "Pipeline").
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/survival.hpp"
#include "io/json.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace budjam::tools {

// A CSV file as text cells; numbers parsed on demand. Quoted fields (RFC 4180) are understood.
struct CsvTable {
  std::string source;
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  // Index of a column; InputError "<source>: no column '<name>'".
  std::size_t column(const std::string& name) const;
  bool has_column(const std::string& name) const;
  // NaN for an empty field; InputError "<source>:<line>: column <name>: not a number" for text that
  // is not a number (also "nan" and "inf": budjam writes a value that does not exist as an empty field).
  double number(std::size_t row, std::size_t col) const;
  // A number in [lo, hi] (finite: budjam writes no NaN or inf). An empty field is NaN where
  // `required` is false; InputError "<source>:<line>: column <name>: ..." for an empty field where
  // a value is required, text, or a value out of range.
  double number_in(std::size_t row, std::size_t col, double lo, double hi, bool required = true) const;
  const std::string& text(std::size_t row, std::size_t col) const { return rows[row][col]; }
  // A whole number in [lo, hi]; InputError "<source>:<line>: column <name>: not an integer in [lo, hi]"
  // for anything else (a fraction, NaN, or a value no integer type holds).
  long long integer(std::size_t row, std::size_t col, long long lo, long long hi) const;
  std::vector<double> numbers(const std::string& name) const;
  std::size_t size() const { return rows.size(); }
};

// A field as a number: NaN for an empty field, ±∞ or 0 for decimal text beyond the double range
// (steps.csv writes Δt and χ_c exactly at any size), nullopt for anything else, "nan" and "inf"
// included.
std::optional<double> csv_number(const std::string& field);

// Whether `path` exists (links followed). A path budjam cannot examine (a directory on the way it
// may not search) is an InputError naming it, never a filesystem error from deep inside.
bool input_exists(const std::filesystem::path& path);

// An entry of an input directory, links followed.
struct InputEntry {
  std::filesystem::path path;
  bool directory = false, regular_file = false;
};
// The entries of the directory `dir`, and with `recursive` of every directory below it (a link to a
// directory is listed, not entered), in path order. `dir` that is not a directory, or any directory
// that cannot be read on the way, is an InputError naming it.
std::vector<InputEntry> input_directory(const std::filesystem::path& dir, bool recursive);

// InputError "<path>:<line>: ..." for a malformed file (wrong field count, unterminated quote,
// text that is not UTF-8).
CsvTable read_csv(const std::filesystem::path& path);
// The same for CSV text read from `source`.
CsvTable parse_csv(const std::string& text, const std::string& source);

// One finished run directory.
struct RunData {
  std::filesystem::path dir;
  io::Json summary;
  CsvTable steps, divisions;
  std::optional<CsvTable> bud_events;  // absent when the scene turned bud events off

  // Typed fields of summary.json: InputError "<dir>/summary.json: <key>: ..." for a value of the
  // wrong type (or a missing L).
  std::string status() const;  // "?" when absent
  double L() const;
  std::optional<double> P0() const;  // nullopt = no feedback
  std::string P0_label() const;      // "none" or the number as text
  std::uint64_t seed() const;        // InputError naming summary.json unless a non-negative integer
  // A number from summary.json, NaN for null or absent; InputError for any other type.
  double get(const std::string& key) const;
  bool jammed() const { return summary.contains("phi_J") && !summary["phi_J"].is_null(); }
};

// An integer field of a JSON object read from `file`; InputError "<file>: <key>: not an integer"
// for a fraction, a string or a number no long long holds.
long long json_integer(const io::Json& j, const std::string& key, const std::filesystem::path& file);

// A number field of a JSON object read from `file`; InputError "<file>: <key>: not a number" for
// anything else (or a missing key). `key` is the name shown (e.g. "targets[2].dphi").
double json_double(const io::Json& j, const std::string& key, const std::filesystem::path& file,
                   const std::string& shown);

// Reads a finished run and checks it, for every reader of runs alike (`budjam analyse`, `budjam
// survival`, Python's load_run and survival): summary.json is a JSON object of format
// "budjam-summary", version 1, each key budjam writes there of its type and range (counts
// non-negative integers, fractions in [0, 1], L > 0, ...; null where a quantity was not reached;
// a jammed run records N_nr_J >= 1), its targets a list of objects with the keys analyse reads;
// steps.csv, divisions.csv and bud_events.csv hold the columns the analyses read, every field a
// number of its range where a value is required (check_run_tables). InputError naming the file and
// key, or file, line and column, otherwise.
RunData load_run(const std::filesystem::path& dir);

// The files of the run in `dir` that its readers read (load_run, run_tables, analyse's scene.toml,
// the packings and their sidecars), for the outputs that must not replace them (io::check_not_an_input).
std::vector<std::filesystem::path> run_input_files(const std::filesystem::path& dir);

// The checks of load_run on summary.json, read from `file`.
void check_summary(const io::Json& summary, const std::filesystem::path& file);
// The checks of load_run on the tables of a run.
void check_run_tables(const RunData& run);

// The tables budjam wrote in a run directory, named by their file without .csv: steps, divisions,
// and bud_events and the observers' logs (run_files::observer_logs) where the scene asked for them.
// Other files in the directory are not read. InputError naming a malformed table.
std::vector<std::pair<std::string, CsvTable>> run_tables(const RunData& run);

// Completion records of the tagged buds of one jamming episode (the last one, -1): completed = event;
// divided / censored_end / censored_unjam = censored; a bud with no terminal row is censored at its
// last logged a.
std::vector<SurvivalRecord> survival_records(const CsvTable& bud_events, int episode = -1);

// Contacts and contact network of a relaxed packing, as every analysis computes them.
struct PackingContacts {
  std::vector<Contact> contacts;
  ContactNetwork network;
  std::vector<double> bud_pressures;
  double P = 0;
  double lc2 = 0;  // ℓ_c²: mean squared centre distance over load-bearing contacts
};
PackingContacts analyse_contacts(const Packing& p);

// Results of `budjam moduli` / `budjam dos` kept beside a packing: packings/<name>.moduli.json,
// packings/<name>.dos.json (the Makefile writes them). nullopt when absent; InputError when the N,
// L or φ it records differ from the packing's (results of an earlier packing of that name).
std::optional<io::Json> sidecar(const std::filesystem::path& pack, const std::string& kind);

}  // namespace budjam::tools
