#include "io/scene_file.hpp"

#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

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
    const std::string range = lo == 0 ? "a non-negative integer" : "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
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

template <class E>
E read_choice(const toml::node& n, const std::string& key, const std::vector<std::pair<std::string, E>>& choices) {
  std::string names;
  for (const auto& [name, value] : choices) names += (names.empty() ? "\"" : ", \"") + name + "\"";
  const auto* s = n.as_string();
  if (!s) type_error(key, "one of " + names, n);
  for (const auto& [name, value] : choices)
    if (s->get() == name) return value;
  type_error(key, "one of " + names, n);
}

const std::vector<std::pair<std::string, DivisionRule>> kDivision = {
    {"random", DivisionRule::random}, {"aligned", DivisionRule::aligned}, {"opposite", DivisionRule::opposite}};
const std::vector<std::pair<std::string, InitialState>> kInit = {{"two_cells", InitialState::two_cells},
                                                                 {"random_seeds", InitialState::random_seeds}};
const std::vector<std::pair<std::string, JammingSearch>> kSearch = {{"bisection", JammingSearch::bisection},
                                                                   {"secant", JammingSearch::secant}};

template <class E>
std::string choice_name(E value, const std::vector<std::pair<std::string, E>>& choices) {
  for (const auto& [name, v] : choices)
    if (v == value) return name;
  return "?";
}

// ---- the key table: the one place every scene key is spelled ----------------------------------

struct Entry {
  SceneKeyInfo info;
  std::function<void(Scene&, const toml::node&, const std::string&)> set;
  std::function<SceneValue(const Scene&)> get;
};

// `ref` is a generic lambda returning a reference to the field in a Scene or const Scene.
template <class Ref>
Entry real(std::string sec, std::string name, std::string help, Ref ref) {
  return {{std::move(sec), std::move(name), std::move(help)},
          [ref](Scene& s, const toml::node& n, const std::string& key) { ref(s) = read_double(n, key); },
          [ref](const Scene& s) -> SceneValue { return static_cast<double>(ref(s)); }};
}

template <class Ref>
Entry integer(std::string sec, std::string name, std::string help, Ref ref) {
  using T = std::remove_cvref_t<decltype(ref(std::declval<Scene&>()))>;
  constexpr std::int64_t lo = std::is_signed_v<T> ? static_cast<std::int64_t>(std::numeric_limits<T>::min()) : 0;
  constexpr std::int64_t hi =
      static_cast<std::uint64_t>(std::numeric_limits<T>::max()) > static_cast<std::uint64_t>(INT64_MAX)
          ? INT64_MAX
          : static_cast<std::int64_t>(std::numeric_limits<T>::max());
  return {{std::move(sec), std::move(name), std::move(help)},
          [ref](Scene& s, const toml::node& n, const std::string& key) {
            ref(s) = static_cast<T>(read_integer(n, key, lo, hi));
          },
          [ref](const Scene& s) -> SceneValue { return static_cast<std::int64_t>(ref(s)); }};
}

template <class Ref>
Entry boolean(std::string sec, std::string name, std::string help, Ref ref) {
  return {{std::move(sec), std::move(name), std::move(help)},
          [ref](Scene& s, const toml::node& n, const std::string& key) { ref(s) = read_bool(n, key); },
          [ref](const Scene& s) -> SceneValue { return static_cast<bool>(ref(s)); }};
}

#define BUDJAM_FIELD(member) [](auto& s) -> auto& { return s.member; }

