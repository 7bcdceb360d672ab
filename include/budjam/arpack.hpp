#pragma once
// Symmetric Lanczos eigensolver: a driver for ARPACK's reverse-communication routines
// dsaupd/dseupd (implicitly restarted Lanczos). The only place in budjam that talks to ARPACK.
//
// The caller supplies the operator as a function y = OP x; the driver owns all ARPACK workspace
// (std::vector, released on every exit path) and turns ARPACK's info codes into exceptions that
// say what to change. ARPACK keeps internal state in Fortran SAVE variables, so one Lanczos
// iteration must run to completion before another starts: the driver serialises calls with a
// process-wide mutex (two threads may call it; they take turns).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

namespace budjam {

// An ARPACK failure; `info` is ARPACK's code, `routine` "dsaupd" or "dseupd".
struct ArpackError : std::runtime_error {
  ArpackError(const std::string& routine, int info, const std::string& what);
  std::string routine;
  int info;
};

struct LanczosOptions {
  int nev = 6;               // eigenpairs wanted
  int ncv = 0;               // Lanczos basis size, nev < ncv ≤ n; 0 = min(n, max(2 nev + 1, nev + 20))
  double tol = 0.0;          // relative Ritz residual |r| ≤ tol |θ|; 0 = machine precision
  int max_restarts = 10000;  // ARPACK's maxitr
  bool vectors = true;       // compute eigenvectors too
  std::uint64_t seed = 1;    // starting vector: uniform in [−1,1)^n from this seed (reproducible;
                             // ARPACK's own random start depends on how often it was called before)
  Eigen::VectorXd start;     // if non-empty (length n), the starting vector instead, e.g. one
                             // projected into the subspace the operator lives in
};

struct LanczosResult {
  Eigen::VectorXd values;         // ascending
  Eigen::MatrixXd vectors;        // matching columns, orthonormal (empty unless options.vectors)
  int ncv = 0;                    // basis size used
  int restarts = 0;               // implicit restarts (ARPACK iparam(3))
  int operator_applications = 0;  // OP x products (iparam(9))
};

// y = OP x for vectors of length n. Must not keep the pointers.
using LinearOperator = std::function<void(const double* x, double* y)>;

// Largest- or smallest-algebraic eigenvalues of a symmetric operator A given by y = A x
// (ARPACK mode 1). `largest` picks "LA", else "SA". Slow for the bottom of a spectrum; use
// shift-invert for that.
LanczosResult lanczos_extremal(int n, const LinearOperator& apply_A, bool largest, const LanczosOptions& options);

// The nev eigenvalues of a symmetric A nearest to the shift σ (ARPACK mode 3, "LM" of
// (A − σI)⁻¹), given y = (A − σI)⁻¹ x. Returns the eigenvalues λ of A (not of the inverse).
LanczosResult lanczos_shift_invert(int n, double sigma, const LinearOperator& solve_shifted,
                                   const LanczosOptions& options);

// ARPACK's documented meaning of an info code, with the remedy where there is one.
std::string arpack_info_message(const std::string& routine, int info);

}  // namespace budjam
