#pragma once
// Active-set Gauss–Newton minimisation of U = (k/2) Σ [δ_c]₊² (δ = σ − r, the overlap of a listed
// pair of lobes) at fixed sizes: the second-order method for the marginal relaxations that FIRE
// creeps through (docs/minimiser.md, "Active-set steps").
//
// Near marginal jamming a relaxation is a path of contact changes: weak contacts open, pairs a
// hair apart (gaps of 10⁻⁸–10⁻⁷) close, and a first-order minimiser escapes one shallow saddle
// after another. Newton on the current contacts fails there (its quadratic model ignores the pairs
// about to close). Each step here linearises every listed pair, δ_c(q + u) ≈ δ_c + g_cᵀu with
// g_c = ∂δ_c/∂q = −nᵀ J_c, and minimises the convex piecewise-quadratic model
//
//     m(u) = (k/2) Σ_c [δ_c + g_cᵀu]₊² + (μ/2) uᵀDu        (D: 1 on x, y and r_g² on θ)
//
// over all listed pairs, open or closed: the pairs that would close on the way are in the model.
// m is minimised exactly by a semismooth Newton iteration on its active set {c : δ_c + g_cᵀu > 0}
// with an exact line search along each Newton direction (m is convex along it). Between two of
// its iterations the set changes by a few contacts; the factor of μD + k Σ_active g gᵀ is then
// updated by rank-1 terms (CholmodSolver::update) instead of factored again; a fresh factor is
// supernodal where that pays (Factorisation::updatable: large packings), and its fill-reducing
// ordering is the one made for all listed pairs, kept while the neighbour list stays. The model drops the
// prestress part of the Hessian (the Gauss–Newton approximation of this least-squares energy), so
// it is convex for every μ > 0 and its minimiser is unique. Levenberg–Marquardt control of μ: a
// step is taken when it lowers U, and μ shrinks when U falls as the model predicted, grows when it
// does not; a step that would move a lobe further than a quarter of the neighbour list's skin is
// shortened to that (the model lists only the pairs within the skin).
//
// The method returns a packing at which FIRE (and its Newton finish) converge at once when the
// model's minimum is the energy's; it never raises U.
#include "budjam/energy.hpp"
#include "budjam/packing.hpp"

namespace budjam {

struct ActiveSetParams {
  double force_tol = 0.0;     // stop when the largest scaled force (θ as τ / r_g) is below this
  double energy_floor = 0.0;  // stop when the total U is below this (certainly unjammed)
  double damping = 1e-4;      // μ of the first step, in units of k
  long max_steps = 100;       // Levenberg–Marquardt steps (one linearisation each)
  long max_inner = 60;        // semismooth Newton iterations per step
  int max_refused = 4;        // consecutive steps that did not lower U before giving up
  // Changes of the active set up to which its factor is updated by rank-1 terms; more are a fresh
  // factorisation. < 0: active_set_max_updates of the number of dofs; 0: a fresh factor at every change.
  long max_updates = -1;
  // > 0: give up (ActiveSetStop::long_step) at the first step whose model minimiser would move a
  // lobe further than this, before taking it. Such a step is a rearrangement, whose prestress the
  // model leaves out; FIRE's speculative try (fire.hpp) hands those back.
  double give_up_move = 0.0;
};

// The break-even number of changes between updating a factor of n dofs and making it afresh:
// max(64, √n / 3). A refactorisation of a 2D contact network costs ∝ n^1.5 (nested dissection);
// the optimum count was measured flat over 64–128 changes at n = 2.3·10⁴ and 128–512 at 2.1·10⁵
// (docs/speed.md), so it grows as √n. 64 up to n = 36 864 (12 288 cells).
long active_set_max_updates(long n);

enum class ActiveSetStop {
  converged,     // largest force below force_tol
  energy_floor,  // U below the floor
  stalled,       // max_refused steps in a row did not lower U (the rounding floor, or a saddle)
  step_cap,      // max_steps steps
  long_step      // a step would have moved a lobe further than give_up_move
};
const char* to_string(ActiveSetStop stop);

struct ActiveSetResult {
  ActiveSetStop stop = ActiveSetStop::step_cap;
  long steps = 0;           // linearisations (accepted or refused)
  long inner = 0;           // semismooth Newton iterations, all steps
  long factorisations = 0;  // LDLᵀ factorisations
  long updates = 0;         // rank-1 changes of a factor (a contact entering or leaving the set)
  long evaluations = 0;     // force evaluations
  double energy = 0.0;
  double max_force = 0.0;
};

// Minimises U from p in place at fixed sizes; `field` is current for p on return.
ActiveSetResult active_set_minimise(Packing& p, ForceField& field, const ActiveSetParams& params);

}  // namespace budjam
