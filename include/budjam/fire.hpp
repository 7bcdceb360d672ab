#pragma once
// FIRE 2.0 energy minimisation (Guénolé et al., Comput. Mater. Sci. 175, 109584 (2020)) over
// (x, y, θ̃) with θ̃ = r_g θ, so every coordinate is a length. docs/minimiser.md explains the
// stopping rule and the choice of parameters.
#include "budjam/energy.hpp"
#include "budjam/newton.hpp"
#include "budjam/packing.hpp"

#include <functional>

namespace budjam {

struct FireParams {
  double dt_start = 0.1;
  double dt_max = 0.4;  // ≈ 2/3 of the stability limit 2/√λ_max (λ_max ≈ 11–13 in these packings)
  double dt_min = 1e-3;
  int n_delay = 5;
  double f_inc = 1.1;
  double f_dec = 0.5;
  double alpha_start = 0.1;
  double f_alpha = 0.99;
  // Stopping rule (docs/minimiser.md): the packing is relaxed when the largest generalised
  // force component (x, y, and τ/r_g) is below max(force_tol, force_resolution(p)), or when E/N is
  // below energy_floor (then it is certainly unjammed: the minimum lies below the jamming
  // threshold ε_U > energy_floor).
  double force_tol = kDefaultForceTol;
  double energy_floor = 1e-20;
  // A safety net, not a tolerance: near jamming a single relaxation of a large packing can take
  // millions of iterations (an L = 100 search trial, N = 7 627: 5.27·10⁶; docs/minimiser.md).
  long max_iterations = 10000000;
  // Second-order finish (newton.hpp): once the largest force falls below newton_force, Newton
  // steps with the analytic Hessian take over; FIRE resumes if they give up (and Newton is tried
  // again only after FIRE has lowered the force tenfold). 0 = FIRE alone. 1e-8 finishes above
  // jamming for 5–10 % fewer force evaluations than FIRE alone, with the same results
  // (docs/minimiser.md, "Newton finish").
  double newton_force = 1e-8;
  // Keep a Newton factor as a modified-Newton approximation of H while the contacts do not change
  // (newton.hpp), across minimisations when the caller passes a NewtonWorkspace.
  bool newton_reuse = true;
  // Active-set Gauss–Newton steps (active_set.hpp) once a minimisation has spent this many force
  // evaluations without converging, and again after twice, four times … as many more: the
  // second-order way through a marginal relaxation, where FIRE creeps from one contact change to
  // the next. 0 = FIRE alone. 1e5, the summary's "marginal relaxation", leaves every relaxation
  // FIRE finishes sooner bit for bit FIRE's (at L = 15 every jamming point of 300 seeds) and cuts the
  // creeps that set a large run's cost (docs/minimiser.md, "Active-set steps").
  long active_set_after = 100000;
  // One speculative active-set try after this many force evaluations (< active_set_after; 0 = no
  // try), for the relaxations that creep into a jammed minimum next to their start: decompressions
  // a hair above the jamming window, whose steps move lobes by 10⁻⁶–3·10⁻³ and converge in tens of
  // linearisations where FIRE spends 10⁵ evaluations. The try is given up at the first step that
  // would move a lobe by more than active_set_try_move × the neighbour list's skin (a
  // rearrangement, which FIRE crosses better than the steps' model), and when it does not end at a
  // minimum the minimisation goes on exactly as if it had not been made: only its cost remains
  // (docs/minimiser.md, "Active-set steps").
  long active_set_try_after = 10000;
  double active_set_try_move = 1.0 / 32.0;
};

// Why a minimisation stopped.
enum class MinimiserStop {
  force,          // largest generalised force below the tolerance
  energy_floor,   // E/N below energy_floor (certainly unjammed)
  iteration_cap,  // max_iterations FIRE iterations without either
};
const char* to_string(MinimiserStop stop);

struct FireResult {
  MinimiserStop stop = MinimiserStop::iteration_cap;
  bool converged = false;              // stop != iteration_cap
  long iterations = 0;                 // FIRE iterations
  long newton_iterations = 0;          // Newton steps (one Hessian factorisation each)
  long newton_chord_steps = 0;         // Newton steps with a reused factor
  long active_set_steps = 0;           // active-set linearisations (active_set.hpp)
  long active_set_factorisations = 0;  // their LDLᵀ factorisations
  long active_set_updates = 0;         // their rank-1 factor changes
  long active_set_tries_undone = 0;    // speculative tries undone (their steps are counted above)
  long evaluations = 0;                // force evaluations made by this call
  double energy = 0.0;                 // U at the end
  double max_force = 0.0;              // largest |F| component at the end (θ component as F_θ / r_g)
};

// Where a minimisation stands before one of its FIRE iterations: with the packing's coordinates,
// everything the rest of it depends on (the neighbour list's origin included), so that minimise()
// resumed from it ends in the bits it would have reached without the stop (a growth run's
// checkpoint inside a long relaxation: docs/growth.md, "Checkpoints and resume").
struct FireProgress {
  FireResult so_far;   // the counters up to here (stop, energy and max_force unused)
  long iteration = 1;  // the FIRE iteration about to be made
  Eigen::VectorXd v;   // velocities in the scaled coordinates (x, y, θ̃ = r_g θ)
  double dt = 0, alpha = 0;
  long n_positive = 0;      // consecutive steps with F·v > 0
  double tol = 0;           // the force tolerance, fixed at the start from the start's extent
  double newton_below = 0;  // the Newton finish is tried when the largest force falls below this
  long next_try = 0, next_active_set = 0, active_set_tries = 0;  // the active-set schedule
  long undone = 0;                                               // evaluations of undone tries
  NeighbourList::Origin neighbours;
};

// Checkpoints inside a minimisation. Before a FIRE iteration, once `every` more force evaluations
// have been made since the last checkpoint (or the start; 0 = never) or when `requested()` says so
// (a signal), `save` receives the packing and the progress; `save` may throw to end the
// minimisation. Never while the Newton workspace keeps a factor, which the progress does not hold.
// With `resume`, minimise goes on from that progress, p holding the coordinates saved with it.
struct FireCheckpoints {
  long every = 0;
  std::function<bool()> requested;
  std::function<void(const Packing&, const FireProgress&)> save;
  const FireProgress* resume = nullptr;
};

// Relaxes p in place. A centroid lying more than L/2 outside the box is first moved back by whole
// periods (a deterministic relabelling of images that leaves U unchanged); no other wrapping.
// `newton` (optional) carries the Newton factor from one minimisation to the next.
FireResult minimise(Packing& p, ForceField& field, const FireParams& params = {}, NewtonWorkspace* newton = nullptr,
                    const FireCheckpoints* checkpoints = nullptr);

// The smallest force FIRE can resolve in double precision: 16 ε k × (the larger of L and the
// largest |coordinate|), since lobe positions, hence overlaps, carry rounding errors of a few
// ulps of the coordinates. The effective force tolerance never goes below it.
double force_resolution(const Packing& p);

}  // namespace budjam
