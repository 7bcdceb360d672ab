// `budjam export PACKING --format FORMAT [--out BASE] [--network load-bearing|raw]`, FORMAT one of
// io::export_formats()
// Writes a packing as particles and bonds for OVITO, ASE, ParaView and HOOMD-blue
// (io/export.hpp, docs/files.md "Export"): BASE.<format>, BASE defaulting to the packing's path
// without its extension. `budjam export RUN/trajectory.xyz --format gsd` writes the run's trajectory
// as one multi-frame GSD file (RUN/trajectory.gsd). Nothing is printed.
#include "commands/command.hpp"

#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/export.hpp"
#include "io/packing_file.hpp"
#include "io/result_files.hpp"
#include "io/run_data.hpp"
#include "io/run_directory.hpp"
#include "io/text.hpp"
#include "observers/run_outputs.hpp"

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace budjam::cli::export_command {
namespace {

struct Options {
  std::string packing;
  std::string format;
  std::string out;
  std::string network = "load-bearing";
  bool network_given = false;
};

std::vector<std::string> format_names() {
  std::vector<std::string> names;
  for (const io::ExportFormat& f : io::export_formats()) names.emplace_back(f.name);
  return names;
}

// A trajectory's options: GSD only, and the clusters its frames carry.
void check_trajectory_options(const Options& o) {
  if (o.format != "gsd")
    throw InputError("--format: a trajectory (" + o.packing + ") exports to gsd only (got " + o.format + ")");
  if (o.network_given) throw InputError("--network: a trajectory's frames keep the rigid clusters the run gave them");
}

// A run's trajectory.xyz (any extended XYZ budjam wrote) becomes one multi-frame GSD file; its
// frames keep the rigid clusters the run labelled them with.
void export_trajectory(const Options& o, const std::filesystem::path& out) {
  io::write_gsd(out, io::read_extxyz(o.packing));
}

// A packing file names its format on its first line, whatever the file is called (p.xyz included);
// any other *.xyz is taken for an extended XYZ trajectory.
bool is_trajectory(const std::string& path) {
  if (std::filesystem::path(path).extension() != ".xyz") return false;
  std::ifstream in(path, std::ios::binary);
  std::string head(64, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return !io::looks_like_packing(head);
}

// RUN/trajectory.xyz to RUN/trajectory.gsd, an entry the run declares: the run is claimed as a
// writer claims it (its lock, its entries checked: a link or another kind at trajectory.gsd is
// refused), and the file is written relative to the run directory's descriptor, atomically, its
// temporaries recorded in the run's list.
void export_run_trajectory(const Options& o) {
  std::filesystem::path dir = std::filesystem::path(o.packing).parent_path();
  if (dir.empty()) dir = ".";
  io::RunDirectory run = io::RunDirectory::resume(dir, tools::run_owned_entries());
  const auto input = run.root().entry(io::run_files::trajectory);
  if (!input || !S_ISREG(input->st_mode))
    throw InputError(io::escape_control(o.packing) + ": not a regular file of the run");
  run.remove_recorded_temporaries();  // those of a writer killed in this run, as grow --resume does
  io::write_gsd(run.root(), io::run_files::trajectory_gsd, io::read_extxyz(run / io::run_files::trajectory));
}

void run(const Options& o) {
  const RigidityNetwork which = parse_rigidity_network(o.network);
  // The input first: where it is missing, that is what is wrong, whatever its output would be named.
  if (!tools::input_exists(o.packing))
    throw InputError(io::escape_control(o.packing) + ": cannot read: No such file or directory");
  std::filesystem::path out =
      o.out.empty() ? std::filesystem::path(o.packing).replace_extension() : std::filesystem::path(o.out);
  out += "." + o.format;
  // A trajectory's own rules before those of its output, which (RUN/trajectory.vtk, an entry of the
  // run) would name the wrong problem.
  const bool trajectory = is_trajectory(o.packing);
  if (trajectory) check_trajectory_options(o);
  // The documented default: a run's trajectory.xyz converts to the run's own trajectory.gsd.
  if (io::is_run_trajectory_conversion(o.packing, out)) return export_run_trajectory(o);
  if (!o.out.empty()) io::check_output_name("--out", o.out);
  io::check_output_name("--out", out);
  io::check_not_an_input("--out", out, {o.packing});  // `export p.xyz --format xyz` with no --out
  if (trajectory) return export_trajectory(o, out);
  const io::PackingFile file = io::read_packing(o.packing);
  io::write_particles(out, io::particle_frame(file, which), o.format);
}

const bool registered = budjam::cli::register_command(
    {"export", "Write a packing as particles (lobes) and bonds for OVITO, ASE, ParaView, HOOMD (--format)",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing,
                      "packing file (.pack), taken as it is, or a run's trajectory.xyz (to --format gsd: one frame "
                      "per frame)")
           ->required();
       sub.add_option("--format", o->format, io::export_formats_text())
           ->required()
           ->check(CLI::IsMember(format_names()));
       sub.add_option("--out", o->out, "write BASE.<format> (default: the input's path without its extension)")
           ->type_name("BASE")
           ->check(budjam::cli::names_a_path());
       const CLI::Option* network = sub.add_option(
           "--network", o->network, "network whose rigid clusters label the lobes: load-bearing (default) or raw");
       sub.callback([o, network] {
         o->network_given = network->count() > 0;
         run(*o);
       });
     }});

}  // namespace
}  // namespace budjam::cli::export_command
