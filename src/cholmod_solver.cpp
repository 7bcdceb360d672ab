#include "budjam/cholmod_solver.hpp"

#include "budjam/blas_threads.hpp"

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <vector>

namespace budjam {

namespace {

// CHOLMOD's view of a compressed Eigen matrix with sorted columns (no copy; `A` must outlive it).
// stype 1: symmetric, upper triangle stored; 0: every entry.
cholmod_sparse cholmod_view(Eigen::SparseMatrix<double>& A, int stype) {
  cholmod_sparse S{};
  S.nrow = static_cast<size_t>(A.rows());
  S.ncol = static_cast<size_t>(A.cols());
  S.nzmax = static_cast<size_t>(A.nonZeros());
  S.p = A.outerIndexPtr();
  S.i = A.innerIndexPtr();
  S.x = A.valuePtr();
  S.stype = stype;
  S.itype = CHOLMOD_INT;
  S.xtype = CHOLMOD_REAL;
  S.dtype = CHOLMOD_DOUBLE;
  S.sorted = 1;
  S.packed = 1;
  return S;
}

}  // namespace

struct CholmodSolver::Impl {
  // Upper-triangle pattern of a compressed matrix (column pointers and sorted row indices). A member
  // type: a field of a file-local type is a -Wsubobject-linkage warning where a unity build includes
  // this file.
  struct Pattern {
    std::vector<int> outer, inner;
    static Pattern of(const Eigen::SparseMatrix<double>& C) {
      return {{C.outerIndexPtr(), C.outerIndexPtr() + C.outerSize() + 1},
              {C.innerIndexPtr(), C.innerIndexPtr() + C.nonZeros()}};
    }
    bool equals(const Eigen::SparseMatrix<double>& C) const {
      return static_cast<Eigen::Index>(outer.size()) == C.outerSize() + 1 &&
             std::equal(outer.begin(), outer.end(), C.outerIndexPtr()) &&
             static_cast<Eigen::Index>(inner.size()) == C.nonZeros() &&
             std::equal(inner.begin(), inner.end(), C.innerIndexPtr());
    }
    // Whether every entry of C (sorted rows per column) is in this pattern.
    bool contains(const Eigen::SparseMatrix<double>& C) const {
      if (static_cast<Eigen::Index>(outer.size()) != C.outerSize() + 1) return false;
      for (Eigen::Index j = 0; j < C.outerSize(); ++j) {
        auto mine = inner.begin() + outer[static_cast<std::size_t>(j)];
        const auto end = inner.begin() + outer[static_cast<std::size_t>(j) + 1];
        for (int k = C.outerIndexPtr()[j]; k < C.outerIndexPtr()[j + 1]; ++k) {
          mine = std::lower_bound(mine, end, C.innerIndexPtr()[k]);
          if (mine == end || *mine != C.innerIndexPtr()[k]) return false;
        }
      }
      return true;
    }
  };

  // A supernodal factor and its solves call the BLAS: on one thread, so that the factor's bits do
  // not depend on the thread count (blas_threads.hpp).
  SerialBlas serial_blas;
  cholmod_common common{};
  cholmod_factor* L = nullptr;
  // Upper-triangle pattern of the last analysed matrix, to reuse its analysis.
  Pattern analysed;
  // keep_ordering_for: a fill-reducing permutation and the pattern it was computed for.
  Pattern ordered;
  std::vector<int> ordering;
  // The factor's row of each matrix row (the inverse of L->Perm), for updates; made at the first
  // update after a factorisation.
  std::vector<int> position;
  // Solve workspace, reused between calls (cholmod_solve2).
  cholmod_dense* X = nullptr;
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;

