// The vibrational spectrum: mass matrix, dense and ARPACK solvers, and the spectral counts
// (paper appendix "Vibrational density of states"; docs/spectrum.md).
#include "budjam/spectrum.hpp"

#include "budjam/energy.hpp"
#include "budjam/errors.hpp"
#include "budjam/hessian.hpp"
#include "budjam/rigidity.hpp"
#include "compressed_packing.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <sys/wait.h>
#include <unistd.h>
#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>

using namespace budjam;

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// Kinetic energy of the lobes of cell i moving with generalised velocity qdot: translation of
// each lobe's centre (from finite differences of the lobe placement) plus each disk's spin
// ½ (m R²/2) θ̇². Independent of the mass matrix.
double lobe_kinetic_energy(const Packing& p, std::size_t i, const Eigen::Vector3d& qdot) {
  const double h = 1e-6;
  Packing plus = p, minus = p;
  plus.q.segment<3>(3 * i) += h * qdot;
  minus.q.segment<3>(3 * i) -= h * qdot;
  Lobes lp, lm;
  place_lobes(plus, lp);
  place_lobes(minus, lm);
  double T = 0;
  for (std::size_t lobe : {mother_lobe(i), bud_lobe(i)}) {
    const double R = lp.R[lobe];
    const double m = R * R / 0.25;  // areal density: mother (R = 1/2) has mass 1
    const double vx = (lp.x[lobe] - lm.x[lobe]) / (2 * h), vy = (lp.y[lobe] - lm.y[lobe]) / (2 * h);
    T += 0.5 * m * (vx * vx + vy * vy) + 0.5 * (0.5 * m * R * R) * qdot[2] * qdot[2];
  }
  return T;
}

// Adds a spring k (q_a − q_b)²/2 to a triplet list.
void spring(std::vector<Eigen::Triplet<double>>& t, int a, int b, double k) {
  t.emplace_back(a, a, k);
  t.emplace_back(b, b, k);
  t.emplace_back(a, b, -k);
  t.emplace_back(b, a, -k);
}

}  // namespace

TEST_CASE("the mass matrix reproduces the kinetic energy of the two moving disks", "[spectrum][mass]") {
  Packing p;
  p.box.L = 10;
  p.add_cell(1.0, 2.0, 0.3, 0.01, 0.002, -1);
  p.add_cell(4.0, 5.0, -2.0, 0.6, 0.002, -1);
  p.add_cell(7.0, 1.0, 2.9, 1.02, 0.002, -1);
  const Eigen::VectorXd M = mass_diagonal(p);
  REQUIRE(M.size() == 9);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Vector3d v(g(rng), g(rng), g(rng));
      // ½ q̇ᵀ M q̇ with diagonal M: no translation–rotation cross term because (x, y) is the
      // centre of mass at uniform areal density.
      const double T_matrix = 0.5 * (M.segment<3>(3 * i).array() * v.array().square()).sum();
      CHECK(T_matrix == Approx(lobe_kinetic_energy(p, i, v)).epsilon(1e-8));
    }
}

TEST_CASE("a single dumbbell's moment of inertia equals the area integral of r² at unit areal density",
          "[spectrum][mass]") {
  // Free rotation about the centroid: I = ∫ ρ r² dA over both disks, ρ = 1/(π/4) (mother mass 1).
  for (double b : {0.01, 0.5, 1.02}) {
    Packing p;
    p.box.L = 10;
    p.add_cell(0.0, 0.0, 0.0, b, 0.002, -1);
    const Dumbbell d = p.dumbbell(0);
    const double rho = 4.0 / std::numbers::pi;
    // Midpoint rule on each disk in polar coordinates about its own centre (exact in angle for
    // r² integrands up to rounding), r² = (c + ρ cos φ)² + (ρ sin φ)² with c the lobe offset.
    auto disk = [&](double c, double R) {
      const int nr = 2000;
      double I = 0;
      for (int k = 0; k < nr; ++k) {
        const double r = (k + 0.5) * R / nr;
        // ∫₀^{2π} (c² + 2 c r cos φ + r²) dφ = 2π (c² + r²)
        I += 2 * std::numbers::pi * (c * c + r * r) * r * (R / nr);
      }
      return rho * I;
    };
    const double I_integral = disk(d.mother_offset, 0.5) + disk(d.bud_offset, 0.5 * b);
    const Eigen::VectorXd M = mass_diagonal(p);
    CHECK(M[0] == Approx(1 + b * b).epsilon(1e-14));
    CHECK(M[1] == M[0]);
    CHECK(M[2] == Approx(I_integral).epsilon(1e-6));
  }
}

TEST_CASE("two springs between two cells give ω² = k (1/m1 + 1/m2) and κ (1/I1 + 1/I2)", "[spectrum][mass]") {
  // A hand-made harmonic system: spring k between x1 and x2, torsion spring κ between θ1 and θ2,
  // y free. Removing the two translations leaves the relative y motion and the common rotation
  // θ1 = θ2 at zero, and the two relative coordinates at k(1/m1 + 1/m2) and κ(1/I1 + 1/I2):
  // the translational mass and the moment of inertia both enter as in M.
  Packing p;
  p.box.L = 10;
  p.add_cell(1, 1, 0.4, 0.3, 0.002, -1);
  p.add_cell(3, 3, 1.9, 0.95, 0.002, -1);
  const Eigen::VectorXd M = mass_diagonal(p);
  const double k = 1.3, kappa = 0.7;
  std::vector<Eigen::Triplet<double>> t;
  spring(t, 0, 3, k);
  spring(t, 2, 5, kappa);
  Sparse H(6, 6);
  H.setFromTriplets(t.begin(), t.end());
  SpectrumOptions opt;
  opt.method = SpectrumMethod::dense;
  const Spectrum s = solve_spectrum(H, M, opt);
  REQUIRE(s.n_dof == 4);
  REQUIRE(s.lambda.size() == 4);
  std::vector<double> expected = {0.0, 0.0, k * (1 / M[0] + 1 / M[3]), kappa * (1 / M[2] + 1 / M[5])};
  std::sort(expected.begin(), expected.end());
  for (int n = 0; n < 4; ++n) CHECK(s.lambda[n] == Approx(expected[n]).margin(1e-14).epsilon(1e-13));
  CHECK(s.translation_residual < 1e-15);
  // Modes are orthonormal and orthogonal to the mass-weighted translations.
  CHECK((s.modes.transpose() * s.modes - Eigen::MatrixXd::Identity(4, 4)).cwiseAbs().maxCoeff() < 1e-13);
  Eigen::VectorXd tx = Eigen::VectorXd::Zero(6);
  tx[0] = std::sqrt(M[0]);
  tx[3] = std::sqrt(M[3]);
  CHECK((s.modes.transpose() * tx).cwiseAbs().maxCoeff() < 1e-13);
  // Each mode solves H v = λ M v with v = M^{-1/2} e.
  for (int n = 0; n < 4; ++n) {
    const Eigen::VectorXd v = s.modes.col(n).cwiseQuotient(M.cwiseSqrt());
    CHECK((H * v - s.lambda[n] * M.cwiseProduct(v)).norm() < 1e-13);
  }
}

