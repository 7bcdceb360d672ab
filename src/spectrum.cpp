#include "budjam/spectrum.hpp"

#include "budjam/arpack.hpp"
#include "budjam/cholmod_solver.hpp"
#include "budjam/errors.hpp"
#include "budjam/hessian.hpp"
#include "budjam/stability.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Householder>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace budjam {

Eigen::VectorXd mass_diagonal(const Packing& p) {
  Eigen::VectorXd m(3 * p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Dumbbell d = p.dumbbell(i);
    m[3 * i] = d.mass;
    m[3 * i + 1] = d.mass;
    m[3 * i + 2] = d.inertia;
  }
  return m;
}

VibrationalProblem vibrational_problem(const Packing& p, const std::vector<Contact>& contacts,
                                       const ContactNetwork& net) {
  const DofMap map = non_rattler_dofs(net);
  VibrationalProblem prob;
  prob.H = restrict_matrix(hessian(p, load_bearing(contacts, net)), map);
  prob.mass = restrict_vector(mass_diagonal(p), map);
  prob.cells = map.cells;
  return prob;
}

const char* to_string(SpectrumMethod method) {
  switch (method) {
    case SpectrumMethod::automatic: return "auto";
    case SpectrumMethod::dense: return "dense";
    case SpectrumMethod::arpack: return "arpack";
  }
  return "?";
}

SpectrumMethod parse_spectrum_method(const std::string& text, const std::string& key) {
  if (text == "auto") return SpectrumMethod::automatic;
  if (text == "dense") return SpectrumMethod::dense;
  if (text == "arpack") return SpectrumMethod::arpack;
  throw InputError(key + ": must be auto, dense or arpack (got '" + text + "')");
}

double signed_omega(double lambda) { return lambda < 0 ? -std::sqrt(-lambda) : std::sqrt(lambda); }

namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Unit mass-weighted translations T_x, T_y (columns) for a 3n layout: T_α ∝ M^{1/2} t_α.
Eigen::MatrixXd translations(const Eigen::VectorXd& mass) {
  const Eigen::Index n3 = mass.size();
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(n3, 2);
  for (Eigen::Index a = 0; a < n3; a += 3) {
    T(a, 0) = std::sqrt(mass[a]);
    T(a + 1, 1) = std::sqrt(mass[a + 1]);
  }
  T.col(0).normalize();
  T.col(1).normalize();
  return T;
}

// K = M^{-1/2} H M^{-1/2}
Sparse dynamical_matrix(const Sparse& H, const Eigen::VectorXd& mass) {
  const Eigen::VectorXd w = mass.cwiseSqrt().cwiseInverse();
  Sparse K = w.asDiagonal() * H * w.asDiagonal();
  K.makeCompressed();
  return K;
}

double max_abs(const Sparse& A) {
  double m = 0;
  for (int k = 0; k < A.outerSize(); ++k)
    for (Sparse::InnerIterator it(A, k); it; ++it) m = std::max(m, std::abs(it.value()));
  return m;
}

// A number for a message (%g: 6 significant digits, exponent when needed).
std::string io_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// ‖·‖_∞ of a symmetric matrix: the largest absolute row sum, a bound on its largest |eigenvalue|.
double norm_inf(const Sparse& A) {
  Eigen::VectorXd rows = Eigen::VectorXd::Zero(A.rows());
  for (int k = 0; k < A.outerSize(); ++k)
    for (Sparse::InnerIterator it(A, k); it; ++it) rows[it.row()] += std::abs(it.value());
  return rows.size() ? rows.maxCoeff() : 0.0;
}

// max_k ‖K v_k − λ_k v_k‖ / (‖K‖_∞ ‖v_k‖) over the columns of V (0 without columns).
double ritz_residual(const Sparse& K, const Eigen::VectorXd& lambda, const Eigen::MatrixXd& V) {
  if (V.cols() == 0 || V.cols() != lambda.size()) return 0;
  const double scale = norm_inf(K);
  if (!(scale > 0)) return 0;
  const Eigen::MatrixXd R = K * V - V * lambda.asDiagonal();
  double worst = 0;
  for (Eigen::Index k = 0; k < V.cols(); ++k) {
    const double r = R.col(k).norm() / (scale * V.col(k).norm());
    worst = std::isfinite(r) ? std::max(worst, r) : std::numeric_limits<double>::infinity();
  }
  return worst;
}

