// The knob table. To add a knob: give Scene (or a struct inside it) the field with its default,
// then add one row to make_keys(), in its section. The builder names the type (real, integer,
// flag, choice; row() with its own get/set for the rest), then come section, name, help, the
// accepted range (above, at_least, at_most, between) and the field, e.g.
//   e.push_back(real("jamming", "newton_threshold", "...", above(0), BUDJAM_FIELD(newton_threshold)));
// Reader, --set, writers, validate() and the docs table follow; a rule that ties the knob to other
// keys goes into validate() (src/scene.cpp), and docs/files.md's table is regenerated with
// `budjam validate --keys-markdown` (test_scene checks that it is).
#include "budjam/scene_keys.hpp"

#include "budjam/errors.hpp"
#include "budjam/jamming.hpp"
#include "budjam/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace budjam {

std::string describe_choices(const std::vector<Choice>& choices) {
  std::string text;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    if (k > 0) text += k + 1 == choices.size() ? " or " : ", ";
    text.append("\"").append(choices[k].name).append("\" (").append(choices[k].meaning).append(")");
  }
  return text;
}

std::string value_text(const SceneValue& value) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const { return shortest_text(d); }
    std::string operator()(const std::string& s) const { return "\"" + s + "\""; }
    // A long list (10⁶ targets, say) as its first and last values and its length: one short line.
    std::string operator()(const std::vector<double>& v) const {
      constexpr std::size_t kHead = 4, kTail = 2;
      std::string s = "[";
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (v.size() > kHead + kTail + 1 && i == kHead) {
          s += ", ... (" + std::to_string(v.size()) + " values) ...";
          i = v.size() - kTail - 1;
          continue;
        }
        s += (i ? ", " : "") + shortest_text(v[i]);
      }
      return s + "]";
    }
  };
  return std::visit(Visitor{}, value);
}