TEST_CASE("dense and ARPACK reproduce the phonons of a ring of cells", "[spectrum][arpack]") {
  // n identical cells on a ring, nearest-neighbour springs kx on x, ky on y and κ on θ:
  // ω² = 2 k_α/m_α (1 − cos(2πj/n)), j = 0 … n−1 for each of x, y, θ. The two j = 0 modes of x
  // and y are the translations (removed); the j = 0 θ mode (common rotation) is a true zero mode.
  const int n = 150;
  const double kx = 1.0, ky = 0.37, kappa = 0.11;
  Packing p;
  p.box.L = 200;
  for (int i = 0; i < n; ++i) p.add_cell(i, 0, 0.0, 0.7, 0.002, -1);
  const Eigen::VectorXd M = mass_diagonal(p);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    spring(t, 3 * i, 3 * j, kx);
    spring(t, 3 * i + 1, 3 * j + 1, ky);
    spring(t, 3 * i + 2, 3 * j + 2, kappa);
  }
  Sparse H(3 * n, 3 * n);
  H.setFromTriplets(t.begin(), t.end());
  std::vector<double> exact;
  for (int j = 0; j < n; ++j) {
    const double c = 1 - std::cos(2 * std::numbers::pi * j / n);
    if (j > 0) exact.push_back(2 * kx / M[0] * c);
    if (j > 0) exact.push_back(2 * ky / M[1] * c);
    exact.push_back(2 * kappa / M[2] * c);
  }
  std::sort(exact.begin(), exact.end());
  REQUIRE(exact.size() == static_cast<std::size_t>(3 * n - 2));

  SpectrumOptions opt;
  opt.method = SpectrumMethod::dense;
  const Spectrum dense = solve_spectrum(H, M, opt);
  REQUIRE(dense.complete());
  for (int k = 0; k < 3 * n - 2; ++k) CHECK(dense.lambda[k] == Approx(exact[k]).margin(1e-13).epsilon(1e-11));

  opt.method = SpectrumMethod::arpack;
  opt.modes = 40;
  const Spectrum lanczos = solve_spectrum(H, M, opt);
  REQUIRE(lanczos.method == SpectrumMethod::arpack);
  REQUIRE(lanczos.lambda.size() == 40);
  // The ring's modes come in degenerate pairs (j, n − j): a single-vector Lanczos finds both
  // copies only through rounding, which ARPACK's restarts and locking exploit.
  for (int k = 0; k < 40; ++k) CHECK(lanczos.lambda[k] == Approx(exact[k]).margin(1e-13).epsilon(1e-11));
}

// ---- arrested packings ---------------------------------------------------------------------

namespace {

// FIRE-compressed random dumbbells just above jamming (tests/support/compressed_packing.hpp),
// built once per (n, seed) and shared by the test cases.
const testing::CompressedPacking& compressed(std::size_t n, std::uint64_t seed) {
  static std::map<std::pair<std::size_t, std::uint64_t>, testing::CompressedPacking> cache;
  auto it = cache.find({n, seed});
  if (it == cache.end()) it = cache.emplace(std::make_pair(n, seed), testing::compress_random_dumbbells(n, seed)).first;
  return it->second;
}

// Rigid rotation of cell i about the centre of the lobe that is not `free_lobe`: the zero mode
// an unconstrained lobe leaves (all contacts act on the other lobe, through its centre). In the
// reduced layout of `cells`, mass-weighted, unit norm.
Eigen::VectorXd pivot_mode(const Packing& p, const std::vector<std::size_t>& cells, std::size_t k,
                           std::size_t free_lobe, const Eigen::VectorXd& mass) {
  const std::size_t i = cells[k];
  const Dumbbell d = p.dumbbell(i);
  // centroid − pivot, along n̂: +mother_offset if the pivot is the mother, −bud_offset if the bud.
  const double arm = is_bud(free_lobe) ? d.mother_offset : -d.bud_offset;
  const double rx = arm * std::cos(p.theta(i)), ry = arm * std::sin(p.theta(i));
  Eigen::VectorXd v = Eigen::VectorXd::Zero(mass.size());
  v[3 * k] = -ry;  // δ(centroid) = δθ ẑ × (centroid − pivot)
  v[3 * k + 1] = rx;
  v[3 * k + 2] = 1;
  v = v.cwiseProduct(mass.cwiseSqrt());
  return v.normalized();
}

}  // namespace