double translation_residual(const Sparse& K, const Eigen::MatrixXd& T) {
  const double scale = max_abs(K);
  if (scale == 0) return 0;
  return (K * T).cwiseAbs().maxCoeff() / scale;
}

void check_problem(const Sparse& H, const Eigen::VectorXd& mass) {
  if (H.rows() != H.cols() || H.rows() != mass.size())
    throw std::invalid_argument("spectrum: H is " + std::to_string(H.rows()) + "x" + std::to_string(H.cols()) +
                                " but M has " + std::to_string(mass.size()) + " entries");
  if (mass.size() % 3 != 0 || mass.size() == 0)
    throw std::invalid_argument("spectrum: the problem needs 3 coordinates per cell and at least one cell");
  if ((mass.array() <= 0).any() || !mass.allFinite())
    throw std::invalid_argument("spectrum: masses must be positive and finite");
}

// Null vectors of K on single cells: right singular vectors of the cell's 3 columns (gathered
// densely: a handful of rows per neighbour) with singular value ≤ tol·max|K|.
std::vector<LocalMode> local_null_vectors(const Sparse& K, double tol) {
  std::vector<LocalMode> out;
  const double cut = tol * max_abs(K);
  const Eigen::Index n = K.cols() / 3;
  std::vector<Eigen::Index> rows;
  for (Eigen::Index c = 0; c < n; ++c) {
    rows.clear();
    for (int j = 0; j < 3; ++j)
      for (Sparse::InnerIterator it(K, 3 * c + j); it; ++it) rows.push_back(it.row());
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    if (rows.empty()) {  // a cell without any stiffness: all three directions are free
      for (int j = 0; j < 3; ++j) out.push_back({static_cast<std::size_t>(c), Eigen::Vector3d::Unit(j)});
      continue;
    }
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), 3);
    for (int j = 0; j < 3; ++j)
      for (Sparse::InnerIterator it(K, 3 * c + j); it; ++it)
        B(std::lower_bound(rows.begin(), rows.end(), it.row()) - rows.begin(), j) = it.value();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(B, Eigen::ComputeFullV);
    const Eigen::VectorXd sv = svd.singularValues();  // descending; fewer than 3 if B has < 3 rows
    for (int j = 0; j < 3; ++j)
      if (j >= sv.size() || sv[j] <= cut) out.push_back({static_cast<std::size_t>(c), svd.matrixV().col(j)});
  }
  return out;
}

// `arpack_most`: where ARPACK could take this problem with fewer modes, the most it takes (for the
// message when the dense method does not fit either).
Spectrum solve_dense(const Sparse& H, const Eigen::VectorXd& mass, const SpectrumOptions& opt,
                     const std::string& arpack_most = "") {
  const Eigen::Index n3 = mass.size(), nd = n3 - 2;
  // K, its complement block, the eigenvectors and the modes.
  require_dense_fits(static_cast<std::size_t>(n3), 4, "spectrum: the dense method",
                     arpack_most.empty() ? "the arpack method (--method arpack)"
                                         : "the arpack method with at most " + arpack_most + " modes (--modes)");
  Spectrum s;
  s.method = SpectrumMethod::dense;
  s.n_cells = static_cast<std::size_t>(n3 / 3);
  s.n_dof = static_cast<std::size_t>(nd);
  const Sparse Ks = dynamical_matrix(H, mass);
  const Eigen::MatrixXd T = translations(mass);
  s.translation_residual = translation_residual(Ks, T);

  // Rotate with the Householder reflectors Q that map span(T) onto the first two axes:
  // QᵀKQ = [[≈0, ≈0], [≈0, K_⊥]]; K_⊥ is K on the complement of the translations.
  Eigen::MatrixXd K = Eigen::MatrixXd(Ks);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(T);
  const auto Q = qr.householderQ();
  K.applyOnTheLeft(Q.adjoint());
  K.applyOnTheRight(Q);
  const Eigen::MatrixXd Kc = K.bottomRightCorner(nd, nd).selfadjointView<Eigen::Lower>();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Kc,
                                                    opt.vectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success)
    throw NoResultError("spectrum: the dense eigensolver did not converge on " + std::to_string(nd) +
                        " modes; try the arpack method, or relax the packing to force balance first");
  s.lambda = es.eigenvalues();
  if (opt.vectors) {
    s.modes = Eigen::MatrixXd::Zero(n3, nd);
    s.modes.bottomRows(nd) = es.eigenvectors();
    s.modes.applyOnTheLeft(Q);
  }
  return s;
}

