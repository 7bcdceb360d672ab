// Scene files: the TOML reader, --set overrides, the writers, budjam::validate, and one default per knob.
#include "analysis/moduli_report.hpp"
#include "budjam/newton.hpp"
#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"
#include "io/scene_file.hpp"

#include <catch2/catch.hpp>

#include <bit>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <tuple>

using namespace budjam;
using namespace budjam::io;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

// The message of the InputError that parsing `text` throws ("" if none).
std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_scene(text, "test.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

}  // namespace

TEST_CASE("absent keys keep the documented defaults of Scene", "[scene]") {
  const Scene parsed = parse_scene("[run]\n", "defaults.toml");
  CHECK(scene_to_toml(parsed) == scene_to_toml(Scene{}));
  CHECK_FALSE(parsed.P0.has_value());
  CHECK(parsed.L == 8.0);
  CHECK(parsed.init == InitialState::two_cells);
}

TEST_CASE("every minimiser knob has one default: the library's structs are the scene's", "[scene]") {
  // A scene built from the library's own defaults reads, key for key, what a default scene reads:
  // neither overrides the other.
  Scene library;
  library.fire = FireParams{};
  library.skin = kDefaultSkin;
  std::size_t minimiser_keys = 0;
  for (const SceneKey& k : scene_keys()) {
    if (k.section != "minimiser") continue;
    ++minimiser_keys;
    INFO(k.key());
    CHECK(value_text(k.get(Scene{})) == value_text(k.get(library)));
  }
  CHECK(minimiser_keys >= 10);
  CHECK(NewtonParams{}.force_tol == Scene{}.fire.force_tol);
  CHECK(tools::moduli_fire().force_tol == Scene{}.fire.force_tol);  // the relaxations of budjam moduli
}

TEST_CASE("a scene file with every section sets every value it names", "[scene]") {
  const Scene s = parse_scene(R"(
[run]
name = "full"
seed = 42
[box]
L = 15
[cells]
r0 = 0.003
delta = 0.2
alpha0 = 1.02
division = "opposite"
[init]
kind = "random_seeds"
cells = 12
[growth]
P0 = 1e-4
dt = 0.5
dt_min = 1e-10
max_steps = 1e6
[jamming]
epsilon_U = 1e-15
target_tolerance = 1e-9
targets = [1e-4, 3e-4, 0.12]
continue_to_phi2 = true
max_dphi = 0.15
[minimiser]
dt_start = 0.05
dt_max = 0.5
dt_min = 1e-4
n_delay = 7
f_inc = 1.2
f_dec = 0.4
alpha_start = 0.2
f_alpha = 0.98
force_tol = 1e-12
energy_floor = 1e-21
max_iterations = 5000
skin = 0.25
[observe]
bud_events = false
rigidity_events = true
checkpoint_every = 100
progress = false
[observe.moduli]
at_jamming = true
at_phi2 = true
at_targets = true
every = 10
[observe.dos]
at_targets = true
every = 3
)",
                              "full.toml");
  CHECK(s.name == "full");
  CHECK(s.seed == 42);
  CHECK(s.L == 15.0);
  CHECK(s.r0 == 0.003);
  CHECK(s.delta == 0.2);
  CHECK(s.alpha0 == 1.02);
  CHECK(s.division == DivisionRule::opposite);
  CHECK(s.init == InitialState::random_seeds);
  CHECK(s.n_seeds == 12);
  REQUIRE(s.P0.has_value());
  CHECK(*s.P0 == 1e-4);
  CHECK(s.dt == 0.5);
  CHECK(s.dt_min == 1e-10);
  CHECK(s.max_steps == 1000000);
  CHECK(s.epsilon_U == 1e-15);
  CHECK(s.target_tolerance == 1e-9);
  CHECK(s.targets == std::vector<double>{1e-4, 3e-4, 0.12});
  CHECK(s.continue_to_phi2);
  CHECK(s.max_dphi == 0.15);
  CHECK(s.fire.dt_start == 0.05);
  CHECK(s.fire.dt_max == 0.5);
  CHECK(s.fire.dt_min == 1e-4);
  CHECK(s.fire.n_delay == 7);
  CHECK(s.fire.f_inc == 1.2);
  CHECK(s.fire.f_dec == 0.4);
  CHECK(s.fire.alpha_start == 0.2);
  CHECK(s.fire.f_alpha == 0.98);
  CHECK(s.fire.force_tol == 1e-12);
  CHECK(s.fire.energy_floor == 1e-21);
  CHECK(s.fire.max_iterations == 5000);
  CHECK(s.skin == 0.25);
  CHECK_FALSE(s.bud_events);
  CHECK(s.rigidity_events);
  CHECK(s.checkpoint_every == 100);
  CHECK_FALSE(s.progress);
  CHECK(s.moduli.at_jamming);
  CHECK(s.moduli.at_phi2);
  CHECK(s.moduli.at_targets);
  CHECK(s.moduli.every == 10);
  CHECK_FALSE(s.dos.at_jamming);
  CHECK(s.dos.at_targets);
  CHECK(s.dos.every == 3);
}

