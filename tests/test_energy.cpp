// The contact energy and its gradient: forces and torques are −∇U (central finite differences),
// across periodic and Lees–Edwards boundaries, with newborn buds, and at the edges of the contact
// law (r = σ, r = 0).
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include "random_packing.hpp"

using namespace budjam;

namespace {

Packing random_packing(std::size_t n, double phi, std::uint64_t seed, double b_min = 0.01, double b_max = 1.02) {
  return budjam::testing::random_packing(n, phi, seed, b_min, b_max, /*periods=*/2);
}

// Independent energy: every lobe pair by brute force, from place_lobes and Box::minimum_image.
double reference_energy(const Packing& p) {
  Lobes l;
  place_lobes(p, l);
  double U = 0;
  for (std::size_t a = 0; a < l.size(); ++a)
    for (std::size_t b = a + 1; b < l.size(); ++b) {
      if (cell_of(a) == cell_of(b)) continue;
      double dx = l.x[a] - l.x[b], dy = l.y[a] - l.y[b];
      p.box.minimum_image(dx, dy);
      const double r = std::hypot(dx, dy), sigma = l.R[a] + l.R[b];
      if (r < sigma) U += 0.5 * kSpring * (sigma - r) * (sigma - r);
    }
  return U;
}

// Largest |F − F_fd| over all 3N coordinates, F_fd = −(U(q + h e) − U(q − h e)) / 2h, computed with
// a fresh field each time so that neighbour-list state cannot leak into the check.
double max_gradient_error(const Packing& p0, double h, double* max_force = nullptr) {
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p0, F);
  double err = 0, fmax = 0;
  for (Eigen::Index k = 0; k < p0.q.size(); ++k) {
    Packing p = p0;
    p.q[k] = p0.q[k] + h;
    ForceField plus;
    const double Up = plus.energy(p);
    p.q[k] = p0.q[k] - h;
    ForceField minus;
    const double Um = minus.energy(p);
    const double fd = -(Up - Um) / (2 * h);
    err = std::max(err, std::abs(fd - F[k]));
    fmax = std::max(fmax, std::abs(F[k]));
  }
  if (max_force) *max_force = fmax;
  return err;
}

}  // namespace

TEST_CASE("energy equals the brute-force sum of (k/2)(sigma - r)^2 over lobe pairs", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 5; ++seed)
    for (double shear : {0.0, 0.21}) {
      Packing p = random_packing(80, 1.0, seed);
      p.box.shear = shear;
      ForceField field;
      Eigen::VectorXd F;
      const double U = field.evaluate(p, F);
      CHECK(U > 0);
      CHECK(U == Approx(reference_energy(p)).epsilon(1e-12));
      CHECK(field.energy(p) == Approx(U).epsilon(1e-14));
    }
}

TEST_CASE("forces and torques equal minus the gradient of U (central differences)", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    // Coordinates are spread over several periods: many contacts cross the box boundary.
    const Packing p = random_packing(40, 1.1, seed);
    double fmax = 0;
    const double err = max_gradient_error(p, 1e-6, &fmax);
    INFO("seed " << seed << " max |F| " << fmax);
    CHECK(fmax > 0.1);
    CHECK(err < 1e-6);
  }
}

TEST_CASE("forces equal minus the gradient of U under Lees-Edwards shear", "[fast]") {
  for (double shear : {0.13, -0.4, 1.7}) {
    Packing p = random_packing(40, 1.1, 7);
    p.box.shear = shear;
    double fmax = 0;
    const double err = max_gradient_error(p, 1e-6, &fmax);
    INFO("shear " << shear);
    CHECK(fmax > 0.1);
    CHECK(err < 1e-6);
  }
}

TEST_CASE("total force vanishes (translation invariance of U)", "[fast]") {
  for (double shear : {0.0, 0.3}) {
    Packing p = random_packing(120, 1.0, 9);
    p.box.shear = shear;
    ForceField field;
    Eigen::VectorXd F;
    field.evaluate(p, F);
    double sx = 0, sy = 0, scale = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      sx += F[3 * i];
      sy += F[3 * i + 1];
      scale += std::abs(F[3 * i]) + std::abs(F[3 * i + 1]);
    }
    CHECK(scale > 1);
    CHECK(std::abs(sx) < 1e-13 * scale);
    CHECK(std::abs(sy) < 1e-13 * scale);
  }
}

