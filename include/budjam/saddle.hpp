#pragma once
// Leaving a saddle of U. FIRE relaxes a state until its force is resolved, and a stationary point
// whose unstable curvature is λ ≈ −10⁻⁸ (the prestress of a packing a hair above jamming) is left
// only at the rate √|λ| from the rounding-sized displacement it starts with: FIRE can stop on the
// saddle again however far it is asked to relax. The unstable mode itself says where to go: a step
// along it lowers U by ½|λ|s², and a relaxation from there leaves the saddle (docs/growth.md,
// "Jamming candidates that are saddles").
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/packing.hpp"
#include "budjam/stability.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <optional>
#include <vector>

namespace budjam {

struct UnstableMode {
  double lambda = 0;  // the Rayleigh quotient vᵀHv (< −δ of the saddle test)
  Eigen::VectorXd v;  // unit vector
  int factorisations = 0;
  int iterations = 0;  // of inverse iteration
};

// The lowest eigenpair of the symmetric H when it lies below −δ, δ = relative_delta · max|diag H|
// (the saddle test's δ); nullopt when no eigenvalue does. The inertia of LDLᵀ factors of H − σ1
// brackets λ_min between a shift with no eigenvalue below it (σ_lo, from Gershgorin's bound) and
// one with some (−δ); bisection in log|σ| narrows the bracket to a factor 1.25, and inverse
// iteration with the shift σ_lo then converges at the rate (λ_min − σ_lo)/(λ₂ − σ_lo). When two
// unstable eigenvalues share the final bracket the vector is a mixture of their modes, still a
// direction of negative curvature below −δ. Deterministic (a fixed start vector).
std::optional<UnstableMode> lowest_unstable_mode(const Eigen::SparseMatrix<double>& H,
                                                 double relative_delta = kSaddleRelativeDelta);

// The same for a packing: the non-rattler Hessian over the load-bearing contacts (as stability()),
// the mode expanded to all 3N coordinates (zero on the rattlers) and normalised there.
std::optional<UnstableMode> lowest_unstable_mode(const Packing& p, const std::vector<Contact>& contacts,
                                                 const ContactNetwork& net,
                                                 double relative_delta = kSaddleRelativeDelta);

struct SaddleStep {
  bool lowered = false;  // false: no step along ±v lowered U beyond its rounding (p unchanged)
  double s = 0;          // the step taken, signed: q ← q + s v
  double U_before = 0, U_after = 0;
  double U_resolution = 0;  // Σ_c f_c · force_resolution / k: what U resolves at this state
  long evaluations = 0;     // energies evaluated
};

// Moves p along the unstable mode of a saddle. For each sign, s doubles from the step whose
// predicted decrease ¼|λ|s² is U's resolution up to 1 (a cell diameter); a step is kept when
// U(q + s v) is below U₀ by half the quadratic decrease and by more than U resolves, and the last
// kept before the first failure that follows one is taken (the end of the mode's own well: a
// contact opens or closes). A direction blocked by a contact about to close fails throughout. Of the
// two signs the lower U is taken. `lowered` false: along its unstable mode the saddle is a minimum
// of U to U's resolution — the mode runs into contacts at zero force, which the Hessian of the
// contacts with an overlap does not hold.
SaddleStep step_off_saddle(Packing& p, ForceField& field, const UnstableMode& mode);

// What a relaxed packing is, given the number of unstable modes of its pressed contacts' Hessian
// (the saddle test, stability.hpp). U is piecewise quadratic: a pair without overlap adds nothing to
// H, yet closes at once along a mode that presses it. So a Hessian with one unstable mode can belong
// to a minimum of U: the mode runs into such a pair, U rises along both of its signs (step_off_saddle
// lowers nothing U resolves), FIRE relaxing on to its force resolution lowers nothing either, and
// the state is a minimum that no linear response describes (the response is one-sided along the
// mode). The growth driver takes such a state as the jamming point, after the same two tests;
// `budjam moduli` and `budjam dos` name it the same way (docs/moduli.md, "Saddles").
enum class StationaryPoint {
  minimum,                 // no unstable mode
  saddle,                  // U falls along the lowest unstable mode, or more than one unstable mode
  contact_bounded_minimum  // one unstable mode, along which a pair at zero force holds U's minimum
};
// "minimum", "saddle", "contact-bounded minimum".
const char* to_string(StationaryPoint s);
// Probes the lowest unstable mode, then relaxes, on a copy of `p` when unstable_modes is 1 (with more,
// one probed mode cannot make a minimum). `contacts`, `net`: those of p, as for the saddle test.
StationaryPoint stationary_point(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 std::size_t unstable_modes);

}  // namespace budjam