TEST_CASE("P0 = \"none\" means no feedback; a number is the feedback scale", "[scene]") {
  CHECK_FALSE(parse_scene("[growth]\nP0 = \"none\"\n").P0.has_value());
  const Scene s = parse_scene("[growth]\nP0 = 1e-5\n");
  REQUIRE(s.P0.has_value());
  CHECK(*s.P0 == 1e-5);
  CHECK_THAT(error_of("[growth]\nP0 = \"off\"\n"), Contains("growth.P0: expected a number or \"none\" (got \"off\")"));
  CHECK_THAT(error_of("[growth]\nP0 = true\n"), Contains("growth.P0: expected a number or \"none\""));
}

TEST_CASE("writing a scene as TOML and reading it back reproduces it bit for bit", "[scene]") {
  Scene s;
  s.name = "tricky \"name\" with \\ and ünïcode";
  s.seed = (std::uint64_t{1} << 63) - 1;
  s.L = 15.000000000000002;
  s.r0 = 0.1 + 0.2;  // 0.30000000000000004
  s.delta = 1.0 / 3.0;
  s.alpha0 = std::nextafter(1.01, 2.0);
  s.P0 = 1e-300;
  s.dt = 1.0;
  s.targets = {1e-4, 3e-4, 2.0 / 3.0 * 1e-2, 0.12};
  s.max_dphi = 0.2;
  s.fire.energy_floor = 0.0;
  s.fire.force_tol = 4.9406564584124654e-324 * 3;  // subnormal
  s.moduli.every = 7;
  s.division = DivisionRule::aligned;
  REQUIRE_NOTHROW(validate(s));

  const std::string text = scene_to_toml(s, true);
  const Scene r = parse_scene(text, "written.toml");
  CHECK(scene_to_toml(r, true) == text);
  CHECK(r.name == s.name);
  CHECK(r.seed == s.seed);
  CHECK(same_bits(r.L, s.L));
  CHECK(same_bits(r.r0, s.r0));
  CHECK(same_bits(r.delta, s.delta));
  CHECK(same_bits(r.alpha0, s.alpha0));
  CHECK(same_bits(*r.P0, *s.P0));
  REQUIRE(r.targets.size() == s.targets.size());
  for (std::size_t i = 0; i < s.targets.size(); ++i) CHECK(same_bits(r.targets[i], s.targets[i]));
  CHECK(same_bits(r.fire.force_tol, s.fire.force_tol));
  CHECK(r.division == DivisionRule::aligned);
  CHECK(r.moduli.every == 7);
}