// Thrown by solve_arpack before any work when the Lanczos run would need as many modes as the problem
// has after deflation; solve_spectrum then takes the dense method (auto) or refuses (arpack asked for).
struct ArpackTooSmall {
  long nev = 0, dim = 0, n_local = 0;
};

// The Lanczos basis (ncv vectors of n3 rows), the eigenvectors asked for and ARPACK's work space are
// dense: bounded like the dense methods (kMaxDenseBytes), before anything is allocated. InputError
// naming the most modes whose default basis (2K + 1 vectors) fits.
double lanczos_bytes(Eigen::Index n3, double nev, double ncv, bool vectors) {
  return 8.0 * (static_cast<double>(n3) * (ncv + (vectors ? nev : 0.0)) + ncv * (ncv + 8.0));
}

long lanczos_most_modes(Eigen::Index n3, bool vectors) {
  // From the leading term, then down to where the whole estimate fits.
  long k = static_cast<long>((kMaxDenseBytes / (8.0 * static_cast<double>(n3)) - 1.0) / (vectors ? 3.0 : 2.0));
  while (k > 1 && lanczos_bytes(n3, k, 2.0 * k + 1, vectors) > kMaxDenseBytes) --k;
  return std::max(1L, k);
}

// Where the basis is the default one (2K + 1 vectors) the fix is fewer modes; where it is larger than
// that (an explicit ncv, or the retry that doubles the basis), a smaller --ncv or the default.
void require_lanczos_fits(Eigen::Index n3, int nev, int ncv, bool vectors) {
  const double bytes = lanczos_bytes(n3, nev, ncv, vectors);
  if (bytes <= kMaxDenseBytes) return;
  const long most = lanczos_most_modes(n3, vectors);
  std::string fix = "ask for at most " + std::to_string(most) + " modes (--modes)";
  if (nev <= most) {
    long largest = ncv;  // the largest basis that fits with these modes
    while (largest > nev + 1 && lanczos_bytes(n3, nev, static_cast<double>(largest), vectors) > kMaxDenseBytes)
      largest = std::max<long>(nev + 1, largest * 9 / 10);
    fix =
        "the basis is larger than the default for these modes (an explicit --ncv, or the retry that doubles it): "
        "use at most --ncv " +
        std::to_string(largest) + ", or fewer modes";
  }
  throw InputError("spectrum: the arpack method: " + std::to_string(nev) + " modes need a Lanczos basis of " +
                   std::to_string(ncv) + " vectors of " + std::to_string(n3) + " rows" +
                   (vectors ? " and their eigenvectors" : "") + ", about " +
                   std::to_string(static_cast<long long>(std::ceil(bytes / 1e9))) + " GB, more than the limit of " +
                   std::to_string(static_cast<int>(kMaxDenseBytes / 1e9)) + " GB; " + fix);
}

// ARPACK's failures on a valid problem (too few iterations, no shifts, a Lanczos breakdown) are
// outcomes of the input, not errors of budjam.
template <class Op>
LanczosResult lanczos_or_no_result(int n, double sigma, const Op& op, const LanczosOptions& lo) {
  try {
    return lanczos_shift_invert(n, sigma, op, lo);
  } catch (const ArpackError& e) {
    throw NoResultError("spectrum: ARPACK did not converge (" + std::string(e.what()) +
                        "); try the dense method, a larger ncv or a looser tol");
  }
}

