#include "budjam/moduli.hpp"

#include "budjam/cholmod_solver.hpp"
#include "budjam/errors.hpp"
#include "budjam/hessian.hpp"
#include "budjam/orientation.hpp"
#include "budjam/stability.hpp"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace budjam {

namespace {

Eigen::Vector2d centroid_separation(const Packing& p, const Contact& c) {
  // d = C + o_a − o_b with o = s ê(θ): the centroid separation of the same image as the contact.
  const std::size_t i = cell_of(c.i), j = cell_of(c.j);
  const double sa = lobe_offset(p, c.i), sb = lobe_offset(p, c.j);
  const Axis ai = axis(p.theta(i)), aj = axis(p.theta(j));
  const Eigen::Vector2d ei(ai.c, ai.s), ej(aj.c, aj.s);
  return c.r * Eigen::Vector2d(c.nx, c.ny) - sa * ei + sb * ej;
}

ContactResponseTerms terms_of(const Packing& p, const Contact& c, const DofMap& map) {
  ContactResponseTerms t;
  const Eigen::Vector2d n(c.nx, c.ny);
  const double f = c.force();
  t.J = contact_jacobian(p, c);
  t.K = kSpring * n * n.transpose() - (f / c.r) * (Eigen::Matrix2d::Identity() - n * n.transpose());
  t.g = f * n;
  t.d = c.r * n;
  t.C = centroid_separation(p, c);
  t.D.setZero();
  for (int gam = 0; gam < 2; ++gam)
    for (int del = 0; del < 2; ++del) t.D(gam, 2 * gam + del) = t.C[del];
  t.bi = map.block[cell_of(c.i)];
  t.bj = map.block[cell_of(c.j)];
  return t;
}

// Rows/columns `keep` of a symmetric sparse matrix (dof granularity).
SparseMatrix select(const SparseMatrix& A, const std::vector<long>& index_of, Eigen::Index n) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (Eigen::Index col = 0; col < A.outerSize(); ++col) {
    const long c = index_of[static_cast<std::size_t>(col)];
    if (c < 0) continue;
    for (SparseMatrix::InnerIterator it(A, col); it; ++it) {
      const long r = index_of[static_cast<std::size_t>(it.row())];
      if (r >= 0) t.emplace_back(r, c, it.value());
    }
  }
  SparseMatrix S(n, n);
  S.setFromTriplets(t.begin(), t.end());
  S.makeCompressed();
  return S;
}

double column_residual(const Eigen::MatrixXd& rhs, const Eigen::MatrixXd& res) {
  double worst = 0;
  for (Eigen::Index k = 0; k < rhs.cols(); ++k) {
    const double b = rhs.col(k).norm();
    if (b > 0)
      worst = std::max(worst, res.col(k).norm() / b);
    else if (res.col(k).norm() > 0)
      worst = std::max(worst, res.col(k).norm());
  }
  return worst;
}

// LDLᵀ factors (ldlt, dense) of an exactly singular H_ff have a pivot at rounding level instead of a
// failure: below this reciprocal condition estimate the system is treated as singular (fallback).
// Pinned systems of real packings measured rcond ≥ 1e-6 (dense) and ≥ 1e-3 (CHOLMOD's estimate).
constexpr double kSingularRcond = 1e-14;

// U = A⁻¹ Ξ by a direct factorisation (`solve`), then at most `max_steps` iterative-refinement steps
// (a couple of cheap solves) while the residual exceeds `threshold`, each kept only if it lowers it.
template <class Solve>
Eigen::MatrixXd refined_solve(const SparseMatrix& Hf, const Eigen::MatrixXd& Xf, const Solve& solve, int max_steps,
                              double threshold, int& steps) {
  Eigen::MatrixXd Uf = solve(Xf);
  double res = column_residual(Xf, Xf - Hf * Uf);
  for (int step = 0; step < max_steps && res > threshold; ++step) {
    const Eigen::MatrixXd Unew = Uf + solve(Eigen::MatrixXd(Xf - Hf * Uf));
    const double rnew = column_residual(Xf, Xf - Hf * Unew);
    if (!(rnew < res)) break;
    Uf = Unew;
    res = rnew;
    ++steps;
  }
  return Uf;
}

// A saddle's response: none (NaN), method unstable, with the count of eigenvalues below −δ.
Eigen::MatrixXd no_response(const Stability& st, const SparseMatrix& Hf, const Eigen::MatrixXd& Xf,
                            KernelTreatment& k) {
  k.method = SolveMethod::unstable;
  k.unstable_modes = st.unstable_modes;
  return Eigen::MatrixXd::Constant(Hf.rows(), Xf.cols(), std::numeric_limits<double>::quiet_NaN());
}

