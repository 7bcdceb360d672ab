// Active-set Gauss–Newton minimisation (active_set.hpp) against FIRE on packings whose sizes
// changed under them: the same minimum, a stable one, reached without raising the energy.
#include "budjam/active_set.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/stability.hpp"
#include "support/compressed_packing.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

using namespace budjam;

namespace {

// A jammed packing of 60 random dumbbells relaxed just above its jamming point, then every bud's
// area multiplied by `factor`: the start of a relaxation at fixed sizes, as a growth trial is.
Packing resized(double factor) {
  static const Packing jammed = [] {
    Packing q = testing::compress_random_dumbbells(60, 5).packing;
    ForceField field;
    REQUIRE(minimise(q, field).converged);
    return q;
  }();
  Packing p = jammed;
  for (double& b : p.b) b *= std::sqrt(factor);
  return p;
}

double energy(const Packing& p) {
  ForceField field;
  return field.energy(p);
}

double largest_contact_force(const Packing& p) {
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  double f = 0;
  for (const Contact& c : find_contacts(p, field.lobes(), field.neighbours())) f = std::max(f, c.force());
  return f;
}

ActiveSetParams params_for(const Packing& p) {
  ActiveSetParams a;
  a.force_tol = force_resolution(p);
  a.energy_floor = 1e-20 * static_cast<double>(p.size());
  return a;
}

}  // namespace

TEST_CASE("active-set steps reach the minimum FIRE reaches, and FIRE started there moves nothing", "[active_set]") {
  for (const double factor : {1.002, 0.9995}) {
    CAPTURE(factor);
    Packing by_fire = resized(factor), by_active_set = resized(factor);
    const double start = energy(by_active_set);
    ForceField fire_field;
    FireParams fire;
    fire.newton_force = 0;
    REQUIRE(minimise(by_fire, fire_field, fire).converged);

    ForceField field;
    const ActiveSetResult r = active_set_minimise(by_active_set, field, params_for(by_active_set));
    // Gauss–Newton steps may stall short of the force tolerance, where the prestress they leave
    // out is what is left of the gradient: at forces a millionth of the contact forces or less.
    CHECK(r.stop != ActiveSetStop::step_cap);
    CHECK(r.max_force < 1e-6 * largest_contact_force(by_active_set));
    CHECK(r.energy < start);
    CHECK(r.energy == Approx(fire_field.energy(by_fire)).epsilon(1e-9));
    CHECK(r.factorisations >= 1);

    const FireResult after = minimise(by_active_set, field, fire);
    CHECK(after.converged);
    CHECK(after.evaluations < 1000);
    CHECK(after.energy == Approx(r.energy).epsilon(1e-12));

    // A stable minimum: no eigenvalue of the Hessian of the non-rattlers below zero.
    Eigen::VectorXd F;
    field.invalidate();
    field.evaluate(by_active_set, F);
    const std::vector<Contact> contacts = find_contacts(by_active_set, field.lobes(), field.neighbours());
    CHECK(stability(by_active_set, contacts, analyse_network(by_active_set.size(), contacts)).minimum());
  }
}

TEST_CASE("a packing shrunk below jamming is relaxed to the energy floor", "[active_set]") {
  Packing p = resized(0.9);
  ForceField field;
  const ActiveSetResult r = active_set_minimise(p, field, params_for(p));
  CHECK(r.stop == ActiveSetStop::energy_floor);
  CHECK(r.energy < 1e-20 * static_cast<double>(p.size()));
  CHECK(energy(p) == r.energy);
}

TEST_CASE("the steps change the factor by rank-1 updates between factorisations", "[active_set]") {
  Packing p = resized(1.002);
  ForceField field;
  const ActiveSetResult r = active_set_minimise(p, field, params_for(p));
  REQUIRE(r.stop != ActiveSetStop::step_cap);
  // Contacts enter and leave the active set one by one: most of its changes are updates.
  CHECK(r.updates > 0);
  CHECK(r.inner > r.factorisations);
}

TEST_CASE("updating the factor and making it afresh at every change reach the same minimum", "[active_set]") {
  Packing updated = resized(1.002), fresh = resized(1.002);
  ForceField f1, f2;
  ActiveSetParams by_updates = params_for(updated), afresh = params_for(fresh);
  by_updates.max_updates = 1000000;  // every change an update
  afresh.max_updates = 0;            // every change a factorisation
  const ActiveSetResult u = active_set_minimise(updated, f1, by_updates);
  const ActiveSetResult a = active_set_minimise(fresh, f2, afresh);
  for (const ActiveSetResult& r : {u, a}) {  // each stops where the Gauss–Newton model leaves off
    CHECK(r.stop != ActiveSetStop::step_cap);
    CHECK(r.max_force < 1e-6 * largest_contact_force(updated));
  }
  CHECK(a.updates == 0);
  CHECK(u.updates > 0);
  CHECK(u.factorisations < a.factorisations);
  CHECK(u.energy == Approx(a.energy).epsilon(1e-9));
}

