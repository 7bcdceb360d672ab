#include "io/run_data.hpp"

#include "budjam/cell_list.hpp"
#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/packing_file.hpp"
#include "io/run_directory.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <span>
#include <string_view>

namespace budjam::tools {

namespace fs = std::filesystem;

std::size_t CsvTable::column(const std::string& name) const {
  for (std::size_t k = 0; k < columns.size(); ++k)
    if (columns[k] == name) return k;
  throw InputError(source + ": no column '" + name + "'");
}

bool CsvTable::has_column(const std::string& name) const {
  for (const auto& c : columns)
    if (c == name) return true;
  return false;
}

std::optional<double> csv_number(const std::string& t) {
  if (t.empty()) return std::numeric_limits<double>::quiet_NaN();
  if (auto v = io::parse_double(t)) {
    if (!std::isfinite(*v)) return std::nullopt;  // "nan", "inf": budjam writes neither
    return *v;
  }
  // A number beyond the double range (steps.csv writes Δt and χ_c exactly at any size): ±∞ or 0.
  errno = 0;
  char* end = nullptr;
  const double beyond = std::strtod(t.c_str(), &end);
  if (errno == ERANGE && end == t.c_str() + t.size()) return beyond;
  return std::nullopt;
}

namespace {
// "<source>:<line>: column <name>: " (the header is line 1).
std::string field_where(const CsvTable& t, std::size_t row, std::size_t col) {
  return t.source + ":" + std::to_string(row + 2) + ": column " + t.columns[col] + ": ";
}
std::string range_text(double lo, double hi) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  if (hi == inf) return lo == -inf ? "a finite number" : "a number >= " + io::format_double(lo);
  return "a number in [" + io::format_double(lo) + ", " + io::format_double(hi) + "]";
}
}  // namespace

double CsvTable::number(std::size_t row, std::size_t col) const {
  const std::string& t = rows.at(row).at(col);
  if (const auto v = csv_number(t)) return *v;
  const bool spelled = io::parse_double(t).has_value();  // "nan", "inf": read, but not finite
  throw InputError(field_where(*this, row, col) + (spelled ? "not a finite number" : "not a number") + " (got \"" + t +
                   "\")");
}

double CsvTable::number_in(std::size_t row, std::size_t col, double lo, double hi, bool required) const {
  const std::string& t = rows.at(row).at(col);
  if (t.empty()) {
    if (!required) return std::numeric_limits<double>::quiet_NaN();
    throw InputError(field_where(*this, row, col) + "empty, expected " + range_text(lo, hi));
  }
  const double v = number(row, col);
  if (!(v >= lo && v <= hi) || !std::isfinite(v))
    throw InputError(field_where(*this, row, col) + "expected " + range_text(lo, hi) + " (got \"" + t + "\")");
  return v;
}

long long CsvTable::integer(std::size_t row, std::size_t col, long long lo, long long hi) const {
  const double v = number(row, col);
  // compare as doubles before converting: a cast of a value outside the integer's range is undefined
  if (!(v >= static_cast<double>(lo) && v <= static_cast<double>(hi)) || v != std::floor(v))
    throw InputError(field_where(*this, row, col) + "not an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "] (got \"" + rows[row][col] + "\")");
  return static_cast<long long>(v);
}

std::vector<double> CsvTable::numbers(const std::string& name) const {
  const std::size_t c = column(name);
  std::vector<double> out(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) out[r] = number(r, c);
  return out;
}

namespace {

// Splits one CSV record starting at `pos`; advances pos past its line end.
std::vector<std::string> parse_record(const std::string& text, std::size_t& pos, const std::string& where) {
  std::vector<std::string> fields;
  std::string cur;
  bool quoted = false, was_quoted = false;
  while (pos < text.size()) {
    const char c = text[pos];
    if (quoted) {
      if (c == '"') {
        if (pos + 1 < text.size() && text[pos + 1] == '"') {
          cur += '"';
          pos += 2;
          continue;
        }
        quoted = false;
        ++pos;
        continue;
      }
      cur += c;
      ++pos;
      continue;
    }
    if (c == '"' && cur.empty() && !was_quoted) {
      quoted = was_quoted = true;
      ++pos;
      continue;
    }
    if (c == ',') {
      fields.push_back(std::move(cur));
      cur.clear();
      was_quoted = false;
      ++pos;
      continue;
    }
    if (c == '\r') {
      ++pos;
      continue;
    }
    if (c == '\n') {
      ++pos;
      break;
    }
    cur += c;
    ++pos;
  }
  if (quoted) throw InputError(where + ": unterminated quoted field");
  fields.push_back(std::move(cur));
  return fields;
}

}  // namespace