// Fallback when the pinned system is singular (a mechanism beyond the pinned modes): LDLᵀ of
// H_ff + δ1 and the iteration u ← u + (H + δ)⁻¹(Ξ − H u) from u = 0, which converges to the solution
// without kernel component when Ξ ⊥ kernel. When H_ff has eigenvalues below −δ the packing is a
// saddle and has no linear response: method "unstable", their number in unstable_modes, U = NaN.
Eigen::MatrixXd regularised_refinement(const SparseMatrix& Hf, const Eigen::MatrixXd& Xf, const ModuliOptions& options,
                                       KernelTreatment& k) {
  k.method = SolveMethod::regularised_refinement;
  CholmodSolver ldl(Factorisation::ldlt);
  // The saddle test (stability.hpp), whose factor of H_ff + δ1 the iteration below uses.
  const Stability st = hessian_stability(Hf, options.regularisation, &ldl);
  if (!st.factored)
    throw NoResultError("elastic_response: no LDLᵀ factor of the regularised Hessian (zero pivot at column " +
                        std::to_string(st.failed_column) + "); try the dense or cg solver, or relax the packing first");
  k.regularisation = st.delta;
  k.rcond = ldl.rcond();
  if (!st.minimum()) return no_response(st, Hf, Xf, k);
  Eigen::MatrixXd Uf = Eigen::MatrixXd::Zero(Hf.rows(), Xf.cols());
  double res = 1.0, best = 1.0;
  int stall = 0;
  for (int step = 0; step < options.max_refinement_steps; ++step) {
    const Eigen::MatrixXd R = Xf - Hf * Uf;
    res = column_residual(Xf, R);
    if (res <= 0.01 * options.residual_tolerance) break;
    if (res < 0.9 * best) {
      best = res;
      stall = 0;
    } else if (++stall > 10) {
      break;
    }
    Uf += ldl.solve(R);
    ++k.refinement_steps;
  }
  return Uf;
}

// Preconditioned conjugate gradients on the SPD pinned system, column by column, to a relative
// residual cg_tolerance (Eigen's criterion: ‖Ξ − H u‖ ≤ tol ‖Ξ‖, the true residual of its recursion).
template <class Preconditioner>
Eigen::MatrixXd cg_solve(const SparseMatrix& Hf, const Eigen::MatrixXd& Xf, const ModuliOptions& options,
                         KernelTreatment& k) {
  Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper, Preconditioner> cg;
  cg.setTolerance(options.cg_tolerance);
  cg.setMaxIterations(options.cg_max_iterations > 0
                          ? options.cg_max_iterations
                          : static_cast<int>(std::min<Eigen::Index>(10 * Hf.rows(), 1 << 30)));
  cg.compute(Hf);
  if (cg.info() != Eigen::Success)
    throw NoResultError(
        "elastic_response: the conjugate-gradient preconditioner could not be built; try the diagonal "
        "preconditioner or a direct solver (ldlt, cholesky, dense)");
  Eigen::MatrixXd Uf = Eigen::MatrixXd::Zero(Hf.rows(), Xf.cols());
  for (Eigen::Index c = 0; c < Xf.cols(); ++c) {
    if (Xf.col(c).norm() == 0) continue;
    Uf.col(c) = cg.solve(Xf.col(c));
    k.iterations += static_cast<int>(cg.iterations());
  }
  return Uf;
}

}  // namespace

const char* to_string(ModuliSolver solver) {
  switch (solver) {
    case ModuliSolver::cholesky: return "cholesky";
    case ModuliSolver::ldlt: return "ldlt";
    case ModuliSolver::dense: return "dense";
    case ModuliSolver::cg: return "cg";
  }
  return "?";
}

const char* to_string(CgPreconditioner preconditioner) {
  switch (preconditioner) {
    case CgPreconditioner::incomplete_cholesky: return "ichol";
    case CgPreconditioner::diagonal: return "diagonal";
  }
  return "?";
}

ModuliSolver parse_moduli_solver(const std::string& text, const std::string& key) {
  if (text == "cholesky") return ModuliSolver::cholesky;
  if (text == "ldlt") return ModuliSolver::ldlt;
  if (text == "dense") return ModuliSolver::dense;
  if (text == "cg") return ModuliSolver::cg;
  throw InputError(key + ": must be cholesky, ldlt, dense or cg (got '" + text + "')");
}

CgPreconditioner parse_cg_preconditioner(const std::string& text, const std::string& key) {
  if (text == "ichol") return CgPreconditioner::incomplete_cholesky;
  if (text == "diagonal") return CgPreconditioner::diagonal;
  throw InputError(key + ": must be ichol or diagonal (got '" + text + "')");
}