  explicit Impl(Factorisation kind) {
    cholmod_start(&common);
    common.print = 0;  // the library never prints; errors come back as exceptions
    if (kind == Factorisation::ldlt) {
      common.supernodal = CHOLMOD_SIMPLICIAL;  // supernodal CHOLMOD is LLᵀ only
      common.final_ll = 0;
    } else if (kind == Factorisation::updatable) {
      common.supernodal = CHOLMOD_AUTO;  // a supernodal factor is LLᵀ; a simplicial one stays LDLᵀ
      common.final_ll = 0;
    } else {
      common.supernodal = CHOLMOD_AUTO;
      // A simplicial factor is otherwise computed as LDLᵀ, which silently accepts indefinite
      // matrices; LLᵀ stops at the first non-positive pivot (CHOLMOD_NOT_POSDEF).
      common.final_ll = 1;
    }
  }
  ~Impl() {
    free_workspace();
    if (L) cholmod_free_factor(&L, &common);
    cholmod_finish(&common);
  }
  void free_workspace() {
    if (X) cholmod_free_dense(&X, &common);
    if (Y) cholmod_free_dense(&Y, &common);
    if (E) cholmod_free_dense(&E, &common);
  }
  void drop_factor() {
    if (L) cholmod_free_factor(&L, &common);
    analysed = {};
  }
  // Symbolic analysis of S, with the kept ordering when it was computed for a pattern containing
  // S's; otherwise CHOLMOD's own choice (AMD, and METIS where AMD fills in much).
  cholmod_factor* analyse(cholmod_sparse& S, const Eigen::SparseMatrix<double>& C) {
    if (ordering.empty() || !ordered.contains(C)) return cholmod_analyze(&S, &common);
    const int methods = common.nmethods, method = common.method[0].ordering;
    common.nmethods = 1;  // only the given ordering (by default CHOLMOD also tries AMD and METIS)
    common.method[0].ordering = CHOLMOD_GIVEN;
    cholmod_factor* F = cholmod_analyze_p(&S, ordering.data(), nullptr, 0, &common);
    common.nmethods = methods;
    common.method[0].ordering = method;
    return F;
  }
  std::string status_text() const {
    switch (common.status) {
      case CHOLMOD_OUT_OF_MEMORY: return "out of memory";
      case CHOLMOD_TOO_LARGE: return "problem too large";
      case CHOLMOD_INVALID: return "invalid input";
      case CHOLMOD_NOT_INSTALLED: return "method not installed";
      case CHOLMOD_GPU_PROBLEM: return "GPU problem";
      default: return "status " + std::to_string(common.status);
    }
  }
};

CholmodSolver::CholmodSolver(Factorisation kind) : impl_(std::make_unique<Impl>(kind)), kind_(kind) {}
CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;

bool CholmodSolver::factor(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) throw CholmodError("CholmodSolver::factor: matrix is not square");
  Eigen::SparseMatrix<double> C = A.triangularView<Eigen::Upper>();
  return factor_matrix(C);
}

bool CholmodSolver::factor(const Eigen::SparseMatrix<double>& A, double sigma, const Eigen::VectorXd& mass) {
  if (A.rows() != A.cols()) throw CholmodError("CholmodSolver::factor: matrix is not square");
  if (mass.size() != 0 && mass.size() != A.rows())
    throw CholmodError("CholmodSolver::factor: mass vector does not match the matrix");
  Eigen::SparseMatrix<double> D(A.rows(), A.cols());
  D.reserve(Eigen::VectorXi::Constant(A.cols(), 1));
  for (Eigen::Index k = 0; k < A.rows(); ++k) D.insert(k, k) = mass.size() ? mass[k] : 1.0;
  Eigen::SparseMatrix<double> C = Eigen::SparseMatrix<double>(A - sigma * D).triangularView<Eigen::Upper>();
  return factor_matrix(C);
}

bool CholmodSolver::factor(const Eigen::SparseMatrix<double>& A, double sigma, const Eigen::SparseMatrix<double>& M) {
  if (A.rows() != A.cols() || M.rows() != A.rows() || M.cols() != A.cols())
    throw CholmodError("CholmodSolver::factor: matrix sizes do not match");
  Eigen::SparseMatrix<double> C = Eigen::SparseMatrix<double>(A - sigma * M).triangularView<Eigen::Upper>();
  return factor_matrix(C);
}

bool CholmodSolver::factor_matrix(const Eigen::SparseMatrix<double>& Cin) {
  Eigen::SparseMatrix<double> C = Cin;
  C.makeCompressed();
  Impl& m = *impl_;
  ok_ = false;
  failed_column_ = -1;
  negative_pivots_ = 0;
  n_ = C.rows();
  m.position.clear();

  cholmod_sparse S = cholmod_view(C, 1);  // symmetric, upper triangle

  const SerialOpenMp serial_openmp;  // CHOLMOD's own OpenMP regions (blas_threads.hpp)
  if (!m.L || !m.analysed.equals(C)) {
    m.drop_factor();
    m.L = m.analyse(S, C);
    if (!m.L) throw CholmodError("CHOLMOD analyse failed: " + m.status_text());
    m.analysed = Impl::Pattern::of(C);
    ++analyses_;
  }
  const int good = cholmod_factorize(&S, m.L, &m.common);
  if (m.common.status == CHOLMOD_NOT_POSDEF || (good && m.L->minor < m.L->n)) {
    failed_column_ = static_cast<long>(m.L->minor);
    m.drop_factor();  // a partial factor is not reused
    return false;
  }
  if (!good || m.common.status < CHOLMOD_OK) throw CholmodError("CHOLMOD factorisation failed: " + m.status_text());
  factor_nonzeros_ = static_cast<long>(m.common.lnz);
  read_factor();
  ok_ = true;
  return true;
}

void CholmodSolver::read_factor() {
  Impl& m = *impl_;
  supernodal_ = m.L->is_super != 0;
  negative_pivots_ = 0;
  if (kind_ == Factorisation::ldlt && (m.L->is_super || m.L->is_ll))
    throw CholmodError("CHOLMOD returned an LLᵀ factor where LDLᵀ was asked");
  if (!m.L->is_super && !m.L->is_ll) {
    const int* Lp = static_cast<const int*>(m.L->p);
    const double* Lx = static_cast<const double*>(m.L->x);
    for (size_t j = 0; j < m.L->n; ++j)
      if (Lx[Lp[j]] < 0) ++negative_pivots_;  // the diagonal D_jj is stored first in column j
  }
}

