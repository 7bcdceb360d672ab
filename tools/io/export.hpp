#pragma once
// A packing as particles and bonds, for the tools of molecular simulation (OVITO, ASE, ParaView,
// HOOMD-blue): one particle per lobe, one bond per mother–bud link and per contact
// (docs/files.md, "Export"). Lengths in mother diameters D0, forces in k·D0.
//
// Positions: every cell is kept whole (its centroid wrapped into the box, its lobes placed from
// it); each lobe is then also given wrapped into the box with its image, so that
// unwrapped = wrapped + image_x·a1 + image_y·a2 with the box vectors a1 = (L, 0), a2 = (γL, L)
// (γ = Lees–Edwards shear, the HOOMD tilt factor xy).
#include "budjam/packing.hpp"
#include "budjam/rigidity.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

enum class BondKind : int { link = 0, contact = 1 };  // mother–bud bar / lobe–lobe overlap

struct Bond {
  std::uint32_t a, b;  // lobes, a < b
  BondKind kind;
  // Compressive force carried, in k·D0. Contact: k(σ − r). Link: −F_bud·n̂, the force the rigid
  // mother–bud bar exerts to hold the bud against its contacts (F_bud = their sum on the bud,
  // parallel to n̂ in a force- and torque-balanced packing); negative = tension.
  double force;
  bool crosses_boundary;  // the bond joins periodic images: the wrapped ends are not its ends
};

struct ParticleFrame {
  std::int64_t step = 0;  // growth step, for trajectories
  double L = 0, shear = 0;
  // Per lobe: lobe 2i is the mother of cell i, lobe 2i+1 its bud (packing.hpp).
  std::vector<double> x, y;  // unwrapped, cells whole
  std::vector<double> wrapped_x, wrapped_y;
  std::vector<int> image_x, image_y;
  std::vector<double> radius;
  std::vector<std::int64_t> id;  // lineage id of the lobe's cell
  std::vector<int> cluster;      // rigid cluster of the cell's mother–bud bar, −1 if not analysed (rattler)
  std::vector<bool> rattler;     // the lobe's cell is a rattler (iterative rule)
  std::vector<Bond> bonds;       // the links of cells 0..N−1 in order, then the contacts by (a, b)

  std::size_t size() const { return radius.size(); }
};

// Contacts, contact network and rigid clusters of the packing as it is (nothing is relaxed), as
// `budjam rigidity` computes them; `which` chooses the network whose clusters label the lobes.
ParticleFrame particle_frame(const Packing& p, RigidityNetwork which = RigidityNetwork::load_bearing);
// The same for a packing file, at the growth step its metadata records (0 when it has none).
ParticleFrame particle_frame(const PackingFile& file, RigidityNetwork which = RigidityNetwork::load_bearing);

// Python source defining gsd_frame(j): the HOOMD frame (gsd.hoomd.Frame, or Snapshot before gsd 3)
// of particle_frame_json(f). The GSD writer and the Python module's Packing.to_gsd_frame() both
// run it, so a frame in memory is the frame in the file.
extern const char* const kGsdFrameSource;
// The frame as the JSON document gsd_frame reads.
Json particle_frame_json(const ParticleFrame& f);

// A per-lobe quantity under the one name every format gives it: the XYZ column, the VTK point data
// and the GSD entry log/particles/<name>. Names that clash with a reader's own attribute (ASE's
// Atoms.cell is the box, OVITO's Cluster the result of its cluster analysis) are avoided.
struct LobeField {
  std::string_view name;
  std::string_view meaning;  // one line, for the docs table
  bool flag;                 // true/false rather than an integer
  std::string_view vtk_type, gsd_dtype;
  std::int64_t (*value)(const ParticleFrame& frame, std::size_t lobe);
};
// cell_id, id, rigid_cluster, rattler, in the order of the XYZ columns.
const std::vector<LobeField>& lobe_fields();

// The per-bond quantities (VTK cell data, GSD log/bonds/<name>).
inline constexpr std::string_view kBondForce = "force";
inline constexpr std::string_view kBondCrossesBoundary = "crosses_boundary";

// Extended XYZ (ASE, OVITO): wrapped positions (z = 0), the cell as Lattice, pbc "T T F"; the
// lobe kind in column `type` (mother/bud; not `species`, which ASE reads as chemical elements).
// Bonds are not part of the format (use GSD or VTK). Frames concatenate into a trajectory.
std::string format_extxyz(const ParticleFrame& frame);

// The frames of an extended XYZ file budjam wrote (format_extxyz; a run's trajectory.xyz), as far
// as the format holds them: positions wrapped (image 0), radius, the lobe fields, box and step; no
// bonds. InputError "<path>:<line>: ..." for anything else.
std::vector<ParticleFrame> read_extxyz(const std::filesystem::path& path);

// Legacy VTK unstructured grid (ParaView, meshio, VisIt): unwrapped points, bonds as line cells,
// per-lobe point data and per-bond cell data.
std::string format_vtk(const ParticleFrame& frame);

// GSD in the HOOMD schema, one frame per element, written by the `gsd` Python package (the HOOMD
// project's reference implementation; Debian ships GSD only as python3-gsd) run by the Python 3
// interpreter found at build time, or $BUDJAM_PYTHON. Atomic: `path` is complete or untouched.
// IoError if the interpreter or its gsd package is missing or the write fails.
void write_gsd(const std::filesystem::path& path, const std::vector<ParticleFrame>& frames);
// The same as the entry `name` of `dir`, relative to its descriptor (a link there is replaced,
// never written through); its temporaries are recorded as the directory records them.
void write_gsd(const Directory& dir, std::string_view name, const std::vector<ParticleFrame>& frames);

// An export format: its name is the value of `--format` and the file's extension. The one list of
// formats: the command line, its help and completion, and the docs table follow it.
struct ExportFormat {
  std::string_view name;
  std::string_view description;  // "extended XYZ: OVITO, ASE", for --help and the docs
  void (*write)(const std::filesystem::path& path, const ParticleFrame& frame);  // atomic
};
// xyz, gsd, vtk.
const std::vector<ExportFormat>& export_formats();
const ExportFormat* find_export_format(std::string_view name);  // nullptr if there is none
// `"xyz" (extended XYZ: OVITO, ASE), "gsd" (...) or "vtk" (...)`: the formats for help and messages.
std::string export_formats_text();

// The format named `format` writes `frame` to `path`; std::invalid_argument for an unknown name.
void write_particles(const std::filesystem::path& path, const ParticleFrame& frame, const std::string& format);

}  // namespace budjam::io
