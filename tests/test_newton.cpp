// Newton finish (newton.hpp): on jammed packings it lands on the minimum FIRE finds, with the
// force falling quadratically, and it hands back to FIRE where the Hessian is indefinite.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/newton.hpp"
#include "support/compressed_packing.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace budjam;

namespace {

// A jammed packing of random dumbbells just above its jamming point, relaxed by FIRE.
const testing::CompressedPacking& jammed() {
  static const testing::CompressedPacking cp = testing::compress_random_dumbbells(60, 5);
  return cp;
}

// The same packing, every bud 0.2 % larger: overlaps grow and the cells are out of balance.
Packing swollen(const Packing& p) {
  Packing s = p;
  for (double& b : s.b) b *= 1.002;
  return s;
}

}  // namespace

TEST_CASE("Newton finish lands on FIRE's minimum of a jammed packing: same energy and positions", "[newton]") {
  Packing fire_only = swollen(jammed().packing), with_newton = fire_only;
  ForceField f1, f2;
  FireParams params;
  params.newton_force = 0.0;
  const FireResult a = minimise(fire_only, f1, params);
  params.newton_force = 1e-5;
  const FireResult b = minimise(with_newton, f2, params);
  REQUIRE(a.converged);
  REQUIRE(b.converged);
  INFO("FIRE alone: " << a.iterations << " iterations; with Newton: " << b.iterations << " + " << b.newton_iterations
                      << " Newton steps");
  CHECK(b.newton_iterations >= 1);
  CHECK(b.max_force < params.force_tol);
  CHECK(b.stop == MinimiserStop::force);
  CHECK(b.energy / 60 > 1e-12);  // jammed: a real minimum with stressed contacts
  CHECK(b.energy == Approx(a.energy).epsilon(1e-8));
  Eigen::VectorXd F;
  f1.evaluate(fire_only, F);
  const std::vector<Contact> c = find_contacts(fire_only, f1.lobes(), f1.neighbours());
  CHECK(testing::largest_lobe_difference(fire_only, with_newton, analyse_network(fire_only.size(), c)) < 1e-7);
  CHECK(b.iterations < a.iterations);
}

TEST_CASE("Newton steps with the analytic Hessian reduce the force quadratically near a minimum", "[newton]") {
  Packing p = jammed().packing;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> kick(0.0, 1e-5);
  for (Eigen::Index k = 0; k < p.q.size(); ++k) p.q[k] += kick(rng);
  ForceField field;
  NewtonParams one;
  one.force_tol = 0;
  one.max_iterations = 1;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  std::vector<double> f{max_scaled_force(p, F)};
  for (int k = 0; k < 3; ++k) {
    const NewtonResult r = newton_finish(p, field, one);
    REQUIRE(r.stop == NewtonStop::iteration_cap);
    f.push_back(r.max_force);
  }
  INFO("largest force per Newton step: " << f[0] << " " << f[1] << " " << f[2] << " " << f[3]);
  // f_{k+1} ≈ C f_k²: the ratio f_{k+1}/f_k falls with f_k, until the rounding floor.
  CHECK(f[1] < 1e-2 * f[0]);
  CHECK(f[2] / f[1] < f[1] / f[0]);
  CHECK(f[2] < 1e-10);
}

TEST_CASE("with the Newton finish on, an unjammed packing still relaxes to E/N below the energy floor", "[newton]") {
  // Below jamming the overlaps must open, and the prestress of the last ones makes H indefinite:
  // Newton hands back to FIRE.
  Packing p = jammed().packing;
  testing::rescale_to(p, jammed().phi_below - 0.02);
  for (std::size_t i = 0; i < p.size(); i += 2) p.q[3 * i] += 0.05;  // fresh overlaps
  ForceField field;
  FireParams params;
  params.newton_force = 1e-2;
  const FireResult r = minimise(p, field, params);
  CHECK(r.converged);
  CHECK(r.energy / static_cast<double>(p.size()) < 1e-16);  // below the jamming threshold ε_U
}

TEST_CASE("a kept Newton factor relaxes a sequence of slowly grown packings to FIRE's minima with fewer factorisations",
          "[newton]") {
  // The arrested regime in miniature: each packing is the last one grown by 1e-6 (and relaxed), so
  // consecutive Hessians barely differ and a factor kept from the previous minimisation is a good
  // approximation of the current one.
  FireParams fire_only, reuse, no_reuse;
  fire_only.newton_force = 0.0;
  reuse.newton_force = no_reuse.newton_force = 1e-5;
  no_reuse.newton_reuse = false;
  NewtonWorkspace kept;
  Packing fire_state = swollen(jammed().packing), reuse_state = fire_state, no_reuse_state = fire_state;
  ForceField f1, f2, f3;
  long chord_steps = 0, factorisations_reuse = 0, factorisations_no_reuse = 0;
  for (int step = 0; step < 6; ++step) {
    const FireResult a = minimise(fire_state, f1, fire_only);
    const FireResult b = minimise(reuse_state, f2, reuse, &kept);
    const FireResult c = minimise(no_reuse_state, f3, no_reuse);
    REQUIRE(a.converged);
    REQUIRE(b.converged);
    REQUIRE(c.converged);
    CHECK(b.max_force < std::max(reuse.force_tol, force_resolution(reuse_state)));  // the same stopping test as FIRE's
    CHECK(b.energy == Approx(a.energy).epsilon(1e-8));
    Eigen::VectorXd F;
    f1.evaluate(fire_state, F);
    const std::vector<Contact> contacts = find_contacts(fire_state, f1.lobes(), f1.neighbours());
    CHECK(testing::largest_lobe_difference(fire_state, reuse_state, analyse_network(fire_state.size(), contacts)) <
          1e-7);
    chord_steps += b.newton_chord_steps;
    factorisations_reuse += b.newton_iterations;
    factorisations_no_reuse += c.newton_iterations;
    CHECK(c.newton_chord_steps == 0);
    for (Packing* p : {&fire_state, &reuse_state, &no_reuse_state})
      for (double& bud : p->b) bud *= 1.0 + 1e-6;
  }
  INFO("factorisations with reuse " << factorisations_reuse << " (+" << chord_steps << " chord steps), without "
                                    << factorisations_no_reuse);
  CHECK(chord_steps > 0);
  CHECK(factorisations_reuse < factorisations_no_reuse);
}
