#pragma once
// The rigidity of one packing's contact network as a result (docs/rigidity.md), for `budjam
// rigidity` and the Python module's rigidity(): the JSON of the counts, clusters and spanning, the
// per-cell table (cell, cluster, bud_rigid) and the summary line. One serialisation, so that the
// command line and Python name every quantity alike.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/rigidity.hpp"
#include "io/json.hpp"
#include "io/result_files.hpp"

#include <string>
#include <vector>

namespace budjam::tools {

struct RigidityReport {
  RigidityNetwork network = RigidityNetwork::load_bearing;
  std::size_t contacts = 0;
  ContactNetwork contact_network;
  RigidityState state;
};

// The pebble game on the packing as it is (nothing relaxed). A load-bearing network of an unjammed
// packing (N_nr = 0) is NoResultError, its message starting with `what`.
RigidityReport rigidity_report(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                               const ContactNetwork& net, RigidityNetwork network, const std::string& what);

// The JSON of `budjam rigidity --json`, without the packing's file name and the timing.
io::Json rigidity_json(const RigidityReport& report);

// The JSON, the per-cell table and the summary line; the CSV writer refers to `report`, which must
// outlive it.
io::CommandResult rigidity_result(const RigidityReport& report);

}  // namespace budjam::tools
