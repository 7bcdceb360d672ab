#pragma once
// A packing's contacts and contact network, found from one fresh force evaluation: what the
// minimum-or-saddle tests start from.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"

#include <vector>

namespace budjam::testing {

struct Analysed {
  std::vector<Contact> contacts;
  ContactNetwork net;
};

Analysed analyse(const Packing& p);

}  // namespace budjam::testing