bool input_exists(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
    throw InputError(path.string() + ": cannot examine: " + ec.message());
  return fs::exists(st);
}

namespace {

void list_directory(const fs::path& dir, bool recursive, std::vector<InputEntry>& out) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code kind;
    const fs::file_status st = fs::status(it->path(), kind);
    InputEntry e{it->path(), fs::is_directory(st), fs::is_regular_file(st)};
    out.push_back(e);
    if (recursive && e.directory && !fs::is_symlink(it->symlink_status(kind))) list_directory(e.path, true, out);
  }
  if (ec) throw InputError(dir.string() + ": cannot read the directory: " + ec.message());
}

}  // namespace

std::vector<InputEntry> input_directory(const fs::path& dir, bool recursive) {
  if (!input_exists(dir)) throw InputError(dir.string() + ": no such directory");
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": not a directory");
  std::vector<InputEntry> out;
  list_directory(dir, recursive, out);
  std::sort(out.begin(), out.end(), [](const InputEntry& a, const InputEntry& b) { return a.path < b.path; });
  return out;
}

CsvTable read_csv(const fs::path& path) { return parse_csv(io::read_text_file(path), path.string()); }

CsvTable parse_csv(const std::string& text, const std::string& source) {
  CsvTable t;
  t.source = source;
  std::size_t pos = 0, line = 1;
  if (text.empty()) throw InputError(t.source + ": empty file (no header)");
  if (const std::string at = io::first_invalid_utf8(text); !at.empty())
    throw InputError(t.source + ":" + at + ": not valid UTF-8 (budjam's tables are UTF-8 text)");
  t.columns = parse_record(text, pos, t.source + ":1");
  while (pos < text.size()) {
    ++line;
    auto rec = parse_record(text, pos, t.source + ":" + std::to_string(line));
    if (rec.size() == 1 && rec[0].empty()) continue;  // blank line
    if (rec.size() != t.columns.size())
      throw InputError(t.source + ":" + std::to_string(line) + ": " + std::to_string(rec.size()) +
                       " fields, header has " + std::to_string(t.columns.size()));
    t.rows.push_back(std::move(rec));
  }
  return t;
}

std::optional<double> RunData::P0() const {
  if (!summary.contains("P0") || summary["P0"].is_null()) return std::nullopt;
  if (!summary["P0"].is_number())
    throw InputError((dir / io::run_files::summary).string() + ": P0: not a number or null (no feedback)");
  return summary["P0"].get<double>();
}

std::string RunData::P0_label() const {
  const auto p = P0();
  return p ? io::format_double(*p) : std::string("none");
}

long long json_integer(const io::Json& j, const std::string& key, const fs::path& file) {
  const auto it = j.find(key);
  if (it != j.end() && it->is_number_integer()) return it->get<long long>();
  throw InputError(file.string() + ": " + key + ": not an integer");
}

std::uint64_t RunData::seed() const {
  const auto& s = summary.contains("seed") ? summary["seed"] : io::Json();
  if (!s.is_number_unsigned())
    throw InputError((dir / io::run_files::summary).string() + ": seed: not a non-negative integer");
  return s.get<std::uint64_t>();
}

double json_double(const io::Json& j, const std::string& key, const fs::path& file, const std::string& shown) {
  const auto it = j.find(key);
  if (it != j.end() && it->is_number()) return it->get<double>();
  throw InputError(file.string() + ": " + shown + (it == j.end() ? ": missing" : ": not a number"));
}

std::string RunData::status() const {
  const auto it = summary.find("status");
  if (it == summary.end()) return "?";
  if (!it->is_string()) throw InputError((dir / io::run_files::summary).string() + ": status: not a string");
  return it->get<std::string>();
}

