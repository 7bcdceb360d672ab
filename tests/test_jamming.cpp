// The jamming criterion and the searches onto it (budjam/jamming.hpp): the window's decision table
// on its edges, and each search's answers to the driver on hand-made trials.
#include "budjam/jamming.hpp"

#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

using namespace budjam;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double below(double x) { return std::nextafter(x, -kInf); }
double above(double x) { return std::nextafter(x, kInf); }

// φ(Δt) of a smooth growth without divisions.
double linear_phi(double dt) { return 0.8 + 0.05 * dt; }

SearchFrom unjammed_from(double phi, double dt) { return SearchFrom{true, phi, dt, std::nullopt, 0, linear_phi}; }

// A trial of step dt whose packing (one cell) has packing fraction phi.
Trial trial_at(double dt, double phi) {
  Trial t;
  t.dt = dt;
  t.packing.add_cell(0, 0, 0, 0.5, 0.002, -1);
  t.packing.box.L = 1.0;
  t.packing.box.L = std::sqrt(t.packing.packing_fraction() / phi);
  return t;
}

Scene scene_with(JammingSearch search) {
  Scene s;
  s.search = search;
  s.epsilon_U = 1e-16;
  return s;
}

}  // namespace

TEST_CASE("jamming window: below under eps_U, inside from eps_U to 2 eps_U inclusive, above beyond", "[fast]") {
  for (const double eps : {1e-16, 1e-6, 0.3}) {
    INFO("eps_U = " << eps);
    const JammingWindow w(eps);
    CHECK(w.side(0.0) == WindowSide::below);
    CHECK(w.side(below(eps)) == WindowSide::below);
    CHECK(w.side(eps) == WindowSide::inside);  // the bottom edge belongs to the window
    CHECK(w.side(above(eps)) == WindowSide::inside);
    CHECK(w.side(1.5 * eps) == WindowSide::inside);
    CHECK(w.side(below(2 * eps)) == WindowSide::inside);
    CHECK(w.side(2 * eps) == WindowSide::inside);  // so does the top edge
    CHECK(w.side(above(2 * eps)) == WindowSide::above);
    CHECK(w.side(2.5 * eps) == WindowSide::above);
    CHECK(w.side(3 * eps) == WindowSide::above);
    CHECK(w.side(kInf) == WindowSide::above);
    CHECK(w.side(std::nan("")) == WindowSide::above);  // an energy that is not a number is no jamming point

    // The predicates the driver asks are the same table.
    CHECK_FALSE(w.jammed(below(eps)));
    CHECK(w.jammed(eps));
    CHECK(w.jammed(3 * eps));  // above jamming, past the window, is jammed
    CHECK_FALSE(w.candidate(below(eps)));
    CHECK(w.candidate(eps));
    CHECK(w.candidate(2 * eps));
    CHECK_FALSE(w.candidate(above(2 * eps)));
    // Named as bench_replay prints them.
    CHECK(std::string(to_string(w.side(0.0))) == "below");
    CHECK(std::string(to_string(w.side(eps))) == "inside");
    CHECK(std::string(to_string(w.side(3 * eps))) == "above");
  }
}

TEST_CASE("jamming window: the searches aim at its middle in sqrt(E/N) and stop classifying relaxations below it",
          "[fast]") {
  const double eps = 1e-16;
  const JammingWindow w(eps);
  CHECK(w.s_centre() == Approx(0.5 * (std::sqrt(eps) + std::sqrt(2 * eps))).epsilon(1e-15));
  CHECK(w.s_top() == std::sqrt(2 * eps));
  CHECK(w.floor() == eps);
  // A budgeted relaxation is finished up to 100 times the top of the window, deferred beyond.
  CHECK(w.near(2 * eps));
  CHECK(w.near(100 * (2 * eps)));
  CHECK_FALSE(w.near(above(100 * (2 * eps))));
}

TEST_CASE("overshoot line: s = sqrt(E/N) and the virial slope s / (2U phi / (U + L^2 P))", "[fast]") {
  const double phi = 0.85, E = 4e-12, P = 1e-7, L = 10;
  const std::size_t N = 50;
  const JammingOvershoot o = overshoot_line(phi, E, N, P, L);
  const double U = E * N;
  CHECK(o.phi == phi);
  CHECK(o.s == Approx(2e-6).epsilon(1e-15));
  CHECK(o.slope == Approx(2e-6 / (2 * U * phi / (U + L * L * P))).epsilon(1e-14));
  CHECK(overshoot_line(phi, 0.0, N, 0.0, L).slope == 0.0);  // no energy, no line
}