TEST_CASE("the factor is updated for up to max(64, sqrt(n)/3) changes: the break-even grows as sqrt(n)",
          "[active_set]") {
  CHECK(active_set_max_updates(3 * 60) == 64);
  CHECK(active_set_max_updates(3 * 7663) == 64);  // an L = 100 colony: as below
  CHECK(active_set_max_updates(36864) == 64);
  CHECK(active_set_max_updates(3 * 68967) == 151);
  CHECK(active_set_max_updates(9000000) == 1000);
}

TEST_CASE("FIRE hands a minimisation to active-set steps after active_set_after evaluations", "[active_set]") {
  Packing alone = resized(1.002), handed = resized(1.002);
  FireParams fire;
  fire.newton_force = 0;
  fire.active_set_after = 0;
  ForceField f1, f2;
  const FireResult a = minimise(alone, f1, fire);
  fire.active_set_after = 50;
  const FireResult b = minimise(handed, f2, fire);
  REQUIRE(a.converged);
  REQUIRE(b.converged);
  CHECK(a.active_set_steps == 0);
  CHECK(b.active_set_steps > 0);
  CHECK(b.active_set_factorisations >= 1);
  CHECK(b.energy == Approx(a.energy).epsilon(1e-9));
}

TEST_CASE("by default a minimisation FIRE finishes within active_set_try_after evaluations is FIRE's, bit for bit",
          "[active_set]") {
  Packing by_default = resized(1.002), alone = resized(1.002);
  FireParams defaults, fire_alone;
  fire_alone.active_set_after = 0;
  ForceField f1, f2;
  const FireResult a = minimise(by_default, f1, defaults);
  const FireResult b = minimise(alone, f2, fire_alone);
  REQUIRE(a.converged);
  REQUIRE(b.evaluations < defaults.active_set_try_after);
  CHECK(a.active_set_steps == 0);
  CHECK(a.evaluations == b.evaluations);
  CHECK(by_default.q == alone.q);
}

TEST_CASE("a step longer than give_up_move ends the active-set steps before it is taken", "[active_set]") {
  Packing p = resized(1.002);
  const Packing start = p;
  ForceField field;
  ActiveSetParams params = params_for(p);
  params.give_up_move = 1e-12;  // far below the overlaps the resizing made
  const ActiveSetResult r = active_set_minimise(p, field, params);
  CHECK(r.stop == ActiveSetStop::long_step);
  CHECK(r.steps == 1);
  CHECK(p.q == start.q);
}

// FIRE alone (the Newton finish off; active_set_after = 0 makes no try either) and FIRE with one
// active-set try after 50 evaluations, the try given up at a step longer than `try_move`, on the
// same resized packing.
struct TryAndAlone {
  Packing tried = resized(1.002), alone = resized(1.002);
  FireResult with_try, without;
  explicit TryAndAlone(double try_move) {
    FireParams fire;
    fire.newton_force = 0;
    fire.active_set_after = 0;
    fire.active_set_try_after = 50;
    fire.active_set_try_move = try_move;
    ForceField f1, f2;
    without = minimise(alone, f1, fire);
    CHECK(without.active_set_steps == 0);
    fire.active_set_after = 1000000;
    with_try = minimise(tried, f2, fire);
    REQUIRE(without.converged);
    REQUIRE(without.evaluations > 50);
  }
};

TEST_CASE("an undone speculative try leaves FIRE's path bit for bit, its cost counted", "[active_set]") {
  const TryAndAlone run(1e-12);  // every step is a "rearrangement": the try is undone
  CHECK(run.with_try.active_set_tries_undone == 1);
  CHECK(run.with_try.active_set_steps == 1);
  CHECK(run.with_try.iterations == run.without.iterations);
  CHECK(run.with_try.evaluations > run.without.evaluations);
  CHECK(run.tried.q == run.alone.q);
}

TEST_CASE("a speculative try that converges ends the minimisation at FIRE's minimum", "[active_set]") {
  const TryAndAlone run(1.0);  // no step is too long
  REQUIRE(run.with_try.converged);
  CHECK(run.with_try.active_set_tries_undone == 0);
  CHECK(run.with_try.active_set_steps > 0);
  CHECK(run.with_try.iterations < run.without.iterations);
  CHECK(run.with_try.energy == Approx(run.without.energy).epsilon(1e-9));
  CHECK(run.with_try.max_force < std::max(kDefaultForceTol, force_resolution(run.tried)));
}

TEST_CASE("active-set minimisation is deterministic", "[active_set]") {
  Packing p1 = resized(1.002), p2 = resized(1.002);
  ForceField f1, f2;
  active_set_minimise(p1, f1, params_for(p1));
  active_set_minimise(p2, f2, params_for(p2));
  CHECK(p1.q == p2.q);
}
