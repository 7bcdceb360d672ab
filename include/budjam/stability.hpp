#pragma once
// Is a relaxed packing a minimum of U, or a saddle? FIRE stops on the force (|F| < force_tol), and
// a hair above jamming, where the prestress term −f/ℓ of the Hessian (f ~ P ~ 10⁻⁸) is as large as
// the stiffness of the softest extended modes, it can stop on a saddle whose energy, relaxed
// further, falls to zero: a false jamming point (docs/growth.md, "Jamming candidates that are
// saddles").
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"

#include <Eigen/SparseCore>
#include <cstddef>
#include <vector>

namespace budjam {

class CholmodSolver;

// δ of the saddle test relative to the largest diagonal entry of H (moduli's regularisation default).
constexpr double kSaddleRelativeDelta = 1e-10;

struct Stability {
  std::size_t unstable_modes = 0;  // eigenvalues of the non-rattler Hessian below −δ
  double delta = 0;                // δ = relative_delta × the largest diagonal entry (× 100 per zero-pivot retry)
  bool factored = true;            // false: every try hit a zero pivot (unstable_modes unknown)
  long failed_column = -1;         // ... where the last try stopped
  bool minimum() const { return unstable_modes == 0; }
};

// The one test of "minimum or saddle", shared by stability(), elastic_response (`budjam moduli`) and
// packing_spectrum (`budjam dos`): the negative pivots of the LDLᵀ factor of H + δ1,
// δ = relative_delta · max|diag H|, count the eigenvalues of H below −δ (Sylvester's law of inertia).
// A zero pivot (δ an eigenvalue to rounding) retries with δ × 100, at most 4 tries; `factored` false
// if all fail. `factor`, if given, receives the factorisation (elastic_response iterates with it).
Stability hessian_stability(const Eigen::SparseMatrix<double>& H, double relative_delta = kSaddleRelativeDelta,
                            CholmodSolver* factor = nullptr);

// The inertia of the LDLᵀ factor of H + δ1 (H: Hessian of the non-rattlers over their load-bearing
// contacts, both terms): by Sylvester's law its negative pivots count the eigenvalues of H below −δ.
// Exact zero modes (translations, unconstrained lobes) become +δ and are not counted; modes in
// (−δ, 0) are rounding. One sparse factorisation: milliseconds at N = 200.
Stability stability(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                    double relative_delta = kSaddleRelativeDelta);

}  // namespace budjam
