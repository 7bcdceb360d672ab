// `budjam rigidity PACKING [--network load-bearing|raw] [--timing] [--out BASE] [--json] [--quiet]`
// Rigidity of a packing's contact network by the (2,3) pebble game (docs/rigidity.md), as JSON:
// BASE.json with --out (and BASE.csv: each cell's rigid cluster), on stdout with --json, else a
// summary line (io/result_files.hpp). The packing is taken as it is (nothing is relaxed): contacts are the
// overlapping lobe pairs, rattlers are removed by the iterative rule for the load-bearing network.
#include "commands/command.hpp"

#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/rigidity.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <ostream>
#include <string>

namespace {

using namespace budjam;
using io::Json;

struct Options {
  std::string packing;
  std::string network = "load-bearing";
  bool timing = false;
  io::OutputRequest output;
};

void run(const Options& o) {
  const RigidityNetwork which = parse_rigidity_network(o.network);
  const io::PackingFile file = io::read_packing(o.packing);
  const Packing& p = file.packing;
  ForceField field;
  Eigen::VectorXd force;
  field.evaluate(p, force);  // places the lobes and builds the neighbour list; moves nothing
  const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  const ContactNetwork net = analyse_network(p.size(), contacts);

  const auto t0 = std::chrono::steady_clock::now();
  const RigidityState s = analyse_rigidity(p, field.lobes(), contacts, net, which);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::size_t buds_rigid = 0;
  for (std::size_t i = 0; i < p.size(); ++i) buds_rigid += s.bud_rigid(i) ? 1 : 0;
  Json j;
  j["file"] = o.packing;
  j["network"] = o.network;
  j["N"] = p.size();
  j["N_nr"] = net.N_nr;
  j["N_f"] = net.N_f;
  j["N_f_single_pass"] = net.N_f_single_pass;
  j["contacts"] = contacts.size();
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
  j["buds_rigid"] = buds_rigid;
  j["conventions"] =
      "joints = lobe centres, bars = one per cell (mother-bud) + one per contact; generic (2,3) pebble game; "
      "free_pebbles F = 2 joints - independent bars; floppy_modes.plane = F - 3 (2 translations + rotation "
      "trivial), floppy_modes.periodic = F - 2 (only the 2 box translations trivial); redundant_bars = states of "
      "self-stress of the generic framework; a cluster spans x (y) if it winds around the periodic box; "
      "docs/rigidity.md";
  if (o.timing) j["seconds"] = seconds;
  char line[256];
  std::snprintf(line, sizeof line,
                "rigidity: %s network, N = %zu, N_nr = %zu, floppy modes %ld (plane), %zu rigid clusters, largest "
                "%zu cells, spans x %s, y %s",
                o.network.c_str(), p.size(), net.N_nr, s.floppy_plane, s.clusters.size(), s.largest_cells(),
                s.spans_x ? "yes" : "no", s.spans_y ? "yes" : "no");
  io::CommandResult result{j, {}, line};
  result.csv = [&s](std::ostream& os) {  // per cell, in the packing's order
    os << "cell,cluster,bud_rigid\n";
    for (std::size_t i = 0; i < s.cell_cluster.size(); ++i)
      os << i << ',' << s.cell_cluster[i] << ',' << (s.bud_rigid(i) ? "true" : "false") << '\n';
  };
  io::emit(o.output, result, std::cout);
}

const bool registered = budjam::cli::register_command(
    {"rigidity", "Pebble-game rigidity of a packing's contact network (floppy modes, clusters, percolation)",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack), taken as it is")->required();
       sub.add_option("--network", o->network, "load-bearing (rattlers removed, default) or raw (every cell)");
       sub.add_flag("--timing", o->timing, "add the wall time of the analysis (not deterministic)");
       budjam::cli::add_output_options(sub, o->output,
                                       "BASE.json (the counts) and BASE.csv (each cell's rigid cluster)");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
