#include "analysed_packing.hpp"

#include "budjam/energy.hpp"

namespace budjam::testing {

Analysed analyse(const Packing& p) {
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  Analysed a;
  a.contacts = find_contacts(p, field.lobes(), field.neighbours());
  a.net = analyse_network(p.size(), a.contacts);
  return a;
}

}  // namespace budjam::testing
