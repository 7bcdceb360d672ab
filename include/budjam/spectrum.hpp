#pragma once
// Vibrational spectrum of an arrested packing (paper, appendix "Vibrational density of states";
// docs/model.md, "One cell", for the masses).
//
// The generalised problem H v = ω² M v is solved on the non-rattler cells, with M the diagonal
// dumbbell mass matrix (m, m, I per cell). It is symmetrised with M^{-1/2}: the dynamical matrix
// K = M^{-1/2} H M^{-1/2} (paper Eq. F2) has the same eigenvalues λ = ω², and its orthonormal
// eigenvectors e are the mass-weighted modes, v = M^{-1/2} e.
//
// The two uniform translations t_x = (1,0,0,1,0,0,…), t_y = (0,1,0,0,1,0,…) are exact zero modes
// of H in a periodic box (H t = 0 for any pair potential). They are removed by M-orthogonal
// deflation: in mass-weighted coordinates T_α = M^{1/2} t_α / ‖M^{1/2} t_α‖ is an exact
// eigenvector of K, so K maps the complement T^⊥ into itself and the spectrum on T^⊥ is the
// rest of the spectrum. Dense: K is rotated by the two Householder reflectors that map T onto
// the first two axes and the (3n−2)² complement block is diagonalised. ARPACK: the Lanczos
// operator is P (K − σI)⁻¹ P with P = 1 − Q Qᵀ (Q orthonormal, spanning T and the cell-local zero
// modes below) and the start vector lies in Q^⊥.
//
// Cell-local zero modes (ARPACK only). An unconstrained lobe leaves an exact zero mode supported
// on its cell alone (rotation about the other lobe's centre). A packing near jamming has hundreds
// to thousands of them, all at λ = 0 to rounding; a single-vector Lanczos method resolves such a
// degenerate cluster only through rounding and takes hundreds of restarts when K cuts through it
// (measured: 389 s instead of 1 s for K = 100 at N = 1000, docs/spectrum.md). They are therefore
// found exactly first: for every cell, the right singular vectors of its three columns of K with
// singular value ≤ local_zero_tol · max|K| are null vectors of K on that cell. They are kept as
// modes of the spectrum (λ = their Rayleigh quotient, ~1e-17) and deflated from the Lanczos
// operator, which then finds the other modes. Nothing is assumed about the packing: the test is
// on K alone, and the independent inertia count (count_below_by_inertia) checks the total.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/saddle.hpp"
#include "budjam/stability.hpp"

