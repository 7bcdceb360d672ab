#include "analysis/rigidity_report.hpp"

#include "budjam/errors.hpp"

#include <cstdio>
#include <ostream>

namespace budjam::tools {

using io::Json;

RigidityReport rigidity_report(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                               const ContactNetwork& net, RigidityNetwork network, const std::string& what) {
  // An empty load-bearing network has no floppy-mode count to report: 0 would read as rigid.
  if (network == RigidityNetwork::load_bearing && net.N_nr == 0)
    throw NoResultError(what + " is not jammed: all " + std::to_string(net.N) +
                        " cells are rattlers (N_nr = 0), so its load-bearing network is empty and has no rigidity to "
                        "analyse; the raw network (--network raw) takes every cell's contacts");
  return {network, contacts.size(), net, analyse_rigidity(p, lobes, contacts, net, network)};
}

namespace {

// The name `--network` takes.
const char* network_name(RigidityNetwork network) { return network == RigidityNetwork::raw ? "raw" : "load-bearing"; }

std::size_t buds_rigid(const RigidityState& s) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < s.cell_cluster.size(); ++i) n += s.bud_rigid(i) ? 1 : 0;
  return n;
}

}  // namespace

Json rigidity_json(const RigidityReport& r) {
  const RigidityState& s = r.state;
  const ContactNetwork& net = r.contact_network;
  Json j;
  j["network"] = network_name(r.network);
  j["N"] = net.N;
  j["N_nr"] = net.N_nr;
  j["N_f"] = net.N_f;
  j["N_f_single_pass"] = net.N_f_single_pass;
  j["contacts"] = r.contacts;
  j["contacts_load_bearing"] = net.N_c / 2;
  j["N_u"] = net.N_u;
  j["N_u_buds"] = net.N_u_buds;
  j["cells"] = s.cells;
  j["joints"] = s.joints;
  j["bars"] = s.bars;
  j["independent_bars"] = s.independent_bars;
  j["redundant_bars"] = s.redundant_bars;
  j["free_pebbles"] = s.free_pebbles;
  j["floppy_modes"] = Json{{"plane", s.floppy_plane}, {"periodic", s.floppy_periodic}};
  j["rigid_clusters"] = Json{{"count", s.clusters.size()},
                             {"with_3_or_more_joints", s.nontrivial_clusters},
                             {"largest_cells", s.largest_cells()},
                             {"largest_joints", s.largest_joints()},
                             {"largest_spans_x", s.largest >= 0 && s.clusters[s.largest].winding.x},
                             {"largest_spans_y", s.largest >= 0 && s.clusters[s.largest].winding.y}};
  j["spans_x"] = s.spans_x;
  j["spans_y"] = s.spans_y;
  j["buds_rigid"] = buds_rigid(s);
  j["conventions"] =
      "joints = lobe centres, bars = one per cell (mother-bud) + one per contact; generic (2,3) pebble game; "
      "free_pebbles F = 2 joints - independent bars; floppy_modes.plane = F - 3 (2 translations + rotation "
      "trivial), floppy_modes.periodic = F - 2 (only the 2 box translations trivial); redundant_bars = states of "
      "self-stress of the generic framework; a cluster spans x (y) if it winds around the periodic box; "
      "docs/rigidity.md";
  return j;
}

io::CommandResult rigidity_result(const RigidityReport& r) {
  const RigidityState& s = r.state;
  char line[256];
  std::snprintf(line, sizeof line,
                "rigidity: %s network, N = %zu, N_nr = %zu, floppy modes %ld (plane), %zu rigid clusters, largest "
                "%zu cells, spans x %s, y %s",
                network_name(r.network), r.contact_network.N, r.contact_network.N_nr, s.floppy_plane, s.clusters.size(),
                s.largest_cells(), s.spans_x ? "yes" : "no", s.spans_y ? "yes" : "no");
  io::CommandResult result{rigidity_json(r), {}, line};
  result.csv = [&s](std::ostream& os) {  // per cell, in the packing's order
    os << "cell,cluster,bud_rigid\n";
    for (std::size_t i = 0; i < s.cell_cluster.size(); ++i)
      os << i << ',' << s.cell_cluster[i] << ',' << (s.bud_rigid(i) ? "true" : "false") << '\n';
  };
  return result;
}

}  // namespace budjam::tools
