#pragma once
// Non-affine linear elastic response of a relaxed packing (derivation in docs/moduli.md).
//
// Strain: an affine displacement gradient e_αβ = ∂u_α/∂x_β applied to the box and the centroids
// (X → (1 + e) X, images included); orientations θ are not strained (cells are rigid). Lees–Edwards
// simple shear γ is e_xy = γ; isotropic rescaling of box and centroids is e = ε·1. The cells then
// relax: q = q_aff(e) + u, H du/de = Ξ with Ξ = −∂²U/∂q∂e (the force response), solved on the
// non-rattler cells with CHOLMOD.
//
// Two stresses, hence two conventions for every modulus (both reported):
//  - the lobe-centre contact virial S_αβ = −(1/L²) Σ f r̂_α r_β, r the lobe-centre separation. The
//    paper's B and G ("B = φ dP/dφ", "G = dΣ_xy/dγ") are slopes of this stress: the headline
//    `B`, `G` (they match the reference's finite-strain measurements);
//  - the energy (thermodynamic) stress τ_αβ = (1/A) ∂U/∂e_αβ = −(1/A) Σ f n_α C_β, C the centroid
//    separation. Its moduli are curvatures of the relaxed energy: G_energy = (1/A) d²U/dγ²,
//    B_energy = A d²U/dA². They follow from U(e)/A = U0/A + τ:e + ½ e:E:e with
//    E = (Born − Ξᵀ H⁺ Ξ)/A; the stiffness tensor of the Lagrangian strain η = (eᵀ + e + eᵀe)/2
//    is C = E − δ_αγ τ_βδ.
// In a force- and torque-balanced cell the contacts load the rigid mother–bud link with an axial
// force Λ (> 0: compressed). τ counts that load, S does not: τ = S − (1/A) Σ_cells s Λ n̂ ⊗ n̂
// (link_stress), and the moduli differ by the slope of the link term. They coincide when no
// link is loaded (every bud contact-free).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/saddle.hpp"
#include "budjam/stability.hpp"