double CholmodSolver::rcond() const { return ok_ ? cholmod_rcond(impl_->L, &impl_->common) : 0.0; }

void CholmodSolver::update(const Eigen::SparseMatrix<double>& C, bool add) {
  if (!ok_) throw CholmodError("CholmodSolver::update: no successful factorisation");
  if (kind_ == Factorisation::llt)
    throw CholmodError("CholmodSolver::update: needs Factorisation::ldlt or Factorisation::updatable");
  if (C.rows() != n_ || C.cols() < 1 || C.cols() > 8)
    throw CholmodError("CholmodSolver::update: C must have rows() rows and 1 to 8 columns");
  Impl& m = *impl_;
  // The factor is of P A Pᵀ (P = L->Perm): row i of C goes to the position k with Perm[k] = i.
  if (m.position.empty()) {
    const int* perm = static_cast<const int*>(m.L->Perm);
    m.position.resize(static_cast<size_t>(n_));
    for (Eigen::Index k = 0; k < n_; ++k) m.position[static_cast<size_t>(perm[k])] = static_cast<int>(k);
  }
  const std::vector<int>& position = m.position;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(C.nonZeros()));
  for (Eigen::Index j = 0; j < C.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(C, j); it; ++it)
      t.emplace_back(position[static_cast<size_t>(it.row())], static_cast<int>(j), it.value());
  Eigen::SparseMatrix<double> PC(n_, C.cols());
  PC.setFromTriplets(t.begin(), t.end());  // compressed, rows sorted within each column
  cholmod_sparse S = cholmod_view(PC, 0);  // unsymmetric: every entry of C
  if (!cholmod_updown(add ? 1 : 0, &S, m.L, &m.common) || m.common.status < CHOLMOD_OK)
    throw CholmodError("CHOLMOD update failed: " + m.status_text());
  // The updated factor's pattern is no longer the analysed one: the next factor() starts afresh.
  m.analysed = {};
  const int* column_nonzeros = static_cast<const int*>(m.L->nz);
  factor_nonzeros_ = std::accumulate(column_nonzeros, column_nonzeros + n_, 0L);
  read_factor();
}

void CholmodSolver::keep_ordering_for(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) throw CholmodError("CholmodSolver::keep_ordering_for: matrix is not square");
  Eigen::SparseMatrix<double> C = A.triangularView<Eigen::Upper>();
  C.makeCompressed();
  Impl& m = *impl_;
  if (!m.ordering.empty() && m.ordered.contains(C)) return;
  cholmod_sparse S = cholmod_view(C, 1);
  const SerialOpenMp serial_openmp;
  cholmod_factor* F = cholmod_analyze(&S, &m.common);
  if (!F) throw CholmodError("CHOLMOD analyse failed: " + m.status_text());
  const int* perm = static_cast<const int*>(F->Perm);
  m.ordering.assign(perm, perm + C.rows());
  cholmod_free_factor(&F, &m.common);
  m.ordered = Impl::Pattern::of(C);
  ++orderings_;
}

void CholmodSolver::solve(const double* b, double* x) const {
  if (!ok_) throw CholmodError("CholmodSolver::solve: no successful factorisation");
  Impl& m = *impl_;
  cholmod_dense B{};
  B.nrow = static_cast<size_t>(n_);
  B.ncol = 1;
  B.nzmax = static_cast<size_t>(n_);
  B.d = static_cast<size_t>(n_);
  B.x = const_cast<double*>(b);
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.common))
    throw CholmodError("CHOLMOD solve failed: " + m.status_text());
  std::memmove(x, m.X->x, sizeof(double) * static_cast<size_t>(n_));
}

Eigen::VectorXd CholmodSolver::solve(const Eigen::VectorXd& b) const {
  if (b.size() != n_) throw CholmodError("CholmodSolver::solve: right-hand side has the wrong size");
  Eigen::VectorXd x(n_);
  solve(b.data(), x.data());
  return x;
}

Eigen::MatrixXd CholmodSolver::solve(const Eigen::MatrixXd& Bm) const {
  if (!ok_) throw CholmodError("CholmodSolver::solve: no successful factorisation");
  if (Bm.rows() != n_) throw CholmodError("CholmodSolver::solve: right-hand sides have the wrong size");
  Impl& m = *impl_;
  cholmod_dense B{};
  B.nrow = static_cast<size_t>(n_);
  B.ncol = static_cast<size_t>(Bm.cols());
  B.nzmax = static_cast<size_t>(Bm.size());
  B.d = static_cast<size_t>(n_);
  B.x = const_cast<double*>(Bm.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.common))
    throw CholmodError("CHOLMOD solve failed: " + m.status_text());
  Eigen::MatrixXd out(n_, Bm.cols());
  std::memcpy(out.data(), m.X->x, sizeof(double) * static_cast<size_t>(Bm.size()));
  return out;
}

}  // namespace budjam
