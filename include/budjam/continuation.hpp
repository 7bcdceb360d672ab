#pragma once
// Continuation of a relaxed branch under growth (docs/jamming.md). Between contact
// events the relaxed state x*(t) of a packing whose bud sizes change with a parameter t is smooth:
// it is followed by a linear-response predictor and a Newton corrector instead of relaxing each
// state from scratch with FIRE, whose cost near jamming grows as the lowest Hessian eigenvalue
// falls.
//
// The path of sizes (BranchSizes): every cell's area grows linearly in t from the sizes at t = 0 to
// those at t = 1, D² + b(t)² = (1 − t)(D² + b₀²) + t(D² + b₁²). A growth step does exactly that to
// the cells it grows (grow_step: area linear in Δt), so t is an affine function of Δt between two
// trials grown from the same state with the same divisions.
//
// Along the branch F(q, t) = 0, so dq/dt = H⁻¹ ∂F/∂t (H = ∂²U/∂q², F = −∂U/∂q): the tangent. It is
// solved on the non-rattler cells, with H + μ1 (μ = tangent_shift) so that the exact zero modes
// (global translations, a bud free to turn about its mother) stay regular; a factorisation of it
// that fails is the network losing stability (a negative pivot). Each step moves q along the
// tangent, sets the sizes of the new t and corrects with Newton (newton_finish, with its factor
// kept while the contacts stay), halving the step when the corrector fails. An accepted step whose
// network (the contacts with a force above the corrector's tolerance) differs from the previous
// point's is an event: a contact opened (its force reached zero) or closed (a new overlap). With event_tol > 0 a step
// containing one is halved until it is at most event_tol long, so the event's t is known within event_tol.
// Where the branch ends (a fold, or an opening that leaves the network unstable) a minimiser may cross
// to the next branch (ContinuationParams::rearrangement).
#include "budjam/cholmod_solver.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/newton.hpp"
#include "budjam/packing.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace budjam {

// Bud sizes along the path t ∈ [0, 1] (area linear in t; exact at both ends).
struct BranchSizes {
  std::vector<double> from, to;  // b at t = 0 and t = 1, one per cell
  std::vector<double> at(double t) const;
  // db/dt at t (the bud must not vanish: b > 0).
  std::vector<double> rate(double t) const;
};

// ∂F/∂t at fixed q: the generalised forces' response to the growth of the buds (their radii and the
// lobe offsets from the centroid), from the contacts of p as it is (sizes at t). Analytic.
Eigen::VectorXd force_rate(const Packing& p, const std::vector<Contact>& contacts, const std::vector<double>& b_rate);
// The same by a central difference of the forces, (F(t + h) − F(t − h)) / 2h, at fixed q.
Eigen::VectorXd force_rate_difference(const Packing& p, ForceField& field, const BranchSizes& sizes, double t,
                                      double h);

// The tangent dq/dt = H⁻¹ ∂F/∂t of the branch through p (relaxed, `contacts` its contacts, buds
// growing at `b_rate`), solved with H + shift·1 on the non-rattler cells (zero on the rattlers).
// false (dq unusable) if that matrix is not positive definite: p is not a stable minimum.
bool branch_tangent(const Packing& p, const std::vector<Contact>& contacts, const std::vector<double>& b_rate,
                    double shift, CholmodSolver& solver, Eigen::VectorXd& dq);

enum class BranchEnd {
  reached,         // the relaxed state at t = 1
  energy_floor,    // U fell below ContinuationParams::energy_floor (certainly below a jamming window)
  stability_lost,  // H lost positive definiteness on the non-rattlers: the branch ends in a rearrangement
  step_underflow,  // the corrector failed down to min_step for another reason
  step_cap,        // max_steps steps without reaching t = 1
};
const char* to_string(BranchEnd end);

struct ContinuationParams {
  double force_tol = kDefaultForceTol;  // the corrector's (never below force_resolution)
  double energy_floor = 0.0;            // total U: ends the branch when U falls below it
  double first_step = 0.25;             // first step in t
  double min_step = 1e-9;               // smallest step before the branch is given up
  double event_tol = 0.0;               // > 0: steps that change the contacts are halved down to this
  double tangent_shift = 1e-10;         // μ of the tangent's H + μ1
  int corrector_iterations = 12;        // Newton iterations per step (factorisations and chord steps)
  long max_steps = 10000;
  // Where the branch ends (the corrector fails down to min_step, or the network loses stability),
  // with a minimiser: the packing is relaxed by it crossing_step further along the path at fixed
  // sizes (a rearrangement) and the branch goes on from that minimum. Without one the branch ends.
  std::optional<FireParams> rearrangement;
  double crossing_step = 1e-2;
};

struct BranchEvent {
  enum class Kind { opening, closing };
  Kind kind;
  double t;            // first point of the branch after the event (within event_tol of it)
  std::uint32_t i, j;  // the lobes
};

struct ContinuationResult {
  BranchEnd end = BranchEnd::step_cap;
  double energy = 0;        // U at the last relaxed point
  double t = 0;             // the last relaxed point on the branch
  long steps = 0;           // accepted steps
  long rejected_steps = 0;  // halved for a failed corrector or to locate an event
  long factorisations = 0;  // tangents and corrector refactorisations
  long chord_steps = 0;
  long evaluations = 0;                // force evaluations
  long rearrangements = 0;             // crossings relaxed by the minimiser
  long rearrangement_evaluations = 0;  // their force evaluations (among `evaluations`)
  std::vector<BranchEvent> events;
};

// From p relaxed with sizes sizes.at(t0) (a minimum: forces below the tolerance), follows the
// relaxed branch to t = 1. On return p is the last relaxed point of the branch, with the sizes of
// result.t, and `field` is current for it.
ContinuationResult follow_branch(Packing& p, ForceField& field, const BranchSizes& sizes,
                                 const ContinuationParams& params, double t0 = 0.0);

// The start of a trial's relaxation from the relaxed state `relaxed` of the same cells at other bud
// sizes: follows the branch from `relaxed` to the trial's sizes and moves the trial's coordinates to
// where the branch ended (the relaxed state itself when it reached them; otherwise the last point
// before a stability loss, from which a minimiser goes on). Requires the same cells in both.
ContinuationResult start_on_branch(Packing& trial, const Packing& relaxed, ForceField& field,
                                   const ContinuationParams& params);

}  // namespace budjam