Eigen::Matrix2d energy_stress(const Packing& p, const std::vector<Contact>& contacts) {
  Eigen::Matrix2d W = Eigen::Matrix2d::Zero();
  for (const Contact& c : contacts)
    W += c.force() * Eigen::Vector2d(c.nx, c.ny) * centroid_separation(p, c).transpose();
  return -W / (p.box.L * p.box.L);
}

Moduli moduli_from(const Response4& R) {
  Moduli m;
  m.B = 0.25 * (R(kXX, kXX) + R(kXX, kYY) + R(kYY, kXX) + R(kYY, kYY));
  m.G_simple = 0.5 * (R(kXY, kXY) + R(kYX, kXY));
  m.G_pure = 0.25 * (R(kXX, kXX) - R(kXX, kYY) - R(kYY, kXX) + R(kYY, kYY));
  m.G_mean = 0.5 * (m.G_simple + m.G_pure);
  return m;
}

namespace {

// ê(φ) = d mᵀ and its derivative dê/dφ = m mᵀ − d dᵀ (d' = m, m' = −d), as 4-vectors (xx, xy, yx, yy).
std::pair<Eigen::Vector4d, Eigen::Vector4d> simple_shear_direction(double phi) {
  const Eigen::Vector2d d(std::cos(phi), std::sin(phi)), m(-std::sin(phi), std::cos(phi));
  Eigen::Vector4d e, de;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      e[2 * a + b] = d[a] * m[b];
      de[2 * a + b] = m[a] * m[b] - d[a] * d[b];
    }
  return {e, de};
}

}  // namespace

double shear_modulus_along(const Response4& E, double phi) {
  const Eigen::Vector4d e = simple_shear_direction(phi).first;
  return e.dot(E * e);
}

ShearStability shear_stability(const Response4& E) {
  if (!E.allFinite()) {  // no relaxed response (a saddle): no direction is known to be stable
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return ShearStability{nan, nan, nan, nan, false};
  }
  // The extremum near the best grid point is the zero of G'(φ) = êᵀ(E + Eᵀ)ê' in the two grid
  // intervals around it (G is smooth and of degree 4: the grid resolves its extrema), found by
  // bisection: an extremum is flat, so G itself would locate it only to √ε.
  constexpr int kGrid = 720;
  constexpr double step = std::numbers::pi / kGrid;
  const Response4 Es = E + E.transpose();
  auto slope = [&](double phi) {
    const auto [e, de] = simple_shear_direction(phi);
    return e.dot(Es * de);
  };
  auto extremum = [&](double sign) {
    int best = 0;
    for (int k = 1; k < kGrid; ++k)
      if (sign * shear_modulus_along(E, k * step) < sign * shear_modulus_along(E, best * step)) best = k;
    double a = (best - 1) * step, b = (best + 1) * step;
    double phi = best * step;
    if (sign * slope(a) < 0 && sign * slope(b) > 0) {
      for (int it = 0; it < 200 && b - a > 1e-15; ++it) {
        const double c = 0.5 * (a + b);
        (sign * slope(c) < 0 ? a : b) = c;
      }
      phi = 0.5 * (a + b);
    }
    phi = std::fmod(phi + std::numbers::pi, std::numbers::pi);
    return std::pair{phi, shear_modulus_along(E, phi)};
  };
  ShearStability s;
  std::tie(s.phi_min, s.G_min) = extremum(1.0);
  std::tie(s.phi_max, s.G_max) = extremum(-1.0);
  s.stable = s.G_min > 0;
  return s;
}

const char* to_string(SolveMethod method) {
  switch (method) {
    case SolveMethod::no_contacts: return "none (no load-bearing contacts)";
    case SolveMethod::no_force_response: return "none (Ξ = 0)";
    case SolveMethod::cholesky: return "cholesky";
    case SolveMethod::ldlt: return "ldlt";
    case SolveMethod::dense: return "dense";
    case SolveMethod::cg_ichol: return "cg-ichol";
    case SolveMethod::cg_diagonal: return "cg-diagonal";
    case SolveMethod::regularised_refinement: return "regularised-refinement";
    case SolveMethod::unstable: return "unstable";
  }
  return "?";
}

