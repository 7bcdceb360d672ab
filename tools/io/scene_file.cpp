#include "io/scene_file.hpp"

#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <regex>
#include <stdexcept>

namespace budjam::io {
namespace {

// ---- reading TOML values, with one-line errors naming the key ---------------------------------

std::string escape_string(std::string_view s) {
  std::string out = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", c);
          out += buf;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

// A TOML value as a short single line, for "(got ...)".
std::string describe(const toml::node& n) {
  if (n.is_table()) return "a table";
  if (const auto* a = n.as_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (i) s += ", ";
      if (i == 8) return s + "...]";
      s += describe(*a->get(i));
    }
    return s + "]";
  }
  if (const auto* v = n.as_string()) {
    std::string t = v->get();
    if (t.size() > 40) t = t.substr(0, 40) + "...";
    return escape_string(t);
  }
  if (const auto* v = n.as_integer()) return std::to_string(v->get());
  if (const auto* v = n.as_floating_point()) return format_double(v->get());
  if (const auto* v = n.as_boolean()) return v->get() ? "true" : "false";
  return "a date/time";
}

[[noreturn]] void type_error(const std::string& key, const std::string& expected, const toml::node& n) {
  throw InputError(key + ": expected " + expected + " (got " + describe(n) + ")");
}

double read_double(const toml::node& n, const std::string& key) {
  if (const auto* v = n.as_floating_point()) return v->get();
  if (const auto* v = n.as_integer()) return static_cast<double>(v->get());
  type_error(key, "a number", n);
}

std::int64_t read_integer(const toml::node& n, const std::string& key, std::int64_t lo, std::int64_t hi) {
  std::int64_t v = 0;
  if (const auto* i = n.as_integer()) {
    v = i->get();
  } else if (const auto* f = n.as_floating_point()) {
    // 1e6 is a fine way to write a step count; 1.5 is not.
    const double d = f->get();
    if (!(std::isfinite(d) && d == std::trunc(d) && std::abs(d) < 9.0e18)) type_error(key, "an integer", n);
    v = static_cast<std::int64_t>(d);
  } else {
    type_error(key, "an integer", n);
  }
  if (v < lo || v > hi) {
    const std::string range =
        lo == 0 ? "a non-negative integer" : "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    type_error(key, range, n);
  }
  return v;
}

bool read_bool(const toml::node& n, const std::string& key) {
  if (const auto* v = n.as_boolean()) return v->get();
  type_error(key, "true or false", n);
}

std::string read_string(const toml::node& n, const std::string& key) {
  if (const auto* v = n.as_string()) return v->get();
  type_error(key, "a string", n);
}

std::string read_choice(const toml::node& n, const std::string& key, const std::vector<std::string>& choices) {
  std::string names;
  for (const auto& name : choices) names += (names.empty() ? "\"" : ", \"") + name + "\"";
  const auto* s = n.as_string();
  if (!s || std::find(choices.begin(), choices.end(), s->get()) == choices.end()) type_error(key, "one of " + names, n);
  return s->get();
}

std::vector<double> read_reals(const toml::node& n, const std::string& key) {
  const auto* a = n.as_array();
  if (!a) type_error(key, "an array of numbers", n);
  std::vector<double> v;
  for (const auto& item : *a) {
    if (!item.is_number()) type_error(key, "an array of numbers", n);
    v.push_back(read_double(item, key));
  }
  return v;
}

// A TOML value as the value of the row's type; InputError "<key>: expected ... (got ...)".
SceneValue read_value(const SceneKey& k, const toml::node& n) {
  const std::string key = k.key();
  switch (k.type) {
    case KeyType::text: return read_string(n, key);
    case KeyType::choice: return read_choice(n, key, k.choices);
    case KeyType::flag: return read_bool(n, key);
    case KeyType::integer: return read_integer(n, key, k.min_integer, k.max_integer);
    case KeyType::real: return read_double(n, key);
    case KeyType::real_or_none:
      if (n.is_number()) return read_double(n, key);
      if (const auto* str = n.as_string(); str && str->get() == "none") return str->get();
      type_error(key, "a number or \"none\"", n);
    case KeyType::reals: return read_reals(n, key);
  }
  throw std::logic_error("read_value: unhandled key type");
}

// Sections in file order, with their parents ("observe" for "observe.moduli").
std::vector<std::string> sections() {
  std::vector<std::string> out;
  for (const auto& k : scene_keys())
    if (std::find(out.begin(), out.end(), k.section) == out.end()) out.push_back(k.section);
  return out;
}

bool is_section(const std::string& key) {
  const auto s = sections();
  return std::find(s.begin(), s.end(), key) != s.end();
}

std::string known_keys_of(const std::string& section) {
  std::string out;
  for (const auto& k : scene_keys())
    if (k.section == section) out += (out.empty() ? "" : ", ") + k.name;
  for (const auto& s : sections())  // sub-tables such as [observe.moduli]
    if (s.size() > section.size() && s.compare(0, section.size() + 1, section + ".") == 0) out += ", [" + s + "]";
  return out;
}

std::string top_sections() {
  std::string out;
  for (const auto& s : sections())
    if (s.find('.') == std::string::npos) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::string location(const std::string& source, const toml::source_region& r) {
  return source + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

void read_table(const toml::table& table, const std::string& prefix, Scene& scene, const std::string& source) {
  for (const auto& [k, node] : table) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    const std::string where = location(source, k.source());
    if (is_section(key)) {
      const auto* sub = node.as_table();
      if (!sub) throw InputError(where + ": " + key + ": expected a table [" + key + "] (got " + describe(node) + ")");
      read_table(*sub, key, scene, source);
      continue;
    }
    const SceneKey* row = find_scene_key(key);
    if (!row) {
      if (!prefix.empty())
        throw InputError(where + ": " + key + ": unknown key (known in [" + prefix + "]: " + known_keys_of(prefix) +
                         ")");
      if (node.is_table()) throw InputError(where + ": " + key + ": unknown section (known: " + top_sections() + ")");
      throw InputError(where + ": " + key + ": unknown key; keys belong in sections (" + top_sections() + ")");
    }
    try {
      row->set(scene, read_value(*row, node));
    } catch (const InputError& err) {
      throw InputError(location(source, node.source()) + ": " + err.what());
    }
  }
}

// `key = word` on line `line` (1-based) with a bare word for its value, as in `P0 = none`: TOML
// takes it for a malformed number or boolean; the hint names the key and the quoted form.
std::string bare_word_hint(std::string_view text, std::size_t line) {
  std::string section, row;
  std::size_t at = 0;
  for (std::size_t n = 1; at <= text.size() && n <= line; ++n) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    row = std::string(text.substr(at, end - at));
    if (const auto l = row.find_first_not_of(" \t"); n < line && l != std::string::npos && row[l] == '[') {
      const auto r = row.find(']', l);
      if (r != std::string::npos) section = row.substr(l + 1, r - l - 1);
    }
    at = end + 1;
  }
  static const std::regex assignment(R"(^\s*([A-Za-z0-9_-]+)\s*=\s*([A-Za-z_][A-Za-z0-9_-]*)\s*(#.*)?\r?$)");
  std::smatch m;
  if (!std::regex_match(row, m, assignment)) return "";
  const std::string word = m[2];
  if (word == "true" || word == "false" || word == "inf" || word == "nan") return "";
  const std::string key = m[1];
  return (section.empty() ? "" : section + ".") + key + " = " + word + ": a text value is quoted in TOML (" + key +
         " = \"" + word + "\"); ";
}

toml::table parse_toml(std::string_view text, const std::string& source) {
  if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
    throw InputError(source +
                     ": empty scene file (a scene names at least one section; [run] alone gives the defaults)");
  // toml++ 3.3 must not see text that is not UTF-8: on some of it, it reaches TOML_UNREACHABLE.
  if (const std::string at = first_invalid_utf8(text); !at.empty())
    throw InputError(source + ":" + at + ": not valid UTF-8 (scene files are UTF-8 text)");
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& err) {
    const auto& b = err.source().begin;
    std::string what(err.description());
    std::replace(what.begin(), what.end(), '\n', ' ');
    throw InputError(source + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                     bare_word_hint(text, b.line) + what);
  }
}

}  // namespace