TEST_CASE("dt_for_phi lands within its tolerance, and returns the lower end when the bracket vanishes", "[fast]") {
  const double dt = dt_for_phi(linear_phi, 0.825, 0.0, 1.0, 1e-9);
  CHECK(std::abs(linear_phi(dt) - 0.825) <= 1e-9);
  CHECK(dt > 0.0);
  CHECK(dt <= 1.0);
  // φ jumps over the goal (a division): the bracket closes on the jump and its lower end is returned.
  const PhiAfter jump = [](double step) { return step < 0.5 ? 0.8 : 0.9; };
  const double at_jump = dt_for_phi(jump, 0.85, 0.0, 1.0, 1e-9);
  CHECK(at_jump < 0.5);
  CHECK(0.5 - at_jump < 1e-12);
}

TEST_CASE(
    "search registry: one row per enumerator in its order, each making its search; the key's values are its names",
    "[fast]") {
  const auto& kinds = jamming_searches();
  std::vector<std::string> names;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    INFO(kinds[k].name);
    CHECK(static_cast<std::size_t>(kinds[k].search) == k);
    CHECK_FALSE(kinds[k].description.empty());
    CHECK(make_jamming_searcher(scene_with(kinds[k].search)) != nullptr);
    names.emplace_back(kinds[k].name);
  }
  const SceneKey* key = find_scene_key("jamming.search");
  REQUIRE(key != nullptr);
  CHECK(key->choices == names);
  for (const std::string& name : names) CHECK(key->help.find('"' + name + '"') != std::string::npos);
}

TEST_CASE("bisection search: passes the driver's step on and keeps no overshoot", "[fast]") {
  const std::unique_ptr<JammingSearcher> s = make_jamming_searcher(scene_with(JammingSearch::bisection));
  const NextTrial next = s->next_trial(unjammed_from(0.8, 0.25));
  CHECK(next.kind == NextTrial::Kind::grow);
  CHECK(next.dt == 0.25);
  CHECK_FALSE(s->keeps_overshoots());
  CHECK_FALSE(s->classifying());
  CHECK(s->trial_budget() == 0);
  // Above jamming it does not aim at targets either: a passed target halves the step.
  SearchFrom jammed{false, 0.84, 1.0, 0.81, 1e-3, linear_phi};
  CHECK(s->next_trial(jammed).dt == 1.0);
}

TEST_CASE("secant search: aims at the middle of the window on the overshoot's line, prunes and resets", "[fast]") {
  const Scene scene = scene_with(JammingSearch::secant);
  const std::unique_ptr<JammingSearcher> s = make_jamming_searcher(scene);
  CHECK(s->next_trial(unjammed_from(0.8, 1.0)).dt == 1.0);  // no overshoot yet: the nominal step
  REQUIRE(s->keeps_overshoots());
  const JammingOvershoot o{0.85, 1e-6, 1e-4};
  s->keep_overshoot(Trial{}, o);
  const double goal = o.phi - (o.s - JammingWindow(scene.epsilon_U).s_centre()) / o.slope;
  const NextTrial next = s->next_trial(unjammed_from(0.8, 1.0));
  CHECK(next.kind == NextTrial::Kind::grow);
  CHECK(std::abs(linear_phi(next.dt) - goal) <= 1e-3 * (o.phi - 0.8));
  CHECK(s->state().bracket_width == Approx(0.05));

  // Accepted below it: the overshoot stays while its line passes under the window there.
  s->accepted(0.84, true, false);
  REQUIRE(s->state().overshoots.size() == 1);
  // A state whose line through the overshoot lies above the window drops it.
  const std::unique_ptr<JammingSearcher> flat = make_jamming_searcher(scene);
  flat->keep_overshoot(Trial{}, {0.85, 1e-6, 1e-9});
  flat->accepted(0.84, true, false);
  CHECK(flat->state().overshoots.empty());

  // Its state round-trips (the checkpoint), and a change of phase forgets it.
  const std::unique_ptr<JammingSearcher> copy = make_jamming_searcher(scene);
  copy->restore(s->state());
  CHECK(copy->state().overshoots.size() == 1);
  CHECK(copy->state().bracket_width == s->state().bracket_width);
  s->accepted(0.86, false, true);
  CHECK(s->state().overshoots.empty());
  CHECK(s->state().bracket_width == 0);
}