namespace budjam {

// Strain components in the order of the 4 × 4 response matrices: e_xx, e_xy, e_yx, e_yy.
inline constexpr int kXX = 0, kXY = 1, kYX = 2, kYY = 3;
using Response4 = Eigen::Matrix4d;  // R(αβ, γδ) = d(stress_αβ)/d(e_γδ), or E(αβ, γδ)

// Energy stress τ = −(1/L²) Σ f n ⊗ C (C: centroid separation of the two cells, minimum image).
// Symmetric when every cell is torque-balanced. P_energy = −tr τ / 2.
Eigen::Matrix2d energy_stress(const Packing& p, const std::vector<Contact>& contacts);

// B, G from a stress-response matrix R (d stress / d e):
//   B        = −A dP/dA under e = ε·1              = (1/4) Σ_α Σ_γ R(αα, γγ)
//   G_simple = dΣ_xy/dγ under Lees–Edwards e_xy = γ = (R(xy, xy) + R(yx, xy))/2
//   G_pure   = d[(Σ_xx − Σ_yy)/2]/dγ under e = diag(γ/2, −γ/2)
//   G_mean   = (G_simple + G_pure)/2
struct Moduli {
  double B = 0, G_simple = 0, G_pure = 0, G_mean = 0;
};
Moduli moduli_from(const Response4& R);

// Shear stability of the box shape. A simple shear along the direction d = (cos φ, sin φ), with
// the displacement gradient along m = (−sin φ, cos φ), is e = γ d mᵀ: it keeps the area exactly, so
// G(φ) = (1/A) d²U/dγ² along the relaxed path is ê(φ) : E : ê(φ) with E the relaxed energy
// stiffness (ElasticResponse::E); G(0) = E_xyxy is Lees–Edwards shear. A packing jammed in a box of
// fixed shape is stable at fixed box (positive-definite Hessian) yet can have G(φ) < 0 for some φ:
// its energy falls under that deformation of the box. This is physics, common in small packings at
// low pressure (Dagois-Bohy et al., PRL 109, 095703 (2012)), not a solver failure.
double shear_modulus_along(const Response4& E, double phi);
struct ShearStability {
  double G_min = 0, phi_min = 0;  // softest simple-shear direction, φ in [0, π)
  double G_max = 0, phi_max = 0;  // stiffest
  bool stable = false;            // G_min > 0: no simple shear of the box lowers the energy
};
// G(φ) is a trigonometric polynomial of degree 4 with period π; its extrema are found on a grid of
// 720 directions and refined by bisection on dG/dφ. Given a stress response R instead of E, the
// same extremes describe that stress's slope ê(φ) : R : ê(φ) over directions (no energy criterion).
ShearStability shear_stability(const Response4& E);

// Stress carried by the rigid mother–bud links, −(1/L²) Σ_cells s_i Λ_i n̂_i ⊗ n̂_i with s_i the
// lobe separation and Λ_i = −F_bud·n̂_i the axial load of the link (F_bud: the total contact force
// on the bud; > 0 when the bud is pushed towards its mother). At force and torque balance
// S + link_stress = τ exactly (docs/moduli.md, "Two conventions").
Eigen::Matrix2d link_stress(const Packing& p, const std::vector<Contact>& contacts);

// How the pinned system H_ff U_f = Ξ_f was solved.
enum class SolveMethod {
  no_contacts,        // no load-bearing contacts: nothing to solve, no response
  no_force_response,  // Ξ = 0: the affine strain is already relaxed (U = 0)
  cholesky,
  ldlt,
  dense,  // the direct solvers of ModuliSolver
  cg_ichol,
  cg_diagonal,             // conjugate gradients with either preconditioner
  regularised_refinement,  // fallback of the direct solvers when the pinned system is still singular
                           // (a mechanism beyond the pinned modes)
  unstable                 // H has negative eigenvalues: a saddle, no relaxed response (relaxed moduli NaN)
};
// "none (no load-bearing contacts)", "none (Ξ = 0)", "cholesky", "ldlt", "dense", "cg-ichol",
// "cg-diagonal", "regularised-refinement", "unstable".
const char* to_string(SolveMethod method);

// How the singular Hessian was handled.
struct KernelTreatment {
  std::size_t dofs = 0;                  // 3 N_nr (reduced system before pinning)
  std::size_t pinned_translation = 0;    // 2: x, y of one reference cell (the two global translations)
  std::size_t pinned_lobe_rotation = 0;  // θ of cells with exactly one contact-free lobe: the free lobe
                                         // swings about the loaded one (an exact zero mode, also of the
                                         // prestress term); pinning θ leaves that mode out
  std::size_t pinned_zero_rows = 0;      // other dofs whose Hessian row is exactly zero
  std::size_t reference_cell = 0;        // packing index of the cell whose x, y are pinned
  SolveMethod method = SolveMethod::no_contacts;
  long cholesky_failed_column = -1;  // where the direct factorisation stopped (fallback only)
  double regularisation = 0;         // δ of the fallback (H + δ1) factor, 0 otherwise
  std::size_t unstable_modes = 0;    // eigenvalues of H below −δ (inertia of the LDLᵀ factor); > 0 only
                                     // with method unstable. Jamming points found by the energy rule
                                     // alone can be such saddles (docs/moduli.md, "Saddles")
  int refinement_steps = 0;          // iterative-refinement steps taken
  int iterations = 0;                // cg: iterations, summed over the strain columns
  double solver_tolerance = 0;       // cg: the relative residual asked for per column; 0 otherwise
  double residual = 0;               // max over strain columns of ‖H u − Ξ‖ / ‖Ξ‖ on ALL non-rattler
                                     // rows (pinned rows included: they check Ξ ⊥ kernel)
  double kernel_component = 0;       // max over columns and pinned kernel vectors v of |vᵀΞ| / (‖v‖ ‖Ξ‖)
  double rcond = 0;                  // CHOLMOD's reciprocal condition estimate of the factor
  bool well_posed = false;           // residual ≤ tolerance: Ξ had no kernel component and the
                                     // response is unique where it is measured
};

// Linear solver for the pinned system H_ff U_f = Ξ_f (accuracy against cost: docs/analysis.md).
//  - ldlt: CHOLMOD simplicial LDLᵀ (no supernodes, no square roots) + ≤ direct_refinement_steps
//    iterative-refinement steps (the default: on the accuracy-against-cost front, 15–25 % faster than
//    cholesky up to 3000 cells, within 7 % at 10⁴; docs/analysis.md);
//  - cholesky: CHOLMOD LLᵀ (supernodal when it pays) + the same refinement;
//  - dense: Eigen's dense LDLᵀ (pivoted) of H_ff + the same refinement: O(n³), an independent
//    reference for small systems;
//  - cg: Eigen's preconditioned conjugate gradients, per strain column, to ‖Ξ_f − H_ff u‖ ≤
//    cg_tolerance ‖Ξ_f‖ (no factorisation; the error of B, G is then of order κ·cg_tolerance).
// A direct solver that finds H_ff singular or indefinite falls back to the regularised refinement;
// every solver goes through the same residual verification.
enum class ModuliSolver { cholesky, ldlt, dense, cg };
enum class CgPreconditioner { incomplete_cholesky, diagonal };
const char* to_string(ModuliSolver solver);
const char* to_string(CgPreconditioner preconditioner);
// "cholesky" | "ldlt" | "dense" | "cg"; throws InputError naming `key` otherwise.
ModuliSolver parse_moduli_solver(const std::string& text, const std::string& key = "solver");
// "ichol" | "diagonal"; throws InputError naming `key` otherwise.
CgPreconditioner parse_cg_preconditioner(const std::string& text, const std::string& key = "cg-preconditioner");

struct ModuliOptions {
  double residual_tolerance = 1e-8;              // relative; above it well_posed = false (cg: above
                                                 // max(residual_tolerance, 10·cg_tolerance))
  double regularisation = kSaddleRelativeDelta;  // fallback δ relative to the largest Hessian diagonal entry;
                                                 // also the saddle test (stability.hpp)
  int max_refinement_steps = 200;
  ModuliSolver solver = ModuliSolver::ldlt;
  int direct_refinement_steps = 3;  // ldlt, cholesky, dense: at most this many refinement steps …
  double refinement_threshold =
      1e-12;                    // … taken while the relative residual on the free rows exceeds this
                                //   (a safety net: the first solve gives ≲ 2e-14 on grown packings; docs/analysis.md)
  double cg_tolerance = 1e-10;  // cg: relative residual per strain column, in (0, 1)
  CgPreconditioner cg_preconditioner = CgPreconditioner::incomplete_cholesky;
  int cg_max_iterations = 0;  // cg: 0 = 10 × the number of free dofs
};

// The packing, its network and its stresses: what the response is measured on.
struct PackingState {
  std::size_t N = 0, N_nr = 0, N_f = 0, N_u = 0, N_u_buds = 0;
  std::size_t contacts = 0;  // load-bearing physical contacts (both cells non-rattlers)
  double L = 0, area = 0, phi = 0;
  double Z = 0, Z_iso = 0, dZ = 0, u = 0, u_buds = 0;
  double n = 0;  // N_nr / L²

