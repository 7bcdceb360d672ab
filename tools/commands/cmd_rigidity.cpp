// `budjam rigidity PACKING [--network load-bearing|raw] [--timing] [--out BASE] [--json] [--quiet]`
// Rigidity of a packing's contact network by the (2,3) pebble game (docs/rigidity.md), as JSON:
// BASE.json with --out (and BASE.csv: each cell's rigid cluster), on stdout with --json, else a
// summary line (io/result_files.hpp). The packing is taken as it is (nothing is relaxed): contacts are the
// overlapping lobe pairs, rattlers are removed by the iterative rule for the load-bearing network.
#include "analysis/rigidity_report.hpp"
#include "commands/command.hpp"

#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace budjam::cli::rigidity_command {
namespace {

using io::Json;

struct Options {
  std::string packing;
  std::string network = "load-bearing";
  bool timing = false;
  io::OutputRequest output;
};

void run(const Options& o) {
  io::check_output_request(o.output, true, {o.packing});
  const RigidityNetwork which = parse_rigidity_network(o.network);
  const io::PackingFile file = io::read_packing(o.packing);
  const Packing& p = file.packing;
  ForceField field;
  Eigen::VectorXd force;
  field.evaluate(p, force);  // places the lobes and builds the neighbour list; moves nothing
  const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  const ContactNetwork net = analyse_network(p.size(), contacts);

  const auto t0 = std::chrono::steady_clock::now();
  const tools::RigidityReport report =
      tools::rigidity_report(p, field.lobes(), contacts, net, which, "rigidity: " + o.packing);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  io::CommandResult result = tools::rigidity_result(report);
  Json j;
  j["file"] = o.packing;
  for (const auto& [k, v] : result.json.items()) j[k] = v;
  if (o.timing) j["seconds"] = seconds;
  result.json = std::move(j);
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
}  // namespace budjam::cli::rigidity_command
