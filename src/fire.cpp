// FIRE 2.0 (Guénolé et al., Comput. Mater. Sci. 175, 109584 (2020), Algorithm 2 with the
// semi-implicit Euler integrator) over the scaled coordinates (x, y, θ̃ = r_g θ).
#include "budjam/fire.hpp"

#include "budjam/active_set.hpp"
#include "budjam/newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace budjam {

namespace {

// Brings a centroid that has wandered more than half a box outside the primary box back by whole
// periods (Lees–Edwards: a shift of k boxes in y moves x by k γL). Only far-out centroids move, so
// ordinary runs keep continuous coordinates, while coordinates stay O(L) and the force resolution
// (∝ ulp of the coordinates) does not degrade in very long runs. The energy is unchanged.
void wrap_far_centroids(Packing& p) {
  const double L = p.box.L;
  for (std::size_t i = 0; i < p.size(); ++i) {
    double& x = p.q[3 * i];
    double& y = p.q[3 * i + 1];
    if (y < -0.5 * L || y >= 1.5 * L) {
      const double k = std::floor(y / L);
      y -= k * L;
      x -= k * p.box.shear * L;
    }
    if (x < -0.5 * L || x >= 1.5 * L) x -= std::floor(x / L) * L;
  }
}

}  // namespace

const char* to_string(MinimiserStop stop) {
  switch (stop) {
    case MinimiserStop::force: return "force";
    case MinimiserStop::energy_floor: return "energy_floor";
    case MinimiserStop::iteration_cap: return "iteration_cap";
  }
  return "?";
}

double force_resolution(const Packing& p) {
  double extent = p.box.L;
  for (std::size_t i = 0; i < p.size(); ++i) extent = std::max({extent, std::abs(p.x(i)), std::abs(p.y(i))});
  return 16.0 * std::numeric_limits<double>::epsilon() * kSpring * extent;
}

