#include "io/packing_file.hpp"

#include "budjam/errors.hpp"
#include "budjam/growth_driver.hpp"
#include "budjam/packing_rules.hpp"
#include "budjam/scene.hpp"  // the default skin
#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

namespace budjam::io {
namespace {

constexpr std::string_view kPackingMagic = "budjam-packing";
constexpr std::string_view kUtf8ByteOrderMark = "\xEF\xBB\xBF";
constexpr std::array<std::string_view, 7> kCellColumns = {"id", "parent", "x", "y", "theta", "b", "gamma0"};

bool valid_meta_key(std::string_view key) {
  return !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
           c == '-';
  });
}

std::vector<std::string_view> tokens_of(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string shown(std::string_view s) {
  constexpr std::size_t kMax = 40;  // keep the one-line message short
  std::string t(s.substr(0, kMax));
  if (s.size() > kMax) t += "...";
  return "\"" + t + "\"";
}

// Splits into lines without their terminators; remembers whether the text ended with '\n'.
struct PackingLines {
  std::vector<std::string_view> lines;
  explicit PackingLines(std::string_view text) {
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string_view::npos) end = text.size();
      std::string_view line = text.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      lines.push_back(line);
      start = end + 1;
    }
  }
};

class Reader {
 public:
  Reader(std::string_view text, const std::string& source) : lines_(text), source_(source) {}