TEST_CASE("every key of the table reads back the value written for it", "[scene]") {
  // For each key: change its value through a one-key TOML file, and check the table's getter
  // sees exactly that value — the parser, the writer and the getter agree key by key.
  for (const SceneKey& k : scene_keys()) {
    INFO(k.key());
    const Scene base;
    const SceneValue before = scene_value(base, k.key());
    SceneValue after = before;
    if (auto* b = std::get_if<bool>(&after))
      *b = !*b;
    else if (auto* i = std::get_if<std::int64_t>(&after))
      *i += 3;
    else if (auto* d = std::get_if<double>(&after))
      *d = *d == 0 ? 0.5 : *d * 1.25;
    else if (auto* v = std::get_if<std::vector<double>>(&after))
      v->push_back(0.0625);
    else if (auto* str = std::get_if<std::string>(&after)) {
      if (k.key() == "cells.division")
        *str = "aligned";
      else if (k.key() == "init.kind")
        *str = "random_seeds";
      else if (k.key() == "jamming.search")
        *str = "bisection";
      else if (k.key() == "growth.P0")
        after = 0.125;
      else
        *str += "x";
    }
    REQUIRE(after != before);
    Scene s;
    apply_override(s, k.key() + "=" + toml_literal(after));
    CHECK(scene_value(s, k.key()) == after);
    // Only that key changed.
    for (const SceneKey& other : scene_keys())
      if (other.key() != k.key()) CHECK(scene_value(s, other.key()) == scene_value(base, other.key()));
  }
}

