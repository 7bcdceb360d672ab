// The checkpoint file: exact round trip, and refusal of anything that was not written for this run.
#include "budjam/growth_driver.hpp"
#include "io/checkpoint.hpp"
#include "io/text.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <istream>
#include <ostream>
#include <sstream>

using namespace budjam;
using namespace budjam::io;
using Catch::Matchers::Contains;

namespace {

Scene small_scene() {
  Scene s;
  s.name = "test";
  s.L = 6.0;
  s.seed = 3;
  s.P0 = 1e-3;
  s.targets = {1e-3, 1e-2};
  return s;
}

// A stateful observer: counts accepted steps; its section is that count.
struct Counter : Observer {
  std::string label = "counter";
  long steps = 0;
  std::string name() const override { return label; }
  bool stateful() const override { return true; }
  void on_step_accepted(const StepAccepted&) override { ++steps; }
  void save_state(std::ostream& os) override { os << steps << '\n'; }
  void load_state(std::istream& is) override {
    if (!(is >> steps) || steps < 0) throw InputError("bad counter state");
  }
};

struct Stateless : Observer {
  std::string name() const override { return "progress"; }
};

// A driver of the small scene with a Counter and a Stateless observer.
struct Run {
  Scene scene = small_scene();
  GrowthDriver driver{scene};
  Counter counter;
  Stateless progress;
  std::vector<Observer*> observers{&counter, &progress};
  Run() {
    for (Observer* o : observers) driver.add_observer(*o);
  }
};

struct Snapshot {
  std::string text;  // a checkpoint taken after jamming
  long step = 0;
  RunResult final;  // of the uninterrupted run
  Packing final_packing;
  long final_count = 0;
};

// One run of the small scene; the checkpoint of the last accepted state past the first target.
const Snapshot& snapshot() {
  static const Snapshot snap = [] {
    Snapshot s;
    Run run;
    GrowthDriver& d = run.driver;
    d.set_checkpoint_hook([&] {
      if (d.result().targets.size() == 1 && s.text.empty()) {
        s.text = format_checkpoint(run.scene, d.state(), run.observers);
        s.step = d.view().step;
      }
    });
    d.run();
    s.final = d.result();
    s.final_packing = d.packing();
    s.final_count = run.counter.steps;
    return s;
  }();
  return snap;
}

// The first checkpoint taken inside the bracket search onto φ_J with both of its ends (a trial below
// the window and one above it) and a trial that divided cells, in a run of the small scene in a
// larger box (seed 7 is one whose search keeps such a trial: few of L = 6 do), and the
// uninterrupted run's end.
struct BracketSnapshot {
  Scene scene = small_scene();
  std::string text;
  long attempts = 0;
  RunResult final;
  Packing final_packing;
};
const BracketSnapshot& bracket_snapshot() {
  static const BracketSnapshot snap = [] {
    BracketSnapshot s;
    s.scene.L = 8.0;
    s.scene.seed = 7;
    const auto divided = [](const OpenBracket& b) {
      return (b.below && !b.below->divisions.empty()) ||
             std::ranges::any_of(b.above, [](const BracketEnd& e) { return !e.trial.divisions.empty(); });
    };
    GrowthDriver d(s.scene);
    d.set_checkpoint_hook([&] {
      if (!s.text.empty()) return;
      const GrowthState state = d.state();
      const auto& b = state.search.bracket;
      if (b && b->below && !b->above.empty() && divided(*b)) {
        s.text = format_checkpoint(s.scene, state, {});
        s.attempts = state.attempts;
      }
    });
    d.run();
    s.final = d.result();
    s.final_packing = d.packing();
    return s;
  }();
  return snap;
}

// The first checkpoint inside a relaxation (every 200 force evaluations of one), in the run of
// bracket_snapshot's scene, and the uninterrupted run's end.
struct RelaxationSnapshot {
  Scene scene = bracket_snapshot().scene;
  std::string text;
  RunResult final;
  Packing final_packing;
};
const RelaxationSnapshot& relaxation_snapshot() {
  static const RelaxationSnapshot snap = [] {
    RelaxationSnapshot s;
    GrowthDriver d(s.scene);
    d.set_relaxation_checkpoints(200, nullptr, [&](const GrowthState& state) {
      if (s.text.empty()) s.text = format_checkpoint(s.scene, state, {});
    });
    d.run();
    s.final = d.result();
    s.final_packing = d.packing();
    return s;
  }();
  return snap;
}

// `text` with its checksum line recomputed: what a deliberate (not accidental) edit looks like.
std::string resealed(const std::string& text) {
  const std::size_t at = text.rfind("checksum ");
  const std::string body = text.substr(0, at);
  char buf[40];
  std::snprintf(buf, sizeof buf, "checksum %016llx\n", static_cast<unsigned long long>(fnv1a64(body)));
  return body + buf;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream is(text);
  for (std::string l; std::getline(is, l);) lines.push_back(l);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string t;
  for (const auto& l : lines) t += l + '\n';
  return t;
}

}  // namespace