namespace {

[[noreturn]] void fail_key(const std::string& key, const std::string& problem, const SceneValue& got) {
  throw InputError(key + ": " + problem + " (got " + value_text(got) + ")");
}
[[noreturn]] void fail(const SceneKey& k, const std::string& problem, const SceneValue& got) {
  fail_key(k.key(), problem, got);
}

// ---- ranges ------------------------------------------------------------------------------

Range above(double lo, std::string why = "") {
  Range r;
  r.lo = lo, r.lo_open = true, r.why = std::move(why);
  return r;
}
Range at_least(double lo, std::string why = "") {
  Range r;
  r.lo = lo, r.why = std::move(why);
  return r;
}
Range at_most(double hi, std::string why) {
  Range r;
  r.hi = hi, r.why = std::move(why);
  return r;
}
// An interval with finite ends; `ends` is "()", "(]", "[)" or "[]".
Range between(double lo, double hi, std::string_view ends, std::string why = "") {
  Range r;
  r.lo = lo, r.lo_open = ends[0] == '(', r.hi = hi, r.hi_open = ends[1] == ')', r.why = std::move(why);
  return r;
}

// ---- row builders: `ref` returns a reference to the field in a Scene or const Scene ---------

SceneKey row(std::string section, std::string name, KeyType type, std::string help, Range range = {}) {
  SceneKey k;
  k.section = std::move(section), k.name = std::move(name), k.type = type, k.help = std::move(help);
  k.range = std::move(range);
  return k;
}

#define BUDJAM_FIELD(member) \
  [](auto& s) -> auto& { return s.member; }

template <class Ref>
SceneKey real(std::string sec, std::string name, std::string help, Range range, Ref ref) {
  SceneKey k = row(std::move(sec), std::move(name), KeyType::real, std::move(help), std::move(range));
  k.get = [ref](const Scene& s) -> SceneValue { return static_cast<double>(ref(s)); };
  k.set = [ref](Scene& s, const SceneValue& v) { ref(s) = std::get<double>(v); };
  return k;
}

template <class Ref>
SceneKey integer(std::string sec, std::string name, std::string help, Range range, Ref ref) {
  using T = std::remove_cvref_t<decltype(ref(std::declval<Scene&>()))>;
  SceneKey k = row(std::move(sec), std::move(name), KeyType::integer, std::move(help), std::move(range));
  k.min_integer = std::is_signed_v<T> ? static_cast<std::int64_t>(std::numeric_limits<T>::min()) : 0;
  // Scene files hold TOML integers (signed 64 bit).
  k.max_integer = static_cast<std::uint64_t>(std::numeric_limits<T>::max()) > static_cast<std::uint64_t>(INT64_MAX)
                      ? INT64_MAX
                      : static_cast<std::int64_t>(std::numeric_limits<T>::max());
  k.get = [ref](const Scene& s) -> SceneValue { return static_cast<std::int64_t>(ref(s)); };
  k.set = [ref](Scene& s, const SceneValue& v) { ref(s) = static_cast<T>(std::get<std::int64_t>(v)); };
  return k;
}

template <class Ref>
SceneKey flag(std::string sec, std::string name, std::string help, Ref ref) {
  SceneKey k = row(std::move(sec), std::move(name), KeyType::flag, std::move(help));
  k.get = [ref](const Scene& s) -> SceneValue { return static_cast<bool>(ref(s)); };
  k.set = [ref](Scene& s, const SceneValue& v) { ref(s) = std::get<bool>(v); };
  return k;
}

// `names` in the order of the enumerators of the field's enum (0, 1, ...).
template <class Ref>
SceneKey choice(std::string sec, std::string name, std::string help, std::vector<std::string> names, Ref ref) {
  using E = std::remove_cvref_t<decltype(ref(std::declval<Scene&>()))>;
  SceneKey k = row(std::move(sec), std::move(name), KeyType::choice, std::move(help));
  k.choices = names;
  k.get = [ref, names](const Scene& s) -> SceneValue { return names.at(static_cast<std::size_t>(ref(s))); };
  k.set = [ref, names, key = k.key()](Scene& s, const SceneValue& v) {
    const auto at = std::find(names.begin(), names.end(), std::get<std::string>(v));
    if (at == names.end()) fail_key(key, "is not one of the choices", v);
    ref(s) = static_cast<E>(at - names.begin());
  };
  return k;
}

const Range kPositive = above(0);
const Range kZeroOrPositive = at_least(0);

std::vector<SceneKey> make_keys() {
  std::vector<SceneKey> e;
  SceneKey name = row("run", "name", KeyType::text, "label stored with the results");
  name.get = [](const Scene& s) -> SceneValue { return s.name; };
  name.set = [](Scene& s, const SceneValue& v) { s.name = std::get<std::string>(v); };
  e.push_back(name);
  e.push_back(integer("run", "seed", "random seed; same scene + same seed = same run", {}, BUDJAM_FIELD(seed)));

  e.push_back(real("box", "L", "side of the periodic square box, in mother diameters",
                   at_most(kMaxBoxSide, " so that the seed placement and the cell list fit in memory"),
                   BUDJAM_FIELD(L)));

  e.push_back(real("cells", "r0", "mean innate growth rate r0 (per unit step)", kPositive, BUDJAM_FIELD(r0)));
  e.push_back(real("cells", "delta", "spread of innate rates: γ0 = r0 (1 + δ (U − 1/2))",
                   between(0, 2, "[)", " so that every γ0 > 0"), BUDJAM_FIELD(delta)));
  e.push_back(real("cells", "alpha0", "aspect ratio of a newborn cell; division at 2 α0", between(1, 2, "()"),
                   BUDJAM_FIELD(alpha0)));
  e.push_back(choice("cells", "division", "orientation of newborn cells: \"random\", \"aligned\" or \"opposite\"",
                     {"random", "aligned", "opposite"}, BUDJAM_FIELD(division)));

  e.push_back(choice("init", "kind", "initial state: \"two_cells\" (the paper's) or \"random_seeds\"",
                     {"two_cells", "random_seeds"}, BUDJAM_FIELD(init)));
  e.push_back(integer("init", "cells", "number of newborn cells placed at random (random_seeds only)",
                      at_most(kMaxInitialCells, " so that the initial state fits in memory"), BUDJAM_FIELD(n_seeds)));

  SceneKey P0 = row("growth", "P0", KeyType::real_or_none,
                    "feedback pressure scale of γ = γ0 exp(−p/P0), or \"none\" for no feedback",
                    at_least(kMinP0, " so that p/P0 stays finite, or \"none\" for no feedback"));
  P0.get = [](const Scene& s) -> SceneValue {
    if (s.P0) return *s.P0;
    return std::string("none");
  };
  P0.set = [](Scene& s, const SceneValue& v) {
    if (const auto* d = std::get_if<double>(&v))
      s.P0 = *d;
    else
      s.P0.reset();
  };
  e.push_back(P0);
  e.push_back(real("growth", "dt", "nominal growth step Δt", kPositive, BUDJAM_FIELD(dt)));
  e.push_back(real("growth", "dt_min", "a bisected step below this is a failure", kPositive, BUDJAM_FIELD(dt_min)));
  e.push_back(integer("growth", "max_steps",
                      "growth steps (accepted + rejected) before the run stops (status step_limit)", kPositive,
                      BUDJAM_FIELD(max_steps)));
  e.push_back(flag("growth", "adaptive_dt",
                   "above jamming with feedback, start each step from dt / max(max_i exp(-p_i/P0), adaptive_floor)",
                   BUDJAM_FIELD(adaptive_dt)));
  e.push_back(real("growth", "adaptive_floor", "smallest growth factor used by adaptive_dt, in [0, 1]; 0 = no floor",
                   between(0, 1, "[]"), BUDJAM_FIELD(adaptive_floor)));

  e.push_back(real("jamming", "epsilon_U", "energy per cell below which a packing is unjammed", kPositive,
                   BUDJAM_FIELD(epsilon_U)));
  e.push_back(real("jamming", "target_tolerance", "landing tolerance |φ − (φ_J + Δφ)|", kPositive,
                   BUDJAM_FIELD(target_tolerance)));
  SceneKey targets =
      row("jamming", "targets", KeyType::reals, "Δφ above jamming to visit, strictly increasing, e.g. [1e-3, 1e-2]",
          above(0, " (Δφ above jamming)"));
  targets.get = [](const Scene& s) -> SceneValue { return s.targets; };
  targets.set = [](Scene& s, const SceneValue& v) { s.targets = std::get<std::vector<double>>(v); };
  e.push_back(targets);
  e.push_back(flag("jamming", "continue_to_phi2", "keep growing past the last target until φ_2 is found",
                   BUDJAM_FIELD(continue_to_phi2)));
  e.push_back(
      real("jamming", "max_dphi", "never grow beyond φ_J + max_dphi",
           between(0, kMaxDphi, "(]", " so that grown packings keep every overlap below half its contact distance"),
           BUDJAM_FIELD(max_dphi)));
  e.push_back(integer("jamming", "phi2_tagged_left",
                      "φ_2 is the first state after jamming with at most this many tagged buds still unconstrained "
                      "(0: the paper's definition)",
                      kZeroOrPositive, BUDJAM_FIELD(phi2_tagged_left)));
  e.push_back(
      flag("jamming", "check_minimum",
           "a jamming candidate that is a saddle (Hessian with an unstable mode) is relaxed further, and stepped "
           "off along its unstable mode where FIRE stops on it again (docs/growth.md)",
           BUDJAM_FIELD(check_minimum)));
  std::vector<Choice> searches;
  std::vector<std::string> search_names;
  for (const JammingSearchKind& k : jamming_searches()) {
    searches.push_back({k.name, k.description});
    search_names.emplace_back(k.name);
  }
  e.push_back(choice("jamming", "search", "step choice near φ_J and the targets: " + describe_choices(searches),
                     search_names, BUDJAM_FIELD(search)));
  e.push_back(real("jamming", "jump_factor",
                   "bracket search: collapse the bracket when its two lowest overshoots, near its lower end, "
                   "extrapolate there to √(E/N) above this many times √(2ε_U) (0 = never)",
                   kZeroOrPositive, BUDJAM_FIELD(jump_factor)));
  e.push_back(flag("jamming", "start_across_divisions",
                   "bracket search: a trial starts from the lowest overshoot also when that overshoot divided more "
                   "cells (false = only with the same divisions)",
                   BUDJAM_FIELD(start_across_divisions)));
  e.push_back(integer("jamming", "trial_budget",
                      "bracket search: FIRE iterations after which a trial still above the window becomes a "
                      "deferred upper end, relaxed on only if the bracket closes in on it (0 = never)",
                      kZeroOrPositive, BUDJAM_FIELD(trial_budget)));
  e.push_back(flag("jamming", "continuation",
                   "bracket search: a trial starting from the lowest overshoot with the same divisions follows its "
                   "relaxed branch to the trial's sizes (Newton continuation) before FIRE (false = FIRE alone)",
                   BUDJAM_FIELD(continuation)));
  e.push_back(real("jamming", "crossing_step",
                   "with continuation: where the branch loses stability, FIRE relaxes the packing this much further "
                   "along the trial's path (fraction of it) and the branch goes on from there (0 = the branch ends)",
                   kZeroOrPositive, BUDJAM_FIELD(crossing_step)));

  // FIRE 2.0 (Guénolé et al. 2020, Table 1 gives the usual values).
  e.push_back(real("minimiser", "dt_start", "FIRE initial time step", kPositive, BUDJAM_FIELD(fire.dt_start)));
  e.push_back(real("minimiser", "dt_max", "FIRE largest time step", kPositive, BUDJAM_FIELD(fire.dt_max)));
  e.push_back(real("minimiser", "dt_min", "FIRE smallest time step", kPositive, BUDJAM_FIELD(fire.dt_min)));
  e.push_back(integer("minimiser", "n_delay", "FIRE steps before the time step may grow", kZeroOrPositive,
                      BUDJAM_FIELD(fire.n_delay)));
  e.push_back(real("minimiser", "f_inc", "FIRE time step growth factor", above(1), BUDJAM_FIELD(fire.f_inc)));
  e.push_back(
      real("minimiser", "f_dec", "FIRE time step shrink factor", between(0, 1, "()"), BUDJAM_FIELD(fire.f_dec)));
  e.push_back(
      real("minimiser", "alpha_start", "FIRE initial mixing α", between(0, 1, "()"), BUDJAM_FIELD(fire.alpha_start)));
  e.push_back(
      real("minimiser", "f_alpha", "FIRE mixing decay factor", between(0, 1, "(]"), BUDJAM_FIELD(fire.f_alpha)));
  e.push_back(real("minimiser", "force_tol", "relaxed when the largest generalised force is below this", kPositive,
                   BUDJAM_FIELD(fire.force_tol)));
  e.push_back(real("minimiser", "energy_floor", "relaxed (certainly unjammed) when E/N is below this", kZeroOrPositive,
                   BUDJAM_FIELD(fire.energy_floor)));
  e.push_back(integer("minimiser", "max_iterations", "FIRE iterations before a minimisation fails", kPositive,
                      BUDJAM_FIELD(fire.max_iterations)));
  e.push_back(real("minimiser", "newton_force",
                   "above jamming, Newton steps (analytic Hessian) finish a minimisation once the largest force is "
                   "below this; 0 = off",
                   kZeroOrPositive, BUDJAM_FIELD(fire.newton_force)));
  e.push_back(flag("minimiser", "newton_reuse",
                   "keep a Newton factorisation while the contacts are unchanged (also from one growth step to the "
                   "next), refactoring when its steps contract the force too slowly",
                   BUDJAM_FIELD(fire.newton_reuse)));
  e.push_back(integer(
      "minimiser", "active_set_after",
      "after this many force evaluations of one minimisation, active-set Gauss-Newton steps on the "
      "contact model with every listed pair take over (again after twice as many more, and so on); 0 = FIRE alone, "
      "the paper's minimiser",
      kZeroOrPositive, BUDJAM_FIELD(fire.active_set_after)));
  e.push_back(integer("minimiser", "active_set_try_after",
                      "one early try of the active-set steps after this many force evaluations (below "
                      "active_set_after), kept where it ends at a minimum without a step longer than 1/32 of the "
                      "skin, undone otherwise (the minimisation then goes on as without it); 0 = no try",
                      kZeroOrPositive, BUDJAM_FIELD(fire.active_set_try_after)));
  e.push_back(real("minimiser", "skin", "Verlet skin of the neighbour list, in mother diameters", kPositive,
                   BUDJAM_FIELD(skin)));
  e.push_back(integer("minimiser", "threads",
                      "threads of a force evaluation (N ≥ 512 cells), 0 = one per core; results do not depend on it",
                      between(0, kMaxThreads, "[]"), BUDJAM_FIELD(threads)));

  e.push_back(flag("observe", "bud_events", "track unconstrained buds from jamming on (bud_events.csv)",
                   BUDJAM_FIELD(bud_events)));
  e.push_back(
      flag("observe", "rigidity_events", "log rigidity (pebble game) along the run", BUDJAM_FIELD(rigidity_events)));
  e.push_back(flag("observe", "trials",
                   "log every relaxed growth attempt, accepted or not: the search onto phi_J (trials.csv)",
                   BUDJAM_FIELD(trials)));
  e.push_back(
      integer("observe", "checkpoint_every",
              "accepted steps between checkpoints; 0 = none (SIGTERM/SIGINT and marginal relaxations still write one)",
              kZeroOrPositive, BUDJAM_FIELD(checkpoint_every)));
  e.push_back(integer("observe", "checkpoint_evaluations",
                      "force evaluations of one relaxation between checkpoints inside it; 0 = none (SIGTERM/SIGINT "
                      "still write one)",
                      kZeroOrPositive, BUDJAM_FIELD(checkpoint_evaluations)));
  e.push_back(
      integer("observe", "trajectory_every",
              "accepted steps between frames of trajectory.xyz (also at jamming, targets, phi_2, end); 0 = none",
              kZeroOrPositive, BUDJAM_FIELD(trajectory_every)));
  e.push_back(flag("observe", "progress", "progress line on stderr", BUDJAM_FIELD(progress)));
  for (const bool moduli : {true, false}) {
    const std::string sec = moduli ? "observe.moduli" : "observe.dos";
    const std::string what = moduli ? "elastic moduli" : "density of states";
    auto at = [moduli](auto& s) -> auto& { return moduli ? s.moduli : s.dos; };
    e.push_back(flag(
        sec, "at_jamming", "compute the " + what + " at jamming", [at](auto& s) -> auto& { return at(s).at_jamming; }));
    e.push_back(flag(
        sec, "at_phi2", "compute the " + what + " at φ_2", [at](auto& s) -> auto& { return at(s).at_phi2; }));
    e.push_back(flag(
        sec, "at_targets",
        "compute the " + what + " at each target", [at](auto& s) -> auto& { return at(s).at_targets; }));
    e.push_back(integer(
        sec, "every", "compute the " + what + " every k accepted steps above jamming; 0 = never",
        kZeroOrPositive, [at](auto& s) -> auto& { return at(s).every; }));
  }
  return e;
}

#undef BUDJAM_FIELD

}  // namespace