TEST_CASE("invalid scenes are refused with one line naming the key and the value", "[scene]") {
  struct Case {
    std::string toml, message;
  };
  const std::vector<Case> cases = {
      {"[growth]\nP00 = 1\n",
       "test.toml:2:1: growth.P00: unknown key (known in [growth]: P0, dt, dt_min, max_steps, adaptive_dt, "
       "adaptive_floor)"},
      {"[grwoth]\nP0 = 1\n", "test.toml:1:2: grwoth: unknown section"},
      {"L = 8\n", "test.toml:1:1: L: unknown key"},
      {"[observe.moduli]\nevery_step = 1\n", "observe.moduli.every_step: unknown key"},
      {"[growth]\nP0 = 0\n",
       "test.toml: growth.P0: must be at least 1e-300 so that p/P0 stays finite, or \"none\" for no feedback (got 0)"},
      {"[growth]\nP0 = -1e-3\n", "growth.P0: must be at least 1e-300 so that p/P0 stays finite, or \"none\""},
      {"[growth]\nP0 = 1e-320\n", "growth.P0: must be at least 1e-300 so that p/P0 stays finite"},
      {"[growth]\nP0 = nan\n", "growth.P0: must be a finite number (got nan)"},
      {"[growth]\nP0 = inf\n", "growth.P0: must be a finite number (got inf)"},
      {"[box]\nL = nan\n", "box.L: must be a finite number (got nan)"},
      {"[box]\nL = 2\n", "box.L: must exceed 2 (largest lobe diameter + minimiser.skin) = 2.34"},
      {"[box]\nL = -8\n", "box.L: must exceed"},
      {"[jamming]\ntargets = [1e-2, 1e-3]\n", "jamming.targets: must be strictly increasing (got [0.01, 0.001])"},
      {"[jamming]\ntargets = [1e-3, 1e-3]\n", "jamming.targets: must be strictly increasing"},
      {"[jamming]\ntargets = [-1e-3]\n", "jamming.targets: must be positive"},
      {"[jamming]\ntargets = [0]\n", "jamming.targets: must be positive"},
      {"[jamming]\ntargets = [1e-3, nan]\n", "jamming.targets: must be finite numbers (got [0.001, nan])"},
      {"[jamming]\ntargets = [1e-3, \"x\"]\n", "jamming.targets: expected an array of numbers"},
      {"[jamming]\ntargets = [0.3]\n", "jamming.targets: must not exceed jamming.max_dphi = 0.2"},
      {"[jamming]\ntargets = [1e-9]\n", "jamming.target_tolerance: must be smaller than the first of jamming.targets"},
      {"[jamming]\nepsilon_U = 0\n", "jamming.epsilon_U: must be positive (got 0)"},
      {"[jamming]\ncrossing_step = 0.01\n",
       "jamming.crossing_step: is only used with jamming.continuation = true (got 0.01)"},
      {"[jamming]\ncontinuation = true\ncrossing_step = -0.01\n", "jamming.crossing_step: must be"},
      {"[jamming]\ntarget_tolerance = -1\n", "jamming.target_tolerance: must be positive"},
      {"[cells]\nr0 = 0\n", "cells.r0: must be positive (got 0)"},
      {"[cells]\ndelta = 2\n", "cells.delta: must lie in [0, 2)"},
      {"[cells]\ndelta = -0.1\n", "cells.delta: must lie in [0, 2)"},
      {"[cells]\nalpha0 = 1\n", "cells.alpha0: must lie in (1, 2) (got 1)"},
      {"[cells]\nalpha0 = 2\n", "cells.alpha0: must lie in (1, 2) (got 2)"},
      {"[cells]\ndivision = \"sideways\"\n",
       "cells.division: expected one of \"random\", \"aligned\", \"opposite\" (got \"sideways\")"},
      {"[init]\nkind = \"one_cell\"\n", "init.kind: expected one of \"two_cells\", \"random_seeds\""},
      {"[init]\nkind = \"random_seeds\"\n", "init.cells: must be at least 1"},
      {"[init]\ncells = 4\n", "init.cells: is only used with init.kind = \"random_seeds\" (got 4)"},
      {"[init]\nkind = \"random_seeds\"\ncells = 32\n", "init.cells: too many seeds for the box"},
      {"[init]\ncells = -4\n", "init.cells: expected a non-negative integer (got -4)"},
      {"[growth]\ndt = 0\n", "growth.dt: must be positive"},
      {"[growth]\ndt = \"fast\"\n", "test.toml:2:6: growth.dt: expected a number (got \"fast\")"},
      {"[growth]\ndt_min = 0\n", "growth.dt_min: must be positive"},
      {"[growth]\ndt_min = 2\n", "growth.dt_min: must be smaller than growth.dt = 1"},
      {"[growth]\nmax_steps = 0\n", "growth.max_steps: must be positive (got 0)"},
      {"[growth]\nadaptive_floor = -1e-300\n", "growth.adaptive_floor: must lie in [0, 1] (got -1e-300)"},
      {"[growth]\nadaptive_floor = 1.5\n", "growth.adaptive_floor: must lie in [0, 1] (got 1.5)"},
      {"[growth]\nmax_steps = 1.5\n", "growth.max_steps: expected an integer (got 1.5)"},
      {"[run]\nseed = -1\n", "run.seed: expected a non-negative integer (got -1)"},
      {"[run]\nname = \"\"\n", "run.name: must not be empty"},
      {"[run]\nname = 3\n", "run.name: expected a string (got 3)"},
      {"[minimiser]\nskin = 0\n", "minimiser.skin: must be positive (got 0)"},
      {"[minimiser]\nf_inc = 1\n", "minimiser.f_inc: must exceed 1"},
      {"[minimiser]\nf_dec = 1\n", "minimiser.f_dec: must lie in (0, 1)"},
      {"[minimiser]\nalpha_start = 0\n", "minimiser.alpha_start: must lie in (0, 1)"},
      {"[minimiser]\nf_alpha = 1.5\n", "minimiser.f_alpha: must lie in (0, 1]"},
      {"[minimiser]\ndt_max = 1.0\ndt_start = 2\n", "minimiser.dt_start: must not exceed minimiser.dt_max = 1"},
      {"[minimiser]\ndt_min = 0.5\n", "minimiser.dt_min: must not exceed minimiser.dt_start = 0.1"},
      {"[minimiser]\nn_delay = -1\n", "minimiser.n_delay: must be zero or positive"},
      {"[minimiser]\nforce_tol = 0\n", "minimiser.force_tol: must be positive"},
      // the residual energy of a relaxation stopped at force_tol, ~force_tol², must lie below ε_U / 100
      {"[minimiser]\nforce_tol = 1e-8\n", "minimiser.force_tol: must be at most √(0.01 jamming.epsilon_U) = 1e-09"},
      {"[jamming]\nepsilon_U = 1e-30\n[minimiser]\nenergy_floor = 0\n",
       "minimiser.force_tol: must be at most √(0.01 jamming.epsilon_U) = 1e-16"},
      {"[minimiser]\nenergy_floor = 1e-16\n", "minimiser.energy_floor: must be below jamming.epsilon_U = 1e-16"},
      {"[minimiser]\nmax_iterations = 0\n", "minimiser.max_iterations: must be positive"},
      {"[minimiser]\nactive_set_after = 5000\n",
       "minimiser.active_set_try_after: must be below minimiser.active_set_after = 5000 (0 = no try) (got 10000)"},
      {"[minimiser]\nactive_set_try_after = 100000\n",
       "minimiser.active_set_try_after: must be below minimiser.active_set_after = 100000 (0 = no try) (got 100000)"},
      {"[observe]\nbud_events = 1\n", "observe.bud_events: expected true or false (got 1)"},
      {"[observe]\ncheckpoint_every = -5\n", "observe.checkpoint_every: must be zero or positive (got -5)"},
      {"[observe]\nmoduli = 1\n", "observe.moduli: expected a table [observe.moduli] (got 1)"},
      {"[observe.dos]\nevery = -1\n", "observe.dos.every: must be zero or positive (got -1)"},
      {"[[run]]\nname = \"x\"\n", "run: expected a table [run]"},
      {"[growth]\nP0 = 1e-3 1e-4\n", "test.toml:2:"},
      // a bare word, which TOML reads as a broken number or boolean: the key and its quoted form
      {"[growth]\nP0 = none\n", "test.toml:2:7: growth.P0 = none: a text value is quoted in TOML (P0 = \"none\")"},
      {"[run]\nseed = 2\n[jamming]\nsearch = secant # x\n",
       "test.toml:4:10: jamming.search = secant: a text value is quoted in TOML (search = \"secant\")"},
      {"[growth]\nP0 = 1\nP0 = 2\n", "test.toml:3:"},
  };
  for (const Case& c : cases) {
    INFO(c.toml);
    const std::string message = error_of(c.toml);
    CHECK_THAT(message, Contains(c.message));
    CHECK_THAT(message, StartsWith("test.toml:"));
    CHECK(message.find('\n') == std::string::npos);
  }
}