std::vector<Entry> make_entries() {
  std::vector<Entry> e;
  e.push_back({{"run", "name", "label stored with the results"},
               [](Scene& s, const toml::node& n, const std::string& key) { s.name = read_string(n, key); },
               [](const Scene& s) -> SceneValue { return s.name; }});
  e.push_back(integer("run", "seed", "random seed; same scene + same seed = same run", BUDJAM_FIELD(seed)));

  e.push_back(real("box", "L", "side of the periodic square box, in mother diameters", BUDJAM_FIELD(L)));

  e.push_back(real("cells", "r0", "mean innate growth rate r0 (per unit step)", BUDJAM_FIELD(r0)));
  e.push_back(real("cells", "delta", "spread of innate rates: γ0 = r0 (1 + δ (U − 1/2))", BUDJAM_FIELD(delta)));
  e.push_back(real("cells", "alpha0", "aspect ratio of a newborn cell; division at 2 α0", BUDJAM_FIELD(alpha0)));
  e.push_back({{"cells", "division", "orientation of newborn cells: \"random\", \"aligned\" or \"opposite\""},
               [](Scene& s, const toml::node& n, const std::string& key) { s.division = read_choice(n, key, kDivision); },
               [](const Scene& s) -> SceneValue { return choice_name(s.division, kDivision); }});

  e.push_back({{"init", "kind", "initial state: \"two_cells\" (the paper's) or \"random_seeds\""},
               [](Scene& s, const toml::node& n, const std::string& key) { s.init = read_choice(n, key, kInit); },
               [](const Scene& s) -> SceneValue { return choice_name(s.init, kInit); }});
  e.push_back(integer("init", "cells", "number of newborn cells placed at random (random_seeds only)",
                      BUDJAM_FIELD(n_seeds)));

  e.push_back({{"growth", "P0", "feedback pressure scale of γ = γ0 exp(−p/P0), or \"none\" for no feedback"},
               [](Scene& s, const toml::node& n, const std::string& key) {
                 if (const auto* str = n.as_string()) {
                   if (str->get() != "none") type_error(key, "a number or \"none\"", n);
                   s.P0.reset();
                 } else if (n.is_number()) {
                   s.P0 = read_double(n, key);
                 } else {
                   type_error(key, "a number or \"none\"", n);
                 }
               },
               [](const Scene& s) -> SceneValue {
                 if (s.P0) return *s.P0;
                 return std::string("none");
               }});
  e.push_back(real("growth", "dt", "nominal growth step Δt", BUDJAM_FIELD(dt)));
  e.push_back(real("growth", "dt_min", "a bisected step below this is a failure", BUDJAM_FIELD(dt_min)));
  e.push_back(integer("growth", "max_steps", "growth steps (accepted + rejected) before the run fails",
                      BUDJAM_FIELD(max_steps)));
  e.push_back(boolean("growth", "adaptive_dt",
                      "above jamming with feedback, start each step from dt / max(max_i exp(-p_i/P0), adaptive_floor)",
                      BUDJAM_FIELD(adaptive_dt)));
  e.push_back(real("growth", "adaptive_floor", "smallest growth factor used by adaptive_dt, in (0, 1]",
                   BUDJAM_FIELD(adaptive_floor)));

  e.push_back(real("jamming", "epsilon_U", "energy per cell below which a packing is unjammed", BUDJAM_FIELD(epsilon_U)));
  e.push_back(real("jamming", "target_tolerance", "landing tolerance |φ − (φ_J + Δφ)|", BUDJAM_FIELD(target_tolerance)));
  e.push_back({{"jamming", "targets", "Δφ above jamming to visit, strictly increasing, e.g. [1e-3, 1e-2]"},
               [](Scene& s, const toml::node& n, const std::string& key) {
                 const auto* a = n.as_array();
                 if (!a) type_error(key, "an array of numbers", n);
                 std::vector<double> v;
                 for (const auto& item : *a) {
                   if (!item.is_number()) type_error(key, "an array of numbers", n);
                   v.push_back(read_double(item, key));
                 }
                 s.targets = std::move(v);
               },
               [](const Scene& s) -> SceneValue { return s.targets; }});
  e.push_back(boolean("jamming", "continue_to_phi2", "keep growing past the last target until φ_2 is found",
                      BUDJAM_FIELD(continue_to_phi2)));
  e.push_back(real("jamming", "max_dphi", "never grow beyond φ_J + max_dphi", BUDJAM_FIELD(max_dphi)));
  e.push_back(boolean("jamming", "check_minimum",
                      "a jamming candidate that is a saddle (Hessian with an unstable mode) is relaxed further",
                      BUDJAM_FIELD(check_minimum)));
  // Speed knob (docs/growth.md, "Jamming search").
  e.push_back({{"jamming", "search", "step choice near φ_J and the targets: \"secant\" or \"bisection\" (MODEL.md's)"},
               [](Scene& s, const toml::node& n, const std::string& key) { s.search = read_choice(n, key, kSearch); },
               [](const Scene& s) -> SceneValue { return choice_name(s.search, kSearch); }});

  e.push_back(real("minimiser", "dt_start", "FIRE initial time step", BUDJAM_FIELD(fire.dt_start)));
  e.push_back(real("minimiser", "dt_max", "FIRE largest time step", BUDJAM_FIELD(fire.dt_max)));
  e.push_back(real("minimiser", "dt_min", "FIRE smallest time step", BUDJAM_FIELD(fire.dt_min)));
  e.push_back(integer("minimiser", "n_delay", "FIRE steps before the time step may grow", BUDJAM_FIELD(fire.n_delay)));
  e.push_back(real("minimiser", "f_inc", "FIRE time step growth factor", BUDJAM_FIELD(fire.f_inc)));
  e.push_back(real("minimiser", "f_dec", "FIRE time step shrink factor", BUDJAM_FIELD(fire.f_dec)));
  e.push_back(real("minimiser", "alpha_start", "FIRE initial mixing α", BUDJAM_FIELD(fire.alpha_start)));
  e.push_back(real("minimiser", "f_alpha", "FIRE mixing decay factor", BUDJAM_FIELD(fire.f_alpha)));
  e.push_back(real("minimiser", "force_tol", "relaxed when the largest generalised force is below this",
                   BUDJAM_FIELD(fire.force_tol)));
  e.push_back(real("minimiser", "energy_floor", "relaxed (certainly unjammed) when E/N is below this",
                   BUDJAM_FIELD(fire.energy_floor)));
  e.push_back(integer("minimiser", "max_iterations", "FIRE iterations before a minimisation fails",
                      BUDJAM_FIELD(fire.max_iterations)));
  // Speed knob (docs/minimiser.md, "Newton finish").
  e.push_back(real("minimiser", "newton_force",
                   "below this largest force, Newton steps with the analytic Hessian finish the minimisation; 0 = FIRE alone",
                   BUDJAM_FIELD(fire.newton_force)));
  e.push_back(real("minimiser", "skin", "Verlet skin of the neighbour list, in mother diameters", BUDJAM_FIELD(skin)));

  e.push_back(boolean("observe", "bud_events", "track unconstrained buds from jamming on (bud_events.csv)",
                      BUDJAM_FIELD(bud_events)));
  e.push_back(boolean("observe", "rigidity_events", "log rigidity (pebble game) along the run",
                      BUDJAM_FIELD(rigidity_events)));
  e.push_back(integer("observe", "checkpoint_every", "accepted steps between checkpoints; 0 = none",
                      BUDJAM_FIELD(checkpoint_every)));
  e.push_back(boolean("observe", "progress", "progress line on stderr", BUDJAM_FIELD(progress)));
  for (const char* which : {"moduli", "dos"}) {
    const std::string sec = std::string("observe.") + which;
    const std::string what = std::string(which) == "moduli" ? "elastic moduli" : "density of states";
    const bool m = std::string(which) == "moduli";
    auto at = [m](auto& s) -> auto& { return m ? s.moduli : s.dos; };
    e.push_back(boolean(sec, "at_jamming", "compute the " + what + " at jamming",
                        [at](auto& s) -> auto& { return at(s).at_jamming; }));
    e.push_back(boolean(sec, "at_phi2", "compute the " + what + " at φ_2", [at](auto& s) -> auto& { return at(s).at_phi2; }));
    e.push_back(boolean(sec, "at_targets", "compute the " + what + " at each target",
                        [at](auto& s) -> auto& { return at(s).at_targets; }));
    e.push_back(integer(sec, "every", "compute the " + what + " every k accepted steps above jamming; 0 = never",
                        [at](auto& s) -> auto& { return at(s).every; }));
  }
  return e;
}