// ---- public API ------------------------------------------------------------------------------

void apply_override(Scene& scene, std::string_view assignment) {
  const std::string prefix = "--set " + std::string(assignment) + ": ";
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos) throw InputError(prefix + "expected section.key=value");
  auto trim = [](std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
  };
  const std::string key(trim(assignment.substr(0, eq)));
  const std::string value(trim(assignment.substr(eq + 1)));
  const SceneKey* k = find_scene_key(key);
  if (!k) {
    const auto dot = key.rfind('.');
    const std::string sec = dot == std::string::npos ? "" : key.substr(0, dot);
    if (is_section(sec))
      throw InputError(prefix + key + ": unknown key (known in [" + sec + "]: " + known_keys_of(sec) + ")");
    throw InputError(prefix + key + ": unknown key (sections: " + top_sections() + ")");
  }
  if (value.find_first_of("\r\n") != std::string::npos) throw InputError(prefix + key + ": the value must be one line");
  // The value is TOML when it parses as one; otherwise a bare word is a string (P0=none).
  std::optional<toml::table> parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {}
  try {
    if (parsed && parsed->size() == 1 && parsed->contains("v")) {
      k->set(scene, read_value(*k, *parsed->get("v")));
    } else {
      const toml::value<std::string> text(value);
      k->set(scene, read_value(*k, text));
    }
  } catch (const InputError& err) {
    throw InputError(prefix + err.what());
  }
}

