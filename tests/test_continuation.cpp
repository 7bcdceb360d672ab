// Branch continuation (continuation.hpp) on a small jammed packing: the growth rate of the forces,
// the tangent, the corrector, the events and the end point against FIRE.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/continuation.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/newton.hpp"
#include "budjam/stability.hpp"
#include "support/compressed_packing.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace budjam;

namespace {

// A jammed packing of random dumbbells just above its jamming point, relaxed to the force tolerance
// of the runs.
const Packing& jammed() {
  static const Packing p = [] {
    Packing q = testing::compress_random_dumbbells(60, 5).packing;
    ForceField field;
    FireParams params;
    params.newton_force = 1e-8;
    REQUIRE(minimise(q, field, params).converged);
    return q;
  }();
  return p;
}

// The path on which every bud's area is multiplied by `factor`.
BranchSizes path(const Packing& p, double factor) {
  BranchSizes s{p.b, p.b};
  for (double& b : s.to) b *= std::sqrt(factor);
  return s;
}

std::vector<Contact> contacts_of(const Packing& p, ForceField& field) {
  Eigen::VectorXd F;
  field.invalidate();
  field.evaluate(p, F);
  return find_contacts(p, field.lobes(), field.neighbours());
}

// The relaxed state at t on `sizes` by Newton alone from p (p relaxed nearby): the same minimum.
Packing relaxed_at(const Packing& p, const BranchSizes& sizes, double t) {
  Packing r = p;
  r.b = sizes.at(t);
  ForceField field;
  NewtonParams params;
  params.force_tol = force_resolution(r);
  REQUIRE(newton_finish(r, field, params).stop == NewtonStop::converged);
  return r;
}

// p followed along `sizes`: where the branch ended (the field current for it) and how.
struct Followed {
  Packing packing;
  ForceField field;
  ContinuationResult run;
};
Followed followed(const Packing& p, const BranchSizes& sizes, const ContinuationParams& params) {
  Followed f{p, ForceField(), {}};
  f.run = follow_branch(f.packing, f.field, sizes, params);
  return f;
}

}  // namespace

TEST_CASE("the analytic growth rate of the forces equals a central difference of the forces", "[continuation]") {
  const Packing& p = jammed();
  ForceField field;
  for (const double factor : {1.01, 0.99}) {
    const BranchSizes sizes = path(p, factor);
    const std::vector<Contact> contacts = contacts_of(p, field);
    REQUIRE(!contacts.empty());
    const Eigen::VectorXd analytic = force_rate(p, contacts, sizes.rate(0.0));
    const Eigen::VectorXd difference = force_rate_difference(p, field, sizes, 0.0, 1e-5);
    REQUIRE(analytic.lpNorm<Eigen::Infinity>() > 1e-3);
    CHECK((analytic - difference).lpNorm<Eigen::Infinity>() < 1e-6 * analytic.lpNorm<Eigen::Infinity>());
  }
}

TEST_CASE("the predicted tangent agrees with a finite difference of relaxed states", "[continuation]") {
  const Packing& p = jammed();
  const BranchSizes sizes = path(p, 1.01);
  ForceField field;
  const std::vector<Contact> contacts = contacts_of(p, field);
  const ContactNetwork net = analyse_network(p.size(), contacts);
  CholmodSolver solver;
  Eigen::VectorXd dq;
  REQUIRE(branch_tangent(p, contacts, sizes.rate(0.0), 1e-10, solver, dq));
  // Predicted minus relaxed, against how far the relaxed state moved: O(δ) against O(1).
  double previous_error = 0;
  for (const double dt : {2e-3, 1e-3}) {
    const Packing relaxed = relaxed_at(p, sizes, dt);
    Packing predicted = p;
    predicted.q += dt * dq;
    predicted.b = relaxed.b;
    const double moved = testing::largest_lobe_difference(p, relaxed, net),
                 error = testing::largest_lobe_difference(predicted, relaxed, net);
    REQUIRE(moved > 0);
    CHECK(error < 0.05 * moved);
    if (previous_error > 0) CHECK(error < 0.35 * previous_error);  // second order in δ
    previous_error = error;
  }
}

TEST_CASE("the corrector converges quadratically on a fixed network", "[continuation]") {
  const Packing& p = jammed();
  // From the relaxed positions with the sizes of t = 1: one Newton iteration at a time, while the
  // force is well above the rounding floor.
  Packing q = p;
  q.b = path(p, 1.0002).at(1.0);
  NewtonParams one;
  one.force_tol = force_resolution(q);
  one.max_iterations = 1;
  one.reuse_factor = false;
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(q, F);
  std::vector<double> force{max_scaled_force(q, F)};
  std::vector<std::vector<Contact>> networks;
  while (force.back() > 1e3 * one.force_tol && force.size() < 8) {
    const NewtonResult r = newton_finish(q, field, one);
    REQUIRE(r.iterations == 1);
    force.push_back(r.max_force);
    networks.push_back(contacts_of(q, field));
  }
  REQUIRE(force.size() >= 4);
  for (std::size_t k = 1; k < networks.size(); ++k) REQUIRE(networks[k].size() == networks[0].size());
  // Quadratic: f_{k+1} ≤ K f_k² once the iteration is in its basin (from the second step on), with
  // K the regularisation's (μ = shift · f) scale over the smallest stiffness; a linear rate
  // f_{k+1} = c f_k fails this as soon as f_k < c / K.
  constexpr double K = 1e4;
  int quadratic_steps = 0;
  for (std::size_t k = 1; k + 1 < force.size(); ++k) {
    INFO("iteration " << k << ": " << force[k] << " -> " << force[k + 1]);
    CHECK(force[k + 1] <= K * force[k] * force[k]);
    if (force[k] < 1e-4) ++quadratic_steps;
  }
  CHECK(quadratic_steps >= 2);
}