Spectrum solve_arpack(const Sparse& H, const Eigen::VectorXd& mass, const SpectrumOptions& opt) {
  const Eigen::Index n3 = mass.size(), nd = n3 - 2;
  if (opt.modes <= 0) throw std::invalid_argument("spectrum: ARPACK needs modes > 0");
  Spectrum s;
  s.method = SpectrumMethod::arpack;
  s.n_cells = static_cast<std::size_t>(n3 / 3);
  s.n_dof = static_cast<std::size_t>(nd);
  const Sparse K = dynamical_matrix(H, mass);
  const Eigen::MatrixXd T = translations(mass);
  s.translation_residual = translation_residual(K, T);

  const auto t0 = Clock::now();
  // Cell-local zero modes, deflated below (spectrum.hpp).
  if (opt.deflate_local) s.local = local_null_vectors(K, opt.local_zero_tol);
  const Eigen::Index n_local = static_cast<Eigen::Index>(s.local.size());
  // Translations made orthogonal to the local modes (disjoint supports make the local modes
  // orthonormal among themselves): Q = [local | Tq] is orthonormal.
  Eigen::MatrixXd Tq = T;
  for (const LocalMode& m : s.local)
    Tq.middleRows<3>(3 * static_cast<Eigen::Index>(m.block)) -=
        m.e * (m.e.transpose() * Tq.middleRows<3>(3 * static_cast<Eigen::Index>(m.block)));
  Tq = Eigen::HouseholderQR<Eigen::MatrixXd>(Tq).householderQ() * Eigen::MatrixXd::Identity(n3, 2);
  auto project = [&](Eigen::Ref<Eigen::VectorXd> x) {
    for (const LocalMode& m : s.local) {
      auto seg = x.segment<3>(3 * static_cast<Eigen::Index>(m.block));
      seg -= m.e * m.e.dot(seg);
    }
    x -= Tq * (Tq.transpose() * x);
  };

  // How many modes below inertia_tol exist in all (one LDLᵀ): the Lanczos run must take every
  // one that is not deflated, or it would cut through a degenerate cluster.
  int nev = opt.modes;
  if (opt.inertia_tol > 0) {
    CholmodSolver ldlt(Factorisation::ldlt);
    if (ldlt.factor(K, opt.inertia_tol, Eigen::VectorXd())) {
      s.inertia_count = ldlt.negative_pivots() - 2;
      nev = static_cast<int>(std::max<long>(nev, s.inertia_count - n_local + 1));
    }
  }
  const Eigen::Index dim = nd - n_local;  // dimension of the space Lanczos works in
  if (nev >= dim) throw ArpackTooSmall{nev, static_cast<long>(dim), static_cast<long>(n_local)};
  const int idim = static_cast<int>(dim);
  // An explicit ncv is raised to nev + 1 if the inertia count raised nev past it.
  const int ncv =
      opt.ncv > 0 ? std::min(idim, std::max(opt.ncv, nev + 1)) : std::min(idim, std::max(2 * nev + 1, nev + 20));
  require_lanczos_fits(n3, nev, ncv, opt.vectors);

  double sigma = opt.sigma;
  CholmodSolver chol(Factorisation::llt);
  const Eigen::VectorXd unit;  // empty: identity mass (K is already mass-weighted)
  for (int attempt = 0;; ++attempt) {
    if (chol.factor(K, sigma, unit)) break;
    if (attempt == 4) {
      // Why: an eigenvalue below σ (the saddle test of moduli, stability.hpp), or a shift so close to 0
      // that the exact zero modes (translations) are not lifted above rounding.
      const Stability st = hessian_stability(H);
      if (st.factored && !st.minimum())
        throw NoResultError("spectrum: K − σ is not positive definite down to σ = " + io_number(sigma) +
                            " (k/m): the packing is a saddle, not an energy minimum (" +
                            std::to_string(st.unstable_modes) +
                            " unstable modes); try the dense method to see them, or relax the packing first");
      throw NoResultError("spectrum: K − σ could not be factored down to σ = " + io_number(sigma) +
                          " (k/m): the shift is too close to the zero modes to lift them above rounding; "
                          "try a shift (--sigma) of -1e-3");
    }
    sigma *= 10;
  }
  s.sigma = sigma;
  s.seconds_factorise = seconds_since(t0);

  // Lanczos on Q^⊥: OP = P (K − σI)⁻¹ P. Q spans exact eigenvectors of K, so P commutes with
  // (K − σI)⁻¹ and the spectrum of OP on Q^⊥ is the rest of the spectrum.
  Eigen::VectorXd buf(n3);
  LanczosOptions lo;
  lo.nev = nev;
  lo.ncv = ncv;
  lo.tol = opt.tol;
  lo.vectors = opt.vectors;
  lo.start.resize(n3);
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (Eigen::Index a = 0; a < n3; ++a) lo.start[a] = U(rng);
  project(lo.start);
  const double scale = max_abs(K);
  for (int attempt = 0;; ++attempt) {
    const auto t1 = Clock::now();
    const auto res = lanczos_or_no_result(
        static_cast<int>(n3), sigma,
        [&](const double* x, double* y) {
          buf = Eigen::Map<const Eigen::VectorXd>(x, n3);
          project(buf);
          Eigen::Map<Eigen::VectorXd> out(y, n3);
          chol.solve(buf.data(), y);
          project(out);
        },
        lo);
    s.seconds_lanczos += seconds_since(t1);
    s.lambda.resize(n_local + nev);
    for (Eigen::Index k = 0; k < n_local; ++k) {
      const LocalMode& m = s.local[static_cast<std::size_t>(k)];
      const Eigen::Index b = 3 * static_cast<Eigen::Index>(m.block);
      // Rayleigh quotient eᵀ K e from the cell's columns.
      s.lambda[k] = m.e.dot((K.middleCols(b, 3) * m.e).segment<3>(b));
    }
    s.lambda.tail(nev) = res.values;
    s.modes = res.vectors;
    s.ncv = res.ncv;
    s.restarts += res.restarts;
    s.operator_applications += res.operator_applications;
    // Are these eigenpairs of K? ‖K e − λ e‖ bounds the distance of λ to an eigenvalue of K; a shift
    // far from the spectrum (λ = σ + 1/θ loses ε|σ|) or a loose tol shows here.
    {
      const double residual = ritz_residual(K, s.lambda.tail(nev), s.modes);
      s.ritz_residual = std::max(s.ritz_residual, residual);
      if (opt.vectors && !(residual <= std::max(1e-9, 10 * opt.tol)))
        throw NoResultError(
            "spectrum: ARPACK's eigenpairs are inaccurate (relative residual ‖Kv − λv‖/‖K‖ = " + io_number(residual) +
            " with shift σ = " + io_number(sigma) + "); try a shift (--sigma) of -1e-3" +
            (opt.tol > 1e-10 ? " and a tighter tol" : "") + ", or the dense method");
    }
    if (!opt.verify) break;

    // Are these the lowest modes? Sylvester: #{λ < μ} from the inertia of K − μ, just below the
    // highest computed λ (just below: K may legitimately cut through a degenerate cluster at the
    // top). A single-vector Lanczos run can miss copies of a degenerate
    // eigenvalue (it sees them only through rounding, less so with a loose tol).
    const auto t2 = Clock::now();
    const double mu = s.lambda.maxCoeff() - 1e-9 * scale;
    CholmodSolver ldlt(Factorisation::ldlt);
    if (!ldlt.factor(K, mu, Eigen::VectorXd())) break;  // μ hit an eigenvalue exactly: no check
    s.inertia_below_top = ldlt.negative_pivots() - 2;
    s.seconds_factorise += seconds_since(t2);
    const long missed = s.inertia_below_top - static_cast<long>((s.lambda.array() < mu).count());
    if (missed <= 0) break;
    if (attempt == 1)
      throw NoResultError("spectrum: ARPACK missed " + std::to_string(missed) + " eigenvalue(s) below " +
                          std::to_string(mu) + " even with tol 0 and ncv " + std::to_string(lo.ncv) +
                          " (a degenerate cluster); try the dense method or a larger ncv");
    // Once more at machine precision with a larger basis.
    ++s.retries;
    lo.tol = 0.0;
    lo.ncv = std::min(idim, 2 * lo.ncv);
    require_lanczos_fits(n3, nev, lo.ncv, opt.vectors);
  }
  return s;
}

}  // namespace