TEST_CASE("dense and ARPACK eigenvalues of a 300-cell packing agree to 1e-8 relative", "[spectrum][arpack]") {
  const auto& cp = compressed(300, 11);
  REQUIRE(cp.network.N_nr > 250);
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  SpectrumOptions opt;
  opt.method = SpectrumMethod::dense;
  const Spectrum dense = solve_spectrum(prob.H, prob.mass, opt);
  const std::size_t n_zero = count_below(dense.lambda, 1e-6);
  REQUIRE(n_zero > 30);
  const double scale = dense.lambda.cwiseAbs().maxCoeff();

  // Both solvers are backward stable: eigenvalues agree to ~ε‖K‖ in absolute terms, which for the
  // band (λ ≳ 1e-4) is far inside 1e-8 relative; the quasi-zero modes (|λ| ~ 1e-14) can only be
  // compared in absolute terms.
  auto compare = [&](const Spectrum& lanczos) {
    REQUIRE(lanczos.has_vectors());
    for (Eigen::Index k = 0; k < lanczos.lambda.size(); ++k) {
      if (dense.lambda[k] > 1e-6)
        CHECK(std::abs(lanczos.lambda[k] - dense.lambda[k]) <= 1e-8 * dense.lambda[k]);
      else
        CHECK(std::abs(lanczos.lambda[k] - dense.lambda[k]) <= 1e-12 * scale);
    }
    // Non-degenerate band modes are the same vectors up to sign.
    for (Eigen::Index k = static_cast<Eigen::Index>(n_zero); k < lanczos.lambda.size(); ++k) {
      const double gap = std::min(dense.lambda[k] - dense.lambda[k - 1], dense.lambda[k + 1] - dense.lambda[k]);
      if (gap < 1e-3 * dense.lambda[k]) continue;
      CHECK(std::abs(dense.modes.col(k).dot(lanczos.mode(k))) == Approx(1.0).epsilon(1e-8));
    }
    CHECK(lanczos.sigma < 0);
    CHECK(lanczos.translation_residual < 1e-12);
  };

  SECTION("with the cell-local zero modes deflated (default)") {
    opt.method = SpectrumMethod::arpack;
    opt.modes = 60;
    const Spectrum lanczos = solve_spectrum(prob.H, prob.mass, opt);
    // The deflated modes are exactly the unconstrained lobes'; the rest of the quasi-zero modes
    // and 60 more come from Lanczos; the inertia count covers them all.
    CHECK(lanczos.local.size() == cp.network.N_u);
    CHECK(lanczos.inertia_count == static_cast<long>(n_zero));
    REQUIRE(lanczos.lambda.size() >= static_cast<Eigen::Index>(cp.network.N_u + 60));
    CHECK(count_below(lanczos.lambda, 1e-6) == n_zero);
    compare(lanczos);
  }
  SECTION("without deflation, asking for all quasi-zero modes and 60 more") {
    opt.method = SpectrumMethod::arpack;
    opt.deflate_local = false;
    opt.modes = static_cast<int>(n_zero) + 60;
    const Spectrum lanczos = solve_spectrum(prob.H, prob.mass, opt);
    CHECK(lanczos.local.empty());
    REQUIRE(lanczos.lambda.size() == opt.modes);
    compare(lanczos);
  }
  SECTION("fewer modes than the zero cluster still returns the whole cluster") {
    opt.method = SpectrumMethod::arpack;
    opt.modes = 10;
    const Spectrum lanczos = solve_spectrum(prob.H, prob.mass, opt);
    CHECK(count_below(lanczos.lambda, 1e-6) == n_zero);
    CHECK(lanczos.lambda.size() >= static_cast<Eigen::Index>(n_zero) + 1);
    compare(lanczos);
  }
}

TEST_CASE("the cell-local zero modes of a packing are the rotations about the contacted lobe of its free lobes",
          "[spectrum]") {
  const auto& cp = compressed(150, 3);
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  const std::vector<LocalMode> local = cell_local_zero_modes(prob.H, prob.mass);
  REQUIRE(local.size() == cp.network.N_u);
  for (const LocalMode& m : local) {
    const std::size_t cell = prob.cells[m.block];
    const bool bud_free = cp.network.lobe_contacts[bud_lobe(cell)] == 0;
    REQUIRE((bud_free || cp.network.lobe_contacts[mother_lobe(cell)] == 0));
    const Eigen::VectorXd pivot =
        pivot_mode(cp.packing, prob.cells, m.block, bud_free ? bud_lobe(cell) : mother_lobe(cell), prob.mass);
    CHECK(std::abs(pivot.segment<3>(3 * static_cast<Eigen::Index>(m.block)).dot(m.e)) == Approx(1.0).epsilon(1e-9));
  }
}

TEST_CASE("modes of a packing solve H v = ω² M v and carry no translation", "[spectrum]") {
  const auto& cp = compressed(150, 5);
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  REQUIRE(prob.cells.size() == cp.network.N_nr);
  for (std::size_t k = 0; k < prob.cells.size(); ++k) CHECK(!cp.network.rattler[prob.cells[k]]);
  SpectrumOptions opt;
  opt.method = SpectrumMethod::dense;
  const Spectrum s = solve_spectrum(prob.H, prob.mass, opt);
  REQUIRE(s.n_dof == 3 * prob.cells.size() - 2);
  REQUIRE(s.complete());
  const double scale = s.lambda.cwiseAbs().maxCoeff();
  const Eigen::VectorXd sqm = prob.mass.cwiseSqrt();
  Eigen::VectorXd tx = Eigen::VectorXd::Zero(prob.mass.size()), ty = tx;
  for (Eigen::Index a = 0; a < tx.size(); a += 3) {
    tx[a] = sqm[a];
    ty[a + 1] = sqm[a + 1];
  }
  double worst_residual = 0, worst_translation = 0;
  for (Eigen::Index n = 0; n < s.lambda.size(); ++n) {
    const Eigen::VectorXd v = s.modes.col(n).cwiseQuotient(sqm);  // physical displacement
    worst_residual = std::max(worst_residual, (prob.H * v - s.lambda[n] * prob.mass.cwiseProduct(v)).norm() /
                                                  std::sqrt(v.dot(prob.mass.cwiseProduct(v))));
    worst_translation = std::max({worst_translation, std::abs(s.modes.col(n).dot(tx)) / tx.norm(),
                                  std::abs(s.modes.col(n).dot(ty)) / ty.norm()});
  }
  CHECK(worst_residual < 1e-12 * scale);
  CHECK(worst_translation < 1e-12);
  // The Hessian of a pair potential is translation invariant to rounding.
  CHECK(s.translation_residual < 1e-13);
  // An arrested packing is at an energy minimum: no eigenvalue below −rounding.
  CHECK(s.lambda[0] > -1e-11 * scale);
}