Eigen::Matrix2d link_stress(const Packing& p, const std::vector<Contact>& contacts) {
  std::vector<Eigen::Vector2d> bud_force(p.size(), Eigen::Vector2d::Zero());
  for (const Contact& c : contacts) {
    const Eigen::Vector2d g = c.force() * Eigen::Vector2d(c.nx, c.ny);  // on lobe i, −g on lobe j
    if (is_bud(c.i)) bud_force[cell_of(c.i)] += g;
    if (is_bud(c.j)) bud_force[cell_of(c.j)] -= g;
  }
  Eigen::Matrix2d W = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Axis a = axis(p.theta(i));
    const Eigen::Vector2d n(a.c, a.s);
    const double s = lobe_offset(p, bud_lobe(i)) - lobe_offset(p, mother_lobe(i));
    const double load = -bud_force[i].dot(n);  // Λ_i
    W += s * load * n * n.transpose();
  }
  return -W / (p.box.L * p.box.L);
}

namespace {

// Counts of the network and the stresses at the state (all contacts).
PackingState describe(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net) {
  PackingState s;
  const double L = p.box.L, A = L * L;
  s.N = p.size();
  s.N_nr = net.N_nr;
  s.N_f = net.N_f;
  s.N_u = net.N_u;
  s.N_u_buds = net.N_u_buds;
  s.L = L;
  s.area = A;
  s.phi = p.packing_fraction();
  s.Z = net.Z;
  s.Z_iso = net.Z_iso;
  s.dZ = net.dZ;
  s.u = net.u;
  s.u_buds = net.u_buds;
  s.n = static_cast<double>(net.N_nr) / A;
  s.P = pressure(contacts, p.box);
  s.stress = stress_tensor(contacts, p.box);
  s.stress_energy = energy_stress(p, contacts);
  s.P_energy = -0.5 * s.stress_energy.trace();
  s.max_torque_imbalance = std::abs(s.stress_energy(0, 1) - s.stress_energy(1, 0));
  return s;
}

// Mean-field estimates (paper Eqs. 17–18, D4, D11) over the load-bearing contacts `lb`.
void add_mean_field(PackingState& s, const std::vector<Contact>& lb) {
  if (lb.empty()) return;
  double sr = 0, sr2 = 0, m4 = 0;
  for (const Contact& c : lb) {
    sr += c.r;
    sr2 += c.r * c.r;
    m4 += c.nx * c.nx * c.ny * c.ny;
  }
  const double m = static_cast<double>(lb.size());
  s.ell_c = sr / m;
  s.ell_c2_mean = sr2 / m;
  s.M4 = m4 / m;
  s.B_ext = s.n * kSpring * s.ell_c * s.ell_c * s.Z / 8.0;
  s.G_mf = s.n * kSpring * s.ell_c * s.ell_c * s.M4 * s.dZ / 2.0;
  s.G_mf_iso = s.n * kSpring * s.ell_c * s.ell_c * 0.125 * s.dZ / 2.0;
}

using KernelVector = std::vector<std::pair<Eigen::Index, double>>;  // sparse (dof, value) list

// The exact kernel directions of H that are pinned (fixed at 0): the two translations on the
// best-connected cell, the θ of every cell with exactly one contact-free lobe, and any dof with an
// exactly zero Hessian row. Fills the counts of `k` and returns the pinned flags and the kernel vectors.
std::pair<std::vector<bool>, std::vector<KernelVector>> pin_kernel(const Packing& p, const DofMap& map,
                                                                   const SparseMatrix& H,
                                                                   const std::vector<int>& lobe_count,
                                                                   KernelTreatment& k) {
  const Eigen::Index nr = map.size();
  std::vector<bool> pinned(static_cast<std::size_t>(nr), false);
  std::vector<KernelVector> kernel;
  std::size_t ref = 0;
  int best = -1;
  for (std::size_t c = 0; c < map.cells.size(); ++c) {
    const std::size_t i = map.cells[c];
    const int cnt = lobe_count[mother_lobe(i)] + lobe_count[bud_lobe(i)];
    if (cnt > best) {
      best = cnt;
      ref = c;
    }
  }
  k.reference_cell = map.cells[ref];
  pinned[3 * ref] = pinned[3 * ref + 1] = true;
  k.pinned_translation = 2;
  KernelVector tx, ty;
  for (Eigen::Index d = 0; d < nr; d += 3) {
    tx.emplace_back(d, 1.0);
    ty.emplace_back(d + 1, 1.0);
  }
  kernel.push_back(std::move(tx));
  kernel.push_back(std::move(ty));
  for (std::size_t c = 0; c < map.cells.size(); ++c) {
    const std::size_t i = map.cells[c];
    const int m = lobe_count[mother_lobe(i)], b = lobe_count[bud_lobe(i)];
    if ((m == 0) == (b == 0)) continue;
    // Rotation about the centre of the loaded lobe ℓ: δX = −s_ℓ ê⊥ δθ leaves every contact unchanged.
    const double s = lobe_offset(p, m > 0 ? mother_lobe(i) : bud_lobe(i));
    const Axis n = axis(p.theta(i));
    const auto b3 = static_cast<Eigen::Index>(3 * c);
    kernel.push_back({{b3, s * n.s}, {b3 + 1, -s * n.c}, {b3 + 2, 1.0}});
    if (!pinned[3 * c + 2]) {
      pinned[3 * c + 2] = true;
      ++k.pinned_lobe_rotation;
    }
  }
  std::vector<bool> nonzero(static_cast<std::size_t>(nr), false);
  for (Eigen::Index col = 0; col < H.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(H, col); it; ++it)
      if (it.value() != 0.0) nonzero[static_cast<std::size_t>(col)] = true;
  for (Eigen::Index d = 0; d < nr; ++d)
    if (!nonzero[d] && !pinned[d]) {
      pinned[d] = true;
      ++k.pinned_zero_rows;
      kernel.push_back({{d, 1.0}});
    }
  return {std::move(pinned), std::move(kernel)};
}

// max over the kernel vectors v of ‖H v‖ / ‖v‖: 0 to rounding at force balance, where each is an exact
// null direction of H; off balance (a packing written with rounded positions) the residual forces
// curve them.
double kernel_curvature(const std::vector<KernelVector>& kernel, const SparseMatrix& H) {
  double worst = 0;
  Eigen::VectorXd Hv = Eigen::VectorXd::Zero(H.rows());
  for (const auto& v : kernel) {
    double vv = 0;
    for (const auto& [d, a] : v) {
      for (SparseMatrix::InnerIterator it(H, d); it; ++it) Hv[it.row()] += a * it.value();  // H symmetric
      vv += a * a;
    }
    double hh = 0;
    for (const auto& [d, a] : v)
      for (SparseMatrix::InnerIterator it(H, d); it; ++it) {
        hh += Hv[it.row()] * Hv[it.row()];
        Hv[it.row()] = 0;  // each row once; the vector is zero again for the next v
      }
    worst = std::max(worst, std::sqrt(hh / vv));
  }
  return worst;
}

// max over strain columns and kernel vectors v of |vᵀΞ| / (‖v‖ ‖Ξ‖): Ξ must have no kernel component.
double kernel_component(const std::vector<KernelVector>& kernel, const Eigen::MatrixXd& Xi) {
  double worst = 0;
  for (int col = 0; col < Xi.cols(); ++col) {
    const double xn = Xi.col(col).norm();
    if (xn == 0) continue;
    for (const auto& v : kernel) {
      double dot = 0, vv = 0;
      for (const auto& [d, a] : v) {
        dot += a * Xi(d, col);
        vv += a * a;
      }
      worst = std::max(worst, std::abs(dot) / (std::sqrt(vv) * xn));
    }
  }
  return worst;
}

// H_ff U_f = Ξ_f with the chosen solver; a direct one falls back to regularised LDLᵀ with iterative
// refinement when H_ff is singular. Records the method and its diagnostics in `k`.
Eigen::MatrixXd solve_pinned(const SparseMatrix& Hf, const Eigen::MatrixXd& Xf, const ModuliOptions& options,
                             KernelTreatment& k) {
  const int steps = options.direct_refinement_steps;
  const double threshold = options.refinement_threshold;
  switch (options.solver) {
    case ModuliSolver::cholesky:
    case ModuliSolver::ldlt: {
      const bool llt = options.solver == ModuliSolver::cholesky;
      CholmodSolver f(llt ? Factorisation::llt : Factorisation::ldlt);
      // LLᵀ stops at the first non-positive pivot; LDLᵀ accepts any nonzero one, so it must also
      // show no negative pivot and no rounding-level one (an exactly singular system).
      const bool factored = f.factor(Hf);
      const double rcond = factored ? f.rcond() : 0.0;
      if (factored && (llt || (f.negative_pivots() == 0 && rcond > kSingularRcond))) {
        k.method = llt ? SolveMethod::cholesky : SolveMethod::ldlt;
        k.rcond = rcond;
        return refined_solve(
            Hf, Xf, [&](const Eigen::MatrixXd& b) { return f.solve(b); }, steps, threshold, k.refinement_steps);
      }
      k.cholesky_failed_column = f.failed_column();
      return regularised_refinement(Hf, Xf, options, k);
    }
    case ModuliSolver::dense: {
      // H_ff and its factor.
      require_dense_fits(static_cast<std::size_t>(Hf.rows()), 2, "moduli: the dense solver",
                         "a sparse one (--solver ldlt)");
      const Eigen::LDLT<Eigen::MatrixXd> ldl{Eigen::MatrixXd(Hf)};
      const bool factored = ldl.info() == Eigen::Success && ldl.vectorD().minCoeff() > 0;
      const double rcond = factored ? ldl.rcond() : 0.0;
      if (factored && rcond > kSingularRcond) {
        k.method = SolveMethod::dense;
        k.rcond = rcond;
        return refined_solve(
            Hf, Xf, [&](const Eigen::MatrixXd& b) { return Eigen::MatrixXd(ldl.solve(b)); }, steps, threshold,
            k.refinement_steps);
      }
      return regularised_refinement(Hf, Xf, options, k);
    }
    case ModuliSolver::cg: {
      if (!(options.cg_tolerance > 0 && options.cg_tolerance < 1))
        throw std::invalid_argument("elastic_response: cg_tolerance must lie in (0, 1)");
      // CG converges on an indefinite H, and on one singular to the Hessian's resolution (a mechanism
      // held by prestress below δ) to a response those modes decide. The direct solvers' test of the
      // factor decides here too, and such a system takes their regularised path (the saddle test,
      // then refinement that converges only without load on the soft modes): every solver tells a
      // saddle or an unresolved mechanism alike.
      CholmodSolver f(Factorisation::ldlt);
      if (!(f.factor(Hf) && f.negative_pivots() == 0 && f.rcond() > kSingularRcond)) {
        k.cholesky_failed_column = f.failed_column();
        return regularised_refinement(Hf, Xf, options, k);
      }
      k.solver_tolerance = options.cg_tolerance;
      if (options.cg_preconditioner == CgPreconditioner::incomplete_cholesky) {
        k.method = SolveMethod::cg_ichol;
        return cg_solve<Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>(Hf, Xf, options, k);
      }
      k.method = SolveMethod::cg_diagonal;
      return cg_solve<Eigen::DiagonalPreconditioner<double>>(Hf, Xf, options, k);
    }
  }
  throw std::invalid_argument("elastic_response: unknown solver");
}

// Slopes of both stresses along the relaxed path (U = du/de) and the affine one (U = 0).
// Each stress is −W/A(e) with W = Σ_c g ⊗ v, g = f n (dg = −K dd), v = d (contact virial S) or
// v = C (energy stress τ); A(e) = A det(1 + e) gives the −Σ_αβ δ_γδ area term.
struct StressSlopes {
  Response4 R, R_affine, R_energy, R_energy_affine;
  Eigen::Matrix2d tau;  // τ over the load-bearing contacts
};

StressSlopes stress_slopes(const std::vector<ContactResponseTerms>& terms, const Eigen::MatrixXd& U, double A) {
  Response4 dW = Response4::Zero(), dW_aff = Response4::Zero(), dWm = Response4::Zero(), dWm_aff = Response4::Zero();
  Eigen::Matrix2d W = Eigen::Matrix2d::Zero(), Wm = Eigen::Matrix2d::Zero();
  for (const ContactResponseTerms& t : terms) {
    Eigen::Matrix<double, 6, 4> Uc;
    Uc.topRows<3>() = U.middleRows(3 * t.bi, 3);
    Uc.bottomRows<3>() = U.middleRows(3 * t.bj, 3);
    const Eigen::Matrix<double, 2, 4> dd = t.D + t.J * Uc;
    const Eigen::Matrix<double, 2, 4> dC = t.D + Uc.topRows<2>() - Uc.middleRows<2>(3);
    const Eigen::Matrix<double, 2, 4> Kdd = t.K * dd, KD = t.K * t.D;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        const int row = 2 * a + b;
        // w = g ⊗ v, dg = −K dd: dw_ab = −(K dd)_a v_b + g_a dv_b
        dW.row(row) += -Kdd.row(a) * t.d[b] + t.g[a] * dd.row(b);
        dW_aff.row(row) += -KD.row(a) * t.d[b] + t.g[a] * t.D.row(b);
        dWm.row(row) += -Kdd.row(a) * t.C[b] + t.g[a] * dC.row(b);
        dWm_aff.row(row) += -KD.row(a) * t.C[b] + t.g[a] * t.D.row(b);
      }
    W += t.g * t.d.transpose();
    Wm += t.g * t.C.transpose();
  }
  const Eigen::Matrix2d S = -W / A, T = -Wm / A;
  // d stress_ab/de_gd = −(1/A) dW_ab/de_gd − stress_ab δ_gd
  auto to_response = [&](const Response4& dw, const Eigen::Matrix2d& s) {
    Response4 R = -dw / A;
    for (int row = 0; row < 4; ++row) {
      R(row, kXX) -= s(row / 2, row % 2);
      R(row, kYY) -= s(row / 2, row % 2);
    }
    return R;
  };
  return {to_response(dW, S), to_response(dW_aff, S), to_response(dWm, T), to_response(dWm_aff, T), T};
}

