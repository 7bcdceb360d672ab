// Contacts and the virial observables: the contact list against brute force, the pressure and the
// stress tensor against finite-difference derivatives of U under affine deformations, bud pressures.
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "random_packing.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

using namespace budjam;
using budjam::testing::random_packing;

namespace {

std::vector<Contact> contacts_of(const Packing& p, ForceField& field) {
  Eigen::VectorXd F;
  field.evaluate(p, F);
  return find_contacts(p, field.lobes(), field.neighbours());
}

// U of the lobes of p with every lobe centre and the box dilated by λ about the origin (the cells'
// shapes are dilated too). Brute force over lobe pairs: independent of ForceField.
double dilated_lobe_energy(const Packing& p, double lambda) {
  Lobes l;
  place_lobes(p, l);
  Box box = p.box;
  box.L *= lambda;
  double U = 0;
  for (std::size_t a = 0; a < l.size(); ++a)
    for (std::size_t b = a + 1; b < l.size(); ++b) {
      if (cell_of(a) == cell_of(b)) continue;
      double dx = lambda * (l.x[a] - l.x[b]), dy = lambda * (l.y[a] - l.y[b]);
      box.minimum_image(dx, dy);
      const double r = std::hypot(dx, dy), sigma = l.R[a] + l.R[b];
      if (r < sigma) U += 0.5 * kSpring * (sigma - r) * (sigma - r);
    }
  return U;
}

// Box and centroids scaled by λ (cells rigid, orientations kept); shear of the centroids by γ.
Packing deformed(const Packing& p, double lambda, double gamma) {
  Packing q = p;
  q.box.L *= lambda;
  q.box.shear += gamma;
  for (std::size_t i = 0; i < p.size(); ++i) {
    q.q[3 * i] = lambda * (p.x(i) + gamma * p.y(i));
    q.q[3 * i + 1] = lambda * p.y(i);
  }
  return q;
}

double energy_of(const Packing& p) {
  ForceField field;
  return field.energy(p);
}

Packing relaxed_jammed(std::size_t n, double phi, std::uint64_t seed) {
  Packing p = random_packing(n, phi, seed);
  ForceField field;
  const FireResult r = minimise(p, field);
  REQUIRE(r.converged);
  REQUIRE(r.energy / n > 1e-8);
  return p;
}

}  // namespace

TEST_CASE("find_contacts lists exactly the overlapping lobe pairs with their geometry", "[fast]") {
  for (double shear : {0.0, 0.45}) {
    Packing p = random_packing(150, 1.0, 3);
    p.box.shear = shear;
    ForceField field;
    const auto contacts = contacts_of(p, field);
    const auto overlapping = brute_force_pairs(field.lobes(), p.box, 0.0);
    REQUIRE(contacts.size() == overlapping.size());
    const Lobes& l = field.lobes();
    for (std::size_t k = 0; k < contacts.size(); ++k) {
      const Contact& c = contacts[k];
      CHECK(c.i == overlapping[k].first);
      CHECK(c.j == overlapping[k].second);
      double dx = l.x[c.i] - l.x[c.j], dy = l.y[c.i] - l.y[c.j];
      p.box.minimum_image(dx, dy);
      CHECK(c.r == Approx(std::hypot(dx, dy)).epsilon(1e-14));
      CHECK(c.sigma == l.R[c.i] + l.R[c.j]);
      CHECK(c.nx * c.r == Approx(dx).margin(1e-14));
      CHECK(c.ny * c.r == Approx(dy).margin(1e-14));
      CHECK(c.force() > 0);
    }
  }
}

TEST_CASE("stress tensor is symmetric and P = -tr(Sigma)/2", "[fast]") {
  Packing p = random_packing(120, 1.0, 5);
  p.box.shear = 0.2;
  ForceField field;
  const auto contacts = contacts_of(p, field);
  const Eigen::Matrix2d s = stress_tensor(contacts, p.box);
  const double P = pressure(contacts, p.box);
  CHECK(P > 0);
  CHECK(s(0, 1) == s(1, 0));
  CHECK(-0.5 * s.trace() == Approx(P).epsilon(1e-13));
  // Compressive contacts: both normal stresses negative.
  CHECK(s(0, 0) < 0);
  CHECK(s(1, 1) < 0);
}

TEST_CASE("pressure P equals -dU/dA when all lobe centres and the box are dilated affinely", "[fast]") {
  // The model's P = (1/2L²) Σ f r is the virial of the lobe–lobe springs: the derivative of U under a
  // dilation of every lobe centre (which also stretches the cells' mother–bud bars).
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Packing p = random_packing(60, 1.0, seed);
    ForceField field;
    const double P = pressure(contacts_of(p, field), p.box);
    const double h = 1e-6, A = p.box.L * p.box.L;
    const double dU = dilated_lobe_energy(p, 1 + h) - dilated_lobe_energy(p, 1 - h);
    const double dA = A * ((1 + h) * (1 + h) - (1 - h) * (1 - h));
    CHECK(P == Approx(-dU / dA).epsilon(1e-7));
  }
}