TEST_CASE("quasi-zero modes, pebble-game floppy modes and unconstrained lobes agree on arrested packings",
          "[spectrum][rigidity]") {
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto& cp = compressed(150, seed);
    const auto& net = cp.network;
    const PackingSpectrum ps = packing_spectrum(cp.packing, cp.contacts, net);
    REQUIRE(ps.spectrum.method == SpectrumMethod::dense);
    const SpectralSummary& m = ps.summary;
    Lobes lobes;
    place_lobes(cp.packing, lobes);
    const RigidityState rig = analyse_rigidity(cp.packing, lobes, cp.contacts, net);
    INFO("seed " << seed << ": N_zero " << m.N_zero << ", floppy " << rig.floppy_plane << ", N_u " << net.N_u);
    // (1) Robust: the same count over three decades of the cutoff (a wide spectral gap).
    for (const auto& [tol, count] : m.zero_counts) CHECK(count == m.N_zero);
    // (2) Spectrum and pebble game count the same floppy modes. Above jamming the backbone spans
    // the box with a self-stress, so the periodic framework loses the plane's rotation too and
    // floppy_plane = F − 3 is its count of non-trivial motions (docs/rigidity.md).
    CHECK(static_cast<long>(m.N_zero) == rig.floppy_plane);
    // (3) Each contact-free lobe of a non-rattler leaves one zero mode; other floppy motions
    // are rare.
    CHECK(m.N_zero >= net.N_u);
    CHECK(m.N_zero <= net.N_u + 2);
    // (4) Sylvester's inertia gives the same count without an eigensolver.
    const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, net);
    CHECK(count_below_by_inertia(prob.H, prob.mass, 1e-6) == static_cast<long>(m.N_zero));
    // (5) The analytic unconstrained-lobe modes (rotation about the contacted lobe) lie in the
    // quasi-zero space plus the two translations.
    Eigen::MatrixXd Z(prob.mass.size(), m.N_zero + 2);
    Z.leftCols(m.N_zero) = ps.spectrum.modes.leftCols(m.N_zero);
    Z.col(m.N_zero).setZero();
    Z.col(m.N_zero + 1).setZero();
    for (Eigen::Index a = 0; a < prob.mass.size(); a += 3) {
      Z(a, m.N_zero) = std::sqrt(prob.mass[a]);
      Z(a + 1, m.N_zero + 1) = std::sqrt(prob.mass[a + 1]);
    }
    Z.col(m.N_zero).normalize();
    Z.col(m.N_zero + 1).normalize();
    std::size_t checked = 0;
    for (std::size_t k = 0; k < prob.cells.size(); ++k)
      for (std::size_t lobe : {mother_lobe(prob.cells[k]), bud_lobe(prob.cells[k])}) {
        if (net.lobe_contacts[lobe] != 0) continue;
        const Eigen::VectorXd v = pivot_mode(cp.packing, prob.cells, k, lobe, prob.mass);
        CHECK((Z.transpose() * v).norm() == Approx(1.0).epsilon(1e-9));
        ++checked;
      }
    CHECK(checked == net.N_u);
    // (6) The band lies well above the cutoff and gives a finite ω*.
    REQUIRE(m.band.available);
    CHECK(ps.spectrum.lambda[m.N_zero] > 1e-5);
    CHECK(m.band.omega_star > 0);
  }
}

TEST_CASE("the quasi-zero modes are localised, the band is extended", "[spectrum]") {
  const auto& cp = compressed(150, 2);
  const PackingSpectrum ps = packing_spectrum(cp.packing, cp.contacts, cp.network);
  const std::size_t nz = ps.summary.N_zero, n = ps.cells.size();
  REQUIRE(ps.participation.size() == ps.spectrum.lambda.size());
  CHECK((ps.participation.array() > 1.0 / static_cast<double>(n) - 1e-12).all());
  CHECK((ps.participation.array() <= 1.0 + 1e-12).all());
  // The zero-mode subspace is degenerate (any rotation of it is as good), so compare subspace
  // averages: the lowest band modes are far more extended than anything in the zero band can be
  // (a zero mode spread evenly over the N_u free cells would have PR = N_u/n).
  const double band = ps.participation.segment(nz, 20).mean();
  CHECK(band > 0.2);
}

TEST_CASE("participation ratio is 1/n for a one-cell mode and 1 for an evenly shared one", "[spectrum]") {
  Spectrum s;
  s.n_cells = 4;
  s.n_dof = 10;
  s.lambda = Eigen::VectorXd::LinSpaced(2, 1.0, 2.0);
  s.modes = Eigen::MatrixXd::Zero(12, 2);
  s.modes(5, 0) = 1.0;                                          // θ of cell 1 only
  for (int i = 0; i < 4; ++i) s.modes(3 * i + i % 3, 1) = 0.5;  // equal weight, different components
  const Eigen::VectorXd pr = participation_ratios(s);
  CHECK(pr[0] == Approx(0.25));
  CHECK(pr[1] == Approx(1.0));
  s.modes.resize(0, 0);
  CHECK_THROWS_AS(participation_ratios(s), std::invalid_argument);
}

TEST_CASE("the band edge is the RMS frequency of the lowest max(5, 1%) modes above the cutoff", "[spectrum]") {
  Spectrum s;
  s.n_cells = 400;
  s.n_dof = 1198;
  // 30 quasi-zero modes, then a band λ = 1e-3 (k+1) for the remaining 1168: n_band = ceil(11.68) = 12.
  s.lambda.resize(1198);
  for (int k = 0; k < 30; ++k) s.lambda[k] = 1e-13 * (k - 15);
  for (int k = 30; k < 1198; ++k) s.lambda[k] = 1e-3 * (k - 29);
  const BandEdge b = band_edge(s);
  CHECK(b.n_zero == 30);
  CHECK(b.n_band == 12);
  CHECK(b.modes_needed == 42);
  REQUIRE(b.available);
  double mean = 0;
  for (int k = 1; k <= 12; ++k) mean += 1e-3 * k / 12;
  CHECK(b.omega_star == Approx(std::sqrt(mean)).epsilon(1e-14));
  // Small systems: at least band_min modes.
  BandEdgeRule rule;
  rule.band_fraction = 0.001;
  CHECK(band_edge(s, rule).n_band == 5);
  // A partial spectrum that stops short of the band modes cannot give ω*.
  Spectrum part = s;
  part.lambda = s.lambda.head(41);
  const BandEdge bp = band_edge(part);
  CHECK_FALSE(bp.available);
  CHECK(std::isnan(bp.omega_star));
  CHECK(bp.modes_needed == 42);
  part.lambda = s.lambda.head(42);
  CHECK(band_edge(part).omega_star == b.omega_star);
  CHECK(modes_for_band_edge(1198, 30, {}, 0) == 42);
  // The summary reports the counts at four cutoffs and whether a partial spectrum reached them.
  part.lambda = s.lambda.head(25);
  CHECK_FALSE(summarise(part).zero_count_complete);
  const SpectralSummary full = summarise(s);
  CHECK(full.zero_count_complete);
  REQUIRE(full.zero_counts.size() == 4);
  CHECK(full.zero_counts[0].first == 1e-5);
  CHECK(full.zero_counts[0].second == 30);
}

TEST_CASE("the D(ω) histogram is normalised by the number of modes", "[spectrum]") {
  Spectrum s;
  s.n_cells = 5;
  s.n_dof = 13;
  s.lambda.resize(13);
  for (int k = 0; k < 3; ++k) s.lambda[k] = 1e-14 * k;              // quasi-zero
  for (int k = 3; k < 13; ++k) s.lambda[k] = std::pow(0.1 * k, 2);  // ω = 0.3 … 1.2
  const DosHistogram h = dos_histogram(s, 10, 1.0, 1e-6);
  CHECK(h.excluded == 3);
  CHECK(h.outside == 3);  // ω = 1.0, 1.1, 1.2
  double integral = 0;
  for (std::size_t b = 0; b < 10; ++b) integral += h.density[b] * (h.edges[b + 1] - h.edges[b]);
  CHECK(integral == Approx(7.0 / 13.0));
  CHECK(std::isinf(h.omega_valid));
  CHECK(signed_omega(-4.0) == -2.0);
  CHECK(signed_omega(9.0) == 3.0);
}