#undef BUDJAM_FIELD

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = make_entries();
  return e;
}

const Entry* find_entry(std::string_view key) {
  for (const auto& e : entries())
    if (e.info.key() == key) return &e;
  return nullptr;
}

// Sections in file order, with their parents ("observe" for "observe.moduli").
std::vector<std::string> sections() {
  std::vector<std::string> out;
  for (const auto& e : entries())
    if (std::find(out.begin(), out.end(), e.info.section) == out.end()) out.push_back(e.info.section);
  return out;
}

bool is_section(const std::string& key) {
  const auto s = sections();
  return std::find(s.begin(), s.end(), key) != s.end();
}

std::string known_keys_of(const std::string& section) {
  std::string out;
  for (const auto& e : entries())
    if (e.info.section == section) out += (out.empty() ? "" : ", ") + e.info.name;
  for (const auto& s : sections())  // sub-tables such as [observe.moduli]
    if (s.size() > section.size() && s.compare(0, section.size() + 1, section + ".") == 0)
      out += ", [" + s + "]";
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
    const Entry* e = find_entry(key);
    if (!e) {
      if (!prefix.empty())
        throw InputError(where + ": " + key + ": unknown key (known in [" + prefix + "]: " + known_keys_of(prefix) + ")");
      if (node.is_table())
        throw InputError(where + ": " + key + ": unknown section (known: " + top_sections() + ")");
      throw InputError(where + ": " + key + ": unknown key; keys belong in sections (" + top_sections() + ")");
    }
    try {
      e->set(scene, node, key);
    } catch (const InputError& err) {
      throw InputError(location(source, node.source()) + ": " + err.what());
    }
  }
}