// Lagrangian-strain stiffness C_abgd = E_abgd − δ_ag τ_bd, Voigt (xx, yy, xy).
Eigen::Matrix3d lagrangian_stiffness(const Response4& E, const Eigen::Matrix2d& tau) {
  Response4 C = E;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int d = 0; d < 2; ++d) C(2 * a + b, 2 * a + d) -= tau(b, d);
  const int v[3] = {kXX, kYY, kXY};
  Eigen::Matrix3d c;
  for (int r = 0; r < 3; ++r)
    for (int s = 0; s < 3; ++s) c(r, s) = C(v[r], v[s]);
  return Eigen::Matrix3d(0.5 * (c + c.transpose()));
}

}  // namespace

ResponseProblem response_problem(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net) {
  if (net.rattler.size() != p.size())
    throw std::invalid_argument("elastic_response: the contact network is not that of this packing (" +
                                std::to_string(net.rattler.size()) + " cells vs " + std::to_string(p.size()) + ")");
  ResponseProblem pr;
  pr.state = describe(p, contacts, net);
  const std::vector<Contact> lb = load_bearing(contacts, net);
  add_mean_field(pr.state, lb);
  pr.state.contacts = lb.size();
  const DofMap map = non_rattler_dofs(net);
  const Eigen::Index nr = map.size();
  pr.kernel.dofs = static_cast<std::size_t>(nr);
  if (nr == 0 || lb.empty()) return pr;  // method no_contacts

  // Hessian of the non-rattlers from their contacts, force response Ξ, Born term.
  pr.H = restrict_matrix(hessian(p, lb), map);
  pr.Xi = Eigen::MatrixXd::Zero(nr, 4);
  pr.terms.reserve(lb.size());
  std::vector<int> lobe_count(2 * p.size(), 0);
  for (const Contact& c : lb) {
    pr.terms.push_back(terms_of(p, c, map));
    const ContactResponseTerms& t = pr.terms.back();
    const Eigen::Matrix<double, 6, 4> x = -t.J.transpose() * t.K * t.D;
    pr.Xi.middleRows(3 * t.bi, 3) += x.topRows<3>();
    pr.Xi.middleRows(3 * t.bj, 3) += x.bottomRows<3>();
    pr.born += t.D.transpose() * t.K * t.D;
    ++lobe_count[c.i];
    ++lobe_count[c.j];
  }
  std::vector<KernelVector> kernel;
  std::tie(pr.pinned, kernel) = pin_kernel(p, map, pr.H, lobe_count, pr.kernel);
  pr.kernel.kernel_component = kernel_component(kernel, pr.Xi);
  pr.kernel_curvature = kernel_curvature(kernel, pr.H);
  return pr;
}