TEST_CASE("energy and forces are invariant under whole-period shifts of a cell", "[fast]") {
  Packing p = random_packing(60, 1.0, 13);
  p.box.shear = 0.35;
  ForceField field;
  Eigen::VectorXd F0, F1;
  const double U0 = field.evaluate(p, F0);
  Packing shifted = p;
  for (std::size_t i = 0; i < p.size(); i += 3) {
    shifted.q[3 * i] += 2 * p.box.L;
    shifted.q[3 * i + 1] -= p.box.L;  // one box down in y: x shifts by −γL too
    shifted.q[3 * i] -= p.box.shear * p.box.L;
  }
  ForceField other;
  const double U1 = other.evaluate(shifted, F1);
  CHECK(U1 == Approx(U0).epsilon(1e-12));
  CHECK((F1 - F0).lpNorm<Eigen::Infinity>() < 1e-11);
}

TEST_CASE("evaluate reuses the neighbour list while cells move little and counts evaluations", "[fast]") {
  Packing p = random_packing(100, 0.9, 17);
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  const long built = field.neighbours().rebuilds();
  for (int k = 0; k < 10; ++k) {
    p.q[0] += 1e-3;
    field.evaluate(p, F);
  }
  CHECK(field.neighbours().rebuilds() == built);
  CHECK(field.evaluations() == 11);
  // A bud growing is seen by the list even without invalidate().
  p.b[4] *= 1.01;
  const double U = field.evaluate(p, F);
  CHECK(field.neighbours().rebuilds() == built + 1);
  CHECK(U == Approx(reference_energy(p)).epsilon(1e-12));
}

TEST_CASE(
    "pair images found at a rebuild stay exact while lobes cross the periodic boundaries: U and F bitwise "
    "those of a fresh field",
    "[fast]") {
  // Each listed pair keeps the minimum image of the last rebuild. Moving every cell by (0.3, 0.2)
  // plus a little noise carries lobes across the box edges (and, with shear, across the shifted
  // rows) without a rebuild: the forces must still be those of images found afresh.
  for (double shear : {0.0, 0.35}) {
    Packing p = random_packing(120, 1.0, 23);
    p.box.shear = shear;
    ForceField field(1.0);
    Eigen::VectorXd F;
    field.evaluate(p, F);
    const long built = field.neighbours().rebuilds();
    int crossings = 0;
    for (int step = 1; step <= 3; ++step) {
      for (std::size_t i = 0; i < p.size(); ++i) {
        const double x0 = p.q[3 * i], y0 = p.q[3 * i + 1];
        p.q[3 * i] += 0.1 + 1e-3 * std::sin(1.3 * static_cast<double>(i + step));
        p.q[3 * i + 1] += 0.2 / 3 + 1e-3 * std::cos(0.7 * static_cast<double>(i * step));
        p.q[3 * i + 2] += 1e-3 * std::sin(static_cast<double>(i));
        crossings += std::floor(x0 / p.box.L) != std::floor(p.q[3 * i] / p.box.L);
        crossings += std::floor(y0 / p.box.L) != std::floor(p.q[3 * i + 1] / p.box.L);
      }
      const double U = field.evaluate(p, F);
      ForceField fresh(1.0);
      Eigen::VectorXd F_fresh;
      const double U_fresh = fresh.evaluate(p, F_fresh);
      INFO("shear " << shear << ", step " << step);
      CHECK(U == U_fresh);
      CHECK(F == F_fresh);
      CHECK(U == Approx(reference_energy(p)).epsilon(1e-12));
    }
    CHECK(field.neighbours().rebuilds() == built);
    CHECK(crossings > 0);
  }
}