TEST_CASE("an active-set try is refused only where it could never be made", "[scene]") {
  Scene s;
  s.fire.active_set_try_after = s.fire.active_set_after - 1;
  CHECK_NOTHROW(validate(s));
  // No try, or FIRE alone (active_set_after = 0 makes no try whatever the try key says).
  s.fire.active_set_try_after = 0;
  s.fire.active_set_after = 500;
  CHECK_NOTHROW(validate(s));
  s.fire.active_set_try_after = 10000;
  s.fire.active_set_after = 0;
  CHECK_NOTHROW(validate(s));
  s.fire.active_set_after = 10000;
  CHECK_THROWS_WITH(validate(s), StartsWith("minimiser.active_set_try_after: must be below"));
}

TEST_CASE("validate names the key for scenes built in code, without a file", "[scene]") {
  CHECK_NOTHROW(validate(Scene{}));
  Scene s;
  s.P0 = 0.0;
  CHECK_THROWS_WITH(validate(s),
                    "growth.P0: must be at least 1e-300 so that p/P0 stays finite, or \"none\" for no "
                    "feedback (got 0)");
  s = Scene{};
  s.targets = {std::numeric_limits<double>::quiet_NaN()};
  CHECK_THROWS_WITH(validate(s), StartsWith("jamming.targets: must be finite numbers"));
  s = Scene{};
  s.seed = ~std::uint64_t{0};
  CHECK_THROWS_WITH(validate(s), StartsWith("run.seed: must be below 2^63"));
}

TEST_CASE("the paper's parameter grid is valid", "[scene]") {
  for (double L : {8.0, 15.0, 20.0}) {
    for (std::optional<double> P0 : {std::optional<double>{}, {1e-1}, {1e-2}, {1e-3}, {1e-4}, {1e-5}}) {
      Scene s;
      s.L = L;
      s.P0 = P0;
      s.targets = {1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 6e-2, 0.1, 0.12};
      CHECK_NOTHROW(validate(s));
    }
  }
  Scene big;  // grown from many seeds: 10^4 cells need L ≈ 150
  big.L = 160;
  big.init = InitialState::random_seeds;
  big.n_seeds = 10000;
  CHECK_NOTHROW(validate(big));
}

