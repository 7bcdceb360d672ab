#pragma once
// A run's description, validated: what to grow, how precisely, and what to observe.
// Plain data; the member initialisers are the defaults. Every field a scene file sets has a row in
// the knob table (scene_keys.hpp); the TOML reader lives in tools/io (the library knows nothing of
// files).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>
#include "budjam/errors.hpp"
#include "budjam/fire.hpp"

namespace budjam {

enum class DivisionRule { random, aligned, opposite };
enum class InitialState { two_cells, random_seeds };
// How a growth step is chosen near φ_J and the Δφ targets (docs/jamming.md).
// bisection: the paper's protocol, halve Δt after every overshoot, restart from the nominal Δt.
// secant: aim each trial at the middle of the jamming window by extrapolating √(E/N), which grows
// linearly in φ − φ_J, and land a target by solving φ(Δt) = φ_J + Δφ before relaxing.
// bracket: as secant, but φ_J is bracketed in Δt from a fixed accepted state: a trial below the
// jamming window only raises the lower end (its relaxation stops at E/N < ε_U) and is not accepted.
enum class JammingSearch { bisection, secant, bracket };

// Where an on-demand computation (moduli, DOS) is made along a run.
struct Schedule {
  bool at_jamming = false;
  bool at_phi2 = false;
  bool at_targets = false;
  long every = 0;  // every k accepted steps above jamming; 0 = never
  bool any() const { return at_jamming || at_phi2 || at_targets || every > 0; }
};

// The most threads a force evaluation may ask for: beyond the cores of any node, and below what a
// thread library fails to create (which ends the process where no error can be reported).
inline constexpr int kMaxThreads = 1024;

struct Scene {
  std::string name = "unnamed";
  std::uint64_t seed = 1;

  // [box]
  double L = 8.0;

  // [cells]
  double r0 = 0.002;     // mean innate rate
  double delta = 0.4;    // spread of γ0 = r0 (1 + δ (U − 1/2))
  double alpha0 = 1.01;  // newborn aspect ratio
  DivisionRule division = DivisionRule::random;

  // [init]
  InitialState init = InitialState::two_cells;
  std::size_t n_seeds = 0;  // cells placed at random for InitialState::random_seeds

  // [growth]
  std::optional<double> P0;  // feedback pressure scale; nullopt = no feedback
  double dt = 1.0;           // nominal growth step
  double dt_min = 1e-12;     // bisection below this is a failure
  long max_steps = 2000000;  // growth steps (accepted + rejected) before failing
  // Adaptive growth step (docs/growth.md; off = the paper's protocol). Above
  // jamming with feedback, strongly compressed buds grow at γ0·exp(−p/P0) ≪ γ0, so Δt = 1 barely
  // moves φ. With adaptive_dt every step (before any bisection halving) starts from
  // Δt = dt / max(g_max, adaptive_floor), g_max = max_i exp(−p_i/P0): the fastest-growing cell
  // then gains the same relative area γ0_i·dt as in a nominal step. The floor bounds Δt by
  // dt / adaptive_floor; 0 = no bound (the step is taken in log space beyond the double range).
  bool adaptive_dt = false;
  double adaptive_floor = 1e-6;  // in [0, 1]

  // [jamming]
  double epsilon_U = 1e-16;        // E/N below this: unjammed
  double target_tolerance = 5e-9;  // |φ − (φ_J + Δφ)| on landing
  std::vector<double> targets;     // Δφ, strictly increasing, > 0
  bool continue_to_phi2 = false;   // keep growing past the last target until φ_2 is found
  double max_dphi = 0.2;           // ... but never beyond φ_J + max_dphi
  // φ_2 is the first accepted state after jamming with at most this many tagged buds still
  // unconstrained: 1 is budjam's reading of u(φ_2) = ε ~ 1/N_nr,J, 0 the paper's "none left".
  std::size_t phi2_tagged_left = 1;
  // A jamming candidate (ε_U ≤ E/N ≤ 2ε_U) whose Hessian has an unstable mode is a saddle FIRE
  // stopped on: relax it to FIRE's force resolution, step off along its unstable mode where FIRE stops
  // on it again, and classify it again (docs/growth.md).
  bool check_minimum = true;
  JammingSearch search = JammingSearch::bracket;
  // Bracket search: collapse the bracket at once when the line through its two lowest overshoots,
  // both close to its lower end, meets that end at s = √(E/N) above jump_factor × √(2ε_U): s jumps
  // across the window there, and further trials would only creep down onto the jump
  // (docs/jamming.md). 0 = only the bracket's width decides.
  double jump_factor = 3.0;
  // Bracket search: a trial starts from the lowest overshoot's relaxed configuration also when that
  // overshoot's larger step divided more cells (they are put back together from their newborns);
  // false = only when both divided the same cells (docs/jamming.md).
  bool start_across_divisions = true;
  // Bracket search: FIRE iterations a trial inside the bracket may spend before it is set aside as
  // a deferred upper end (relaxed on only if the bracket closes in on it; docs/growth.md, "Jamming
  // search"). 0 = every trial relaxed to convergence, the default: at L = 100 a budget of 2·10⁵
  // cut one seed's search 4.7 times in force evaluations and made another's slower.
  long trial_budget = 0;
  // Bracket search: a trial that starts from the lowest overshoot with the same divisions follows
  // the overshoot's relaxed branch down to its own sizes by continuation (continuation.hpp) before
  // FIRE (docs/jamming.md). false = FIRE from the overshoot's positions.
  bool continuation = false;
  // With continuation: where the branch ends (a stability loss), FIRE relaxes the packing this much
  // further along the trial's path of sizes (a rearrangement) and the branch goes on from there
  // (continuation.hpp). 0 = the branch ends and FIRE relaxes at the trial's sizes.
  double crossing_step = 0;

  // [minimiser]: the library's defaults are the scene's (fire.hpp).
  FireParams fire;
  double skin = kDefaultSkin;  // Verlet skin (cell_list.hpp)
  int threads = 1;  // of each force evaluation (ForceField); 0 = one per core. Not physics: results are identical.

  // [observe]
  bool bud_events = true;
  bool rigidity_events = false;
  bool trials = false;  // trials.csv: every relaxed growth attempt, accepted or not
  Schedule moduli;
  Schedule dos;
  long checkpoint_every = 100;  // accepted steps between checkpoints; 0 = none (a signal still writes one)
  // Force evaluations of one relaxation between the checkpoints inside it (a marginal relaxation of a
  // large packing runs for hours); 0 = none (a signal still writes one). 10⁵ = kMarginalEvaluations.
  long checkpoint_evaluations = 100000;
  long trajectory_every = 0;  // accepted steps between trajectory frames (and at events); 0 = none
  bool progress = true;
};

// Throws InputError naming the first offending key.
void validate(const Scene& scene);

}  // namespace budjam
