// Reads a packing with the installed file layer and prints N, φ and the number of contacts from
// the installed core: the same numbers `budjam validate` and `budjam rigidity` print.
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
  std::printf("%zu %.17g %zu\n", f.packing.size(), f.packing.packing_fraction(), contacts.size());
  return 0;
}
