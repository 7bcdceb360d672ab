// The CHOLMOD wrapper (budjam/cholmod_solver.hpp) against dense Eigen on small banded matrices.
#include "budjam/cholmod_solver.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>

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