TEST_CASE("U and F are bitwise independent of the skin and of the neighbour-list history", "[fast]") {
  // Pairs are kept sorted by (a, b) and non-contacts add nothing, so the sums run over the same
  // contacts in the same order whatever the list holds beyond them.
  Packing p = random_packing(120, 1.0, 19);
  p.box.shear = 0.1;
  ForceField reference(0.3);
  Eigen::VectorXd F0;
  const double U0 = reference.evaluate(p, F0);
  for (double skin : {0.01, 0.2, 1.0}) {
    ForceField field(skin);
    Eigen::VectorXd F;
    // A history: evaluate elsewhere first, then come back without invalidating.
    Packing moved = p;
    for (Eigen::Index k = 0; k < moved.q.size(); ++k) moved.q[k] += 1e-3 * std::sin(1.7 * static_cast<double>(k));
    field.evaluate(moved, F);
    const double U = field.evaluate(p, F);
    INFO("skin " << skin);
    CHECK(U == U0);
    CHECK(F == F0);
  }
}

TEST_CASE("0.01-diameter bud pressed into a full lobe: finite forces equal to -grad U", "[.hard]") {
  // Cell 0 is a newborn (b = 0.01) whose bud pokes into the mother of cell 1, across the x boundary.
  for (double depth : {1e-9, 1e-4, 0.004, 0.0099}) {
    for (double angle : {0.0, 0.08, -0.06}) {  // near the axis: the mothers stay apart
      Packing p;
      p.box = {6.0, 0.0};
      const Dumbbell newborn = Dumbbell::of(0.01);
      p.add_cell(5.9, 3.0, 0.0, 0.01, 0.002, -1);
      const double bud_x = 5.9 + newborn.bud_offset;  // bud centre, radius 0.005
      // Mother of cell 1 (radius 0.5) at distance 0.505 − depth from the bud, direction `angle`.
      const Dumbbell big = Dumbbell::of(0.8);
      const double d = 0.505 - depth;
      const double mx = bud_x + d * std::cos(angle) - 6.0, my = 3.0 + d * std::sin(angle);
      const double th1 = angle + 0.4;  // cell 1's bud points away, roughly
      p.add_cell(mx + big.mother_offset * std::cos(th1), my + big.mother_offset * std::sin(th1), th1, 0.8, 0.002, -1);
      ForceField field;
      Eigen::VectorXd F;
      const double U = field.evaluate(p, F);
      INFO("depth " << depth << " angle " << angle);
      // Overlaps carry absolute rounding errors of about ulp(6) ≈ 1e-15.
      CHECK(std::abs(U - reference_energy(p)) <= 1e-9 * U + 1e-14 * depth);
      CHECK(F.allFinite());
      if (angle == 0.0) {
        // Collinear: the bud–mother contact is the only one (off the axis the mothers touch too),
        // and the force on the newborn is k·depth along the line of centres.
        CHECK(U == Approx(0.5 * depth * depth).epsilon(1e-5));
        CHECK(std::hypot(F[0], F[1]) == Approx(depth).epsilon(1e-5));
        CHECK(std::abs(F[1]) < 1e-12);
      }
      const double h = std::min(1e-7, 0.1 * depth);
      CHECK(max_gradient_error(p, h) < 1e-6 * std::max(depth, 1e-3));
    }
  }
}

TEST_CASE("lobes exactly touching (r = sigma) carry no energy, no force and no contact", "[.hard]") {
  // Two cells along x (θ = 0 and y exact): bud of 0 meets mother of 1. σ = 0.25 + 0.5 is a multiple
  // of the spacing of doubles near the lobe positions, so cell 1 can be placed (nudged by ulps)
  // where the computed distance is exactly σ; then one ulp closer must be a contact.
  Packing p;
  p.box = {10.0, 0.0};
  p.add_cell(2.0, 5.0, 0.0, 0.5, 0.002, -1);
  const Dumbbell d0 = Dumbbell::of(0.5), d1 = Dumbbell::of(0.9);
  p.add_cell(2.0 + d0.bud_offset + 0.25 + 0.5 + d1.mother_offset, 5.0, 0.0, 0.9, 0.002, -1);
  Lobes l;
  auto gap = [&] {
    place_lobes(p, l);
    return (l.x[2] - l.x[1]) - (l.R[1] + l.R[2]);
  };
  for (int k = 0; k < 100 && gap() != 0.0; ++k) p.q[3] = std::nextafter(p.q[3], gap() > 0 ? -1e300 : 1e300);
  REQUIRE(gap() == 0.0);
  ForceField field;
  Eigen::VectorXd F;
  CHECK(field.evaluate(p, F) == 0.0);
  CHECK(F.isZero(0.0));
  CHECK(find_contacts(p, field.lobes(), field.neighbours()).empty());
  // One ulp closer: a contact with a force of order one ulp, still finite and tiny.
  p.q[3] = std::nextafter(p.q[3], -1e300);
  if (gap() < 0) {
    const double U = field.evaluate(p, F);
    CHECK(U < 1e-28);
    CHECK(F.lpNorm<Eigen::Infinity>() < 1e-14);
    CHECK(find_contacts(p, field.lobes(), field.neighbours()).size() == 1);
  }
}