Spectrum solve_spectrum(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass,
                        const SpectrumOptions& options) {
  check_problem(H, mass);
  const std::size_t nd = static_cast<std::size_t>(mass.size()) - 2;
  SpectrumMethod method = options.method;
  if (method == SpectrumMethod::automatic)
    method = (nd <= options.dense_max_dof || static_cast<std::size_t>(options.modes) >= nd) ? SpectrumMethod::dense
                                                                                            : SpectrumMethod::arpack;
  Spectrum s;
  if (method == SpectrumMethod::dense) {
    s = solve_dense(H, mass, options);
  } else {
    try {
      s = solve_arpack(H, mass, options);
    } catch (const ArpackTooSmall& t) {
      const long most = std::min(t.dim - 1, lanczos_most_modes(mass.size(), options.vectors));
      // Too few modes left after deflating the cell-local zero modes for a partial solve: the automatic
      // choice takes the dense method; an explicit request for ARPACK is refused.
      if (options.method != SpectrumMethod::automatic)
        throw InputError("spectrum: the arpack method computes fewer modes than the problem has: it has " +
                         std::to_string(t.dim) + " modes besides its " + std::to_string(t.n_local) +
                         " cell-local zero modes and would need " + std::to_string(t.nev) +
                         " of them; ask for at most " + std::to_string(most) +
                         " modes (--modes) or use the dense method (--method dense or auto)");
      s = solve_dense(H, mass, options, std::to_string(most));
    }
  }
  // A Hessian that is not finite (no packing the readers accept gives one) must not pass as a spectrum.
  if (!s.lambda.allFinite())
    throw NoResultError("spectrum: eigenvalues not finite (the Hessian is not); relax the packing first");
  return s;
}