TEST_CASE("the automatic method is dense for small problems and ARPACK for large ones, and says so",
          "[spectrum][arpack]") {
  const auto& cp = compressed(150, 1);
  SpectrumOptions opt;
  PackingSpectrum ps = packing_spectrum(cp.packing, cp.contacts, cp.network, opt);
  CHECK(ps.spectrum.method == SpectrumMethod::dense);
  CHECK(ps.summary.method == SpectrumMethod::dense);
  opt.dense_max_dof = 100;
  opt.modes = 0;  // enough for ω*
  ps = packing_spectrum(cp.packing, cp.contacts, cp.network, opt);
  CHECK(ps.spectrum.method == SpectrumMethod::arpack);
  CHECK(ps.summary.band.available);
  CHECK(ps.summary.zero_count_complete);
  CHECK(std::string(to_string(ps.spectrum.method)) == "arpack");
  CHECK(parse_spectrum_method("dense") == SpectrumMethod::dense);
  CHECK_THROWS_AS(parse_spectrum_method("lanczos", "--method"), InputError);
  // ARPACK cannot return the whole spectrum: asked for, it is refused as an input error naming the
  // dense method; chosen automatically, the dense method takes over.
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  opt.method = SpectrumMethod::arpack;
  opt.modes = static_cast<int>(prob.mass.size()) - 2;
  try {
    solve_spectrum(prob.H, prob.mass, opt);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("dense") != std::string::npos);
  }
}

TEST_CASE("when the cell-local zero modes leave ARPACK too few modes, auto solves densely and agrees with dense",
          "[spectrum][arpack]") {
  // Few Lanczos modes are left once the cell-local zero modes are deflated: asking for all but
  // one of the 3n − 2 modes minus those would cut nothing, so auto must fall back.
  const auto& cp = compressed(150, 1);
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  const auto n_local = static_cast<int>(cell_local_zero_modes(prob.H, prob.mass).size());
  REQUIRE(n_local > 0);
  const int nd = static_cast<int>(prob.mass.size()) - 2;
  SpectrumOptions opt;
  opt.dense_max_dof = 0;     // auto would take ARPACK by size alone
  opt.modes = nd - n_local;  // < nd, but ≥ the dimension left after deflation
  const Spectrum a = solve_spectrum(prob.H, prob.mass, opt);
  CHECK(a.method == SpectrumMethod::dense);
  opt.method = SpectrumMethod::dense;
  const Spectrum d = solve_spectrum(prob.H, prob.mass, opt);
  REQUIRE(a.lambda.size() == d.lambda.size());
  CHECK((a.lambda - d.lambda).cwiseAbs().maxCoeff() == 0);
  opt.method = SpectrumMethod::arpack;
  CHECK_THROWS_AS(solve_spectrum(prob.H, prob.mass, opt), InputError);
}

TEST_CASE("an unjammed packing has no spectrum and says why", "[spectrum]") {
  Packing p;
  p.box.L = 10;
  p.add_cell(2, 2, 0, 0.5, 0.002, -1);
  p.add_cell(6, 6, 0, 0.5, 0.002, -1);
  const ContactNetwork net = analyse_network(p.size(), {});
  try {
    packing_spectrum(p, {}, net);
    FAIL("no error");
  } catch (const NoResultError& e) {  // a valid packing without that answer, as its moduli
    CHECK(std::string(e.what()).find("non-rattler") != std::string::npos);
  }
}

TEST_CASE("shift-invert finds a negative eigenvalue by lowering the shift, and refuses a hopeless one",
          "[spectrum][arpack]") {
  // Ring of cells (as above) with one soft x spring of negative stiffness: an unstable mode.
  const int n = 60;
  Packing p;
  p.box.L = 100;
  for (int i = 0; i < n; ++i) p.add_cell(i, 0, 0.0, 0.3, 0.002, -1);
  const Eigen::VectorXd M = mass_diagonal(p);
  auto ring = [&](double kneg) {
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      spring(t, 3 * i, 3 * j, i == 0 ? kneg : 1.0);
      spring(t, 3 * i + 1, 3 * j + 1, 1.0);
      spring(t, 3 * i + 2, 3 * j + 2, 1.0);
    }
    Sparse H(3 * n, 3 * n);
    H.setFromTriplets(t.begin(), t.end());
    return H;
  };
  SpectrumOptions opt;
  opt.modes = 6;
  const Sparse H = ring(-0.05);
  opt.method = SpectrumMethod::dense;
  const Spectrum dense = solve_spectrum(H, M, opt);
  REQUIRE(dense.lambda[0] < -1e-3);
  opt.method = SpectrumMethod::arpack;
  const Spectrum lanczos = solve_spectrum(H, M, opt);
  CHECK(lanczos.sigma < dense.lambda[0]);
  for (int k = 0; k < 6; ++k) CHECK(lanczos.lambda[k] == Approx(dense.lambda[k]).margin(1e-12));
  // The first Lanczos run may miss one copy of the ring's degenerate pairs (tol 1e-10); the inertia
  // check must then have caught it and rerun: a retry happens exactly when the unverified run
  // is wrong.
  SpectrumOptions unverified = opt;
  unverified.verify = false;
  const Spectrum raw = solve_spectrum(H, M, unverified);
  bool raw_ok = true;
  for (int k = 0; k < 6; ++k) raw_ok = raw_ok && std::abs(raw.lambda[k] - dense.lambda[k]) < 1e-12;
  CHECK(raw_ok == (lanczos.retries == 0));
  CHECK(lanczos.inertia_below_top == 5);  // the 5 modes below the 6th
  try {
    solve_spectrum(ring(-1e3), M, opt);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("not positive definite") != std::string::npos);
  }
}

// ---- `budjam dos` and the growth-run observer ------------------------------------------------

