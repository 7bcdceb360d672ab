// A shared library built on the installed static libraries (tests/install/consumer/CMakeLists.txt).
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/moduli.hpp"
#include "io/packing_file.hpp"

// The shear modulus of a packing file, for a host program that loads this library.
extern "C" double budjam_plugin_shear_modulus(const char* path) {
  const budjam::io::PackingFile f = budjam::io::read_packing(path);
  budjam::ForceField field;
  Eigen::VectorXd force;
  field.evaluate(f.packing, force);
  const auto contacts = budjam::find_contacts(f.packing, field.lobes(), field.neighbours());
  return budjam::elastic_response(f.packing, contacts, budjam::analyse_network(f.packing.size(), contacts)).G();
}