TEST_CASE("bracket search: an overshoot opens it, trials fall inside, a collapsed bracket settles its lower end",
          "[fast]") {
  Scene scene = scene_with(JammingSearch::bracket);
  scene.trial_budget = 5000;
  const std::unique_ptr<JammingSearcher> s = make_jamming_searcher(scene);
  CHECK_FALSE(s->classifying());
  CHECK(s->trial_budget() == 0);
  CHECK(s->next_trial(unjammed_from(0.8, 1.0)).dt == 1.0);

  // The overshoot at Δt = 1 (s = 1e-6, slope 1e-4: its line reaches the middle of the window
  // ≈ 9.9e-3 below it in φ) opens the bracket.
  Trial top = trial_at(1.0, 0.85);
  top.E = 1e-12;
  s->keep_overshoot(std::move(top), {0.85, 1e-6, 1e-4});
  CHECK(s->classifying());
  CHECK(s->trial_budget() == 5000);
  const NextTrial inside = s->next_trial(unjammed_from(0.8, 1.0));
  CHECK(inside.kind == NextTrial::Kind::grow);
  CHECK(inside.dt >= 1.0 / 32);
  CHECK(inside.dt <= 1.0 - 1.0 / 32);

  // A trial placed inside starts from the overshoot's relaxed positions.
  Trial placed = trial_at(inside.dt, 0.84);
  s->place(placed);
  CHECK(placed.start == TrialStart::lowest_overshoot);

  // A trial below the window 1e-2 under the overshoot: still wider than an eighth of the reach.
  s->keep_below(trial_at(0.8, 0.84));
  const NextTrial between = s->next_trial(unjammed_from(0.8, 1.0));
  CHECK(between.kind == NextTrial::Kind::grow);
  CHECK(between.dt > 0.8);
  CHECK(between.dt < 1.0);

  // One 1e-3 under it: collapsed, the lower end is settled and the bracket closed.
  s->keep_below(trial_at(0.98, 0.849));
  const NextTrial settle = s->next_trial(unjammed_from(0.8, 1.0));
  CHECK(settle.kind == NextTrial::Kind::settle);
  CHECK(settle.trial.dt == 0.98);
  CHECK_FALSE(s->classifying());
}

TEST_CASE("bracket search: a deferred upper end is resumed once the bracket collapses onto it", "[fast]") {
  const std::unique_ptr<JammingSearcher> s = make_jamming_searcher(scene_with(JammingSearch::bracket));
  Trial deferred = trial_at(1.0, 0.85);
  deferred.deferred = true;
  s->keep_overshoot(std::move(deferred), {0.85, 1e-6, 1e-4});
  s->keep_below(trial_at(0.98, 0.849));
  const NextTrial next = s->next_trial(unjammed_from(0.8, 1.0));
  CHECK(next.kind == NextTrial::Kind::resume);
  CHECK(next.trial.deferred);
  CHECK(next.trial.dt == 1.0);
  CHECK(s->classifying());  // the bracket stays open for the resumed trial's verdict
}

TEST_CASE("secant and bracket searches land a target above jamming; a phase change closes the bracket", "[fast]") {
  for (const JammingSearch kind : {JammingSearch::secant, JammingSearch::bracket}) {
    const std::unique_ptr<JammingSearcher> s = make_jamming_searcher(scene_with(kind));
    const SearchFrom from{false, 0.8, 1.0, 0.83, 1e-6, linear_phi};
    const NextTrial next = s->next_trial(from);
    CHECK(std::abs(linear_phi(next.dt) - 0.83) <= 0.5e-6);
    // The nominal step that does not pass the target is kept.
    CHECK(s->next_trial(SearchFrom{false, 0.8, 0.2, 0.83, 1e-6, linear_phi}).dt == 0.2);
  }
  const std::unique_ptr<JammingSearcher> b = make_jamming_searcher(scene_with(JammingSearch::bracket));
  b->keep_overshoot(trial_at(1.0, 0.85), {0.85, 1e-6, 1e-4});
  REQUIRE(b->classifying());
  b->accepted(0.83, false, true);
  CHECK_FALSE(b->classifying());
}
