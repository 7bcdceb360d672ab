// The ARPACK reverse-communication driver against matrices with known spectra.
#include "budjam/arpack.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

using namespace budjam;

namespace {

// 1D Dirichlet Laplacian tridiag(−1, 2, −1) of size n: λ_k = 2 − 2 cos(kπ/(n+1)) = 4 sin²(kπ/(2(n+1))),
// k = 1..n (the sine form keeps full relative precision at the bottom of the spectrum).
double laplacian_eigenvalue(int n, int k) {
  const double s = std::sin(k * std::numbers::pi / (2.0 * (n + 1)));
  return 4.0 * s * s;
}

void apply_laplacian(int n, const double* x, double* y) {
  for (int j = 0; j < n; ++j) {
    y[j] = 2.0 * x[j];
    if (j > 0) y[j] -= x[j - 1];
    if (j + 1 < n) y[j] -= x[j + 1];
  }
}

Eigen::SparseMatrix<double> laplacian(int n, double shift) {
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n; ++j) {
    t.emplace_back(j, j, 2.0 - shift);
    if (j > 0) t.emplace_back(j, j - 1, -1.0);
    if (j + 1 < n) t.emplace_back(j, j + 1, -1.0);
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

// Residual ‖A v − λ v‖ of an eigenpair of the Laplacian.
double residual(int n, const Eigen::VectorXd& v, double lambda) {
  Eigen::VectorXd Av(n);
  apply_laplacian(n, v.data(), Av.data());
  return (Av - lambda * v).norm();
}

}  // namespace

// Eigenvalues of a symmetric matrix are well conditioned in absolute terms: backward-stable
// arithmetic gives |δλ| ~ ε‖A‖ (‖A‖ ≤ 4 here), whatever λ is.
TEST_CASE("shift-invert Lanczos finds the lowest Laplacian eigenvalues to 1e-14 absolute", "[arpack]") {
  const int n = 2000;
  const double sigma = -1e-3;  // below the spectrum: (A − σI) is positive definite
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(laplacian(n, sigma));
  REQUIRE(ldlt.info() == Eigen::Success);
  LanczosOptions opt;
  opt.nev = 12;
  const auto res = lanczos_shift_invert(
      n, sigma,
      [&](const double* x, double* y) {
        Eigen::Map<Eigen::VectorXd>(y, n) = ldlt.solve(Eigen::Map<const Eigen::VectorXd>(x, n));
      },
      opt);
  REQUIRE(res.values.size() == 12);
  for (int k = 0; k < 12; ++k) {
    const double exact = laplacian_eigenvalue(n, k + 1);
    CHECK(std::abs(res.values[k] - exact) <= 1e-14);
    CHECK(residual(n, res.vectors.col(k), res.values[k]) < 1e-10);
  }
  // Orthonormal eigenvectors.
  const Eigen::MatrixXd G = res.vectors.transpose() * res.vectors;
  CHECK((G - Eigen::MatrixXd::Identity(12, 12)).cwiseAbs().maxCoeff() < 1e-10);
}

TEST_CASE("regular-mode Lanczos finds the largest eigenvalues of the 1D Laplacian", "[arpack]") {
  const int n = 500;
  LanczosOptions opt;
  opt.nev = 5;
  const auto res = lanczos_extremal(
      n, [&](const double* x, double* y) { apply_laplacian(n, x, y); }, true, opt);
  for (int k = 0; k < 5; ++k) {
    const double exact = laplacian_eigenvalue(n, n - 4 + k);  // ascending: λ_{n−4} … λ_n
    CHECK(res.values[k] == Approx(exact).epsilon(1e-12));
  }
  // Smallest algebraic in regular mode: slow (the bottom of a Laplacian is clustered) but correct.
  opt.nev = 3;
  opt.ncv = 60;
  const auto low = lanczos_extremal(
      120, [&](const double* x, double* y) { apply_laplacian(120, x, y); }, false, opt);
  for (int k = 0; k < 3; ++k) CHECK(low.values[k] == Approx(laplacian_eigenvalue(120, k + 1)).epsilon(1e-10));
}

TEST_CASE("a loose tolerance gives a larger but bounded eigenvalue error", "[arpack]") {
  // ARPACK's tol bounds the Ritz residual relative to the Ritz value of OP; for a symmetric
  // operator the eigenvalue error of OP is at most residual²/gap, so eigenvalues stay good.
  const int n = 3000;
  const double sigma = -1e-4;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(laplacian(n, sigma));
  LanczosOptions opt;
  opt.nev = 8;
  opt.tol = 1e-4;
  opt.vectors = false;
  const auto res = lanczos_shift_invert(
      n, sigma,
      [&](const double* x, double* y) {
        Eigen::Map<Eigen::VectorXd>(y, n) = ldlt.solve(Eigen::Map<const Eigen::VectorXd>(x, n));
      },
      opt);
  CHECK(res.vectors.size() == 0);
  for (int k = 0; k < 8; ++k) {
    const double exact = laplacian_eigenvalue(n, k + 1);
    CHECK(std::abs(res.values[k] - exact) <= 1e-4 * exact);
  }
}

TEST_CASE("the same seed gives bit-identical Lanczos results", "[arpack]") {
  const int n = 300;
  LanczosOptions opt;
  opt.nev = 4;
  auto op = [&](const double* x, double* y) { apply_laplacian(n, x, y); };
  const auto a = lanczos_extremal(n, op, true, opt);
  const auto b = lanczos_extremal(n, op, true, opt);
  CHECK(a.values == b.values);
  CHECK(a.vectors == b.vectors);
}

TEST_CASE("ARPACK errors name the problem and the remedy", "[arpack]") {
  const int n = 50;
  auto op = [&](const double* x, double* y) { apply_laplacian(n, x, y); };
  LanczosOptions opt;
  opt.nev = 10;
  opt.ncv = 8;  // must exceed nev
  try {
    lanczos_extremal(n, op, true, opt);
    FAIL("ncv <= nev was accepted");
  } catch (const ArpackError& e) {
    CHECK(e.info == -3);
    CHECK(std::string(e.what()).find("ncv") != std::string::npos);
  }
  opt.ncv = 0;
  opt.nev = n;  // the whole spectrum is not a Lanczos job
  CHECK_THROWS_AS(lanczos_extremal(n, op, true, opt), ArpackError);

  // Too few restarts to converge: info 1 from dsaupd becomes an exception, never a silent
  // partial answer.
  opt.nev = 6;
  opt.ncv = 13;
  opt.max_restarts = 1;
  opt.tol = 1e-15;
  try {
    lanczos_extremal(
        1000, [&](const double* x, double* y) { apply_laplacian(1000, x, y); }, false, opt);
    FAIL("an unconverged run was accepted");
  } catch (const ArpackError& e) {
    CHECK(e.info == 1);
    CHECK(std::string(e.what()).find("restarts") != std::string::npos);
  }
  CHECK(arpack_info_message("dseupd", -17).find("ncv") != std::string::npos);
}