namespace {

namespace fs = std::filesystem;

using testing::run_budjam;
using testing::slurp;
using testing::work_dir;

fs::path scene(const std::string& name) { return testing::source_file("data/scenes/" + name); }

// The demo scene grown with the DOS observer at jamming, the targets and φ_2.
fs::path grown_demo(std::uint64_t seed) {
  const fs::path dir = work_dir() / ("demo-" + std::to_string(seed));
  if (!fs::exists(dir / "summary.json")) {
    const auto r = run_budjam("grow '" + scene("demo.toml").string() + "' --quiet --seed " + std::to_string(seed) +
                              " --out '" + dir.string() +
                              "' --set observe.dos.at_jamming=true --set observe.dos.at_targets=true"
                              " --set observe.dos.at_phi2=true --set jamming.continue_to_phi2=true");
    INFO(r.err);
    REQUIRE(r.code == 0);
  }
  return dir;
}

std::vector<double> csv_column(const fs::path& file, const std::string& column) {
  std::istringstream in(slurp(file));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  {
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) head.push_back(c);
  }
  const auto at = std::find(head.begin(), head.end(), column) - head.begin();
  REQUIRE(at < static_cast<long>(head.size()));
  std::vector<double> v;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string c;
    for (long k = 0; k <= at; ++k) std::getline(ss, c, ',');
    v.push_back(c.empty() ? std::numeric_limits<double>::quiet_NaN() : std::stod(c));
  }
  return v;
}

}  // namespace

TEST_CASE("on grown packings N_zero, the pebble game's floppy modes and N_u agree at jamming, targets and phi_2",
          "[spectrum][cli]") {
  for (std::uint64_t seed : {1, 2, 3}) {
    const fs::path dir = grown_demo(seed);
    const fs::path log = dir / "dos.csv";
    REQUIRE(fs::exists(log));
    const auto N_zero = csv_column(log, "N_zero"), floppy = csv_column(log, "floppy_modes"),
               N_u = csv_column(log, "N_u"), omega = csv_column(log, "omega_star");
    REQUIRE(N_zero.size() >= 3);  // jamming, two targets (and φ_2 if reached)
    for (std::size_t r = 0; r < N_zero.size(); ++r) {
      INFO("seed " << seed << ", row " << r);
      CHECK(N_zero[r] == floppy[r]);
      CHECK(N_zero[r] >= N_u[r]);
      CHECK(N_zero[r] <= N_u[r] + 2);
      CHECK(omega[r] > 0);
    }
    // The sidecar beside the jammed packing carries the same numbers, for `budjam analyse`: those of
    // the last episode's jamming, its first row (a run that unjams keeps the rows of the episodes
    // before).
    const auto episode = csv_column(log, "episode");
    const auto J = std::find(episode.begin(), episode.end(), episode.back()) - episode.begin();
    const io::Json j = io::read_json(dir / "packings" / "jammed.dos.json");
    CHECK(j["N_zero"].get<double>() == N_zero[J]);
    CHECK(j["N_u"].get<double>() == N_u[J]);
    CHECK(j["omega_star"].is_number());
  }
}

TEST_CASE("budjam dos reproduces the run's spectrum byte for byte and ARPACK agrees with dense", "[spectrum][cli]") {
  const fs::path dir = grown_demo(1);
  const fs::path pack = dir / "packings" / "target_1.pack";
  const fs::path base = work_dir() / "t1";
  auto r = run_budjam("dos '" + pack.string() + "' --out '" + base.string() + ".dos'");
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("dos: dense") != std::string::npos);
  CHECK(slurp(base.string() + ".dos.json") == slurp(dir / "packings" / "target_1.dos.json"));
  CHECK(slurp(base.string() + ".dos.csv") == slurp(dir / "packings" / "target_1.dos.csv"));

  const fs::path lb = work_dir() / "t1-arpack";
  r = run_budjam("dos '" + pack.string() + "' --method arpack --modes 30 --out '" + lb.string() + ".dos' --quiet");
  REQUIRE(r.code == 0);
  const io::Json j = io::read_json(lb.string() + ".dos.json");
  CHECK(j["method"] == "arpack");
  // K = 30 Lanczos modes besides the deflated cell-local zero modes (one per free lobe).
  CHECK(j["modes_computed"].get<long>() == 30 + j["N_u"].get<long>());
  const auto dense = csv_column(base.string() + ".dos.csv", "lambda");
  const auto lanczos = csv_column(lb.string() + ".dos.csv", "lambda");
  REQUIRE(lanczos.size() >= 30);
  for (std::size_t k = 0; k < lanczos.size(); ++k) {
    if (dense[k] > 1e-6)
      CHECK(std::abs(lanczos[k] - dense[k]) <= 1e-8 * dense[k]);
    else
      CHECK(std::abs(lanczos[k]) < 1e-10);
  }
}

TEST_CASE("the 1e5-cell scene at 500 cells jams at its epsilon_U, rigid and stable by two methods each",
          "[spectrum][cli]") {
  // data/scenes/jammed-1e5.toml with 1/200 of its seeds in 1/200 of its area (the same φ at
  // seeding). One thread: the result is the same for any count, and ctest may run other tests on
  // the other core.
  const fs::path dir = work_dir() / "jammed-500";
  auto r = run_budjam("grow '" + scene("jammed-1e5.toml").string() + "' --quiet --out '" + dir.string() +
                      "' --set box.L=25 --set init.cells=250 --set minimiser.threads=1");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const io::Json s = io::read_json(dir / "summary.json");
  REQUIRE(s["status"] == "finished");
  CHECK(s["N_J"].get<long>() >= 250);
  // The jamming point of this scene: a minimum with E/N in (ε_U, 2ε_U], ε_U = 1e-6.
  CHECK(s["E_J"].get<double>() > 1e-6);
  CHECK(s["E_J"].get<double>() <= 2e-6);
  CHECK(s["P_J"].get<double>() > 0);
  const fs::path pack = dir / "packings" / "jammed.pack";

  // Rigid: linear response and finite strain give the same positive B and G. Where a contact is pressed
  // less than the smallest strain step keeps (its force at the relaxation's resolution: which packing
  // has one depends on the last bits of the BLAS), every strain opens or closes it, the finite strain
  // has no slope, and the check says why instead of comparing.
  r = run_budjam("moduli '" + pack.string() + "' --check --json");
  REQUIRE(r.code == 0);
  const io::Json m = io::Json::parse(r.out);
  CHECK(m["energy_minimum"].get<bool>());
  CHECK(m["B"].get<double>() > 0);
  CHECK(m["G"].get<double>() > 0);
  const io::Json& check = m["check"];
  if (check.contains("not_applicable")) {
    WARN(check["not_applicable"].get<std::string>());
    const double h = check["simple_shear_G"]["strain_step"].get<double>();
    CHECK(check["smallest_overlap"].get<double>() < 100 * h);  // the automatic step wanted a smaller one
    CHECK_FALSE(check["agree_within_1_percent"].get<bool>());
  } else {
    CHECK(check["agree_within_1_percent"].get<bool>());
    CHECK(check["agree_within_1_percent_energy"].get<bool>());
  }

  // Stable: the lowest modes by ARPACK equal the dense spectrum's, and none is negative.
  const fs::path dense = work_dir() / "jammed-500-dense", lanczos = work_dir() / "jammed-500-arpack";
  REQUIRE(run_budjam("dos '" + pack.string() + "' --method dense --quiet --out '" + dense.string() + "'").code == 0);
  REQUIRE(run_budjam("dos '" + pack.string() + "' --method arpack --modes 20 --quiet --out '" + lanczos.string() + "'")
              .code == 0);
  const auto lambda_dense = csv_column(dense.string() + ".csv", "lambda");
  const auto lambda_arpack = csv_column(lanczos.string() + ".csv", "lambda");
  REQUIRE(lambda_arpack.size() >= 20);
  for (std::size_t k = 0; k < lambda_arpack.size(); ++k) {
    INFO("mode " << k);
    if (lambda_dense[k] > 1e-6)
      CHECK(std::abs(lambda_arpack[k] - lambda_dense[k]) <= 1e-8 * lambda_dense[k]);
    else
      CHECK(std::abs(lambda_arpack[k]) < 1e-10);
  }
  CHECK(lambda_dense.front() > -1e-10);
  // The quasi-zero modes are the pebble game's floppy modes.
  const io::Json d = io::read_json(dense.string() + ".json");
  CHECK(d["N_zero"].get<long>() == d["floppy_modes"].get<long>());
}