TEST_CASE("centroid pressure equals -dU/dA under affine compression of box and centroids", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    for (double shear : {0.0, 0.3}) {
      Packing p = random_packing(60, 1.0, seed);
      p.box.shear = shear;
      ForceField field;
      const double Pc = centroid_pressure(p, contacts_of(p, field));
      const double h = 1e-6, A = p.box.L * p.box.L;
      const double dU = energy_of(deformed(p, 1 + h, 0)) - energy_of(deformed(p, 1 - h, 0));
      const double dA = A * ((1 + h) * (1 + h) - (1 - h) * (1 - h));
      INFO("seed " << seed << " shear " << shear);
      CHECK(Pc == Approx(-dU / dA).epsilon(1e-7));
    }
  }
}

TEST_CASE("centroid shear stress equals (1/L^2) dU/dgamma under Lees-Edwards shear of the centroids", "[fast]") {
  for (double shear : {0.0, 0.17, -0.6}) {
    Packing p = random_packing(60, 1.0, 8);
    p.box.shear = shear;
    ForceField field;
    const Eigen::Matrix2d s = centroid_stress_tensor(p, contacts_of(p, field));
    const double h = 1e-6, A = p.box.L * p.box.L;
    const double dUdg = (energy_of(deformed(p, 1, h)) - energy_of(deformed(p, 1, -h))) / (2 * h);
    INFO("shear " << shear);
    CHECK(std::abs(s(0, 1)) > 1e-4);
    CHECK(s(0, 1) == Approx(dUdg / A).epsilon(1e-6));
  }
}

TEST_CASE("relaxed packing: centroid stress is symmetric and differs from Sigma by the bar virial", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Packing p = relaxed_jammed(80, 0.95, seed);
    ForceField field;
    const auto contacts = contacts_of(p, field);
    const Eigen::Matrix2d s = stress_tensor(contacts, p.box);
    const Eigen::Matrix2d sc = centroid_stress_tensor(p, contacts);
    const double scale = s.norm();
    INFO("seed " << seed << " P " << pressure(contacts, p.box) << " centroid P " << centroid_pressure(p, contacts));
    // Torque balance makes Σᶜ symmetric (its antisymmetric part is Σ torques / L²).
    CHECK(std::abs(sc(0, 1) - sc(1, 0)) < 1e-9 * scale);
    // Σ − Σᶜ = −(1/L²) Σ_cells s (F_bud·n̂) n̂n̂ᵀ, from the total contact force on each bud.
    std::vector<double> fbx(p.size(), 0.0), fby(p.size(), 0.0);
    for (const Contact& c : contacts) {
      const double f = c.force();
      if (is_bud(c.i)) fbx[cell_of(c.i)] += f * c.nx, fby[cell_of(c.i)] += f * c.ny;
      if (is_bud(c.j)) fbx[cell_of(c.j)] -= f * c.nx, fby[cell_of(c.j)] -= f * c.ny;
    }
    Eigen::Matrix2d bars = Eigen::Matrix2d::Zero();
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d n(std::cos(p.theta(i)), std::sin(p.theta(i)));
      bars -= p.dumbbell(i).separation * (fbx[i] * n.x() + fby[i] * n.y()) * n * n.transpose();
    }
    bars /= p.box.L * p.box.L;
    CHECK((s - sc - bars).norm() < 1e-9 * scale);
    CHECK(bars.norm() > 1e-3 * scale);  // the difference is real, not a rounding effect
  }
}

TEST_CASE("bud pressure is the total contact force on the bud over its perimeter pi b", "[fast]") {
  // Cell 0 has its bud (b = 0.6) pressed by the mothers of cells 1 and 2 with overlaps 0.01, 0.02.
  Packing p;
  p.box = {10.0, 0.0};
  p.add_cell(5.0, 5.0, 0.0, 0.6, 0.002, -1);
  const Dumbbell d0 = Dumbbell::of(0.6), d1 = Dumbbell::of(0.3);
  const double bx = 5.0 + d0.bud_offset, by = 5.0;
  auto press = [&](double angle, double overlap) {
    const double r = 0.3 + 0.5 - overlap;
    const double mx = bx + r * std::cos(angle), my = by + r * std::sin(angle);
    p.add_cell(mx + d1.mother_offset * std::cos(angle), my + d1.mother_offset * std::sin(angle), angle, 0.3, 0.002, -1);
  };
  press(1.2, 0.01);
  press(-1.2, 0.02);
  ForceField field;
  const auto contacts = contacts_of(p, field);
  REQUIRE(contacts.size() == 2);
  const auto pb = bud_pressures(p, contacts);
  REQUIRE(pb.size() == 3);
  CHECK(pb[0] == Approx(0.03 / (std::numbers::pi * 0.6)).epsilon(1e-9));
  CHECK(pb[1] == 0.0);  // only their mothers are touched
  CHECK(pb[2] == 0.0);
}

TEST_CASE("bud pressures add up to the bud-borne contact forces of a random packing", "[fast]") {
  Packing p = random_packing(100, 1.0, 12);
  ForceField field;
  const auto contacts = contacts_of(p, field);
  const auto pb = bud_pressures(p, contacts);
  double lhs = 0, rhs = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    CHECK(pb[i] >= 0);
    lhs += pb[i] * std::numbers::pi * p.b[i];
  }
  for (const Contact& c : contacts) rhs += c.force() * ((is_bud(c.i) ? 1 : 0) + (is_bud(c.j) ? 1 : 0));
  CHECK(rhs > 0);
  CHECK(lhs == Approx(rhs).epsilon(1e-12));
}
