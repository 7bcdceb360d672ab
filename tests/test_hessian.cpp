// The analytic Hessian (budjam/hessian.hpp) against central finite differences of the analytic
// forces of ForceField, in periodic boxes with and without Lees–Edwards shear.
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/hessian.hpp"
#include "budjam/packing.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace budjam;

namespace {

// Strongly overlapping random dumbbells (not relaxed: forces and torques are far from balanced,
// so the prestress terms are large and every term of H is exercised).
Packing random_overlapping(std::size_t n, double L, double shear, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing p;
  p.box.L = L;
  p.box.shear = shear;
  for (std::size_t i = 0; i < n; ++i)
    p.add_cell(L * u(rng), L * u(rng), 2 * M_PI * (u(rng) - 0.5), 0.05 + 0.95 * u(rng), 0.002, -1);
  return p;
}

std::vector<Contact> contacts_of(const Packing& p, ForceField& field) {
  Eigen::VectorXd f;
  field.evaluate(p, f);
  return find_contacts(p, field.lobes(), field.neighbours());
}

// Smallest |r − σ| over all lobe pairs of different cells: a finite-difference step must not
// open or close a contact.
double closest_to_threshold(const Packing& p) {
  Lobes l;
  place_lobes(p, l);
  double best = 1e300;
  for (std::size_t a = 0; a < l.size(); ++a)
    for (std::size_t b = a + 1; b < l.size(); ++b) {
      if (cell_of(a) == cell_of(b)) continue;
      double dx = l.x[a] - l.x[b], dy = l.y[a] - l.y[b];
      p.box.minimum_image(dx, dy);
      best = std::min(best, std::abs(std::hypot(dx, dy) - (l.R[a] + l.R[b])));
    }
  return best;
}

// −∂F/∂q by central differences of ForceField::evaluate, column by column.
Eigen::MatrixXd finite_difference_hessian(const Packing& p, double h) {
  const auto n = p.q.size();
  Eigen::MatrixXd H(n, n);
  ForceField field;
  Eigen::VectorXd fp, fm;
  for (Eigen::Index a = 0; a < n; ++a) {
    Packing plus = p, minus = p;
    plus.q[a] += h;
    minus.q[a] -= h;
    field.evaluate(plus, fp);
    field.evaluate(minus, fm);
    H.col(a) = -(fp - fm) / (2 * h);
  }
  return H;
}

// Number of contacts whose minimum image is not the raw difference of the lobe centres.
int contacts_across_boundary(const Packing& p, const std::vector<Contact>& contacts) {
  Lobes l;
  place_lobes(p, l);
  int n = 0;
  for (const auto& c : contacts) {
    const double dx = l.x[c.i] - l.x[c.j], dy = l.y[c.i] - l.y[c.j];
    if (std::abs(dx - c.r * c.nx) > 1e-9 || std::abs(dy - c.r * c.ny) > 1e-9) ++n;
  }
  return n;
}

void check_against_forces(const Packing& p) {
  REQUIRE(closest_to_threshold(p) > 1e-4);
  ForceField field;
  const auto contacts = contacts_of(p, field);
  REQUIRE(contacts.size() > p.size());
  REQUIRE(contacts_across_boundary(p, contacts) > 0);
  const Eigen::MatrixXd H = Eigen::MatrixXd(hessian(p, contacts));
  const Eigen::MatrixXd Hfd = finite_difference_hessian(p, 1e-6);
  const double scale = H.cwiseAbs().maxCoeff();
  const double err = (H - Hfd).cwiseAbs().maxCoeff() / scale;
  INFO("max |H − H_fd| / max |H| = " << err);
  CHECK(err < 1e-6);
}

}  // namespace

TEST_CASE("Hessian equals central differences of the analytic forces in a periodic box", "[fast]") {
  check_against_forces(random_overlapping(12, 4.0, 0.0, 7));
}

TEST_CASE("Hessian equals central differences of the forces with Lees-Edwards shear", "[fast]") {
  check_against_forces(random_overlapping(12, 4.0, 0.37, 11));
  check_against_forces(random_overlapping(12, 4.0, -0.21, 12));
}

TEST_CASE("Hessian is exactly symmetric and both global translations are exact zero modes", "[fast]") {
  for (double shear : {0.0, 0.29}) {
    const Packing p = random_overlapping(40, 6.0, shear, 5);
    ForceField field;
    const auto contacts = contacts_of(p, field);
    const SparseMatrix H = hessian(p, contacts);
    const Eigen::MatrixXd Hd(H);
    CHECK((Hd - Hd.transpose()).cwiseAbs().maxCoeff() == 0.0);
    Eigen::VectorXd tx = Eigen::VectorXd::Zero(H.rows()), ty = tx;
    for (Eigen::Index k = 0; k < H.rows(); k += 3) {
      tx[k] = 1;
      ty[k + 1] = 1;
    }
    const double scale = Hd.cwiseAbs().maxCoeff();
    CHECK((H * tx).cwiseAbs().maxCoeff() < 1e-13 * scale);
    CHECK((H * ty).cwiseAbs().maxCoeff() < 1e-13 * scale);
  }
}

TEST_CASE("Stiffness and prestress terms add up to the full Hessian; prestress vanishes without overlap", "[fast]") {
  const Packing p = random_overlapping(30, 5.0, 0.1, 3);
  ForceField field;
  const auto contacts = contacts_of(p, field);
  const Eigen::MatrixXd full(hessian(p, contacts));
  const Eigen::MatrixXd stiff(hessian(p, contacts, {true, false}));
  const Eigen::MatrixXd pre(hessian(p, contacts, {false, true}));
  CHECK((full - stiff - pre).cwiseAbs().maxCoeff() < 1e-14 * full.cwiseAbs().maxCoeff());
  // Contacts at r = σ carry no force: the prestress part of their Hessian is zero.
  std::vector<Contact> touching = contacts;
  for (auto& c : touching) c.r = c.sigma;
  CHECK(Eigen::MatrixXd(hessian(p, touching, {false, true})).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("Restriction to a subset of cells is the principal submatrix and round-trips vectors", "[fast]") {
  const Packing p = random_overlapping(20, 5.0, 0.0, 9);
  ForceField field;
  const auto contacts = contacts_of(p, field);
  const SparseMatrix H = hessian(p, contacts);
  std::vector<bool> keep(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) keep[i] = (i % 3 != 1);
  const DofMap map = keep_cells(keep);
  REQUIRE(map.cells.size() == 13);
  const Eigen::MatrixXd R(restrict_matrix(H, map));
  const Eigen::MatrixXd Hd(H);
  for (Eigen::Index a = 0; a < map.size(); ++a)
    for (Eigen::Index b = 0; b < map.size(); ++b) REQUIRE(R(a, b) == Hd(map.full(a), map.full(b)));
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(H.rows(), 1.0, 2.0);
  const Eigen::VectorXd back = expand_vector(restrict_vector(v, map), map);
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) CHECK(back[3 * i + k] == (keep[i] ? v[3 * i + k] : 0.0));
}
