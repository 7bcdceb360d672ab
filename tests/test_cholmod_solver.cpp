// The CHOLMOD wrapper (budjam/cholmod_solver.hpp) against dense Eigen on small banded matrices.
#include "budjam/cholmod_solver.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>

#include <cmath>

using namespace budjam;

namespace {

// A symmetric positive definite banded matrix (bandwidth 3) with a known spectrum spread.
Eigen::MatrixXd banded_spd(int n, unsigned seed) {
  std::srand(seed);
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (std::abs(i - j) > 1) B(i, j) = 0;
  Eigen::MatrixXd A = B * B.transpose() + 0.05 * Eigen::MatrixXd::Identity(n, n);
  return A;
}

}  // namespace

TEST_CASE("LLT factor solves a positive definite system with one and many right-hand sides", "[fast]") {
  const Eigen::MatrixXd A = banded_spd(60, 1);
  const Eigen::SparseMatrix<double> S = A.sparseView();
  CholmodSolver s;
  REQUIRE(s.factor(S));
  CHECK(s.failed_column() == -1);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(60, -1.0, 2.0);
  CHECK((A * s.solve(b) - b).norm() < 1e-10 * b.norm());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(60, 5);
  CHECK((A * s.solve(B) - B).norm() < 1e-10 * B.norm());
  Eigen::VectorXd x(60);
  s.solve(b.data(), x.data());
  CHECK((A * x - b).norm() < 1e-10 * b.norm());
}

TEST_CASE("LLT reports an indefinite or singular matrix instead of factoring it", "[fast]") {
  const Eigen::MatrixXd A = banded_spd(40, 2);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A);
  const double sigma = 0.5 * (es.eigenvalues()[3] + es.eigenvalues()[4]);
  CholmodSolver s;
  CHECK_FALSE(s.factor(A.sparseView(), sigma, Eigen::VectorXd()));
  CHECK(s.failed_column() >= 0);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(40);
  CHECK_THROWS_AS(s.solve(ones), CholmodError);
  Eigen::MatrixXd Z = A;
  Z.row(7).setZero();
  Z.col(7).setZero();
  CHECK_FALSE(s.factor(Eigen::SparseMatrix<double>(Z.sparseView())));
}

TEST_CASE("LDLT inertia counts the generalised eigenvalues below the shift (Sylvester)", "[fast]") {
  const Eigen::MatrixXd A = banded_spd(50, 3);
  Eigen::VectorXd m(50);
  for (int k = 0; k < 50; ++k) m[k] = 1.0 + 0.1 * (k % 3);
  // Eigenvalues of (A, diag m) via M^{-1/2} A M^{-1/2}.
  const Eigen::VectorXd mi = m.cwiseSqrt().cwiseInverse();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(mi.asDiagonal() * A * mi.asDiagonal());
  CholmodSolver s(Factorisation::ldlt);
  const Eigen::SparseMatrix<double> S = A.sparseView();
  for (int k : {0, 5, 17, 33}) {
    const double sigma = 0.5 * (es.eigenvalues()[k] + es.eigenvalues()[k + 1]);
    REQUIRE(s.factor(S, sigma, m));
    CHECK(s.negative_pivots() == k + 1);
    const Eigen::VectorXd b = Eigen::VectorXd::Ones(50);
    const Eigen::MatrixXd shifted = A - sigma * Eigen::MatrixXd(m.asDiagonal());
    CHECK((shifted * s.solve(b) - b).norm() < 1e-8 * b.norm());
  }
  // The same pattern is analysed once: the ordering is reused for every shift.
  CHECK(s.analyses() == 1);
}

TEST_CASE("Factoring A - sigma M with a sparse M equals the diagonal-mass overload", "[fast]") {
  const Eigen::MatrixXd A = banded_spd(30, 4);
  Eigen::VectorXd m = Eigen::VectorXd::Constant(30, 2.0);
  Eigen::SparseMatrix<double> M(30, 30);
  for (int k = 0; k < 30; ++k) M.insert(k, k) = 2.0;
  CholmodSolver a, b;
  REQUIRE(a.factor(A.sparseView(), -0.3, m));
  REQUIRE(b.factor(A.sparseView(), -0.3, M));
  const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(30, 0.0, 1.0);
  CHECK((a.solve(rhs) - b.solve(rhs)).norm() < 1e-12 * a.solve(rhs).norm());
  const Eigen::MatrixXd shifted = A + 0.6 * Eigen::MatrixXd::Identity(30, 30);
  CHECK((shifted * a.solve(rhs) - rhs).norm() < 1e-10);
}

