#include "budjam/stability.hpp"

#include "budjam/cholmod_solver.hpp"
#include "budjam/hessian.hpp"

#include <stdexcept>
#include <string>

namespace budjam {

Stability hessian_stability(const Eigen::SparseMatrix<double>& H, double relative_delta, CholmodSolver* factor) {
  Stability s;
  if (H.rows() == 0) return s;
  CholmodSolver own(Factorisation::ldlt);
  CholmodSolver& ldl = factor ? *factor : own;
  s.delta = relative_delta * H.diagonal().cwiseAbs().maxCoeff();
  for (int attempt = 0; attempt < 4; ++attempt, s.delta *= 100) {
    if (ldl.factor(H, -s.delta, Eigen::VectorXd())) {
      s.unstable_modes = static_cast<std::size_t>(ldl.negative_pivots());
      return s;
    }
  }
  s.delta /= 100;
  s.factored = false;
  s.failed_column = ldl.failed_column();
  return s;
}

Stability stability(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                    double relative_delta) {
  const std::vector<Contact> lb = load_bearing(contacts, net);
  if (lb.empty()) return {};  // no stressed contact: U = 0 is the minimum
  const Stability s = hessian_stability(restrict_matrix(hessian(p, lb), non_rattler_dofs(net)), relative_delta);
  if (!s.factored)
    throw std::runtime_error("stability: zero pivot in the LDLᵀ factor of H + δ1 at column " +
                             std::to_string(s.failed_column));
  return s;
}

}  // namespace budjam