  // Stresses at the state (from all contacts).
  double P = 0;                                             // lobe-centre contact virial, (1/(2L²)) Σ f r
  double P_energy = 0;                                      // −tr τ / 2 = −dU/dA
  Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();         // S (lobe-centre contact virial)
  Eigen::Matrix2d stress_energy = Eigen::Matrix2d::Zero();  // τ
  double max_torque_imbalance = 0;                          // |τ_xy − τ_yx|: 0 in a relaxed packing

  // Mean-field estimates of the paper (Eqs. 17–18, D4, D11), with this packing's n, Z, ΔZ.
  double ell_c = 0;        // ℓ_c: mean lobe-centre distance r of the load-bearing contacts
  double ell_c2_mean = 0;  // ⟨r²⟩ (for comparison; the formulas use ℓ_c²)
  double M4 = 0;           // ⟨n_x² n_y²⟩ measured over the load-bearing contacts (isotropic: 1/8)
  double B_ext = 0;        // n k ℓ_c² Z / 8
  double G_mf = 0;         // n k ℓ_c² M4 ΔZ / 2 with the measured M4
  double G_mf_iso = 0;     // same with M4 = 1/8
};

// Everything of one contact that the response needs (per load-bearing contact).
struct ContactResponseTerms {
  Eigen::Matrix<double, 2, 6> J;  // ∂d/∂(q_i, q_j), d the lobe-centre separation
  Eigen::Matrix<double, 2, 4> D;  // ∂d/∂e: column (γδ) = ê_γ C_δ
  Eigen::Matrix2d K;              // pair stiffness in d (stiffness + prestress)
  Eigen::Vector2d g;              // f n: the force on lobe i (= −∂V/∂d)
  Eigen::Vector2d d;              // lobe-centre separation r n
  Eigen::Vector2d C;              // centroid separation
  long bi = 0, bj = 0;            // reduced blocks of the two cells
};

// The linear-response problem of a packing: the Hessian H of the non-rattlers (over their
// load-bearing contacts, in the coordinates (x, y, θ) of the cells), the force response Ξ, the
// Born term and the pinned kernel dofs. No solve.
struct ResponseProblem {
  PackingState state;
  Eigen::SparseMatrix<double> H;            // 3N_nr × 3N_nr
  Eigen::MatrixXd Xi;                       // Ξ = −∂²U/∂q∂e, 3N_nr × 4
  Response4 born = Response4::Zero();       // ∂²U/∂e∂e at fixed q (affine, prestress included)
  std::vector<ContactResponseTerms> terms;  // one per load-bearing contact
  std::vector<bool> pinned;                 // per non-rattler dof: fixed at 0 (an exact kernel direction)
  KernelTreatment kernel;                   // the pinning (counts, reference cell, kernel_component)
  double kernel_curvature = 0;              // max ‖H v‖/‖v‖ over the pinned kernel directions v
};

// The non-affine relaxation du/de = H⁺Ξ of a problem (pinned rows 0; NaN for a saddle) and how it
// was obtained and verified.
struct Relaxation {
  Eigen::MatrixXd U;       // 3N_nr × 4
  KernelTreatment kernel;  // the problem's pinning plus the solve
};

struct ElasticResponse : PackingState {
  // Response matrices (rows: stress component αβ, columns: strain component γδ; order xx, xy, yx, yy).
  Response4 R = Response4::Zero();         // dS/de, relaxed (non-affine)
  Response4 R_affine = Response4::Zero();  // dS/de, affine (u = 0)
  Response4 R_energy = Response4::Zero();  // dτ/de, relaxed
  Response4 R_energy_affine = Response4::Zero();
  Response4 E = Response4::Zero();         // (1/A) d²U/de de, relaxed
  Response4 E_affine = Response4::Zero();  // Born term (1/A) ∂²U/∂e∂e (with the prestress part)
  // Stiffness tensor of the Lagrangian strain, Voigt order (xx, yy, xy): C11 = C_xxxx, C22 = C_yyyy,
  // C12 = C_xxyy, C33 = C_xyxy, C13 = C_xxxy, C23 = C_yyxy.
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d C_affine = Eigen::Matrix3d::Zero();