TEST_CASE("an opening event is located where the contact force crosses zero", "[continuation]") {
  const Packing& p = jammed();
  const BranchSizes sizes = path(p, 0.995);
  ContinuationParams params;
  params.event_tol = 1e-4;
  params.first_step = 0.01;
  const ContinuationResult run = followed(p, sizes, params).run;
  const auto opening =
      std::ranges::find_if(run.events, [](const BranchEvent& e) { return e.kind == BranchEvent::Kind::opening; });
  REQUIRE(opening != run.events.end());

  const double t = opening->t;
  // The same branch followed to just before and to the event: the contact is there and its force
  // is about to vanish; then it is gone.
  const auto force_at = [&](double t_end) {
    Packing q = p;
    ForceField f;
    const ContinuationResult r = follow_branch(q, f, BranchSizes{p.b, sizes.at(t_end)}, params);
    REQUIRE(r.t == 1.0);
    for (const Contact& c : contacts_of(q, f))
      if (c.i == opening->i && c.j == opening->j) return c.force();
    return 0.0;
  };
  const double before = force_at(t - 2 * params.event_tol), at = force_at(t);
  const double scale = std::abs(force_at(std::max(0.0, t - 0.2)));
  const double tol = std::max(params.force_tol, force_resolution(p));
  CHECK(before > tol);
  CHECK(before < 0.1 * scale);
  CHECK(at <= tol);
}

TEST_CASE("continuation reaches the state FIRE relaxes to at the same sizes, with the same network", "[continuation]") {
  const Packing& p = jammed();
  const BranchSizes sizes = path(p, 1.00002);
  auto [branch, field, run] = followed(p, sizes, {});
  REQUIRE(run.end == BranchEnd::reached);
  CHECK(run.events.empty());
  Packing fire = p;
  fire.b = sizes.at(1.0);
  ForceField fire_field;
  FireParams fp;
  fp.newton_force = 0;
  REQUIRE(minimise(fire, fire_field, fp).converged);
  const std::vector<Contact> a = contacts_of(branch, field), b = contacts_of(fire, fire_field);
  REQUIRE(a.size() == b.size());
  const ContactNetwork net = analyse_network(p.size(), a);
  const double Ua = field.energy(branch), Ub = fire_field.energy(fire);
  CHECK(std::abs(Ua - Ub) < 1e-9 * Ub);
  CHECK(testing::largest_lobe_difference(branch, fire, net) < 1e-8);
  CHECK(run.factorisations < 20);
}

TEST_CASE("start_on_branch refuses packings of different cells", "[continuation]") {
  Packing trial = jammed(), other = jammed();
  other.b.pop_back();
  other.q.conservativeResize(other.q.size() - 3);
  ForceField field;
  CHECK_THROWS_AS(start_on_branch(trial, other, field, {}), std::invalid_argument);
}

TEST_CASE(
    "a stability loss is crossed by a rearrangement and the branch goes on to a stable minimum at the trial's sizes",
    "[continuation]") {
  const Packing& p = jammed();
  const BranchSizes sizes = path(p, 0.99);
  ContinuationParams params;
  const ContinuationResult lost = followed(p, sizes, params).run;
  REQUIRE(lost.end == BranchEnd::stability_lost);
  REQUIRE(lost.t < 1.0);

  params.rearrangement = FireParams{};
  auto [crossed, field, run] = followed(p, sizes, params);
  REQUIRE(run.end == BranchEnd::reached);
  CHECK(run.rearrangements >= 1);
  CHECK(run.rearrangement_evaluations > 0);
  CHECK(run.rearrangement_evaluations < run.evaluations);
  CHECK(crossed.b == sizes.at(1.0));
  // Up to the first loss the two followed the same branch.
  const auto before_loss = [&](const BranchEvent& e) { return e.t <= lost.t; };
  CHECK(std::ranges::count_if(run.events, before_loss) == std::ranges::count_if(lost.events, before_loss));
  // A minimum: no force above the tolerance, no unstable mode, and FIRE started there stays.
  Eigen::VectorXd F;
  field.invalidate();
  const double U = field.evaluate(crossed, F);
  CHECK(max_scaled_force(crossed, F) <= std::max(params.force_tol, force_resolution(crossed)));
  const std::vector<Contact> contacts = contacts_of(crossed, field);
  CHECK(stability(crossed, contacts, analyse_network(crossed.size(), contacts)).minimum());
  Packing again = crossed;
  ForceField fire_field;
  FireParams fp;
  fp.newton_force = 0;
  const FireResult fr = minimise(again, fire_field, fp);
  CHECK(fr.iterations <= 1);
  CHECK(std::abs(fr.energy - U) <= 1e-12 * U);
}