TEST_CASE("a run resumed from a checkpoint text ends identical to the uninterrupted run", "[checkpoint]") {
  const Snapshot& snap = snapshot();
  REQUIRE_FALSE(snap.text.empty());
  Run run;
  GrowthDriver& d = run.driver;
  const Counter& c = run.counter;
  d.restore(parse_checkpoint(snap.text, "cp", run.scene, 3, run.observers));
  CHECK(c.steps == snap.step + 1);  // the initial state counts too
  CHECK(d.view().step == snap.step);
  // The state reads back exactly: written again, the same bytes.
  CHECK(format_checkpoint(run.scene, d.state(), run.observers) == snap.text);
  d.run();
  CHECK(d.result().jamming->phi == snap.final.jamming->phi);
  REQUIRE(d.result().targets.size() == snap.final.targets.size());
  CHECK(d.result().targets.back().phi == snap.final.targets.back().phi);
  CHECK(d.packing().q == snap.final_packing.q);
  CHECK(c.steps == snap.final_count);
}

TEST_CASE("a run resumed from a checkpoint taken between the trials of the bracket search ends identical",
          "[checkpoint]") {
  const BracketSnapshot& snap = bracket_snapshot();
  REQUIRE_FALSE(snap.text.empty());
  const Scene& scene = snap.scene;
  GrowthDriver d(scene);
  d.restore(parse_checkpoint(snap.text, "cp", scene, scene.seed, {}));
  // The open bracket, its trials' packings, random streams and divisions read back exactly.
  CHECK(format_checkpoint(scene, d.state(), {}) == snap.text);
  CHECK(d.view().attempts == snap.attempts);
  CHECK(d.phase() == Phase::unjammed);
  d.run();
  const RunResult &r = d.result(), &u = snap.final;
  const auto counts = [](const RunResult& x) {
    return std::vector<long>{x.accepted, x.rejected, x.search_trials, x.force_evaluations, x.divisions};
  };
  CHECK(counts(r) == counts(u));
  REQUIRE(r.jamming);
  CHECK(r.jamming->phi == u.jamming->phi);
  CHECK(r.jamming->E_per_cell == u.jamming->E_per_cell);
  CHECK(d.packing().q == snap.final_packing.q);
  CHECK(d.packing().b == snap.final_packing.b);
}

