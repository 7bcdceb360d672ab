#pragma once
// Second-order finish of an energy minimisation (docs/minimiser.md, "Newton finish"). Close to a
// minimum of U = Σ (k/2)(σ − r)² the energy is a quadratic form in the displacements as long as
// the contact network does not change, so Newton steps with the analytic Hessian (hessian.hpp)
// converge quadratically where FIRE, a first-order method, needs thousands of iterations through
// the soft modes of a marginal packing.
//
// Each iteration re-lists the contacts, factors H + μ1 with CHOLMOD (LLᵀ) and moves along
// δq = (H + μ1)⁻¹ F. The shift μ = newton_shift × (largest generalised force) regularises the exact
// zero modes (global translations, rattlers, rotations of a contact-free bud about its mother)
// along which F vanishes, and tends to 0 with the force, so convergence stays quadratic. A step is
// accepted when it lowers the force norm; it is halved up to kMaxHalvings times otherwise.
// Newton gives up (the caller continues with FIRE) when H + μ1 is not positive definite (a saddle
// or a contact change made the quadratic model wrong) or when no halving lowers the force.
#include "budjam/energy.hpp"
#include "budjam/packing.hpp"

namespace budjam {

enum class NewtonStop {
  converged,     // largest force below the tolerance, or U below the energy floor
  indefinite,    // H + μ1 not positive definite
  line_search,   // no step along δq lowered the force norm
  iteration_cap  // max_iterations Newton steps without converging
};
const char* to_string(NewtonStop stop);

struct NewtonParams {
  double force_tol = 1e-12;   // same meaning as FireParams::force_tol (θ component as τ / r_g)
  double energy_floor = 0.0;  // total U below which the packing counts as relaxed
  long max_iterations = 20;
  double shift = 4.0;  // μ / (largest generalised force)
};

struct NewtonResult {
  NewtonStop stop = NewtonStop::iteration_cap;
  long iterations = 0;   // factorisations
  long evaluations = 0;  // force evaluations (including rejected line-search points)
  double energy = 0.0;
  double max_force = 0.0;  // at the end, θ component as τ / r_g
};

// Newton iterations from p (which should be close to a minimum). On any stop p holds the last
// accepted iterate, whose force norm is never above the starting one, and `field` is current for it.
NewtonResult newton_finish(Packing& p, ForceField& field, const NewtonParams& params);

// The largest generalised force component with the torque scaled to a force, τ / r_g: the
// quantity both minimisers compare with their force tolerance.
double max_scaled_force(const Packing& p, const Eigen::VectorXd& force);

}  // namespace budjam