namespace {

// A contact's rank-1 term: √k g with g supported on the six dofs of two cells (i, j), g_j = −g_i,
// as k_c (Jᵀn)(Jᵀn)ᵀ of a contact at zero force.
Eigen::SparseMatrix<double> contact_column(int n, int i, int j, double k, double angle, double arm) {
  const double c = std::cos(angle), s = std::sin(angle), r = std::sqrt(k);
  const double gi[3] = {c, s, arm * (c * 0.3 - s * 0.7)};
  Eigen::SparseMatrix<double> C(n, 1);
  for (int a = 0; a < 3; ++a) {
    C.insert(3 * i + a, 0) = r * gi[a];
    C.insert(3 * j + a, 0) = -r * gi[a];
  }
  C.makeCompressed();
  return C;
}

}  // namespace

TEST_CASE("an LDLT factor updated by contact terms solves as the factor of the changed matrix", "[fast]") {
  const int cells = 40, n = 3 * cells;
  Eigen::MatrixXd A = banded_spd(n, 5);
  const Eigen::SparseMatrix<double> C1 = contact_column(n, 3, 17, 2.0, 0.4, 0.6);
  const Eigen::SparseMatrix<double> C2 = contact_column(n, 30, 8, 0.5, 2.1, 0.2);
  const Eigen::MatrixXd D1 = Eigen::MatrixXd(C1), D2 = Eigen::MatrixXd(C2);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 1.0);
  auto fresh_solve = [&](const Eigen::MatrixXd& M) {
    CholmodSolver f(Factorisation::ldlt);
    REQUIRE(f.factor(Eigen::SparseMatrix<double>(M.sparseView())));
    return Eigen::VectorXd(f.solve(b));
  };

  CholmodSolver s(Factorisation::ldlt);
  REQUIRE(s.factor(Eigen::SparseMatrix<double>(A.sparseView())));
  // A contact closes: A + c cᵀ.
  s.update(C1, true);
  const Eigen::MatrixXd closed = A + D1 * D1.transpose();
  CHECK((s.solve(b) - fresh_solve(closed)).norm() < 1e-10 * fresh_solve(closed).norm());
  CHECK((closed * s.solve(b) - b).norm() < 1e-10 * b.norm());
  // Two contacts change at once (one opens, one closes): a rank-2 update in two calls.
  s.update(C2, true);
  s.update(C1, false);
  const Eigen::MatrixXd swapped = A + D2 * D2.transpose();
  CHECK((swapped * s.solve(b) - b).norm() < 1e-10 * b.norm());
  CHECK(s.negative_pivots() == 0);
  CHECK(s.factor_nonzeros() > 0);
}

TEST_CASE("the condition estimate follows rank-1 updates: that of the changed matrix factored in the same order",
          "[fast]") {
  const int cells = 40, n = 3 * cells;
  const Eigen::MatrixXd A = banded_spd(n, 7);
  const Eigen::SparseMatrix<double> C = contact_column(n, 5, 29, 3.0, 1.1, 0.5);
  const Eigen::MatrixXd Cd = Eigen::MatrixXd(C);
  const Eigen::SparseMatrix<double> before = A.sparseView(),
                                    after = Eigen::MatrixXd(A + Cd * Cd.transpose()).sparseView();
  // One ordering for both, so that the LDLᵀ factors, and with them min|D| / max|D|, are unique.
  CholmodSolver updated(Factorisation::ldlt), fresh(Factorisation::ldlt);
  updated.keep_ordering_for(after);
  fresh.keep_ordering_for(after);
  REQUIRE(updated.factor(before));
  const double rcond_before = updated.rcond();
  updated.update(C, true);
  REQUIRE(fresh.factor(after));
  CHECK(updated.rcond() == Approx(fresh.rcond()).epsilon(1e-10));
  CHECK(updated.rcond() != Approx(rcond_before).epsilon(1e-6));
  // Each pivot of D is a Schur complement's diagonal, within [λ_min, λ_max]: rcond ≥ 1 / κ₂.
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(after)).eigenvalues();
  CHECK(updated.rcond() >= lambda.minCoeff() / lambda.maxCoeff());
  CHECK(updated.rcond() <= 1.0);
}