Relaxation relax(const ResponseProblem& pr, const ModuliOptions& options) {
  Relaxation r;
  r.kernel = pr.kernel;
  if (pr.terms.empty()) return r;
  const Eigen::Index nr = pr.H.rows();
  std::vector<long> free_index(static_cast<std::size_t>(nr), -1);
  long nf = 0;
  for (Eigen::Index d = 0; d < nr; ++d)
    if (!pr.pinned[d]) free_index[d] = nf++;
  const SparseMatrix Hf = select(pr.H, free_index, nf);
  Eigen::MatrixXd Xf(nf, 4);
  for (Eigen::Index d = 0; d < nr; ++d)
    if (free_index[d] >= 0) Xf.row(free_index[d]) = pr.Xi.row(d);

  // Pinning exact null directions of H keeps its inertia, so the solve's own test of H_ff decides as
  // the test of H itself (`budjam dos`'s) would. Off force balance (a packing written with rounded
  // positions) those directions curve by more than δ, and then H itself is tested first: one
  // verdict and one count of unstable modes for both commands.
  Stability full;
  if (const double delta = options.regularisation * pr.H.diagonal().cwiseAbs().maxCoeff(); pr.kernel_curvature > delta)
    full = hessian_stability(pr.H, options.regularisation);
  Eigen::MatrixXd Uf = Eigen::MatrixXd::Zero(nf, 4);
  if (full.factored && !full.minimum()) {
    r.kernel.regularisation = full.delta;
    Uf = no_response(full, Hf, Xf, r.kernel);
  } else if (nf > 0 && Xf.norm() > 0) {
    Uf = solve_pinned(Hf, Xf, options, r.kernel);
  } else {
    r.kernel.method = SolveMethod::no_force_response;
  }
  r.U = Eigen::MatrixXd::Zero(nr, 4);
  for (Eigen::Index d = 0; d < nr; ++d)
    if (free_index[d] >= 0) r.U.row(d) = Uf.row(free_index[d]);

  r.kernel.residual = r.kernel.unstable_modes == 0 ? column_residual(pr.Xi, pr.Xi - pr.H * r.U)
                                                   : std::numeric_limits<double>::quiet_NaN();
  // An iterative solve is verified against the tolerance it was asked for (its residual is that large
  // by design); a direct one against residual_tolerance.
  const double tolerance = options.solver == ModuliSolver::cg && r.kernel.solver_tolerance > 0
                               ? std::max(options.residual_tolerance, 10 * options.cg_tolerance)
                               : options.residual_tolerance;
  r.kernel.well_posed = std::isfinite(r.kernel.residual) && r.kernel.residual <= tolerance;
  return r;
}

