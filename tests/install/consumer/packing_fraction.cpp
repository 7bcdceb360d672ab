// Reads a packing with the installed file layer and prints N, φ and the number of contacts from
// the installed core, and the contacts above isostaticity from the installed analysis: the same
// numbers `budjam validate` and `budjam rigidity` give.
#include "analysis/structure_estimators.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "io/packing_file.hpp"

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const budjam::io::PackingFile f = budjam::io::read_packing(argv[1]);
  budjam::ForceField field;
  Eigen::VectorXd force;
  field.evaluate(f.packing, force);
  const auto contacts = budjam::find_contacts(f.packing, field.lobes(), field.neighbours());
  const budjam::ContactNetwork net = budjam::analyse_network(f.packing.size(), contacts);
  const long excess = budjam::tools::excess_contacts(static_cast<long>(net.N_c), static_cast<long>(net.N_nr),
                                                     static_cast<long>(net.N_u));
  std::printf("%zu %.17g %zu %ld\n", f.packing.size(), f.packing.packing_fraction(), contacts.size(), excess);
  return 0;
}