  PackingFile read() {
    PackingFile out;
    read_magic();
    const std::size_t cells_line = read_header(out);
    // The box rule with the default skin of the neighbour list every command builds: first for
    // mother lobes (before any position is judged against L), then for the largest bud.
    if (const auto problem = box_problem(out.packing, Scene{}.skin)) fail(L_line_, *problem);
    read_rows(out.packing);
    read_end();
    if (const auto problem = box_problem(out.packing, Scene{}.skin)) fail(L_line_, *problem);
    // Degenerate geometry: the density first, which bounds the cost of the pair check.
    if (const auto problem = density_problem(out.packing)) fail(L_line_, *problem);
    std::pair<std::size_t, std::size_t> cells;
    if (const auto problem = overlap_problem(out.packing, &cells)) fail(cells_line + 1 + cells.second, *problem);
    return out;
  }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& problem) const {
    throw InputError(source_ + ":" + std::to_string(line) + ": " + problem);
  }
  bool at_eof() const { return next_ >= lines_.lines.size(); }
  std::size_t line_number() const { return next_ + 1; }  // of the line about to be read

  void read_magic() {
    if (at_eof()) fail(1, "empty file, not a budjam packing file");
    if (lines_.lines[0].starts_with(kUtf8ByteOrderMark))
      fail(1, "the file starts with a UTF-8 byte-order mark before \"" + std::string(kPackingMagic) +
                  "\" (a packing file has none: save it without one)");
    const auto t = tokens_of(lines_.lines[0]);
    if (t.empty() || t[0] != kPackingMagic)
      fail(1, "not a budjam packing file (the first line must be \"budjam-packing " +
                  std::to_string(kPackingFormatVersion) + "\")");
    if (t.size() != 2) fail(1, "the first line must be \"budjam-packing <version>\"");
    const auto version = parse_int64(t[1]);
    if (!version) fail(1, "format version is not an integer (got " + shown(t[1]) + ")");
    if (*version != kPackingFormatVersion)
      fail(1, "unsupported packing format version " + std::string(t[1]) + " (this budjam reads version " +
                  std::to_string(kPackingFormatVersion) + ")");
    next_ = 1;
  }

  double header_number(std::size_t line, std::string_view key, const std::vector<std::string_view>& t) {
    if (t.size() != 2) fail(line, "header line \"" + std::string(key) + "\" needs exactly one value");
    const auto v = parse_double(t[1]);
    if (!v) fail(line, std::string(key) + ": not a number (got " + shown(t[1]) + ")");
    if (!std::isfinite(*v)) fail(line, std::string(key) + ": not finite (got " + std::string(t[1]) + ")");
    return *v;
  }
  std::int64_t header_integer(std::size_t line, std::string_view key, const std::vector<std::string_view>& t) {
    if (t.size() != 2) fail(line, "header line \"" + std::string(key) + "\" needs exactly one value");
    const auto v = parse_int64(t[1]);
    if (!v) fail(line, std::string(key) + ": not an integer (got " + shown(t[1]) + ")");
    if (*v < 0) fail(line, std::string(key) + ": must not be negative (got " + std::string(t[1]) + ")");
    return *v;
  }

  // Returns the line number of the "cells" line.
  std::size_t read_header(PackingFile& out) {
    std::optional<double> L, shear;
    std::optional<std::int64_t> N, next_id;
    while (true) {
      if (at_eof()) fail(line_number(), "truncated: the header has no \"cells\" line");
      const std::size_t n = line_number();
      const std::string_view line = lines_.lines[next_++];
      const auto t = tokens_of(line);
      if (t.empty() || t[0].front() == '#') continue;
      const std::string_view key = t[0];
      auto once = [&](bool seen) {
        if (seen) fail(n, "duplicate header key \"" + std::string(key) + "\"");
      };
      if (key == "L") {
        once(L.has_value());
        L = header_number(n, key, t);
        L_line_ = n;
        if (!(*L > 0)) fail(n, "L: must be positive (got " + std::string(t[1]) + ")");
      } else if (key == "shear") {
        once(shear.has_value());
        shear = header_number(n, key, t);
      } else if (key == "N") {
        once(N.has_value());
        N = header_integer(n, key, t);
      } else if (key == "next_id") {
        once(next_id.has_value());
        next_id = header_integer(n, key, t);
      } else if (key == "meta") {
        // "meta <key> <value>": the value is the rest of the line after one space, verbatim.
        std::string_view rest = line.substr(line.find("meta") + 4);
        if (rest.empty() || rest.front() != ' ') fail(n, "a meta line is \"meta <key> <value>\"");
        rest.remove_prefix(1);
        const std::size_t sp = rest.find(' ');
        const std::string mkey(rest.substr(0, sp));
        const std::string value(sp == std::string_view::npos ? std::string_view() : rest.substr(sp + 1));
        if (!valid_meta_key(mkey)) fail(n, "invalid meta key " + shown(mkey) + " (letters, digits, _ . -)");
        // Only what can be written back is read: a value is one line, with no carriage return, of
        // UTF-8 text (a JSON output or a Python str holds nothing else).
        if (value.find('\r') != std::string::npos) fail(n, "meta " + mkey + ": the value holds a carriage return");
        if (const std::string at = first_invalid_utf8(value); !at.empty())
          fail(n, "meta " + mkey + ": the value is not valid UTF-8 (byte " + at.substr(at.find(':') + 1) +
                      " of the value; packing files are UTF-8 text)");
        if (!out.meta.values.emplace(mkey, value).second) fail(n, "duplicate meta key \"" + mkey + "\"");
      } else if (key == "cells") {
        if (t.size() != kCellColumns.size() + 1 || !std::equal(kCellColumns.begin(), kCellColumns.end(), t.begin() + 1))
          fail(n, "the cells line must be \"cells id parent x y theta b gamma0\"");
        for (auto [have, name] : {std::pair{L.has_value(), "L"}, std::pair{shear.has_value(), "shear"},
                                  std::pair{N.has_value(), "N"}, std::pair{next_id.has_value(), "next_id"}})
          if (!have) fail(n, std::string("the header lacks \"") + name + "\"");
        out.packing.box.L = *L;
        out.packing.box.shear = *shear;
        out.packing.next_id = *next_id;
        n_cells_ = static_cast<std::size_t>(*N);
        return n;
      } else {
        fail(n, "unknown header key " + shown(key));
      }
    }
  }

  void read_rows(Packing& p) {
    // Reserve no more than the file can hold: a corrupt N must not allocate gigabytes.
    const std::size_t cap = std::min(n_cells_, lines_.lines.size());
    p.q.resize(static_cast<Eigen::Index>(3 * cap));
    p.b.reserve(cap);
    p.gamma0.reserve(cap);
    p.id.reserve(cap);
    p.parent.reserve(cap);
    std::unordered_map<std::int64_t, std::size_t> first_line;
    first_line.reserve(cap);
    for (std::size_t k = 0; k < n_cells_; ++k) {
      if (at_eof())
        fail(line_number(), "truncated: expected N = " + std::to_string(n_cells_) + " cell rows, the file ends after " +
                                std::to_string(k));
      const std::size_t n = line_number();
      const auto t = tokens_of(lines_.lines[next_++]);
      if (t.size() == 1 && t[0] == "end")
        fail(n, "expected N = " + std::to_string(n_cells_) + " cell rows, found " + std::to_string(k));
      if (t.size() != kCellColumns.size())
        fail(n, "expected " + std::to_string(kCellColumns.size()) + " columns (id parent x y theta b gamma0), found " +
                    std::to_string(t.size()));
      std::int64_t ids[2];
      for (int c = 0; c < 2; ++c) {
        const auto v = parse_int64(t[c]);
        if (!v) fail(n, "column " + std::string(kCellColumns[c]) + ": not an integer (got " + shown(t[c]) + ")");
        ids[c] = *v;
      }
      double val[5];
      for (int c = 0; c < 5; ++c) {
        const auto v = parse_double(t[c + 2]);
        if (!v) fail(n, "column " + std::string(kCellColumns[c + 2]) + ": not a number (got " + shown(t[c + 2]) + ")");
        if (!std::isfinite(*v))
          fail(n, "column " + std::string(kCellColumns[c + 2]) + ": not finite (got " + std::string(t[c + 2]) + ")");
        val[c] = *v;
      }
      const auto [id, parent] = ids;
      if (id < 0 || id >= p.next_id)
        fail(n, "column id: must lie in [0, next_id = " + std::to_string(p.next_id) + ") (got " + std::to_string(id) +
                    ")");
      if (parent < -1 || parent >= p.next_id || parent == id)
        fail(n, "column parent: must be -1 or another id below next_id (got " + std::to_string(parent) + ")");
      if (!(val[3] >= 0)) fail(n, "column b: must not be negative (got " + std::string(t[5]) + ")");
      if (!(val[4] >= 0)) fail(n, "column gamma0: must not be negative (got " + std::string(t[6]) + ")");
      if (const auto [it, fresh] = first_line.emplace(id, n); !fresh)
        fail(n, "duplicate id " + std::to_string(id) + " (first on line " + std::to_string(it->second) + ")");
      if (k >= cap) p.q.conservativeResize(static_cast<Eigen::Index>(3 * (k + 1)));
      p.q[3 * k] = val[0];
      p.q[3 * k + 1] = val[1];
      p.q[3 * k + 2] = val[2];
      p.b.push_back(val[3]);
      p.gamma0.push_back(val[4]);
      p.id.push_back(id);
      p.parent.push_back(parent);
      if (const auto problem = cell_problem(p, k, kMaxBudDiameter)) fail(n, *problem);
    }
    p.q.conservativeResize(static_cast<Eigen::Index>(3 * n_cells_));
  }

  void read_end() {
    if (at_eof()) fail(line_number(), "truncated: missing the \"end\" line after the cell rows");
    const std::size_t n = line_number();
    const auto t = tokens_of(lines_.lines[next_++]);
    if (!(t.size() == 1 && t[0] == "end")) {
      if (t.size() == kCellColumns.size()) fail(n, "more cell rows than N = " + std::to_string(n_cells_));
      fail(n, "expected \"end\" after the cell rows");
    }
    while (!at_eof()) {
      const std::size_t m = line_number();
      if (!tokens_of(lines_.lines[next_++]).empty()) fail(m, "unexpected text after \"end\"");
    }
  }

  PackingLines lines_;
  const std::string& source_;
  std::size_t next_ = 0;  // index of the next line to read
  std::size_t n_cells_ = 0;
  std::size_t L_line_ = 0;
};

}  // namespace