ElasticResponse elastic_response(const ResponseProblem& pr, const Relaxation& relaxation) {
  ElasticResponse out;
  static_cast<PackingState&>(out) = pr.state;
  out.kernel = relaxation.kernel;
  out.stationary = out.kernel.unstable_modes > 0 ? StationaryPoint::saddle : StationaryPoint::minimum;
  if (pr.terms.empty()) return out;
  const double A = out.area;
  // Energy expansion: E = (Born − Ξᵀ du/de)/A along the relaxed path.
  out.E_affine = pr.born / A;
  out.E = (pr.born - pr.Xi.transpose() * relaxation.U) / A;
  out.E = 0.5 * (out.E + out.E.transpose()).eval();
  const StressSlopes slopes = stress_slopes(pr.terms, relaxation.U, A);
  out.R = slopes.R;
  out.R_affine = slopes.R_affine;
  out.R_energy = slopes.R_energy;
  out.R_energy_affine = slopes.R_energy_affine;
  out.C = lagrangian_stiffness(out.E, slopes.tau);
  out.C_affine = lagrangian_stiffness(out.E_affine, slopes.tau);

  out.moduli = moduli_from(out.R);
  out.moduli_affine = moduli_from(out.R_affine);
  out.moduli_energy = moduli_from(out.R_energy);
  out.moduli_energy_affine = moduli_from(out.R_energy_affine);
  out.shear = shear_stability(out.E);
  out.shear_stress = shear_stability(out.R);
  return out;
}