TEST_CASE("coincident lobe centres (r = 0) give a finite, deterministic, separating force", "[.hard]") {
  SECTION("mother of one cell on the bud of another: force along the centroid line") {
    // b = 1: offsets are exactly 0.5, so the coincidence is exact in floating point.
    Packing p;
    p.box = {8.0, 0.0};
    p.add_cell(4.0, 4.0, 0.0, 1.0, 0.002, -1);  // mother at 3.5, bud at 4.5
    p.add_cell(3.0, 4.0, 0.0, 1.0, 0.002, -1);  // mother at 2.5, bud at 3.5
    ForceField field;
    Eigen::VectorXd F;
    const double U = field.evaluate(p, F);
    CHECK(U == 0.5);  // one contact, r = 0, σ = 1; the other pairs touch exactly (r = σ)
    CHECK(F.allFinite());
    CHECK(F[0] == 1.0);  // centroid 1 → centroid 0 is +x
    CHECK(F[3] == -1.0);
    CHECK(F[1] == 0.0);
    CHECK(F[2] == 0.0);  // force along the axis: no torque
    const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
    REQUIRE(contacts.size() == 1);
    CHECK(contacts[0].r == 0.0);
    CHECK(contacts[0].nx == 1.0);
    // The force is a one-sided derivative: moving cell 0 by +h along x lowers U by h·kσ.
    Packing q = p;
    q.q[0] += 1e-7;
    ForceField other;
    CHECK((U - other.energy(q)) / 1e-7 == Approx(1.0).epsilon(1e-6));
    // FIRE pushes them apart to a contact-free state.
    const FireResult r = minimise(p, field);
    CHECK(r.converged);
    CHECK(r.energy < 2e-20);
  }
  SECTION("two identical cells on top of each other: +x fallback; FIRE separates them when perturbed") {
    Packing p;
    p.box = {8.0, 0.0};
    p.add_cell(4.0, 4.0, 0.0, 1.0, 0.002, -1);
    p.add_cell(4.0, 4.0, 0.0, 1.0, 0.002, -1);
    ForceField field;
    Eigen::VectorXd F;
    const double U = field.evaluate(p, F);
    CHECK(U == 1.0);  // mother–mother and bud–bud at r = 0; mother–bud pairs exactly touch
    CHECK(F[0] == 2.0);
    CHECK(F[3] == -2.0);
    // Exactly on top of each other, the motion stays on the x axis, where U has a stationary point
    // with overlaps (a saddle in 2D). A 1e-9 offset in y (r ≈ 1e-9) lets FIRE leave it.
    p.q[4] += 1e-9;
    const FireResult r = minimise(p, field);
    CHECK(r.converged);
    CHECK(r.energy / 2 < 1e-20);
  }
}

TEST_CASE("forces equal -grad U for a pair in a huge box (L = 1000) across the corner", "[.hard]") {
  Packing p;
  p.box = {1000.0, 0.0};
  p.add_cell(999.8, 999.9, 0.3, 1.0, 0.002, -1);
  p.add_cell(0.2, 0.1, 2.0, 0.5, 0.002, -1);
  double fmax = 0;
  CHECK(max_gradient_error(p, 1e-6, &fmax) < 1e-6);
  CHECK(fmax > 0.1);
  ForceField field;
  const FireResult r = minimise(p, field);
  CHECK(r.converged);
  CHECK(r.energy < 2e-20);
  CHECK(field.neighbours().grid() <= 4);
}