FireResult minimise(Packing& p, ForceField& field, const FireParams& prm, NewtonWorkspace* newton_workspace,
                    const FireCheckpoints* checkpoints) {
  FireResult res;
  const std::size_t n = p.size();
  if (n == 0) {
    res.stop = MinimiserStop::energy_floor;
    res.converged = true;
    return res;
  }
  const FireProgress* resume = checkpoints ? checkpoints->resume : nullptr;
  if (resume && resume->v.size() != static_cast<Eigen::Index>(3 * n))
    throw std::invalid_argument("minimise: a progress of " + std::to_string(resume->v.size() / 3) + " cells for " +
                                std::to_string(n) + " cells");
  // Resumed, the coordinates are the progress's: wrapped at the start, and moved only by FIRE since.
  if (!resume) wrap_far_centroids(p);

  const Eigen::Index m = static_cast<Eigen::Index>(3 * n);
  std::vector<double> rg(n), inv_rg(n);
  for (std::size_t i = 0; i < n; ++i) {
    rg[i] = p.dumbbell(i).gyration;
    inv_rg[i] = 1.0 / rg[i];
  }
  const double tol = resume ? resume->tol : std::max(prm.force_tol, force_resolution(p));
  const double floor_total = prm.energy_floor * static_cast<double>(n);

  Eigen::VectorXd F(m), v = Eigen::VectorXd::Zero(m);
  double* q = p.q.data();
  double* f = F.data();
  double* vel = v.data();

  // Forces on the scaled coordinates: F_θ̃ = τ / r_g. Returns the largest |component|.
  auto scale_forces = [&]() {
    double fmax = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      f[3 * i + 2] *= inv_rg[i];
      fmax = std::max({fmax, std::abs(f[3 * i]), std::abs(f[3 * i + 1]), std::abs(f[3 * i + 2])});
    }
    return fmax;
  };
  // x̃ += h v in scaled coordinates: θ moves by h v_θ̃ / r_g.
  auto move = [&](double h) {
    for (std::size_t i = 0; i < n; ++i) {
      q[3 * i] += h * vel[3 * i];
      q[3 * i + 1] += h * vel[3 * i + 1];
      q[3 * i + 2] += h * vel[3 * i + 2] * inv_rg[i];
    }
  };
  // v ← a v + c F, then the move by h, in one pass over the cells (element by element the same
  // arithmetic as the two passes).
  auto mix_and_move = [&](double a, double c, double h) {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = 3 * i; k < 3 * i + 2; ++k) {
        vel[k] = a * vel[k] + c * f[k];
        q[k] += h * vel[k];
      }
      vel[3 * i + 2] = a * vel[3 * i + 2] + c * f[3 * i + 2];
      q[3 * i + 2] += h * vel[3 * i + 2] * inv_rg[i];
    }
  };
  // A NaN force never satisfies a tolerance: the run then ends at max_iterations, not converged.
  auto stopped = [&](double U, double fmax) {
    if (U < floor_total)
      res.stop = MinimiserStop::energy_floor;  // the more telling reason when both hold
    else if (fmax < tol)
      res.stop = MinimiserStop::force;
    else
      return false;
    res.converged = true;
    return true;
  };

  if (resume) field.restore_neighbours(p, resume->neighbours);
  double U = field.evaluate(p, F);  // a resumed minimisation counted this evaluation before its stop
  if (!resume) ++res.evaluations;
  double fmax = scale_forces();

  double dt = prm.dt_start;
  double alpha = prm.alpha_start;
  long n_positive = 0;
  double newton_below = prm.newton_force;  // Newton is tried when fmax falls below this
  NewtonParams newton{tol, floor_total};
  newton.reuse_factor = prm.newton_reuse;
  std::optional<NewtonWorkspace> own_workspace;
  constexpr long kNever = std::numeric_limits<long>::max();
  long next_active_set = prm.active_set_after > 0 ? prm.active_set_after : kNever;
  long active_set_tries = 0;
  // active_set_after = 0 is FIRE alone: no try either.
  long next_try =
      prm.active_set_after > 0 && prm.active_set_try_after > 0 && prm.active_set_try_after < prm.active_set_after
          ? prm.active_set_try_after
          : kNever;
  // Evaluations of undone tries: the schedule counts the others, so that FIRE's path after an undone
  // try is the path it takes without one.
  long undone = 0;
  long first = 1;
  if (resume) {
    res = resume->so_far;
    first = resume->iteration;
    v = resume->v;
    dt = resume->dt;
    alpha = resume->alpha;
    n_positive = resume->n_positive;
    newton_below = resume->newton_below;
    next_try = resume->next_try;
    next_active_set = resume->next_active_set;
    active_set_tries = resume->active_set_tries;
    undone = resume->undone;
  }
  const long every = checkpoints ? checkpoints->every : 0;
  long next_checkpoint = every > 0 ? res.evaluations + every : kNever;
  auto offer_checkpoint = [&](long it) {
    if (!checkpoints->save || (newton_workspace && newton_workspace->factored)) return;
    if (res.evaluations < next_checkpoint && !(checkpoints->requested && checkpoints->requested())) return;
    next_checkpoint = every > 0 ? res.evaluations + every : kNever;
    checkpoints->save(p, FireProgress{res, it, v, dt, alpha, n_positive, tol, newton_below, next_try, next_active_set,
                                      active_set_tries, undone, field.neighbours().origin()});
  };
  // FIRE resumes from rest at the packing a second-order method left (the field is current for it).
  auto restart_fire = [&]() {
    U = field.evaluate(p, F);
    ++res.evaluations;
    fmax = scale_forces();
    v.setZero();
    dt = prm.dt_start;
    alpha = prm.alpha_start;
    n_positive = 0;
  };
  auto active_set = [&](const ActiveSetParams& as) {
    const ActiveSetResult ar = active_set_minimise(p, field, as);
    res.active_set_steps += ar.steps;
    res.active_set_factorisations += ar.factorisations;
    res.active_set_updates += ar.updates;
    res.evaluations += ar.evaluations;
    return ar;
  };
  for (long it = first; !stopped(U, fmax); ++it) {
    if (checkpoints) offer_checkpoint(it);
    if (res.evaluations - undone >= next_try) {
      next_try = kNever;
      const Eigen::VectorXd q0 = p.q, F0 = F;
      const ForceField field0 = field;
      const ActiveSetResult ar = active_set({.force_tol = tol,
                                             .energy_floor = floor_total,
                                             .give_up_move = prm.active_set_try_move * field.neighbours().skin()});
      // Kept where the steps reached the minimum or the rounding floor of their model (stalled, as
      // at a prestressed minimum: FIRE finishes from there); undone after a long step or the cap.
      if (ar.stop != ActiveSetStop::long_step && ar.stop != ActiveSetStop::step_cap) {
        restart_fire();
        if (stopped(U, fmax)) break;
      } else {
        p.q = q0;  // into p's own buffer, which q points to
        F = F0;
        field = field0;
        undone += ar.evaluations;
        ++res.active_set_tries_undone;
      }
    }
    if (res.evaluations - undone >= next_active_set) {
      active_set({.force_tol = tol, .energy_floor = floor_total});
      restart_fire();
      // Each new hand-over waits twice as long as the last: where the steps stall (a large rearrangement
      // whose prestress the model leaves out), they cost at most a few tries per minimisation.
      // Saturating: a huge active_set_after means never again.
      const int doublings = static_cast<int>(std::min(++active_set_tries, 20L));
      const long wait = prm.active_set_after > (kNever >> doublings) ? kNever : prm.active_set_after << doublings;
      const long counted = res.evaluations - undone;
      next_active_set = wait > kNever - counted ? kNever : counted + wait;
      if (stopped(U, fmax)) break;
    }
    if (fmax < newton_below) {
      if (!newton_workspace) newton_workspace = &own_workspace.emplace();
      const NewtonResult nr = newton_finish(p, field, newton, *newton_workspace);
      res.newton_iterations += nr.iterations;
      res.newton_chord_steps += nr.chord_steps;
      res.evaluations += nr.evaluations;
      U = nr.energy;
      if (nr.stop == NewtonStop::converged) {
        fmax = nr.max_force;
        continue;  // stopped() now holds
      }
      // Back to FIRE from rest at the best Newton iterate (the field is current for it). An
      // indefinite Hessian means FIRE is not near a minimum (typically an unjammed packing whose
      // last overlaps are being pushed apart): Newton is not tried again in this minimisation.
      newton_below = nr.stop == NewtonStop::indefinite ? 0.0 : 0.1 * nr.max_force;
      restart_fire();
    }
    if (it > prm.max_iterations) break;
    res.iterations = it;
    const double power = F.dot(v);
    if (power > 0.0) {
      ++n_positive;
      if (n_positive > prm.n_delay) {
        dt = std::min(dt * prm.f_inc, prm.dt_max);
        alpha *= prm.f_alpha;
      }
    } else {
      n_positive = 0;
      // Half step back: undo half of the last move, which went uphill (FIRE 2.0 inertia correction),
      // with the step that made it.
      move(-0.5 * dt);
      v.setZero();
      if (it > prm.n_delay) {  // no slow-down during the initial delay
        if (dt * prm.f_dec >= prm.dt_min) dt *= prm.f_dec;
        alpha = prm.alpha_start;
      }
    }
    // Semi-implicit Euler with FIRE mixing: v ← v + dt F; v ← (1−α) v + α |v| F̂; x ← x + dt v.
    // The norms stay Eigen reductions (their summation order is Eigen's); the mixing and the
    // move share one pass.
    v += dt * F;
    const double vn = v.norm(), fn = F.norm();
    if (fn > 0.0)
      mix_and_move(1.0 - alpha, alpha * vn / fn, dt);
    else
      move(dt);

    U = field.evaluate(p, F);
    ++res.evaluations;
    fmax = scale_forces();
  }
  res.energy = U;
  res.max_force = fmax;
  return res;
}

}  // namespace budjam