TEST_CASE("a run resumed from a checkpoint inside a relaxation ends identical to the uninterrupted run",
          "[checkpoint]") {
  const RelaxationSnapshot& snap = relaxation_snapshot();
  REQUIRE(snap.text.find("\nrelaxation 1 ") != std::string::npos);
  const Scene& scene = snap.scene;
  GrowthDriver d(scene);
  GrowthState state = parse_checkpoint(snap.text, "cp", scene, scene.seed, {});
  REQUIRE(state.relaxation);
  // Read back exactly: written again, the same bytes.
  CHECK(format_checkpoint(scene, state, {}) == snap.text);
  d.restore(std::move(state));
  d.run();
  const RunResult &r = d.result(), &u = snap.final;
  const auto counts = [](const RunResult& x) {
    return std::vector<long>{x.accepted,
                             x.rejected,
                             x.search_trials,
                             x.force_evaluations,
                             x.fire_iterations,
                             x.divisions,
                             x.marginal_relaxations,
                             x.active_set_steps,
                             x.newton_factorisations,
                             x.saddles_relaxed,
                             x.saddle_escapes};
  };
  CHECK(counts(r) == counts(u));
  REQUIRE(r.jamming);
  CHECK(r.jamming->phi == u.jamming->phi);
  CHECK(r.jamming->E_per_cell == u.jamming->E_per_cell);
  CHECK(d.packing().q == snap.final_packing.q);
}

TEST_CASE("a relaxation in progress that the resumed attempt does not make is refused", "[checkpoint]") {
  const RelaxationSnapshot& snap = relaxation_snapshot();
  const Scene& scene = snap.scene;
  const GrowthState state = parse_checkpoint(snap.text, "cp", scene, scene.seed, {});
  REQUIRE(state.relaxation);
  const auto refused = [&](GrowthState s, const std::string& why) {
    GrowthDriver d(scene);
    d.restore(std::move(s));
    CHECK_THROWS_WITH(d.advance(), Contains(why));
  };
  GrowthState other_index = state;
  other_index.relaxation->index = 2;  // no attempt makes a third relaxation unless a saddle is relaxed on
  refused(other_index, "made no relaxation 2");
  GrowthState moved = state;
  moved.relaxation->q[0] += 1.0;  // a cell moved beyond what its neighbour list allows
  refused(moved, "does not fit its neighbour list");
  GrowthState fewer = state;
  fewer.relaxation->q.conservativeResize(fewer.relaxation->q.size() - 3);
  refused(fewer, "is not the one this run makes");
}

TEST_CASE("an open bracket whose trials disagree with the accepted state or the window is refused at its line",
          "[checkpoint]") {
  const std::vector<std::string> lines = split_lines(bracket_snapshot().text);
  const auto line_of = [&](const std::string& prefix) {
    const auto at =
        std::find_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.rfind(prefix, 0) == 0; });
    REQUIRE(at != lines.end());
    return static_cast<std::size_t>(at - lines.begin());
  };
  const auto refused = [&](std::size_t k, const std::string& edited, const std::string& why) {
    std::vector<std::string> v = lines;
    v[k] = edited;
    INFO(edited);
    CHECK_THROWS_WITH(
        parse_checkpoint(resealed(join_lines(v)), "cp", bracket_snapshot().scene, bracket_snapshot().scene.seed, {}),
        Contains("cp:" + std::to_string(k + 1) + ":") && Contains(why));
  };
  const auto words = [&](std::size_t k) {
    std::vector<std::string> w;
    std::istringstream ws(lines[k]);
    for (std::string x; ws >> x;) w.push_back(x);
    return w;
  };
  const auto joined = [](const std::vector<std::string>& w) {
    std::string l;
    for (const auto& x : w) l += (l.empty() ? "" : " ") + x;
    return l;
  };
  const std::size_t below = line_of("trial below "), above = line_of("trial above ");
  std::vector<std::string> w = words(below);
  w[3] = "1";  // E/N of the lower end far above the window
  refused(below, joined(w), "the lower end of the bracket is not below the window");
  w = words(above);
  w[3] = "0";  // E/N of an upper end below the window
  refused(above, joined(w), "an upper end of the bracket is below the window");
  w = words(above);
  w[9] = "0.5";  // its line's φ is not the trial's
  refused(above, joined(w), "overshoot phi");
  w = words(above);
  w[2] = words(below)[2];  // its Δt not above the lower end's
  refused(above, joined(w), "increasing dt");
  w = words(above);
  w[6] = std::to_string(std::stoul(w[6]) + 1);  // a cell more than its divisions make
  refused(above, joined(w), "divisions make");
  // Under another search, or when jammed, no bracket is open.
  Scene secant = bracket_snapshot().scene;
  secant.search = JammingSearch::secant;
  CHECK_THROWS_WITH(parse_checkpoint(bracket_snapshot().text, "cp", secant, secant.seed, {}),
                    Contains("scene.toml has changed"));
}

