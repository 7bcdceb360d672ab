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
//
// Factor reuse (NewtonWorkspace): in the arrested regime far above jamming consecutive growth steps
// minimise nearly the same packing with the same contacts, and H barely changes between them. A
// factor of H + μ1 is then kept as a fixed approximation of the Hessian (modified Newton, "chord"
// steps δq = K⁻¹ F) while the contacts are those it was factored with and every step shrinks the
// force norm by at least `chord_contraction`; otherwise H is refactored at the current iterate. The
// symbolic analysis (fill-reducing ordering) is reused whenever H's sparsity pattern is unchanged.
// The stopping test is the same force tolerance either way.
#include "budjam/cholmod_solver.hpp"
#include "budjam/energy.hpp"
#include "budjam/packing.hpp"

#include <cstdint>
#include <utility>
#include <vector>

namespace budjam {

enum class NewtonStop {
  converged,     // largest force below the tolerance, or U below the energy floor
  indefinite,    // H + μ1 not positive definite
  line_search,   // no step along δq lowered the force norm
  iteration_cap  // max_iterations Newton steps without converging
};
const char* to_string(NewtonStop stop);

// The force tolerance of both minimisers (FireParams::force_tol, minimiser.force_tol): below the
// force resolution of double precision for L ≥ 3, so that a relaxation goes to the rounding floor;
// on the accuracy-against-cost front, where 1e-12 is not (docs/minimiser.md, "Newton finish").
inline constexpr double kDefaultForceTol = 1e-14;

struct NewtonParams {
  double force_tol = kDefaultForceTol;  // same meaning as FireParams::force_tol (θ component as τ / r_g)
  double energy_floor = 0.0;            // total U below which the packing counts as relaxed
  long max_iterations = 20;
  double shift = 4.0;  // μ / (largest generalised force)
  bool reuse_factor = true;
  double chord_contraction = 0.25;  // a chord step must multiply the force norm by less than this
};

// The factor one Newton finish leaves for the next, with the contacts it was computed for.
struct NewtonWorkspace {
  CholmodSolver solver;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> network;  // lobe pairs in contact
  bool factored = false;
  // Forget the factor (the symbolic analysis too), e.g. where a resumed run starts without one.
  void clear();
};

struct NewtonResult {
  NewtonStop stop = NewtonStop::iteration_cap;
  long iterations = 0;   // Newton steps with a fresh factorisation of H + μ1
  long chord_steps = 0;  // steps with a factor kept from an earlier iterate (no factorisation)
  long evaluations = 0;  // force evaluations (including rejected line-search points)
  double energy = 0.0;
  double max_force = 0.0;  // at the end, θ component as τ / r_g
};

// Newton iterations from p (which should be close to a minimum). On any stop p holds the last
// accepted iterate, whose force norm is never above the starting one, and `field` is current for it.
// `workspace` supplies a factor to reuse (if params.reuse_factor) and keeps the last one.
NewtonResult newton_finish(Packing& p, ForceField& field, const NewtonParams& params, NewtonWorkspace& workspace);
// The same with a fresh workspace: every step factors H + μ1.
NewtonResult newton_finish(Packing& p, ForceField& field, const NewtonParams& params);

// The largest generalised force component with the torque scaled to a force, τ / r_g: the
// quantity both minimisers compare with their force tolerance.
double max_scaled_force(const Packing& p, const Eigen::VectorXd& force);

}  // namespace budjam