TEST_CASE("budjam dos refuses bad options with one line naming the option", "[spectrum][cli]") {
  const fs::path pack = grown_demo(1) / "packings" / "jammed.pack";
  auto r = run_budjam("dos '" + pack.string() + "' --method lanczos");
  CHECK(r.code == 2);
  CHECK(r.err.find("--method") != std::string::npos);
  r = run_budjam("dos '" + pack.string() + "' --method arpack --modes 100000");
  CHECK(r.code == 2);
  CHECK(r.err.find("--modes") != std::string::npos);
  r = run_budjam("dos '" + pack.string() + "' --sigma 0.1");
  CHECK(r.code == 2);
  CHECK(r.err.find("--sigma") != std::string::npos);
  // Non-finite or out-of-range floating values: exit 2, one line naming the option.
  for (const std::string bad : {"--tol nan", "--tol 1", "--sigma -1e20", "--sigma -1e-300", "--sigma inf",
                                "--lambda-tol inf", "--lambda-tol 0"}) {
    INFO(bad);
    r = run_budjam("dos '" + pack.string() + "' --method arpack " + bad);
    CHECK(r.code == 2);
    CHECK(r.err.find(bad.substr(0, bad.find(' '))) != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  // An unjammed packing: the reason is that it has no non-rattlers, whatever --modes says.
  const fs::path one = work_dir() / "one.pack";
  std::ofstream(one) << "budjam-packing 1\nL 8\nshear 0\nN 1\nnext_id 1\ncells id parent x y theta b gamma0\n"
                        "0 -1 4 4 0 0.5 0.002\nend\n";
  r = run_budjam("dos '" + one.string() + "' --method arpack --modes 3");
  CHECK(r.code == 1);
  CHECK(r.err.find("no non-rattler") != std::string::npos);
  CHECK(r.err.find("--modes") == std::string::npos);
}

TEST_CASE("ARPACK's dense Lanczos basis is bounded like the dense methods, naming the most modes that fit",
          "[spectrum][arpack]") {
  // 12 000 cells: 20 000 modes would need tens of GB; the refusal comes before any allocation.
  const Eigen::Index n3 = 36000;
  Eigen::SparseMatrix<double> H(n3, n3);
  H.setIdentity();
  const Eigen::VectorXd mass = Eigen::VectorXd::Ones(n3);
  for (const bool vectors : {false, true}) {
    SpectrumOptions opt;
    opt.method = SpectrumMethod::arpack;
    opt.modes = 20000;
    opt.vectors = vectors;
    std::string message;
    try {
      solve_spectrum(H, mass, opt);
    } catch (const InputError& e) {
      message = e.what();
    }
    INFO(message);
    const auto at = message.find("ask for at most ");
    REQUIRE(at != std::string::npos);
    CHECK(message.find("--modes") != std::string::npos);
    const double most = std::stod(message.substr(at + 16));
    // The named count's default basis (2K + 1 vectors of n3 rows, K eigenvectors if asked) fits in
    // kMaxDenseBytes; one mode more does not.
    const auto bytes = [&](double k) {
      return 8.0 * (static_cast<double>(n3) * (2 * k + 1 + (vectors ? k : 0)) + (2 * k + 1) * (2 * k + 9));
    };
    CHECK(bytes(most) <= kMaxDenseBytes);
    CHECK(bytes(most + 1) > kMaxDenseBytes);
  }
  // a basis made too large by an explicit ncv names --ncv, not the modes already few enough
  SpectrumOptions opt;
  opt.method = SpectrumMethod::arpack;
  opt.modes = 100;
  opt.ncv = 30000;
  CHECK_THROWS_WITH(solve_spectrum(H, mass, opt), Catch::Matchers::Contains("use at most --ncv "));
}

TEST_CASE("budjam dos on a 3-cell packing: auto solves densely; --method arpack is refused naming the dense method",
          "[spectrum][cli]") {
  const fs::path dir = work_dir() / "small";
  auto r = run_budjam("grow '" + scene("demo.toml").string() + "' --quiet --out '" + dir.string() +
                      "' --set box.L=2.35 --set 'jamming.targets=[1e-3]'");
  REQUIRE(r.code == 0);
  const fs::path pack = dir / "packings" / "jammed.pack";
  r = run_budjam("dos '" + pack.string() + "' --method arpack");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("internal") == std::string::npos);
  CHECK(r.err.find("--method dense") != std::string::npos);
  CHECK(r.err.find("ask for at most") != std::string::npos);  // or fewer modes, named
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  const fs::path a = work_dir() / "small-auto", d = work_dir() / "small-dense";
  r = run_budjam("dos '" + pack.string() + "' --dense-max-dof 0 --quiet --out '" + a.string() + "'");
  REQUIRE(r.code == 0);
  REQUIRE(run_budjam("dos '" + pack.string() + "' --method dense --quiet --out '" + d.string() + "'").code == 0);
  const io::Json ja = io::read_json(a.string() + ".json"), jd = io::read_json(d.string() + ".json");
  CHECK(ja["method"] == "dense");
  CHECK(ja["N_zero"] == jd["N_zero"]);
  // Physics: the zero modes are the floppy ones (3 cells: no rattler inside, N_zero = floppy count).
  CHECK(ja["N_zero"] == ja["floppy_modes"]);
}

TEST_CASE("ARPACK eigenpairs are validated: a far shift is refused naming the shift, a tiny one is not called a saddle",
          "[spectrum][arpack]") {
  const auto& cp = compressed(150, 1);
  const VibrationalProblem prob = vibrational_problem(cp.packing, cp.contacts, cp.network);
  SpectrumOptions opt;
  opt.method = SpectrumMethod::arpack;
  opt.modes = 20;
  const Spectrum good = solve_spectrum(prob.H, prob.mass, opt);
  CHECK(good.ritz_residual < 1e-9);
  opt.sigma = -1e20;  // λ = σ + 1/θ loses ε|σ| ≈ 2e4: garbage
  try {
    solve_spectrum(prob.H, prob.mass, opt);
    FAIL("no error");
  } catch (const NoResultError& e) {
    CHECK(std::string(e.what()).find("sigma") != std::string::npos);
    CHECK(std::string(e.what()).find("-1e-3") != std::string::npos);
  }
  opt.sigma = -1e-300;  // the translations stay singular to rounding: not a negative eigenvalue
  try {
    solve_spectrum(prob.H, prob.mass, opt);
    FAIL("no error");
  } catch (const NoResultError& e) {
    CHECK(std::string(e.what()).find("saddle") == std::string::npos);
    CHECK(std::string(e.what()).find("-1e-3") != std::string::npos);
  }
}

TEST_CASE("on a saddle the unstable modes are not zero modes: N_zero + N_negative is Sylvester's inertia count",
          "[spectrum]") {
  // A jamming candidate FIRE stopped on (tests/test_stability.cpp): one eigenvalue of its
  // non-rattler problem is negative beyond rounding. It is an unstable mode, not a quasi-zero one.
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const Packing p = io::read_packing(std::filesystem::path(src) / "tests/data/saddle_jamming_L15_seed3.pack").packing;
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  const VibrationalProblem prob = vibrational_problem(p, contacts, analyse_network(p.size(), contacts));
  SpectrumOptions options;
  options.method = SpectrumMethod::dense;
  options.vectors = false;
  const Spectrum s = solve_spectrum(prob.H, prob.mass, options);
  const double lambda_min = s.lambda.minCoeff();
  INFO("lowest eigenvalue " << lambda_min);
  REQUIRE(lambda_min < -1e-12);
  for (const double tol : {0.5 * -lambda_min, 1e-6}) {
    INFO("tol " << tol);
    const auto near_zero = static_cast<std::size_t>((s.lambda.array().abs() < tol).count());
    const auto unstable = static_cast<std::size_t>((s.lambda.array() <= -tol).count());
    CHECK(count_below(s.lambda, tol) == near_zero + unstable);
    CHECK(static_cast<long>(count_below(s.lambda, tol)) == count_below_by_inertia(prob.H, prob.mass, tol));
  }
  CHECK(count_below(s.lambda, 0.5 * -lambda_min) > count_quasi_zero(s.lambda, 0.5 * -lambda_min));
  // The summary: the negative mode counted as unstable, never as quasi-zero; the saddle test of
  // moduli flags the packing, as a whole.
  BandEdgeRule rule;
  rule.lambda_tol = 0.5 * -lambda_min;
  const SpectralSummary m = summarise(s, rule);
  CHECK(m.N_negative == static_cast<std::size_t>((s.lambda.array() <= -rule.lambda_tol).count()));
  CHECK(m.N_negative >= 1);
  CHECK(m.N_zero + m.N_negative == count_below(s.lambda, rule.lambda_tol));
  CHECK(hessian_stability(prob.H).unstable_modes == m.N_negative);
}

TEST_CASE("budjam dos on a saddle writes its spectrum, then a notice and exit 1, as moduli does", "[spectrum][cli]") {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const std::string pack = std::string(src) + "/tests/data/saddle_jamming_L15_seed3.pack";
  const fs::path dir = work_dir();
  for (const std::string method : {"dense", "arpack"}) {
    INFO(method);
    const fs::path base = dir / method;
    const auto r = run_budjam("dos '" + pack + "' --method " + method + " --out '" + base.string() + "'");
    const auto m = run_budjam("moduli '" + pack + "' --quiet");
    CHECK(m.code == 1);
    CHECK(r.code == m.code);
    CHECK(r.err.find("is a saddle") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    const io::Json j = io::Json::parse(testing::slurp(base.string() + ".json"));
    CHECK(j["energy_minimum"] == false);
    CHECK(j["stationary_point"] == "saddle");
    CHECK(j["unstable_modes"].get<long>() >= 1);
    // Its unstable mode is shallow (|λ| < lambda_tol, near jamming): the inertia test still finds it;
    // the table marks as unstable only the modes below −lambda_tol.
    CHECK(j["N_negative"].get<long>() <= j["unstable_modes"].get<long>());
    // No negative λ beyond the cutoff is marked quasi-zero in the table.
    std::istringstream csv(testing::slurp(base.string() + ".csv"));
    std::string line;
    std::getline(csv, line);
    long negative_rows = 0;
    while (std::getline(csv, line)) {
      const auto c1 = line.find(','), c2 = line.find(',', c1 + 1);
      const double lambda = std::stod(line.substr(c1 + 1, c2 - c1 - 1));
      if (lambda <= -1e-6) {
        ++negative_rows;
        CHECK(line.substr(line.rfind(',') + 1) == "false");
      }
    }
    CHECK(negative_rows == j["N_negative"].get<long>());
  }
}

TEST_CASE(
    "budjam dos on a minimum held by a pair at zero force writes its spectrum and names it, as moduli does: "
    "energy_minimum true, a notice, exit 1",
    "[spectrum][cli]") {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const std::string pack = std::string(src) + "/tests/data/contact_bounded_jamming_L20_seed3.pack";
  const fs::path base = work_dir() / "bounded";
  const auto r = run_budjam("dos '" + pack + "' --method dense --out '" + base.string() + "'");
  CHECK(r.code == 1);
  CHECK(r.code == run_budjam("moduli '" + pack + "' --quiet").code);
  CHECK(r.err.find("is a minimum of U held by a pair at zero force") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  const io::Json j = io::Json::parse(testing::slurp(base.string() + ".json"));
  CHECK(j["energy_minimum"] == true);
  CHECK(j["stationary_point"] == "contact-bounded minimum");
  CHECK(j["unstable_modes"].get<long>() == 1);
}