std::optional<std::string> meta_problem(const std::string& key, std::string_view value) {
  if (!valid_meta_key(key)) return "meta key " + shown(key) + ": letters, digits, _ . - only";
  if (value.find_first_of("\r\n") != std::string_view::npos)
    return "meta[" + shown(key) + "]: the value must be one line (no line break)";
  if (!first_invalid_utf8(value).empty()) return "meta[" + shown(key) + "]: the value is not valid UTF-8";
  return std::nullopt;
}

void PackingMeta::set(const std::string& key, std::string value) {
  if (const auto problem = meta_problem(key, value)) throw std::invalid_argument("packing " + *problem);
  values[key] = std::move(value);
}
void PackingMeta::set_number(const std::string& key, double value) { set(key, format_double(value)); }
void PackingMeta::set_integer(const std::string& key, std::int64_t value) { set(key, std::to_string(value)); }

std::optional<std::string> PackingMeta::get(const std::string& key) const {
  const auto it = values.find(key);
  if (it == values.end()) return std::nullopt;
  return it->second;
}

double PackingMeta::number(const std::string& key) const {
  const auto v = get(key);
  if (!v) throw InputError("meta." + key + ": missing");
  const auto d = parse_double(*v);
  if (!d) throw InputError("meta." + key + ": not a number (got \"" + *v + "\")");
  return *d;
}

std::int64_t PackingMeta::integer(const std::string& key) const {
  const auto v = get(key);
  if (!v) throw InputError("meta." + key + ": missing");
  const auto i = parse_int64(*v);
  if (!i) throw InputError("meta." + key + ": not an integer (got \"" + *v + "\")");
  return *i;
}