TEST_CASE("checkpoints fall on every k-th accepted step, after a marginal relaxation and on a signal", "[checkpoint]") {
  // Steps 0 (the initial state), 1, 1 (a rejected trial), 2, ...; the force evaluations so far.
  CheckpointSchedule every2(2, 0, 0);
  CHECK_FALSE(every2.due(0, kMarginalEvaluations + 1, true, true));   // the initial state: never
  CHECK(every2.due(1, kMarginalEvaluations + 1, false, true));        // the initial state's attempts count here
  CHECK(every2.due(2, kMarginalEvaluations + 2, false, false));       // periodic: complete by construction
  CHECK_FALSE(every2.due(2, kMarginalEvaluations + 3, false, true));  // a rejected trial at step 2: not again
  // A marginal relaxation, accepted or not, when the state is complete.
  CHECK(every2.due(2, 2 * kMarginalEvaluations + 4, false, true));
  CHECK_FALSE(every2.due(3, 3 * kMarginalEvaluations + 5, false, false));
  CHECK(every2.due(3, 4 * kMarginalEvaluations + 6, false, true));
  CHECK_FALSE(every2.due(3, 5 * kMarginalEvaluations + 6, false, true));  // exactly kMarginalEvaluations: not
  // A signal, when the state is complete.
  CHECK(every2.due(3, 5 * kMarginalEvaluations + 7, true, true));
  CHECK_FALSE(every2.due(5, 5 * kMarginalEvaluations + 8, true, false));
  // observe.checkpoint_every = 0: no periodic ones.
  CheckpointSchedule never(0, 10, 0);
  CHECK_FALSE(never.due(20, 1, false, true));
  CHECK(never.due(20, 2, true, true));
}

TEST_CASE("a run under the paper's phi_2 (no tagged bud left) resumes from a checkpoint past phi_2 unchanged",
          "[checkpoint]") {
  Scene scene = small_scene();
  scene.P0.reset();  // without feedback the last tagged bud can be used up before the last target
  scene.targets = {1e-4, 3e-2};
  scene.phi2_tagged_left = 0;
  // The first seed whose run reaches that φ_2 before its last state (some runs of this small box
  // end with a tagged bud left).
  for (scene.seed = 1; scene.seed <= 20; ++scene.seed) {
    GrowthDriver d(scene);
    d.run();
    if (d.result().depletion && d.result().depletion->step < d.result().accepted) break;
  }
  REQUIRE(scene.seed <= 20);
  std::string text;
  RunResult uninterrupted;
  {
    GrowthDriver d(scene);
    d.set_checkpoint_hook([&] {
      if (d.result().depletion && text.empty()) text = format_checkpoint(scene, d.state(), {});
    });
    d.run();
    uninterrupted = d.result();
  }
  REQUIRE_FALSE(text.empty());
  REQUIRE(uninterrupted.depletion);
  CHECK(uninterrupted.depletion->still_unconstrained == 0);
  GrowthDriver d(scene);
  d.restore(parse_checkpoint(text, "cp", scene, scene.seed, {}));
  CHECK(format_checkpoint(scene, d.state(), {}) == text);
  d.run();
  REQUIRE(d.result().depletion);
  CHECK(d.result().depletion->step == uninterrupted.depletion->step);
  CHECK(d.result().depletion->network.Z == uninterrupted.depletion->network.Z);
  CHECK(d.result().depletion->network.N_f_single_pass == uninterrupted.depletion->network.N_f_single_pass);
  CHECK(d.result().targets.back().phi == uninterrupted.targets.back().phi);
  // The same text under the default definition (at most one left) is another scene: refused.
  scene.phi2_tagged_left = 1;
  CHECK_THROWS_WITH(parse_checkpoint(text, "cp", scene, scene.seed, {}), Contains("scene.toml has changed"));
}