namespace budjam {

// Diagonal of M in the layout of Packing::q: (m_i, m_i, I_i) for every cell, m = 1 + (b/D)²,
// I = Σ_lobes m_lobe (ℓ² + R²/2). Diagonal because (x, y) is the centre of mass: the kinetic
// energy of a rigid dumbbell has no translation–rotation cross term.
Eigen::VectorXd mass_diagonal(const Packing& p);

// H v = λ M v on a subset of the cells. H is the stiffness (Hessian of U) in the (x, y, θ) layout
// of the kept cells, both triangles stored.
struct VibrationalProblem {
  Eigen::SparseMatrix<double> H;   // 3n × 3n
  Eigen::VectorXd mass;            // 3n, diagonal of M
  std::vector<std::size_t> cells;  // packing index of each kept cell (n of them)
};

// The problem of the non-rattler cells with the load-bearing contacts (rattlers and their
// contacts removed), using the analytic Hessian (stiffness + prestress terms).
VibrationalProblem vibrational_problem(const Packing& p, const std::vector<Contact>& contacts,
                                       const ContactNetwork& net);

enum class SpectrumMethod { automatic, dense, arpack };
const char* to_string(SpectrumMethod method);
// "auto" | "dense" | "arpack"; throws InputError naming `key` otherwise.
SpectrumMethod parse_spectrum_method(const std::string& text, const std::string& key = "method");

struct SpectrumOptions {
  SpectrumMethod method = SpectrumMethod::automatic;
  std::size_t dense_max_dof = 2000;  // automatic: dense when 3n − 2 ≤ this (≈ 670 cells, ~1 s)
  int modes = 100;                   // ARPACK: K modes by Lanczos besides the deflated cell-local
                                     // zero modes (so at least the lowest K); packing_spectrum():
                                     // ≤ 0 means as many as ω* needs
  int ncv = 0;                       // ARPACK Lanczos vectors; 0 = max(2K+1, K+20) (K: Lanczos modes,
                                     // after the inertia guard); at least K + 1
  double tol = 1e-10;                // ARPACK relative Ritz residual tolerance; 0 = machine precision.
                                     // 1e-10 gives the same eigenvalues (to 1e-12) 2–3× faster than
                                     // 0 (docs/spectrum.md, "What accuracy costs")
  double sigma = -1e-3;              // ARPACK shift (units k/m); negative so K − σI is positive
                                     // definite despite the zero modes. Retried ×10 more negative
                                     // (up to 4 times) if the factorisation finds K − σI indefinite.
  bool vectors = true;               // eigenvectors (needed for participation ratios)
  std::uint64_t seed = 1;            // ARPACK start vector
  bool deflate_local = true;         // ARPACK: find and deflate cell-local zero modes (see above)
  double local_zero_tol = 1e-10;     // ... singular value threshold relative to max|K|
  double inertia_tol = 1e-6;         // ARPACK: also count #{λ < inertia_tol} by Sylvester inertia
                                     // (one LDLᵀ); the Lanczos run then takes all of them (0: skip)
  bool verify = true;                // ARPACK: check by inertia that no mode below the highest
                                     // computed one (less 1e-9 max|K|) was missed; if one was, rerun once with tol 0
                                     // and 2·ncv, then throw NoResultError
};

// A zero mode supported on one cell: mass-weighted unit 3-vector e on block `block` (the cell's
// position among the kept cells).
struct LocalMode {
  std::size_t block = 0;
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
};

struct Spectrum {
  SpectrumMethod method = SpectrumMethod::dense;  // the one used (never automatic)
  std::size_t n_cells = 0;                        // n
  std::size_t n_dof = 0;                          // 3n − 2: modes of the full problem
  // ω² of the computed modes. Dense: all n_dof, ascending. ARPACK: first the local.size()
  // deflated cell-local zero modes, then the Lanczos modes ascending, i.e. ascending except for
  // rounding-level order inside the zero cluster (all below any cutoff in use). ARPACK computes the
  // local modes plus max(K, N_inertia − local + 1) more, so every mode below inertia_tol is in.
  Eigen::VectorXd lambda;
  std::vector<LocalMode> local;  // ARPACK: the deflated cell-local zero modes (lambda[0 … local.size()))
  // Mass-weighted eigenvectors (3n rows) of lambda[local.size() …] as columns, orthonormal and
  // orthogonal to the translations and to the local modes; empty without vectors. (The local modes
  // are kept as LocalMode: storing them densely would take 3n × N_u doubles.)
  Eigen::MatrixXd modes;
  double translation_residual = 0;  // ‖K T‖/‖K‖_max: 0 up to rounding for a correct Hessian
  // ARPACK only:
  double sigma = 0;  // shift actually used
  int ncv = 0, restarts = 0, operator_applications = 0;
  long inertia_count = -1;      // #{λ < inertia_tol} by Sylvester inertia; −1 if not computed
  long inertia_below_top = -1;  // #{λ < max computed λ − 1e-9 max|K|} by inertia (verify); −1 if not
  int retries = 0;              // Lanczos reruns after the verification found a missed mode
  double ritz_residual = 0;  // max ‖K v − λ v‖ / (‖K‖_∞ ‖v‖) of the Lanczos pairs (with vectors); above
                             // max(1e-9, 10 tol) solve_spectrum throws NoResultError
  double seconds_factorise = 0, seconds_lanczos = 0;