std::optional<std::string> unwritable_problem(const Packing& p, const PackingMeta& meta) {
  const std::size_t n = p.size();
  if (static_cast<std::size_t>(p.q.size()) != 3 * n || p.gamma0.size() != n || p.id.size() != n || p.parent.size() != n)
    return "the packing's arrays have inconsistent sizes";
  if (!(std::isfinite(p.box.L) && p.box.L > 0)) return "L: must be finite and > 0 (got " + format_double(p.box.L) + ")";
  if (!std::isfinite(p.box.shear)) return "shear: must be finite (got " + format_double(p.box.shear) + ")";
  std::vector<std::int64_t> ids = p.id;
  std::sort(ids.begin(), ids.end());
  if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) return "duplicate cell ids";
  for (const auto& [key, value] : meta.values)
    if (auto problem = meta_problem(key, value)) return problem;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (p.id[i] < 0 || p.id[i] >= p.next_id || p.parent[i] < -1 || p.parent[i] >= p.next_id)
      return "cell " + std::to_string(i) + ": id or parent outside [0, next_id)";
    const std::pair<const char*, double> v[5] = {
        {"x", p.q[3 * i]}, {"y", p.q[3 * i + 1]}, {"theta", p.q[3 * i + 2]}, {"b", p.b[i]}, {"gamma0", p.gamma0[i]}};
    for (const auto& [name, x] : v)
      if (!std::isfinite(x)) return name + at + ": not finite (got " + format_double(x) + ")";
    if (!(p.b[i] >= 0)) return "b" + at + ": must be >= 0 (got " + format_double(p.b[i]) + ")";
    if (!(p.gamma0[i] >= 0)) return "gamma0" + at + ": must be >= 0 (got " + format_double(p.gamma0[i]) + ")";
  }
  return std::nullopt;
}

std::string format_packing(const Packing& p, const PackingMeta& meta) {
  if (const auto problem = unwritable_problem(p, meta)) throw std::invalid_argument("format_packing: " + *problem);
  const std::size_t n = p.size();
  std::string s;
  s.reserve(64 * n + 256);
  s += std::string(kPackingMagic) + " " + std::to_string(kPackingFormatVersion) + "\n";
  s += "L " + format_double(p.box.L) + "\n";
  s += "shear " + format_double(p.box.shear) + "\n";
  s += "N " + std::to_string(n) + "\n";
  s += "next_id " + std::to_string(p.next_id) + "\n";
  for (const auto& [key, value] : meta.values) {
    s += "meta " + key;
    if (!value.empty()) s += " " + value;
    s += "\n";
  }
  s += "cells id parent x y theta b gamma0\n";
  for (std::size_t i = 0; i < n; ++i) {
    const double v[5] = {p.q[3 * i], p.q[3 * i + 1], p.q[3 * i + 2], p.b[i], p.gamma0[i]};
    s += std::to_string(p.id[i]);
    s += ' ';
    s += std::to_string(p.parent[i]);
    for (double x : v) {
      s += ' ';
      s += format_double(x);
    }
    s += '\n';
  }
  s += "end\n";
  return s;
}

PackingFile parse_packing(std::string_view text, const std::string& source) { return Reader(text, source).read(); }

void write_packing(const std::filesystem::path& path, const Packing& packing, const PackingMeta& meta) {
  write_atomically(path, format_packing(packing, meta));
}

void write_packing(const Directory& dir, std::string_view name, const Packing& packing, const PackingMeta& meta) {
  write_atomically(dir, name, format_packing(packing, meta));
}

PackingFile read_packing(const std::filesystem::path& path) {
  PackingFile file = parse_packing(read_text_file(path), path.string());
  file.source = path;
  return file;
}

bool looks_like_packing(std::string_view text) {
  if (text.starts_with(kUtf8ByteOrderMark)) text.remove_prefix(kUtf8ByteOrderMark.size());  // refused by the reader
  return text.starts_with(kPackingMagic);
}

PackingMeta state_meta(const StateView& s, const std::string& kind, std::uint64_t seed, std::optional<double> dphi) {
  PackingMeta meta;
  meta.set("kind", kind);
  meta.set("phase", to_string(s.phase));
  meta.set_integer("step", s.step);
  meta.set_integer("seed", static_cast<std::int64_t>(seed));
  meta.set_number("phi", s.phi);
  meta.set_number("P", s.P);
  meta.set_number("E_per_cell", s.E_per_cell);
  if (s.scene->P0)
    meta.set_number("P0", *s.scene->P0);
  else
    meta.set("P0", "none");
  if (s.jamming) meta.set_number("phi_J", s.jamming->phi);
  if (dphi) meta.set_number("dphi", *dphi);
  if (s.network) {
    meta.set_integer("N_nr", static_cast<std::int64_t>(s.network->N_nr));
    meta.set_number("Z", s.network->Z);
  }
  return meta;
}

}  // namespace budjam::io