TEST_CASE("a checkpoint of a retired version is refused at line 1, naming what it was written before", "[checkpoint]") {
  struct Retired {
    const char* version;
    const char* lacks;
  };
  for (const Retired& r : {Retired{"4", "network summary"}, Retired{"5", "log scale"}, Retired{"6", "cost"},
                           Retired{"7", "relaxed branches"}, Retired{"8", "stability losses its branches crossed"},
                           Retired{"9", "active-set steps"}}) {
    INFO("version " << r.version);
    std::string text = snapshot().text;
    text.replace(0, text.find('\n'), std::string("budjam-checkpoint ") + r.version);
    Counter c;
    CHECK_THROWS_WITH(parse_checkpoint(text, "cp", small_scene(), 3, {&c}),
                      Contains("cp:1:") && Contains(std::string("version ") + r.version) && Contains(r.lacks) &&
                          Contains("start the run again"));
  }
}

// A run of `scene` uninterrupted, and the same run resumed from its first checkpoint at which
// `ready` holds: the checkpoint, both results, and whether the restored state wrote it again.
struct Resumed {
  std::string text;
  RunResult uninterrupted, resumed;
  bool rewritten = false;
};
template <class Ready>
Resumed resumed_from_checkpoint(const Scene& scene, Ready ready) {
  Resumed out;
  {
    GrowthDriver d(scene);
    d.set_checkpoint_hook([&] {
      if (ready(d.result()) && out.text.empty()) out.text = format_checkpoint(scene, d.state(), {});
    });
    d.run();
    out.uninterrupted = d.result();
  }
  REQUIRE_FALSE(out.text.empty());
  GrowthDriver d(scene);
  d.restore(parse_checkpoint(out.text, "cp", scene, scene.seed, {}));
  out.rewritten = format_checkpoint(scene, d.state(), {}) == out.text;
  d.run();
  out.resumed = d.result();
  return out;
}

TEST_CASE("a run with active-set steps resumed from a checkpoint counts the same steps and ends the same",
          "[checkpoint]") {
  Scene scene = small_scene();
  scene.fire.active_set_after = 500;
  scene.fire.active_set_try_after = 0;
  const Resumed run = resumed_from_checkpoint(scene, [](const RunResult& r) { return r.active_set_steps > 0; });
  CHECK(run.rewritten);
  const RunResult &r = run.resumed, &uninterrupted = run.uninterrupted;
  CHECK(r.active_set_steps == uninterrupted.active_set_steps);
  CHECK(r.active_set_factorisations == uninterrupted.active_set_factorisations);
  CHECK(r.active_set_updates == uninterrupted.active_set_updates);
  CHECK(r.force_evaluations == uninterrupted.force_evaluations);
  REQUIRE(r.jamming);
  CHECK(r.jamming->phi == uninterrupted.jamming->phi);
}

