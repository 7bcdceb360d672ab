#include "budjam/stability.hpp"

#include "budjam/cholmod_solver.hpp"
#include "budjam/hessian.hpp"

#include <stdexcept>
#include <string>

namespace budjam {

Stability stability(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                    double relative_delta) {
  Stability s;
  const std::vector<Contact> lb = load_bearing(contacts, net);
  if (lb.empty()) return s;  // no stressed contact: U = 0 is the minimum
  const SparseMatrix H = restrict_matrix(hessian(p, lb), non_rattler_dofs(net));
  s.delta = relative_delta * H.diagonal().cwiseAbs().maxCoeff();
  CholmodSolver ldl(Factorisation::ldlt);
  if (!ldl.factor(H, -s.delta, Eigen::VectorXd()))
    throw std::runtime_error("stability: zero pivot in the LDLᵀ factor of H + δ1 at column " +
                             std::to_string(ldl.failed_column()));
  s.unstable_modes = static_cast<std::size_t>(ldl.negative_pivots());
  return s;
}

}  // namespace budjam
