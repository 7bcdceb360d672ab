// `budjam export PACKING --format FORMAT [--out BASE] [--network load-bearing|raw]`, FORMAT one of
// io::export_formats()
// Writes a packing as particles and bonds for OVITO, ASE, ParaView and HOOMD-blue
// (io/export.hpp, docs/files.md "Export"): BASE.<format>, BASE defaulting to the packing's path
// without its extension. Nothing is printed.
#include "commands/command.hpp"

#include "io/atomic_file.hpp"
#include "io/export.hpp"
#include "io/packing_file.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace budjam;

struct Options {
  std::string packing;
  std::string format;
  std::string out;
  std::string network = "load-bearing";
};

std::vector<std::string> format_names() {
  std::vector<std::string> names;
  for (const io::ExportFormat& f : io::export_formats()) names.emplace_back(f.name);
  return names;
}

void run(const Options& o) {
  const RigidityNetwork which = parse_rigidity_network(o.network);
  if (!o.out.empty()) io::check_output_name("--out", o.out);
  const io::PackingFile file = io::read_packing(o.packing);
  std::filesystem::path out =
      o.out.empty() ? std::filesystem::path(o.packing).replace_extension() : std::filesystem::path(o.out);
  out += "." + o.format;
  io::check_output_name("--out", out);
  io::write_particles(out, io::particle_frame(file, which), o.format);
}

const bool registered = budjam::cli::register_command(
    {"export", "Write a packing as particles (lobes) and bonds for OVITO, ASE, ParaView, HOOMD (--format)",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack), taken as it is")->required();
       sub.add_option("--format", o->format, io::export_formats_text())
           ->required()
           ->check(CLI::IsMember(format_names()));
       sub.add_option("--out", o->out, "write BASE.<format> (default: the packing's path without .pack)")
           ->type_name("BASE");
       sub.add_option("--network", o->network,
                      "network whose rigid clusters label the lobes: load-bearing (default) or raw");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