TEST_CASE("a run with jamming.continuation resumed from a checkpoint counts the same relaxed branches and crossings",
          "[checkpoint]") {
  Scene scene = small_scene();
  scene.continuation = true;
  scene.crossing_step = 0.01;
  // The first seed whose run crosses a stability loss (many runs of this small box cross none).
  for (scene.seed = 1; scene.seed <= 20; ++scene.seed) {
    GrowthDriver d(scene);
    d.run();
    if (d.result().branch_rearrangements > 0) break;
  }
  REQUIRE(scene.seed <= 20);
  const Resumed run = resumed_from_checkpoint(scene, [](const RunResult& r) { return r.branches > 0; });
  CHECK(run.rewritten);
  const std::string& text = run.text;
  const RunResult &r = run.resumed, &uninterrupted = run.uninterrupted;
  CHECK(r.branches == uninterrupted.branches);
  CHECK(r.branches_reached == uninterrupted.branches_reached);
  CHECK(r.branch_stability_losses == uninterrupted.branch_stability_losses);
  CHECK(r.branch_steps == uninterrupted.branch_steps);
  CHECK(r.branch_events == uninterrupted.branch_events);
  CHECK(uninterrupted.branch_rearrangements > 0);
  CHECK(r.branch_rearrangements == uninterrupted.branch_rearrangements);
  CHECK(r.newton_factorisations == uninterrupted.newton_factorisations);
  CHECK(r.jamming->phi == uninterrupted.jamming->phi);
  // More branches reached than followed is refused at the line, naming the counter.
  std::vector<std::string> lines = split_lines(text);
  const auto at =
      std::find_if(lines.begin(), lines.end(), [](const std::string& l) { return l.rfind("branches ", 0) == 0; });
  REQUIRE(at != lines.end());
  *at = "branches 1 2 0 0 0 0";
  const std::string line = std::to_string(at - lines.begin() + 1);
  CHECK_THROWS_WITH(parse_checkpoint(resealed(join_lines(lines)), "cp", scene, scene.seed, {}),
                    Contains("cp:" + line + ":") && Contains("branches reached: 2 is outside [0, 1]"));
}

TEST_CASE("a checkpoint is refused for another scene, seed or set of observers", "[checkpoint]") {
  const Snapshot& snap = snapshot();
  Counter c;
  Stateless p;
  const std::vector<Observer*> obs{&c, &p};
  Scene edited = small_scene();
  edited.P0 = 2e-3;
  CHECK_THROWS_WITH(parse_checkpoint(snap.text, "cp", edited, 3, obs),
                    Contains("cp:2:") && Contains("scene.toml has changed"));
  CHECK_THROWS_WITH(parse_checkpoint(snap.text, "cp", small_scene(), 4, obs), Contains("cp:3:") && Contains("seed"));
  // A stateful observer that the checkpoint does not know (an observer added to the scene).
  Counter extra;
  extra.label = "extra";
  CHECK_THROWS_WITH(parse_checkpoint(snap.text, "cp", small_scene(), 3, {&c, &p, &extra}),
                    Contains("no section for observer 'extra'"));
  // A section with state for an observer this run does not have.
  CHECK_THROWS_WITH(parse_checkpoint(snap.text, "cp", small_scene(), 3, {&p}),
                    Contains("state saved for observer 'counter'"));
  // A stateless observer may come and go (e.g. --quiet drops the progress display).
  CHECK_NOTHROW(parse_checkpoint(snap.text, "cp", small_scene(), 3, {&c}));
}

TEST_CASE("any accidental change of a checkpoint is refused by its checksum, naming the line", "[checkpoint]") {
  const Snapshot& snap = snapshot();
  const std::vector<std::string> lines = split_lines(snap.text);
  Counter c;
  const std::vector<Observer*> obs{&c};
  long refused = 0;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    std::vector<std::string> edits;
    std::vector<std::string> v = lines;
    v.erase(v.begin() + static_cast<long>(k));
    edits.push_back(join_lines(v));  // line removed
    v = lines;
    v.insert(v.begin() + static_cast<long>(k), lines[k]);
    edits.push_back(join_lines(v));  // line repeated
    v = lines;
    if (!v[k].empty()) v[k].back() = v[k].back() == '1' ? '2' : '1';
    edits.push_back(join_lines(v));  // last character changed
    for (const std::string& e : edits) {
      if (e == snap.text) continue;
      INFO("edit of line " << k + 1);
      CHECK_THROWS_AS(parse_checkpoint(e, "cp", small_scene(), 3, obs), InputError);
      ++refused;
    }
  }
  CHECK(refused > 3 * 50);
  for (std::size_t cut = 0; cut < snap.text.size(); cut += 97)
    CHECK_THROWS_AS(parse_checkpoint(snap.text.substr(0, cut), "cp", small_scene(), 3, obs), InputError);
}