double RunData::L() const { return json_double(summary, "L", dir / io::run_files::summary, "L"); }

double RunData::get(const std::string& key) const {
  const auto it = summary.find(key);
  if (it == summary.end() || it->is_null()) return std::numeric_limits<double>::quiet_NaN();
  return json_double(summary, key, dir / io::run_files::summary, key);
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// What a key of summary.json holds (docs/columns.md, "RUN/summary.json").
enum class Kind { count, real, nonnegative, positive, fraction, text };
struct KeyRule {
  const char* key;
  Kind kind;
  bool nullable;  // null: a quantity not reached
  bool required;  // every reader needs it (an absent key otherwise reads as null)
};

// Top-level keys.
constexpr KeyRule kSummaryRules[] = {
    {"status", Kind::text, false, false},
    {"message", Kind::text, false, false},
    {"scene", Kind::text, false, false},
    {"blas", Kind::text, false, false},
    {"L", Kind::positive, false, true},
    {"N_J", Kind::count, true, false},
    {"phi_J", Kind::positive, true, false},
    {"P_J", Kind::real, true, false},
    {"E_J", Kind::nonnegative, true, false},
    {"Z_J", Kind::nonnegative, true, false},
    {"Z_iso_J", Kind::real, true, false},
    {"dZ_J", Kind::real, true, false},
    {"u_J", Kind::fraction, true, false},
    {"u_J_lobes", Kind::fraction, true, false},
    {"n_J", Kind::nonnegative, true, false},
    {"N_nr_J", Kind::count, true, false},
    {"N_f_J", Kind::count, true, false},
    {"tagged_J", Kind::count, true, false},
    {"step_J", Kind::count, true, false},
    {"jamming_episode", Kind::count, true, false},
    {"phi_2", Kind::positive, true, false},
    {"P_2", Kind::real, true, false},
    {"N_2", Kind::count, true, false},
    {"Z_2", Kind::nonnegative, true, false},
    {"dZ_2", Kind::real, true, false},
    {"N_div_2", Kind::count, true, false},
    {"step_2", Kind::count, true, false},
    {"phi_2_tagged_left", Kind::count, false, false},
    {"accepted_steps", Kind::count, false, false},
    {"rejected_steps", Kind::count, false, false},
    {"divisions", Kind::count, false, false},
    {"force_evaluations", Kind::count, false, false},
    {"fire_iterations", Kind::count, false, false},
    {"saddles_relaxed", Kind::count, false, false},
    {"saddle_escapes", Kind::count, false, false},
    {"search_trials", Kind::count, false, false},
    {"marginal_relaxations", Kind::count, false, false},
    {"newton_factorisations", Kind::count, false, false},
    {"newton_factor_reuses", Kind::count, false, false},
    {"active_set_steps", Kind::count, false, false},
    {"active_set_factorisations", Kind::count, false, false},
    {"active_set_updates", Kind::count, false, false},
    {"force_evaluations_initial", Kind::count, false, false},
    {"force_evaluations_search", Kind::count, false, false},
    {"force_evaluations_above_jamming", Kind::count, false, false},
    {"branches", Kind::count, false, false},
    {"branches_reached", Kind::count, false, false},
    {"branch_stability_losses", Kind::count, false, false},
    {"branch_rearrangements", Kind::count, false, false},
    {"branch_steps", Kind::count, false, false},
    {"branch_events", Kind::count, false, false},
};

// The keys of each entry of `targets` (those analyse reads are required).
constexpr KeyRule kTargetRules[] = {
    {"index", Kind::count, false, true},
    {"dphi", Kind::positive, false, true},
    {"phi", Kind::positive, false, true},
    {"phi_target", Kind::positive, false, false},
    {"P", Kind::real, false, true},
    {"E_per_cell", Kind::nonnegative, false, false},
    {"N", Kind::count, false, false},
    {"N_nr", Kind::count, false, true},
    {"Z", Kind::nonnegative, false, true},
    {"u", Kind::fraction, false, true},
    {"u_buds", Kind::fraction, false, true},
    {"Z_iso", Kind::real, false, true},
    {"dZ", Kind::real, false, true},
    {"N_c", Kind::count, false, false},
    {"N_u", Kind::count, false, false},
    {"N_u_buds", Kind::count, false, false},
    {"N_f", Kind::count, false, false},
    {"N_f_single", Kind::count, false, false},
    {"chi_c", Kind::nonnegative, false, true},
    {"N_div", Kind::count, false, true},
    {"step", Kind::count, false, true},
};

// The keys of each entry of `unjammings`, and of `final`.
constexpr KeyRule kUnjammingRules[] = {{"episode", Kind::count, false, false},
                                       {"step", Kind::count, false, false},
                                       {"phi", Kind::positive, false, false},
                                       {"phi_J", Kind::positive, false, false},
                                       {"targets_lost", Kind::count, false, false}};
constexpr KeyRule kFinalRules[] = {{"step", Kind::count, false, false},
                                   {"phase", Kind::text, false, false},
                                   {"phi", Kind::nonnegative, false, false},
                                   {"P", Kind::real, false, false},
                                   {"N", Kind::count, false, false}};

const char* expected(Kind kind) {
  switch (kind) {
    case Kind::count: return "a non-negative integer";
    case Kind::real: return "a number";
    case Kind::nonnegative: return "a number >= 0";
    case Kind::positive: return "a number > 0";
    case Kind::fraction: return "a number in [0, 1]";
    case Kind::text: return "a string";
  }
  return "?";
}

bool holds(const io::Json& v, Kind kind) {
  if (kind == Kind::text) return v.is_string();
  if (kind == Kind::count) return v.is_number_unsigned() || (v.is_number_integer() && v.get<long long>() >= 0);
  if (!v.is_number()) return false;
  const double x = v.get<double>();
  switch (kind) {
    case Kind::real: return std::isfinite(x);
    case Kind::nonnegative: return x >= 0 && x < kInf;
    case Kind::positive: return x > 0 && x < kInf;
    case Kind::fraction: return x >= 0 && x <= 1;
    default: return false;
  }
}

// The value as a short text for a message ("-5", "\"0.83\"", "{...}").
std::string shown(const io::Json& v) {
  if (v.is_object()) return "an object";
  if (v.is_array()) return "a list";
  return v.dump(-1, ' ', false, io::Json::error_handler_t::replace);
}

// Values of the wrong type or range first, then a missing key.
template <std::size_t n>
void check_keys(const io::Json& object, const KeyRule (&rules)[n], const std::string& file, const std::string& prefix) {
  for (const KeyRule& rule : rules) {
    const auto it = object.find(rule.key);
    if (it == object.end() || (it->is_null() && rule.nullable) || holds(*it, rule.kind)) continue;
    throw InputError(file + ": " + prefix + rule.key + ": expected " + expected(rule.kind) +
                     (rule.nullable ? " or null" : "") + " (got " + shown(*it) + ")");
  }
  for (const KeyRule& rule : rules)
    if (rule.required && !object.contains(rule.key))
      throw InputError(file + ": " + prefix + rule.key + ": missing (expected " + expected(rule.kind) + ")");
}

// A list of objects under `key` (absent allowed unless `required`), each held to `rules`.
template <std::size_t n>
void check_list(const io::Json& summary, const char* key, const KeyRule (&rules)[n], const std::string& file,
                bool required) {
  const auto it = summary.find(key);
  if (it == summary.end()) {
    if (required) throw InputError(file + ": " + key + ": missing (expected a list)");
    return;
  }
  if (!it->is_array()) throw InputError(file + ": " + key + ": not a list (got " + shown(*it) + ")");
  for (std::size_t k = 0; k < it->size(); ++k) {
    const std::string name = std::string(key) + "[" + std::to_string(k) + "]";
    if (!(*it)[k].is_object()) throw InputError(file + ": " + name + ": not an object");
    check_keys((*it)[k], rules, file, name + ".");
  }
}

}  // namespace