TEST_CASE("a downdate that makes the matrix indefinite shows in the inertia (Sylvester)", "[fast]") {
  // A = B + t ccᵀ with B having one negative eigenvalue along c: A is positive definite, and the
  // downdate by t ccᵀ leaves B, whose inertia the updated factor must report.
  const int n = 60;
  const Eigen::MatrixXd P = banded_spd(n, 6);
  const Eigen::SparseMatrix<double> C = contact_column(n, 4, 11, 1.0, 0.9, 0.5);
  const Eigen::VectorXd c = Eigen::MatrixXd(C).col(0);
  // P − s ccᵀ loses definiteness at s = 1/(cᵀP⁻¹c) and has one negative eigenvalue past it.
  const double q = c.dot(P.ldlt().solve(c));
  const Eigen::MatrixXd B = P - (2.0 / q) * c * c.transpose();
  const Eigen::MatrixXd A = B + (4.0 / q) * c * c.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eb(B), ea(A);
  REQUIRE(ea.eigenvalues()[0] > 0);
  REQUIRE(eb.eigenvalues()[0] < 0);
  REQUIRE(eb.eigenvalues()[1] > 0);

  CholmodSolver s(Factorisation::ldlt);
  REQUIRE(s.factor(Eigen::SparseMatrix<double>(A.sparseView())));
  CHECK(s.negative_pivots() == 0);
  const Eigen::SparseMatrix<double> scaled = std::sqrt(4.0 / q) * C;
  s.update(scaled, false);
  CHECK(s.negative_pivots() == 1);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  CHECK((B * s.solve(b) - b).norm() < 1e-8 * b.norm());
}

TEST_CASE("an update needs a successful LDLT factor and a C of the factor's size", "[fast]") {
  const int n = 30;
  const Eigen::SparseMatrix<double> A = Eigen::MatrixXd(banded_spd(n, 7)).sparseView();
  const Eigen::SparseMatrix<double> C = contact_column(n, 1, 5, 1.0, 0.2, 0.3);
  CholmodSolver ldlt(Factorisation::ldlt), llt(Factorisation::llt);
  CHECK_THROWS_AS(ldlt.update(C, true), CholmodError);  // nothing factored yet
  REQUIRE(ldlt.factor(A));
  REQUIRE(llt.factor(A));
  CHECK_THROWS_AS(llt.update(C, true), CholmodError);
  CHECK_THROWS_AS(ldlt.update(Eigen::SparseMatrix<double>(n + 3, 1), true), CholmodError);
  CHECK_THROWS_AS(ldlt.update(Eigen::SparseMatrix<double>(n, 9), true), CholmodError);
  // A refactorisation after an update analyses afresh and solves the new matrix.
  ldlt.update(C, true);
  REQUIRE(ldlt.factor(A));
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  CHECK((Eigen::MatrixXd(A) * ldlt.solve(b) - b).norm() < 1e-10 * b.norm());
}

namespace {

// μI + Σ_contacts c cᵀ on a periodic m × m lattice of cells (three dofs each), every cell in contact
// with its right and upper neighbours — the matrix of a 2D contact network; `skip` drops every
// skip-th contact (0: none), so that two calls give two networks with different patterns.
Eigen::SparseMatrix<double> lattice_network(int m, int skip) {
  const int n = 3 * m * m;
  Eigen::SparseMatrix<double> A(n, n);
  for (int k = 0; k < n; ++k) A.insert(k, k) = 1e-3;
  int contact = 0;
  for (int x = 0; x < m; ++x)
    for (int y = 0; y < m; ++y)
      for (int dir = 0; dir < 2; ++dir) {
        ++contact;
        if (skip > 0 && contact % skip == 0) continue;
        const int i = x * m + y, j = dir == 0 ? ((x + 1) % m) * m + y : x * m + (y + 1) % m;
        const Eigen::SparseMatrix<double> C = contact_column(n, i, j, 1.0 + 0.1 * (contact % 7), 0.3 * contact, 0.5);
        A += Eigen::SparseMatrix<double>(C * C.transpose());
      }
  A.makeCompressed();
  return A;
}

double relative_residual(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (A * x - b).norm() / b.norm();
}

}  // namespace