void require_relaxed_moduli(const ElasticResponse& e, const std::string& what) {
  if (e.N_nr == 0 || e.contacts == 0)
    throw NoResultError(what + " is not jammed: all " + std::to_string(e.N) +
                        " cells are rattlers (N_nr = 0), so it has no rigid backbone and no elastic moduli; "
                        "moduli need a jammed, relaxed packing such as a run's packings/jammed.pack");
  if (!e.linear_response()) return;
  const bool finite = std::isfinite(e.B()) && std::isfinite(e.G()) && std::isfinite(e.B_energy()) &&
                      std::isfinite(e.G_energy()) && e.R.allFinite() && e.E.allFinite();
  if (!finite || !e.kernel.well_posed) {
    char residual[32];
    std::snprintf(residual, sizeof residual, "%.3g", e.kernel.residual);
    const std::string diagnosis = "(solver " + std::string(to_string(e.kernel.method)) + ", relative residual " +
                                  residual + (finite ? "" : ", moduli not finite") + ")";
    // Every solver takes the regularised path when the factor is singular to the Hessian's resolution.
    if (e.kernel.method == SolveMethod::regularised_refinement)
      throw NoResultError(what +
                          ": no resolved linear response: the non-rattler Hessian is singular to its resolution and "
                          "the strain loads its soft modes (a mechanism held only by prestress below the "
                          "regularisation, as at or below the jamming point) " +
                          diagnosis +
                          "; every solver gives this; relax the packing to force balance first, or take one "
                          "at a larger pressure");
    throw NoResultError(what + ": the linear response did not converge " + diagnosis +
                        "; try another of the solvers ldlt, cholesky, dense and cg, or relax the packing to force "
                        "balance first");
  }
}

ElasticResponse elastic_response(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 const ModuliOptions& options) {
  const ResponseProblem problem = response_problem(p, contacts, net);
  ElasticResponse e = elastic_response(problem, relax(problem, options));
  e.stationary = stationary_point(p, contacts, net, e.kernel.unstable_modes);
  return e;
}

}  // namespace budjam