void check_summary(const io::Json& summary, const fs::path& path) {
  const std::string file = path.string();
  if (!summary.is_object()) throw InputError(file + ": not a budjam run summary (not a JSON object)");
  if (const auto f = summary.find("format"); f == summary.end() || *f != "budjam-summary")
    throw InputError(file + ": format: not a budjam run summary (expected \"budjam-summary\")");
  const auto version = summary.find("version");
  if (version == summary.end()) throw InputError(file + ": version: missing (expected 1)");
  if (*version != io::run_files::summary_version)
    throw InputError(file + ": version: " + shown(*version) + " is not a summary format this budjam reads (expected " +
                     std::to_string(io::run_files::summary_version) + ")");
  check_keys(summary, kSummaryRules, file, "");
  if (const auto status = summary.find("status"); status != summary.end()) {
    const std::string s = status->get<std::string>();
    if (s != "finished" && s != "step_limit" && s != "dt_underflow" && s != "minimiser_failed" && s != "overlap_bound")
      throw InputError(file + ": status: \"" + s +
                       "\" is not the status of a finished run (finished, step_limit, dt_underflow, minimiser_failed "
                       "or overlap_bound)");
  }
  if (const auto seed = summary.find("seed"); seed == summary.end() || !seed->is_number_unsigned())
    throw InputError(file + ": seed: not a non-negative integer");
  if (const auto p0 = summary.find("P0"); p0 != summary.end() && !p0->is_null() && !holds(*p0, Kind::positive))
    throw InputError(file + ": P0: expected a number > 0 or null (no feedback) (got " + shown(*p0) + ")");
  check_list(summary, "targets", kTargetRules, file, true);
  check_list(summary, "unjammings", kUnjammingRules, file, false);
  if (const auto final = summary.find("final"); final != summary.end()) {
    if (!final->is_object()) throw InputError(file + ": final: not an object (got " + shown(*final) + ")");
    check_keys(*final, kFinalRules, file, "final.");
  }
  // A jammed run has a rigid backbone: analyse and survival take ε = 1/N_nr,J.
  if (const auto phi_J = summary.find("phi_J"); phi_J != summary.end() && !phi_J->is_null()) {
    const auto nr = summary.find("N_nr_J");
    if (nr == summary.end() || nr->is_null() || nr->get<long long>() < 1)
      throw InputError(file + ": N_nr_J: " + (nr == summary.end() ? std::string("missing") : shown(*nr)) +
                       ", but a jammed run (phi_J not null) has N_nr_J >= 1 non-rattler cells");
  }
}