  bool complete() const { return static_cast<std::size_t>(lambda.size()) == n_dof; }
  bool has_vectors() const { return static_cast<Eigen::Index>(local.size()) + modes.cols() == lambda.size(); }
  // Mass-weighted eigenvector of lambda[k] (3n entries).
  Eigen::VectorXd mode(Eigen::Index k) const;
};

// Solves a problem given by H and diag(M) (any matrix, not only a packing's). A solver that does not
// converge (dense eigensolver, ARPACK, a shift that is not below the spectrum, missed modes) or
// eigenvalues that are not finite: NoResultError saying what to try.
Spectrum solve_spectrum(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass,
                        const SpectrumOptions& options = {});

// ---- spectral observables ------------------------------------------------------------------

// Null vectors of K = M^{-1/2} H M^{-1/2} supported on a single cell (see the top of this file):
// singular value of the cell's three columns of K ≤ tol · max|K|.
std::vector<LocalMode> cell_local_zero_modes(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass,
                                             double tol = 1e-10);

// Number of modes with λ < tol (negative ones included).
std::size_t count_below(const Eigen::VectorXd& lambda, double tol);
// Number of quasi-zero modes, |λ| < tol: rounding noise of either sign, never a clearly negative λ
// (an unstable mode of a saddle).
std::size_t count_quasi_zero(const Eigen::VectorXd& lambda, double tol);

// #{λ < tol} among the 3n − 2 modes without computing any: Sylvester's law of inertia on an
// LDLᵀ factorisation of K − tol·I (negative pivots, minus the two translations). An independent
// check of N_zero for systems too large for the dense solver. tol > 0.
long count_below_by_inertia(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& mass, double tol);

// The band edge ω*: the root-mean-square frequency of the lowest n_band modes above the
// quasi-zero modes, ω* = sqrt(mean λ over those modes), with
//   n_band = max(band_min, ceil(band_fraction · (n_dof − N_below))),  N_below = #{λ < lambda_tol}
// (N_zero = #{|λ| < lambda_tol} plus, in a saddle, the unstable modes).
// A fixed fraction of the extended band keeps ω* intensive (the paper's "lowest few modes" at
// L = 15 are ≈ 1 % of ≈ 600 modes). `available` is false (ω* = NaN) when a partial spectrum
// does not reach that far; `modes_needed` then says how many lowest modes would.
struct BandEdgeRule {
  double lambda_tol = 1e-6;
  std::size_t band_min = 5;
  double band_fraction = 0.01;
};
struct BandEdge {
  bool available = false;
  double omega_star = 0;
  std::size_t n_zero = 0;        // modes below lambda_tol
  std::size_t n_band = 0;        // modes averaged
  std::size_t modes_needed = 0;  // n_zero + n_band
};
BandEdge band_edge(const Spectrum& s, const BandEdgeRule& rule = {});

// Participation ratio of each computed mode, PR = (Σ_i w_i)² / (n Σ_i w_i²) with w_i the
// kinetic-energy share of cell i (sum of its three squared mass-weighted components): 1/n for a
// mode on one cell, O(1) for an extended mode. Requires eigenvectors.
Eigen::VectorXd participation_ratios(const Spectrum& s);

// D(ω) = (1/n_dof) Σ_n δ(ω − ω_n), binned on [0, omega_max) with `bins` equal bins; modes with
// λ < exclude_below are left out (the paper's panel A omits the quasi-zero band) and counted.
// For a partial spectrum only ω below the highest computed mode is meaningful: `omega_valid`.
struct DosHistogram {
  std::vector<double> edges;    // bins + 1
  std::vector<double> density;  // bins, normalised by n_dof and bin width
  std::size_t excluded = 0;     // modes below exclude_below
  std::size_t outside = 0;      // modes with ω ≥ omega_max
  double omega_valid = 0;       // histogram is complete below this ω
};
DosHistogram dos_histogram(const Spectrum& s, std::size_t bins, double omega_max, double exclude_below);

// Signed frequency ω = sign(λ) sqrt(|λ|): a negative λ (instability or rounding) stays visible.
double signed_omega(double lambda);

// Everything `budjam dos` and the DOS observer report about one spectrum.
struct SpectralSummary {
  SpectrumMethod method = SpectrumMethod::dense;
  std::size_t n_cells = 0, n_dof = 0, computed = 0;
  double lambda_min = 0, lambda_max_computed = 0;
  double lambda_tol = 1e-6;
  std::size_t N_zero = 0;           // #{|λ| < lambda_tol}: quasi-zero modes
  std::size_t N_negative = 0;       // #{λ ≤ −lambda_tol}: unstable modes (a saddle) among the computed ones
  bool zero_count_complete = true;  // false if a partial spectrum does not reach max(lambda_tol,
                                    // 1e-5): the counts are then only lower bounds (compute more modes)
  std::vector<std::pair<double, std::size_t>> zero_counts;  // (tol, #{λ < tol}) for 1e-5 … 1e-8
  BandEdge band;
  double translation_residual = 0;
};
SpectralSummary summarise(const Spectrum& s, const BandEdgeRule& rule = {});

// The number of lowest modes that `summarise` needs for ω* on a problem with n_dof modes and
// about `expected_zero` quasi-zero modes (e.g. N_u), plus a margin of `spare`.
int modes_for_band_edge(std::size_t n_dof, std::size_t expected_zero, const BandEdgeRule& rule = {},
                        std::size_t spare = 16);

// ---- one packing, end to end ----------------------------------------------------------------

struct PackingSpectrum {
  std::vector<std::size_t> cells;  // the non-rattler cells, in the order of the modes' blocks
  Spectrum spectrum;
  SpectralSummary summary;
  Eigen::VectorXd participation;  // per computed mode (empty without vectors)
  // The saddle test of `budjam moduli` (hessian_stability) on the non-rattler Hessian: unstable_modes > 0
  // means the packing is a saddle, not an energy minimum (its spectrum has negative λ).
  Stability stability;
  StationaryPoint stationary = StationaryPoint::minimum;  // a saddle, or a contact-bounded minimum (saddle.hpp)
  bool energy_minimum() const { return stationary != StationaryPoint::saddle; }
};

// Spectrum of the non-rattlers of a relaxed packing (vibrational_problem + solve_spectrum +
// summarise). With options.modes ≤ 0 the ARPACK path computes as many modes as ω* needs:
// modes_for_band_edge(n_dof, N_u), less the N_u cell-local zero modes when they are deflated. Throws NoResultError
// if the packing has no non-rattler cell (unjammed: no spectrum).
PackingSpectrum packing_spectrum(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 SpectrumOptions options = {}, const BandEdgeRule& rule = {});

}  // namespace budjam