  Moduli moduli;                // from R: the lobe-centre-stress moduli (the paper's B and G)
  Moduli moduli_affine;         // from R_affine
  Moduli moduli_energy;         // from R_energy: B = A d²U/dA², G_simple = E_xyxy (to rounding)
  Moduli moduli_energy_affine;  // from R_energy_affine
  ShearStability shear;         // from E: the softest and stiffest simple shear of the box (energy)
  ShearStability shear_stress;  // from R: extremes over directions of the lobe-centre-stress G(φ);
                                // describes that convention's anisotropy, not a stability (its
                                // `stable` is no energy criterion)

  KernelTreatment kernel;
  // With unstable modes (method unstable): a saddle, or a minimum held by a pair at zero force
  // (saddle.hpp); only elastic_response of a packing can tell, the problem alone says saddle.
  StationaryPoint stationary = StationaryPoint::minimum;
  bool energy_minimum() const { return stationary != StationaryPoint::saddle; }
  bool linear_response() const { return kernel.unstable_modes == 0; }  // false: relaxed response NaN

  // The headline moduli in the two conventions (docs/moduli.md, "Two conventions").
  double G() const { return moduli.G_simple; }         // dS_xy/dγ, Lees–Edwards: the paper's G
  double G_energy() const { return E(kXY, kXY); }      // (1/A) d²U/dγ²: the thermodynamic shear modulus
  double B() const { return moduli.B; }                // −A dP/dA, P the lobe-centre virial: the paper's B
  double B_energy() const { return moduli_energy.B; }  // A d²U/dA² = −A dP_energy/dA
};

// The three steps of elastic_response, separately (e.g. to time the solve):
// the problem of a relaxed packing (`contacts`: all contacts of the state, `net` their network;
// rattlers and their contacts are removed). Throws std::invalid_argument for inconsistent input.
ResponseProblem response_problem(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net);
// Solves it with the chosen solver and verifies the residual on all non-rattler rows. A factorisation
// that fails even regularised, or a preconditioner that cannot be built: NoResultError.
Relaxation relax(const ResponseProblem& problem, const ModuliOptions& options = {});
// Stress slopes, energy stiffness, moduli and shear directions along the relaxed path.
ElasticResponse elastic_response(const ResponseProblem& problem, const Relaxation& relaxation);

// Throws NoResultError (one line beginning with `what`, the packing's name, and saying what to try)
// when a response that is not a saddle has no relaxed moduli to report: an unjammed packing (no
// load-bearing network: N_nr = 0, every cell a rattler, so no rigid backbone), or a relaxation that
// did not converge (not well_posed, or a modulus not finite). A response with unstable modes (a saddle or
// a contact-bounded minimum: linear_response() false) is left to the caller, which reports its affine response.
void require_relaxed_moduli(const ElasticResponse& e, const std::string& what);

// The response of a relaxed packing: the three steps above. A packing whose Hessian has negative
// eigenvalues is a result, not an error: kernel.method unstable, kernel.unstable_modes > 0, the
// relaxed response NaN, the affine one finite, and `stationary` says whether it is a saddle or a
// contact-bounded minimum.
ElasticResponse elastic_response(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 const ModuliOptions& options = {});

}  // namespace budjam