namespace {

// What a column of a run's table holds.
enum class Field { count, id, real, nonnegative, positive_or_inf, text };
struct ColumnRule {
  const char* name;
  Field field;
  bool column_required;  // the analyses read it
  bool value_required;   // false: empty where not reached (steps.csv before jamming)
};

void check_table(const CsvTable& t, std::span<const ColumnRule> rules) {
  for (const ColumnRule& rule : rules) {
    if (!t.has_column(rule.name)) {
      if (rule.column_required) t.column(rule.name);  // throws naming the column
      continue;
    }
    const std::size_t c = t.column(rule.name);
    for (std::size_t r = 0; r < t.size(); ++r) {
      if (!rule.value_required && t.text(r, c).empty()) continue;
      switch (rule.field) {
        case Field::count: t.integer(r, c, 0, std::numeric_limits<long long>::max()); break;
        case Field::id: t.integer(r, c, -1, std::numeric_limits<long long>::max()); break;
        case Field::real: t.number_in(r, c, -kInf, kInf); break;
        case Field::nonnegative: t.number_in(r, c, 0, kInf); break;
        case Field::positive_or_inf:  // Δt: decimal text beyond the double range reads as inf
          if (const double v = t.number(r, c); !(v > 0) && t.text(r, c) != "0")
            t.number_in(r, c, 0, kInf);  // throws with the range
          break;
        case Field::text: break;
      }
    }
  }
}

constexpr ColumnRule kStepsRules[] = {
    {"step", Field::count, true, true},
    {"attempts", Field::count, false, true},
    {"dt", Field::positive_or_inf, false, true},
    {"N", Field::count, true, true},
    {"phi", Field::nonnegative, true, true},
    {"P", Field::real, true, true},
    {"E_per_cell", Field::nonnegative, false, true},
    {"N_c", Field::count, false, false},
    {"N_f", Field::count, true, false},
    {"N_f_single", Field::count, false, false},
    {"N_u", Field::count, false, false},
    {"N_u_buds", Field::count, true, false},
    {"Z", Field::real, true, false},
    {"Z_iso", Field::real, false, false},
    {"dZ", Field::real, true, false},
    {"chi_c", Field::nonnegative, true, false},
    {"compressed_buds", Field::count, false, false},
    {"tagged_active", Field::count, true, false},
    {"tagged_completed", Field::count, false, false},
    {"tagged_divided", Field::count, false, false},
    {"divisions_since_jamming", Field::count, true, false},
};

constexpr ColumnRule kDivisionsRules[] = {
    {"step", Field::count, true, true},
    {"phi", Field::nonnegative, true, true},
    {"N", Field::count, false, true},
    {"mother_id", Field::count, false, true},
    {"daughter_id", Field::count, false, true},
    {"mother_index", Field::count, false, true},
    {"daughter_index", Field::count, false, true},
    {"x", Field::real, false, true},
    {"y", Field::real, false, true},
    {"theta", Field::real, false, true},
    {"b", Field::nonnegative, false, true},
};

constexpr ColumnRule kBudEventsRules[] = {
    {"episode", Field::count, true, true},    {"cell_id", Field::count, true, true},
    {"event", Field::text, true, true},       {"step", Field::count, false, true},
    {"phi", Field::nonnegative, false, true}, {"a", Field::nonnegative, true, true},
};

constexpr std::string_view kBudEventKinds[] = {"tagged",  "first_contact", "completed",
                                               "divided", "censored_end",  "censored_unjam"};

}  // namespace