toml::table parse_toml(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& err) {
    const auto& b = err.source().begin;
    std::string what(err.description());
    std::replace(what.begin(), what.end(), '\n', ' ');
    throw InputError(source + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " + what);
  }
}

}  // namespace

// ---- public API ------------------------------------------------------------------------------

const std::vector<SceneKeyInfo>& scene_keys() {
  static const std::vector<SceneKeyInfo> keys = [] {
    std::vector<SceneKeyInfo> k;
    for (const auto& e : entries()) k.push_back(e.info);
    return k;
  }();
  return keys;
}

SceneValue scene_value(const Scene& scene, std::string_view key) {
  const Entry* e = find_entry(key);
  if (!e) throw InputError(std::string(key) + ": unknown key");
  return e->get(scene);
}

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
  const Entry* e = find_entry(key);
  if (!e) {
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
  } catch (const toml::parse_error&) {
  }
  try {
    if (parsed && parsed->size() == 1 && parsed->contains("v")) {
      e->set(scene, *parsed->get("v"), key);
    } else {
      const toml::value<std::string> text(value);
      e->set(scene, text, key);
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
    throw InputError(source + ": " + err.what());
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
  for (const auto& e : entries()) {
    if (e.info.section != section) {
      section = e.info.section;
      out += "\n[" + section + "]\n";
    }
    std::string line = e.info.name + " = " + toml_literal(e.get(scene));
    if (comments) {
      line.resize(std::max<std::size_t>(line.size() + 2, 34), ' ');
      line += "# " + e.info.help;
    }
    out += line + "\n";
  }
  return out;
}

Json scene_to_json(const Scene& scene) {
  Json out = Json::object();
  for (const auto& e : entries()) {
    Json* at = &out;
    std::string sec = e.info.section;
    for (std::size_t start = 0;;) {
      const auto dot = sec.find('.', start);
      at = &(*at)[sec.substr(start, dot - start)];
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    (*at)[e.info.name] = std::visit([](const auto& v) { return Json(v); }, e.get(scene));
  }
  return out;
}

}  // namespace budjam::io
