#pragma once
// A small RAII wrapper around CHOLMOD (SuiteSparse) for symmetric sparse systems: the moduli solve
// H u = Ξ with it, the spectrum solves (H − σM) x = b in shift-invert Lanczos.
//
//   CholmodSolver s;                       // LLᵀ (supernodal when it pays)
//   if (!s.factor(H)) ...                  // false: not positive definite (s.failed_column())
//   Eigen::MatrixXd X = s.solve(B);        // many right-hand sides at once
//   s.factor(H, sigma, mass);              // H − σ diag(mass): the fill-reducing ordering of the
//                                          // previous call is reused when the pattern is the same
//   s.update(C, false);                    // ldlt: the factor of A − C Cᵀ, from the factor of A
//   s.keep_ordering_for(P);                // later factors of sub-patterns of P reuse P's ordering
//
// With Factorisation::ldlt the factor is a simplicial LDLᵀ without pivoting: it accepts symmetric
// indefinite matrices (fails only on an exactly zero or NaN pivot), and negative_pivots() is the
// inertia — by Sylvester's law the number of eigenvalues of H − σM below 0, i.e. of (H, M)
// below σ. Not backward stable for strongly indefinite matrices: check residuals.
//
// Factorisation::updatable is for positive definite matrices that are then changed by update():
// a supernodal LLᵀ (dense BLAS-3 kernels) where CHOLMOD's analysis finds that it pays — many flops
// per factor entry, i.e. large 2D networks — else the simplicial LDLᵀ of ldlt. The first update()
// of a supernodal factor turns it into a simplicial LDLᵀ (CHOLMOD converts it in place).
//
// Matrices are Eigen column-major with int indices; only the upper triangle (row ≤ col) is
// read, so a matrix with both triangles stored (as budjam::hessian returns) is fine. One solver
// must not be used by two threads at once; two solvers may.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <stdexcept>
#include <string>

namespace budjam {

// CHOLMOD reported an error other than "not positive definite" (out of memory, invalid input,
// solve before a successful factorisation).
struct CholmodError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Factorisation { llt, ldlt, updatable };

class CholmodSolver {
 public:
  explicit CholmodSolver(Factorisation kind = Factorisation::llt);
  ~CholmodSolver();
  CholmodSolver(CholmodSolver&&) noexcept;
  CholmodSolver& operator=(CholmodSolver&&) noexcept;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  // Factors A (square, symmetric; upper triangle read). Returns true on success; false if A is
  // not positive definite (llt) or has a zero pivot (ldlt) — then failed_column() is the column
  // (in CHOLMOD's permuted order) where the factorisation stopped and solve() throws.
  bool factor(const Eigen::SparseMatrix<double>& A);
  // Factors A − σ diag(mass); mass.size() == A.rows(). mass may be empty: identity.
  bool factor(const Eigen::SparseMatrix<double>& A, double sigma, const Eigen::VectorXd& mass);
  // Factors A − σ M for a sparse symmetric M.
  bool factor(const Eigen::SparseMatrix<double>& A, double sigma, const Eigen::SparseMatrix<double>& M);

  // Changes the factored matrix A to A + C Cᵀ (add) or A − C Cᵀ, C a sparse rows() × k matrix
  // (k ≤ 8 per call), by updating the factor in place (cholmod_updown) instead of factoring
  // again: a contact that opens or closes at zero force changes the Hessian by k_c g gᵀ, one rank-1
  // term (g = Jᵀn, six entries), so an event costs an update where it would cost a factorisation.
  // ldlt and updatable; the factor is then a simplicial LDLᵀ and negative_pivots() and rcond()
  // follow it (the inertia of the changed matrix). The next factor() analyses its matrix again.
  // Throws CholmodError without a successful factor, for llt, or for a C of the wrong size.
  void update(const Eigen::SparseMatrix<double>& C, bool add);

  // Computes and keeps the fill-reducing ordering of A's pattern (the values are not read), unless
  // the kept one was computed for a pattern that contains A's. A later factor() of a matrix whose
  // pattern lies within the kept one is analysed with it instead of with a new ordering (METIS and
  // AMD are most of an analysis of a large 2D network): eliminated in the same order, a
  // sub-pattern fills in no more than the pattern the ordering was made for. For a sequence of
  // matrices drawn from one pattern — the contact sets of one neighbour list.
  void keep_ordering_for(const Eigen::SparseMatrix<double>& A);

  // x = (A − σM)⁻¹ b. Throws CholmodError unless the last factor() succeeded.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;
  // Same on raw arrays of length rows() (for ARPACK's reverse communication); x may alias b.
  void solve(const double* b, double* x) const;

  bool ok() const { return ok_; }
  Factorisation kind() const { return kind_; }
  Eigen::Index rows() const { return n_; }
  long failed_column() const { return failed_column_; }  // −1 after success
  // A simplicial LDLᵀ factor: number of negative D entries (inertia); an LLᵀ factor: 0.
  long negative_pivots() const { return negative_pivots_; }
  // CHOLMOD's cheap reciprocal condition estimate (min/max diagonal of L, squared for LDLᵀ's D),
  // of the current factor; computed when asked, so that updates do not pay for it.
  double rcond() const;
  long factor_nonzeros() const { return factor_nonzeros_; }
  bool supernodal() const { return supernodal_; }
  long analyses() const { return analyses_; }    // symbolic analyses done (ordering reuse is visible)
  long orderings() const { return orderings_; }  // orderings kept by keep_ordering_for

 private:
  struct Impl;
  bool factor_matrix(const Eigen::SparseMatrix<double>& C);
  void read_factor();  // inertia of the current factor
  std::unique_ptr<Impl> impl_;
  Factorisation kind_;
  bool ok_ = false;
  Eigen::Index n_ = 0;
  long failed_column_ = -1;
  long negative_pivots_ = 0;
  long factor_nonzeros_ = 0;
  bool supernodal_ = false;
  long analyses_ = 0;
  long orderings_ = 0;
};

}  // namespace budjam