void check_run_tables(const RunData& run) {
  check_table(run.steps, kStepsRules);
  check_table(run.divisions, kDivisionsRules);
  if (run.bud_events) {
    const CsvTable& ev = *run.bud_events;
    check_table(ev, kBudEventsRules);
    const std::size_t c = ev.column("event");
    for (std::size_t r = 0; r < ev.size(); ++r)
      if (std::find(std::begin(kBudEventKinds), std::end(kBudEventKinds), ev.text(r, c)) == std::end(kBudEventKinds))
        throw InputError(
            ev.source + ":" + std::to_string(r + 2) + ": column event: \"" + ev.text(r, c) +
            "\" is not a bud event (tagged, first_contact, completed, divided, censored_end, censored_unjam)");
  }
}

RunData load_run(const fs::path& dir) {
  namespace run_files = io::run_files;
  RunData r;
  r.dir = dir;
  const fs::path s = dir / run_files::summary;
  if (!input_exists(s)) throw InputError(dir.string() + ": not a finished run directory (no summary.json)");
  r.summary = io::read_json(s);
  if (!r.summary.is_object()) throw InputError(s.string() + ": not a budjam run summary (not a JSON object)");
  if (const fs::path packings = dir / io::run_files::packings; input_exists(packings) && !fs::is_directory(packings))
    throw InputError(packings.string() + ": not a directory (a run keeps its packings in one)");
  check_summary(r.summary, s);
  r.steps = read_csv(dir / run_files::steps);
  r.divisions = read_csv(dir / run_files::divisions);
  if (input_exists(dir / run_files::bud_events)) r.bud_events = read_csv(dir / run_files::bud_events);
  check_run_tables(r);
  return r;
}

std::vector<fs::path> run_input_files(const fs::path& dir) {
  namespace run_files = io::run_files;
  std::vector<fs::path> files;
  for (const std::string_view name :
       {run_files::summary, run_files::scene, run_files::steps, run_files::divisions, run_files::bud_events})
    files.push_back(dir / name);
  for (const std::string_view name : run_files::observer_logs) files.push_back(dir / name);
  // the packings and the sidecars beside them (moduli, spectra), which analyse reads too
  for (const std::string_view sub : {run_files::packings, run_files::spectra}) {
    std::error_code ec;
    for (fs::directory_iterator it(dir / sub, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec)) files.push_back(it->path());
  }
  return files;
}