TEST_CASE("--set overrides go through the same keys and types as the file", "[scene]") {
  Scene s = parse_scene("[growth]\nP0 = 1e-3\n");
  apply_override(s, "growth.P0=none");
  CHECK_FALSE(s.P0.has_value());
  apply_override(s, " growth.P0 = 1e-4 ");
  CHECK(s.P0 == 1e-4);
  apply_override(s, "cells.division=aligned");
  CHECK(s.division == DivisionRule::aligned);
  apply_override(s, "jamming.targets=[1e-3, 1e-2]");
  CHECK(s.targets == std::vector<double>{1e-3, 1e-2});
  apply_override(s, "growth.max_steps=1e5");
  CHECK(s.max_steps == 100000);
  apply_override(s, "observe.moduli.at_jamming=true");
  CHECK(s.moduli.at_jamming);
  apply_override(s, "run.name=sweep-7");
  CHECK(s.name == "sweep-7");

  CHECK_THROWS_WITH(apply_override(s, "growth.P00=1"), StartsWith("--set growth.P00=1: growth.P00: unknown key"));
  CHECK_THROWS_WITH(apply_override(s, "growth.P0"), StartsWith("--set growth.P0: expected section.key=value"));
  CHECK_THROWS_WITH(apply_override(s, "growth.dt=fast"),
                    "--set growth.dt=fast: growth.dt: expected a number (got \"fast\")");
  // Overrides are validated with the scene.
  CHECK_THAT(error_of("[run]\n", {"growth.P0=-1"}), Contains("growth.P0: must be at least 1e-300"));
  CHECK_THAT(error_of("[run]\n", {"box.L=1"}), Contains("box.L: must exceed"));
}

TEST_CASE("scene_to_json nests sections and keeps every key", "[scene]") {
  Scene s;
  s.P0 = 1e-3;
  const Json j = scene_to_json(s);
  CHECK(j["growth"]["P0"] == 1e-3);
  CHECK(j["observe"]["moduli"]["every"] == 0);
  CHECK(j["run"]["name"] == "unnamed");
  std::size_t n = 0;
  for (const auto& k : scene_keys()) {
    const Json* at = &j;
    std::string rest = k.key();
    for (std::size_t dot; (dot = rest.find('.')) != std::string::npos; rest = rest.substr(dot + 1))
      at = &(*at)[rest.substr(0, dot)];
    CHECK(at->contains(rest));
    ++n;
  }
  CHECK(n == scene_keys().size());
  s.P0.reset();
  CHECK(scene_to_json(s)["growth"]["P0"] == "none");
}

TEST_CASE("shipped scenes are valid and each bad example fails with the message it documents", "[scene]") {
  const char* root = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(root != nullptr);
  const std::filesystem::path scenes = std::filesystem::path(root) / "data" / "scenes";
  for (const auto& entry : std::filesystem::directory_iterator(scenes)) {
    if (entry.path().extension() != ".toml") continue;
    INFO(entry.path());
    CHECK_NOTHROW(load_scene(entry.path()));
  }
  std::size_t bad = 0;
  for (const auto& entry : std::filesystem::directory_iterator(scenes / "bad")) {
    if (entry.path().extension() != ".toml") continue;
    INFO(entry.path());
    std::ifstream in(entry.path());
    std::string first;
    std::getline(in, first);
    REQUIRE_THAT(first, StartsWith("# expect: "));
    const std::string expected = first.substr(10);
    std::string message;
    try {
      load_scene(entry.path());
    } catch (const InputError& e) {
      message = e.what();
    }
    CHECK_THAT(message, StartsWith(entry.path().string()));
    CHECK_THAT(message, Contains(expected));
    ++bad;
  }
  CHECK(bad >= 5);
}

TEST_CASE("validate enforces each key's range from the knob table, with the row's requirement", "[scene]") {
  // For every number with a bound: the value just beyond each end is refused naming the key and the
  // requirement the docs table shows; the bound itself is accepted on a closed end.
  std::size_t bounded = 0;
  for (const SceneKey& k : scene_keys()) {
    if (k.type != KeyType::real && k.type != KeyType::integer) continue;
    INFO(k.key());
    const auto value = [&](double v) -> SceneValue {
      if (k.type == KeyType::integer) return static_cast<std::int64_t>(v);
      return v;
    };
    const auto beyond = [&](double end, bool open, double outward) {
      if (open) return end;
      return k.type == KeyType::integer ? end + outward : std::nextafter(end, outward * HUGE_VAL);
    };
    for (const auto& [end, open, outward] :
         {std::tuple{k.range.lo, k.range.lo_open, -1.0}, std::tuple{k.range.hi, k.range.hi_open, 1.0}}) {
      if (!std::isfinite(end)) continue;
      ++bounded;
      Scene s;
      k.set(s, value(beyond(end, open, outward)));
      CHECK_THROWS_WITH(validate(s), StartsWith(k.key() + ": " + k.range.requirement() + " (got "));
      if (!open) {
        Scene at;
        k.set(at, value(end));
        CHECK_NOTHROW(k.check(at));
      }
    }
  }
  CHECK(bounded >= 20);
}

