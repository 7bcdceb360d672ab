#include "io/run_data.hpp"

#include "budjam/cell_list.hpp"
#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/packing_file.hpp"
#include "io/run_directory.hpp"
#include "io/text.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>

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
  if (auto v = io::parse_double(t)) return *v;
  // A number beyond the double range (steps.csv writes Δt and χ_c exactly at any size): ±∞ or 0.
  errno = 0;
  char* end = nullptr;
  const double beyond = std::strtod(t.c_str(), &end);
  if (errno == ERANGE && end == t.c_str() + t.size()) return beyond;
  return std::nullopt;
}

double CsvTable::number(std::size_t row, std::size_t col) const {
  const std::string& t = rows.at(row).at(col);
  if (const auto v = csv_number(t)) return *v;
  // line numbers: header is line 1
  throw InputError(source + ":" + std::to_string(row + 2) + ": " + columns[col] + ": not a number (got \"" + t + "\")");
}

long long CsvTable::integer(std::size_t row, std::size_t col, long long lo, long long hi) const {
  const double v = number(row, col);
  // compare as doubles before converting: a cast of a value outside the integer's range is undefined
  if (!(v >= static_cast<double>(lo) && v <= static_cast<double>(hi)) || v != std::floor(v))
    throw InputError(source + ":" + std::to_string(row + 2) + ": " + columns[col] + ": not an integer in [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "] (got \"" + rows[row][col] + "\")");
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

RunData load_run(const fs::path& dir) {
  namespace run_files = io::run_files;
  RunData r;
  r.dir = dir;
  const fs::path s = dir / run_files::summary;
  if (!fs::exists(s)) throw InputError(dir.string() + ": not a finished run directory (no summary.json)");
  r.summary = io::read_json(s);
  if (!r.summary.is_object()) throw InputError(s.string() + ": not a budjam run summary (not a JSON object)");
  if (const auto f = r.summary.find("format"); f == r.summary.end() || *f != "budjam-summary")
    throw InputError(s.string() + ": format: not a budjam run summary (expected \"budjam-summary\")");
  if (const fs::path packings = dir / io::run_files::packings; fs::exists(packings) && !fs::is_directory(packings))
    throw InputError(packings.string() + ": not a directory (a run keeps its packings in one)");
  r.steps = read_csv(dir / run_files::steps);
  r.divisions = read_csv(dir / run_files::divisions);
  if (fs::exists(dir / run_files::bud_events)) r.bud_events = read_csv(dir / run_files::bud_events);
  return r;
}

std::vector<std::pair<std::string, CsvTable>> run_tables(const RunData& run) {
  namespace run_files = io::run_files;
  std::vector<std::pair<std::string, CsvTable>> tables{{"steps", run.steps}, {"divisions", run.divisions}};
  if (run.bud_events) tables.emplace_back("bud_events", *run.bud_events);
  for (const std::string_view name : {run_files::moduli, run_files::dos, run_files::rigidity, run_files::trials})
    if (const fs::path path = run.dir / name; fs::exists(path))
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
      last[id] = {kind, ev.number(r, c_a)};
    } else if (it->second.first == "tagged" || it->second.first == "first_contact") {
      it->second = {kind, ev.number(r, c_a)};  // terminal rows end a tag: later rows cannot follow
    }
  }
  std::vector<SurvivalRecord> out;
  for (const auto& id : order) {
    const auto& [kind, a] = last[id];
    out.push_back({std::max(0.0, a), kind == "completed"});
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
  if (!fs::exists(pack)) return;
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
  if (!fs::exists(f)) return std::nullopt;
  io::Json j = io::read_json(f);
  check_sidecar_matches(pack, f, j);
  return j;
}

}  // namespace budjam::tools