std::vector<LocalMode> cell_local_zero_modes(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass,
                                             double tol) {
  check_problem(H, mass);
  return local_null_vectors(dynamical_matrix(H, mass), tol);
}

Eigen::VectorXd Spectrum::mode(Eigen::Index k) const {
  if (!has_vectors()) throw std::invalid_argument("Spectrum::mode: the spectrum was computed without eigenvectors");
  const Eigen::Index n_local = static_cast<Eigen::Index>(local.size());
  if (k >= n_local) return modes.col(k - n_local);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * n_cells));
  v.segment<3>(3 * static_cast<Eigen::Index>(local[static_cast<std::size_t>(k)].block)) =
      local[static_cast<std::size_t>(k)].e;
  return v;
}

// ---- observables ---------------------------------------------------------------------------

std::size_t count_below(const Eigen::VectorXd& lambda, double tol) {
  return static_cast<std::size_t>((lambda.array() < tol).count());
}

std::size_t count_quasi_zero(const Eigen::VectorXd& lambda, double tol) {
  return static_cast<std::size_t>((lambda.array().abs() < tol).count());
}

BandEdge band_edge(const Spectrum& s, const BandEdgeRule& rule) {
  BandEdge b;
  b.n_zero = count_quasi_zero(s.lambda, rule.lambda_tol);
  // The band starts after every mode below lambda_tol: the quasi-zero ones and, in a saddle, the
  // unstable ones (in the order of Spectrum::lambda all of them come first).
  const std::size_t below = count_below(s.lambda, rule.lambda_tol);
  const std::size_t extended = s.n_dof - std::min(s.n_dof, below);
  b.n_band =
      std::min(extended, std::max(rule.band_min, static_cast<std::size_t>(std::ceil(rule.band_fraction * extended))));
  b.modes_needed = below + b.n_band;
  // A partial spectrum counts its quasi-zero modes correctly only if it reaches above lambda_tol;
  // then the band modes must be among the computed ones as well.
  if (b.n_band == 0 || b.modes_needed > static_cast<std::size_t>(s.lambda.size())) {
    b.available = false;
    b.omega_star = std::numeric_limits<double>::quiet_NaN();
    return b;
  }
  double sum = 0;
  for (std::size_t k = below; k < b.modes_needed; ++k) sum += s.lambda[static_cast<Eigen::Index>(k)];
  b.omega_star = std::sqrt(sum / static_cast<double>(b.n_band));
  b.available = true;
  return b;
}

Eigen::VectorXd participation_ratios(const Spectrum& s) {
  if (!s.has_vectors() || s.lambda.size() == 0)
    throw std::invalid_argument("participation_ratios: the spectrum was computed without eigenvectors");
  const Eigen::Index n = static_cast<Eigen::Index>(s.n_cells);
  const Eigen::Index n_local = static_cast<Eigen::Index>(s.local.size());
  Eigen::VectorXd pr(s.lambda.size());
  for (Eigen::Index k = 0; k < n_local; ++k) pr[k] = 1.0 / static_cast<double>(n);  // one cell
  for (Eigen::Index k = 0; k < s.modes.cols(); ++k) {
    double sum = 0, sum2 = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = s.modes.col(k).segment<3>(3 * i).squaredNorm();
      sum += w;
      sum2 += w * w;
    }
    pr[n_local + k] = sum * sum / (static_cast<double>(n) * sum2);
  }
  return pr;
}