TEST_CASE("a deliberately edited checkpoint (checksum recomputed) is range-checked field by field", "[checkpoint]") {
  // Every field of every line is replaced by values that break a range, a type or a relation;
  // each edit must be refused with InputError naming file and line, or give a state the driver
  // can continue from — never another exception, never a crash or a hang. Three checkpoints: one
  // past the first target (with an observer's section), one inside the bracket search (its trials),
  // one inside a relaxation.
  for (const int source : {0, 1, 2}) {
    const bool bracket = source > 0, relaxation = source == 2;
    const std::vector<std::string> lines = split_lines(relaxation ? relaxation_snapshot().text
                                                       : bracket  ? bracket_snapshot().text
                                                                  : snapshot().text);
    // Of a relaxation in progress its two header lines and the first row of each of its blocks.
    std::vector<std::size_t> edited;
    for (std::size_t k = 1; k + 1 < lines.size(); ++k) edited.push_back(k);  // not the magic, not the checksum
    if (relaxation) {
      const auto at =
          std::ranges::find_if(lines, [](const std::string& l) { return l.rfind("relaxation 1 ", 0) == 0; });
      REQUIRE(at != lines.end());
      const std::size_t r = static_cast<std::size_t>(at - lines.begin());
      std::istringstream words(*at);
      std::string w;
      for (int i = 0; i < 5; ++i) words >> w;  // relaxation 1 attempts index cells
      edited = {r, r + 1, r + 2, r + 2 + std::stoul(w)};
    }
    const std::vector<std::string> values{"",
                                          "x",
                                          "-1",
                                          "0",
                                          "1e308",
                                          "nan",
                                          "inf",
                                          "9223372036854775807",
                                          "-9223372036854775808",
                                          "99999999999999999999",
                                          "0.5",
                                          "\x1b[2J"};
    long refused = 0, accepted = 0;
    for (const std::size_t k : edited) {
      std::vector<std::string> fields;
      std::istringstream ws(lines[k]);
      for (std::string w; ws >> w;) fields.push_back(w);
      if (lines[k].rfind("rng ", 0) == 0) fields.resize(3);  // 313 numbers of one kind: a few suffice
      for (std::size_t f = 0; f < fields.size(); ++f)
        for (const std::string& val : values) {
          std::vector<std::string> w;
          std::istringstream again(lines[k]);
          for (std::string x; again >> x;) w.push_back(x);
          w[f] = val;
          std::string line;
          for (std::size_t i = 0; i < w.size(); ++i) line += (i ? " " : "") + w[i];
          std::vector<std::string> v = lines;
          v[k] = line;
          const std::string text = resealed(join_lines(v));
          const Scene scene = bracket ? bracket_snapshot().scene : small_scene();
          Counter c;
          std::vector<Observer*> obs;
          if (!bracket) obs.push_back(&c);
          INFO((relaxation ? "relaxation checkpoint, "
                : bracket  ? "bracket checkpoint, "
                           : "")
               << "line " << k + 1 << " field " << f + 1 << " = '" << io::escape_control(val) << "'");
          try {
            GrowthState s = parse_checkpoint(text, "cp", scene, scene.seed, obs);
            // One growth attempt from the accepted state, with a short FIRE budget (an edited
            // coordinate can leave overlaps that take long to relax; ending unconverged is fine).
            Scene quick = scene;
            quick.fire.max_iterations = 200;
            GrowthDriver d(quick);
            for (Observer* o : obs) d.add_observer(*o);
            d.restore(std::move(s));
            d.advance();
            ++accepted;
          } catch (const InputError& e) {
            // The driver names the checkpoint when the attempt it resumes does not fit the relaxation.
            const std::string m = e.what();
            CHECK((m.rfind("cp:", 0) == 0 || (relaxation && m.rfind("checkpoint: ", 0) == 0)));
            CHECK(m.find('\x1b') == std::string::npos);
            ++refused;
          }
        }
    }
    INFO(refused << " refused, " << accepted << " accepted");
    CHECK(refused > (relaxation ? 200 : 1000));
    CHECK(accepted > 0);  // e.g. a coordinate changed within its range: a valid state of another run
  }
}