Scene parse_scene(std::string_view toml_text, const std::string& source, const std::vector<std::string>& overrides) {
  const toml::table table = parse_toml(toml_text, source);
  Scene scene;
  read_table(table, "", scene, source);
  for (const auto& o : overrides) apply_override(scene, o);
  try {
    validate(scene);
  } catch (const InputError& err) {
    // A rule broken by a value that --set gave (the last --set of that key) is the command line's,
    // not the file's: the message names the key first ("growth.P0: must be positive"), or, for a
    // rule between two keys, names it further on ("growth.dt_min: must be smaller than growth.dt").
    const std::string what = err.what();
    const auto key_of = [](const std::string& o) {
      std::string key = o.substr(0, o.find('='));
      key.erase(std::remove_if(key.begin(), key.end(), [](char c) { return c == ' ' || c == '\t'; }), key.end());
      return key;
    };
    const auto names = [&what](const std::string& key) {  // the key as a whole word, not a prefix of one
      for (auto at = what.find(key); !key.empty() && at != std::string::npos; at = what.find(key, at + 1)) {
        const auto end = at + key.size();
        const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; };
        if ((at == 0 || !word(what[at - 1])) && (end == what.size() || !word(what[end]) || what[end] == '.'))
          return true;
      }
      return false;
    };
    for (auto o = overrides.rbegin(); o != overrides.rend(); ++o)
      if (const std::string key = key_of(*o); !key.empty() && what.rfind(key + ":", 0) == 0)
        throw InputError("--set " + *o + ": " + what);
    for (auto o = overrides.rbegin(); o != overrides.rend(); ++o)
      if (names(key_of(*o))) throw InputError("--set " + *o + ": " + what);
    throw InputError(source + ": " + what);
  }
  return scene;
}

Scene load_scene(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  return parse_scene(read_text_file(path), path.string(), overrides);
}

std::string toml_literal(const SceneValue& value) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const {
      std::string s = format_double(d);
      // TOML needs a '.' or an exponent to read a float back as a float.
      if (s.find_first_of(".eni") == std::string::npos) s += ".0";
      return s;
    }
    std::string operator()(const std::string& s) const { return escape_string(s); }
    std::string operator()(const std::vector<double>& v) const {
      std::string s = "[";
      for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + (*this)(v[i]);
      return s + "]";
    }
  };
  return std::visit(Visitor{}, value);
}

std::string scene_to_toml(const Scene& scene, bool comments) {
  std::string out = "# budjam scene: every key with its effective value\n";
  std::string section;
  for (const auto& k : scene_keys()) {
    if (k.section != section) {
      section = k.section;
      out += "\n[" + section + "]\n";
    }
    std::string line = k.name + " = " + toml_literal(k.get(scene));
    if (comments) {
      line.resize(std::max<std::size_t>(line.size() + 2, 34), ' ');
      line += "# " + k.help;
    }
    out += line + "\n";
  }
  return out;
}

Json scene_to_json(const Scene& scene) {
  Json out = Json::object();
  for (const auto& k : scene_keys()) {
    Json* at = &out;
    std::string sec = k.section;
    for (std::size_t start = 0;;) {
      const auto dot = sec.find('.', start);
      at = &(*at)[sec.substr(start, dot - start)];
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    (*at)[k.name] = std::visit([](const auto& v) { return Json(v); }, k.get(scene));
  }
  return out;
}

std::string scene_keys_markdown() {
  auto cell = [](const std::string& text) {  // a '|' would end the cell
    std::string escaped;
    for (const char c : text) {
      if (c == '|') escaped += '\\';
      escaped += c;
    }
    return escaped;
  };
  const Scene defaults;
  std::string out = "| key | type | default | accepted | meaning |\n|-----|------|---------|----------|---------|\n";
  for (const auto& k : scene_keys()) {
    std::string type, accepted;
    const std::string range = k.range.interval() + k.range.why;
    switch (k.type) {
      case KeyType::text: type = "string", accepted = "non-empty, one line"; break;
      case KeyType::choice:
        type = "choice";
        for (const auto& c : k.choices) {
          accepted += accepted.empty() ? "`\"" : "`, `\"";
          accepted += c + "\"";
        }
        accepted += "`";
        break;
      case KeyType::flag: type = "bool"; break;
      case KeyType::integer:
        type = "integer", accepted = range.empty() ? std::string("≥ ") + std::to_string(k.min_integer) : range;
        break;
      case KeyType::real: type = "number", accepted = range; break;
      case KeyType::real_or_none: type = "number or `\"none\"`", accepted = range; break;
      case KeyType::reals:
        type = "list of numbers", accepted = std::string("each ") + range + ", strictly increasing";
        break;
    }
    out += "| `" + k.key() + "` | " + type + " | `" + toml_literal(k.get(defaults)) + "` | " + cell(accepted) + " | " +
           cell(k.help) + " |\n";
  }
  return out;
}

}  // namespace budjam::io