std::vector<std::pair<std::string, CsvTable>> run_tables(const RunData& run) {
  namespace run_files = io::run_files;
  std::vector<std::pair<std::string, CsvTable>> tables{{"steps", run.steps}, {"divisions", run.divisions}};
  if (run.bud_events) tables.emplace_back("bud_events", *run.bud_events);
  for (const std::string_view name : run_files::observer_logs)
    if (const fs::path path = run.dir / name; input_exists(path))
      tables.emplace_back(path.stem().string(), read_csv(path));
  return tables;
}

namespace {
// The episode of row r: a whole number that fits an int (no float→int overflow on bad input).
int episode_of(const CsvTable& ev, std::size_t r, std::size_t c) {
  return static_cast<int>(ev.integer(r, c, 0, std::numeric_limits<int>::max()));
}
}  // namespace

std::vector<SurvivalRecord> survival_records(const CsvTable& ev, int episode) {
  const std::size_t c_ep = ev.column("episode"), c_id = ev.column("cell_id"), c_kind = ev.column("event"),
                    c_a = ev.column("a");
  if (episode < 0) {
    for (std::size_t r = 0; r < ev.size(); ++r) episode = std::max(episode, episode_of(ev, r, c_ep));
    if (episode < 0) return {};
  }
  // Last row per tagged bud (rows are in time order), in order of first appearance.
  std::map<std::string, std::pair<std::string, double>> last;
  std::vector<std::string> order;
  for (std::size_t r = 0; r < ev.size(); ++r) {
    if (episode_of(ev, r, c_ep) != episode) continue;
    const std::string& id = ev.text(r, c_id);
    const std::string& kind = ev.text(r, c_kind);
    auto it = last.find(id);
    if (it == last.end()) {
      order.push_back(id);
      last[id] = {kind, ev.number_in(r, c_a, 0, kInf)};
    } else if (it->second.first == "tagged" || it->second.first == "first_contact") {
      it->second = {kind, ev.number_in(r, c_a, 0, kInf)};  // terminal rows end a tag: later rows cannot follow
    }
  }
  std::vector<SurvivalRecord> out;
  for (const auto& id : order) {
    const auto& [kind, a] = last[id];
    out.push_back({a, kind == "completed"});
  }
  return out;
}

PackingContacts analyse_contacts(const Packing& p) {
  PackingContacts pc;
  Lobes lobes;
  place_lobes(p, lobes);
  NeighbourList nl;
  nl.update(lobes, p.box);
  pc.contacts = find_contacts(p, lobes, nl);
  pc.network = analyse_network(p.size(), pc.contacts);
  pc.bud_pressures = bud_pressures(p, pc.contacts);
  pc.P = pressure(pc.contacts, p.box);
  double s = 0;
  std::size_t n = 0;
  for (const auto& c : load_bearing(pc.contacts, pc.network)) {
    s += c.r * c.r;
    ++n;
  }
  pc.lc2 = n ? s / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
  return pc;
}

namespace {

// A sidecar belongs to the packing beside it only while that packing is unchanged: a run grown
// again into its directory (--overwrite) or a packing replaced by hand would otherwise lend it the
// numbers of another packing. What the sidecar records of its packing (N, L, φ) must match it.
void check_sidecar_matches(const fs::path& pack, const fs::path& file, const io::Json& j) {
  if (!input_exists(pack)) return;
  const io::PackingFile p = io::read_packing(pack);
  const auto check = [&](const char* key, double of_packing) {
    if (!j.contains(key) || !j[key].is_number()) return;
    const double recorded = j[key].get<double>();
    if (recorded != of_packing)
      throw InputError(file.string() + ": results of another packing than " + pack.string() + " (" + key + " " +
                       io::format_double(recorded) + " against the packing's " + io::format_double(of_packing) +
                       "): compute them again");
  };
  check("N", static_cast<double>(p.packing.size()));
  check("L", p.packing.box.L);
  check("phi", p.packing.packing_fraction());
}

}  // namespace

std::optional<io::Json> sidecar(const fs::path& pack, const std::string& kind) {
  fs::path f = pack;
  f.replace_extension("." + kind + ".json");
  if (!input_exists(f)) return std::nullopt;
  io::Json j = io::read_json(f);
  check_sidecar_matches(pack, f, j);
  return j;
}

}  // namespace budjam::tools