TEST_CASE("docs/files.md holds the scene key table that the knob table generates", "[scene]") {
  const char* root = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(root != nullptr);
  std::ifstream in(std::filesystem::path(root) / "docs" / "files.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string docs = text.str();
  const std::string begin = "<!-- scene keys: generated by `budjam validate --keys-markdown` -->\n";
  const std::string end = "<!-- end of scene keys -->";
  const auto a = docs.find(begin), b = docs.find(end);
  REQUIRE(a != std::string::npos);
  REQUIRE(b != std::string::npos);
  // Regenerate it after changing a row: budjam validate --keys-markdown.
  CHECK(docs.substr(a + begin.size(), b - a - begin.size()) == scene_keys_markdown());
}

TEST_CASE("box.L has an upper bound so that seed placement and the cell list fit in memory", "[scene]") {
  CHECK(error_of("[box]\nL = 1e5\n") ==
        "test.toml: box.L: must be at most 10000 so that the seed placement and the cell list fit in memory "
        "(got 1e+05)");
  CHECK_NOTHROW(parse_scene("[box]\nL = 1e4\n"));
  CHECK_NOTHROW(parse_scene("[box]\nL = 1e4\n[init]\nkind = \"random_seeds\"\ncells = 10\n"));
}

TEST_CASE("text that is not UTF-8 is refused with its line and column before the TOML parser sees it", "[scene]") {
  struct Case {
    std::string toml, where;
  };
  const std::vector<Case> cases = {
      {"[run]\nname = \"\xff\"\n", "test.toml:2:9:"},              // never a UTF-8 byte
      {"[run]\nname = \"\xc0\xaf\"\n", "test.toml:2:9:"},          // overlong '/'
      {"[run]\nname = \"\xed\xa0\x80\"\n", "test.toml:2:9:"},      // a surrogate
      {"[run]\nname = \"\xf4\x90\x80\x80\"\n", "test.toml:2:9:"},  // above U+10FFFF
      {"[run]\nname = \"\xe2\x82\"\n", "test.toml:2:9:"},          // truncated sequence
      {"[run]\n# \xe2\x82", "test.toml:2:3:"},                     // truncated at the end
      {"[run]\nname = \"x\xbf\"\n", "test.toml:2:10:"},            // a stray continuation byte
  };
  for (const Case& c : cases) {
    INFO(c.toml);
    CHECK(error_of(c.toml) == c.where + " not valid UTF-8 (scene files are UTF-8 text)");
  }
  // Well-formed UTF-8 of every length passes, and comes back unchanged.
  const std::string name = "φ_J \u2713 \U0001D711 caf\u00e9";
  CHECK(parse_scene("[run]\nname = \"" + name + "\"  # Δφ \u2192 φ_2\n").name == name);
}

TEST_CASE("an empty scene file is refused naming the file; a file of comments is a scene of defaults", "[scene]") {
  for (const std::string text : {"", "\n", " \t\r\n\n"}) {
    INFO(text.size());
    CHECK_THAT(error_of(text), StartsWith("test.toml: empty scene file"));
  }
  CHECK(scene_to_toml(parse_scene("# all defaults\n")) == scene_to_toml(Scene{}));
}

TEST_CASE("a choice is set by one of its names only", "[scene]") {
  const SceneKey* division = find_scene_key("cells.division");
  REQUIRE(division != nullptr);
  Scene s;
  division->set(s, std::string("opposite"));
  CHECK(s.division == DivisionRule::opposite);
  CHECK_THROWS_WITH(division->set(s, std::string("sideways")),
                    "cells.division: is not one of the choices (got \"sideways\")");
  CHECK(s.division == DivisionRule::opposite);
}