TEST_CASE("an updatable factor is the LDLT factor, bit for bit, where CHOLMOD keeps it simplicial", "[fast]") {
  const Eigen::SparseMatrix<double> A = Eigen::MatrixXd(banded_spd(60, 8)).sparseView();
  CholmodSolver ldlt(Factorisation::ldlt), updatable(Factorisation::updatable);
  REQUIRE(ldlt.factor(A));
  REQUIRE(updatable.factor(A));
  CHECK_FALSE(updatable.supernodal());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(60, -1.0, 1.0);
  CHECK(ldlt.solve(b) == updatable.solve(b));
  const Eigen::SparseMatrix<double> C = contact_column(60, 2, 13, 1.5, 0.7, 0.4);
  ldlt.update(C, true);
  updatable.update(C, true);
  CHECK(ldlt.solve(b) == updatable.solve(b));
}

TEST_CASE("an updatable factor of a large 2D network is supernodal, and updated it solves the changed matrix",
          "[fast]") {
  const int m = 40, n = 3 * m * m;
  const Eigen::SparseMatrix<double> A = lattice_network(m, 0);
  CholmodSolver s(Factorisation::updatable);
  REQUIRE(s.factor(A));
  CHECK(s.supernodal());
  CHECK(s.negative_pivots() == 0);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  CHECK(relative_residual(A, s.solve(b), b) < 1e-10);
  // Contact 11 (cells 5 and m + 5) opens, a new one closes: the factor becomes a simplicial LDLᵀ.
  const Eigen::SparseMatrix<double> opened = contact_column(n, 5, m + 5, 1.0 + 0.1 * (11 % 7), 0.3 * 11, 0.5);
  const Eigen::SparseMatrix<double> closed = contact_column(n, 0, 2 * m + 3, 2.0, 1.1, 0.3);
  s.update(opened, false);
  s.update(closed, true);
  CHECK_FALSE(s.supernodal());
  CHECK(s.negative_pivots() == 0);
  const Eigen::SparseMatrix<double> changed = A - Eigen::SparseMatrix<double>(opened * opened.transpose()) +
                                              Eigen::SparseMatrix<double>(closed * closed.transpose());
  CHECK(relative_residual(changed, s.solve(b), b) < 1e-10);
}

TEST_CASE("a kept ordering serves every sub-pattern: no new ordering, no more fill, the same solution", "[fast]") {
  const int m = 24, n = 3 * m * m;
  const Eigen::SparseMatrix<double> all = lattice_network(m, 0), some = lattice_network(m, 5);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 0.5, 1.5);
  for (Factorisation kind : {Factorisation::ldlt, Factorisation::updatable}) {
    CholmodSolver kept(kind), fresh(kind);
    kept.keep_ordering_for(all);
    kept.keep_ordering_for(some);  // within the kept pattern: the ordering stays
    CHECK(kept.orderings() == 1);
    REQUIRE(kept.factor(all));
    const long fill_all = kept.factor_nonzeros();
    REQUIRE(kept.factor(some));
    CHECK(kept.analyses() == 2);
    CHECK(kept.factor_nonzeros() <= fill_all);
    REQUIRE(fresh.factor(some));
    CHECK(relative_residual(some, kept.solve(b), b) < 1e-10);
    CHECK((kept.solve(b) - fresh.solve(b)).norm() < 1e-10 * fresh.solve(b).norm());
    // A contact outside the kept pattern: CHOLMOD orders that matrix itself, as a fresh solver does.
    const Eigen::SparseMatrix<double> extra = contact_column(n, 0, n / 6, 1.0, 0.2, 0.4);
    const Eigen::SparseMatrix<double> beyond = all + Eigen::SparseMatrix<double>(extra * extra.transpose());
    REQUIRE(kept.factor(beyond));
    REQUIRE(fresh.factor(beyond));
    CHECK(kept.solve(b) == fresh.solve(b));
    kept.keep_ordering_for(beyond);
    CHECK(kept.orderings() == 2);
  }
}