DosHistogram dos_histogram(const Spectrum& s, std::size_t bins, double omega_max, double exclude_below) {
  if (bins == 0 || !(omega_max > 0)) throw std::invalid_argument("dos_histogram: need bins > 0 and omega_max > 0");
  DosHistogram h;
  h.edges.resize(bins + 1);
  h.density.assign(bins, 0.0);
  const double width = omega_max / static_cast<double>(bins);
  for (std::size_t k = 0; k <= bins; ++k) h.edges[k] = width * static_cast<double>(k);
  for (Eigen::Index n = 0; n < s.lambda.size(); ++n) {
    const double lam = s.lambda[n];
    if (lam < exclude_below) {
      ++h.excluded;
      continue;
    }
    const double w = std::sqrt(std::max(lam, 0.0));
    if (w >= omega_max) {
      ++h.outside;
      continue;
    }
    h.density[std::min(bins - 1, static_cast<std::size_t>(w / width))] += 1.0;
  }
  for (auto& d : h.density) d /= static_cast<double>(s.n_dof) * width;
  h.omega_valid = s.complete() ? std::numeric_limits<double>::infinity()
                               : (s.lambda.size() ? signed_omega(s.lambda[s.lambda.size() - 1]) : 0.0);
  return h;
}

SpectralSummary summarise(const Spectrum& s, const BandEdgeRule& rule) {
  SpectralSummary m;
  m.method = s.method;
  m.n_cells = s.n_cells;
  m.n_dof = s.n_dof;
  m.computed = static_cast<std::size_t>(s.lambda.size());
  m.lambda_min = s.lambda.size() ? s.lambda.minCoeff() : std::numeric_limits<double>::quiet_NaN();
  m.lambda_max_computed = s.lambda.size() ? s.lambda.maxCoeff() : std::numeric_limits<double>::quiet_NaN();
  m.lambda_tol = rule.lambda_tol;
  m.N_zero = count_quasi_zero(s.lambda, rule.lambda_tol);
  m.N_negative = count_below(s.lambda, -rule.lambda_tol);
  m.zero_count_complete = s.complete() || m.lambda_max_computed >= std::max(rule.lambda_tol, 1e-5);
  for (double tol : {1e-5, 1e-6, 1e-7, 1e-8}) m.zero_counts.emplace_back(tol, count_quasi_zero(s.lambda, tol));
  m.band = band_edge(s, rule);
  m.translation_residual = s.translation_residual;
  return m;
}

long count_below_by_inertia(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass, double tol) {
  check_problem(H, mass);
  if (!(tol > 0)) throw std::invalid_argument("count_below_by_inertia: tol must be positive");
  // Sylvester: the inertia of K − tol·I = L D Lᵀ is that of D. The two translations are exact
  // zero eigenvalues of K, below any positive tol.
  CholmodSolver ldlt(Factorisation::ldlt);
  if (!ldlt.factor(dynamical_matrix(H, mass), tol, Eigen::VectorXd()))
    throw std::runtime_error(
        "count_below_by_inertia: zero pivot in the LDLᵀ factorisation of K − tol; "
        "tol is an eigenvalue to working precision");
  return ldlt.negative_pivots() - 2;
}

int modes_for_band_edge(std::size_t n_dof, std::size_t expected_zero, const BandEdgeRule& rule, std::size_t spare) {
  const std::size_t extended = n_dof - std::min(n_dof, expected_zero);
  const std::size_t n_band =
      std::max(rule.band_min, static_cast<std::size_t>(std::ceil(rule.band_fraction * extended)));
  return static_cast<int>(std::min(n_dof, expected_zero + n_band + spare));
}

PackingSpectrum packing_spectrum(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 SpectrumOptions options, const BandEdgeRule& rule) {
  if (net.N_nr == 0)  // a valid packing with no answer, as its moduli (moduli.cpp)
    throw NoResultError("packing: no non-rattler cells (unjammed): no vibrational spectrum");
  const VibrationalProblem prob = vibrational_problem(p, contacts, net);
  const std::size_t nd = static_cast<std::size_t>(prob.mass.size()) - 2;
  // Enough modes for ω*: the quasi-zero modes (≈ N_u; with deflation the cell-local ones come for
  // free and the inertia count adds any other) plus n_band and a margin.
  if (options.modes <= 0)
    options.modes = modes_for_band_edge(nd, net.N_u, rule) - (options.deflate_local ? static_cast<int>(net.N_u) : 0);
  PackingSpectrum out;
  out.cells = prob.cells;
  // The saddle test of `budjam moduli` (stability.hpp) on the same Hessian.
  out.stability = hessian_stability(prob.H);
  out.stationary = stationary_point(p, contacts, net, out.stability.unstable_modes);
  out.spectrum = solve_spectrum(prob.H, prob.mass, options);
  out.summary = summarise(out.spectrum, rule);
  if (options.vectors) out.participation = participation_ratios(out.spectrum);
  return out;
}

}  // namespace budjam