bool Range::contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }

std::string Range::requirement() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  std::string r;
  if (has_lo && has_hi)
    r = "must lie in " + interval();
  else if (has_lo && lo == 0)
    r = lo_open ? "must be positive" : "must be zero or positive";
  else if (has_lo)
    r = std::string(lo_open ? "must exceed " : "must be at least ") + shortest_text(lo);
  else if (has_hi)
    r = std::string(hi_open ? "must be below " : "must be at most ") + shortest_text(hi);
  else
    return "";
  return r + why;
}

std::string Range::interval() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return std::string(lo_open ? "(" : "[") + shortest_text(lo) + ", " + shortest_text(hi) + (hi_open ? ")" : "]");
  if (has_lo) return std::string(lo_open ? "> " : "≥ ") + shortest_text(lo);
  if (has_hi) return std::string(hi_open ? "< " : "≤ ") + shortest_text(hi);
  return "";
}

void SceneKey::check(const Scene& scene) const {
  const SceneValue v = get(scene);
  auto number = [&](double x) {
    if (!std::isfinite(x)) fail(*this, "must be a finite number", v);
    if (!range.contains(x)) fail(*this, range.requirement(), v);
  };
  switch (type) {
    case KeyType::text: {
      const auto& s = std::get<std::string>(v);
      if (s.empty()) fail(*this, "must not be empty", v);
      if (s.find_first_of("\n\r") != std::string::npos)
        throw InputError(key() + ": must be a single line (got a line break)");
      break;
    }
    case KeyType::choice:
    case KeyType::flag: break;
    case KeyType::integer: {
      const auto i = std::get<std::int64_t>(v);
      if (!range.contains(static_cast<double>(i))) fail(*this, range.requirement(), v);
      break;
    }
    case KeyType::real: number(std::get<double>(v)); break;
    case KeyType::real_or_none:
      if (const auto* d = std::get_if<double>(&v)) number(*d);
      break;
    case KeyType::reals: {
      const auto& xs = std::get<std::vector<double>>(v);
      for (std::size_t i = 0; i < xs.size(); ++i) {
        if (!std::isfinite(xs[i])) fail(*this, "must be finite numbers", v);
        if (!range.contains(xs[i])) fail(*this, range.requirement(), v);
        if (i > 0 && !(xs[i] > xs[i - 1])) fail(*this, "must be strictly increasing", v);
      }
      break;
    }
  }
}

const std::vector<SceneKey>& scene_keys() {
  static const std::vector<SceneKey> keys = make_keys();
  return keys;
}

const SceneKey* find_scene_key(std::string_view key) {
  for (const auto& k : scene_keys())
    if (k.key() == key) return &k;
  return nullptr;
}

SceneValue scene_value(const Scene& scene, std::string_view key) {
  const SceneKey* k = find_scene_key(key);
  if (!k) throw InputError(std::string(key) + ": unknown key");
  return k->get(scene);
}

}  // namespace budjam
