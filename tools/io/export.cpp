#include "io/export.hpp"

#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/errors.hpp"
#include "budjam/orientation.hpp"
#include "budjam/scene_keys.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/run_data.hpp"
#include "io/run_program.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#ifndef BUDJAM_PYTHON_EXECUTABLE
#define BUDJAM_PYTHON_EXECUTABLE "python3"
#endif

namespace budjam::io {

namespace {

// Lattice coordinates of (x, y) in the box vectors a1 = (L, 0), a2 = (γL, L), rounded down:
// (x, y) − n·a1 − m·a2 lies in the box.
struct Image {
  int n, m;
};
Image image_of(double x, double y, const Box& box) {
  const double m = std::floor(y / box.L);
  const double n = std::floor((x - box.shear * y) / box.L);
  return {static_cast<int>(n), static_cast<int>(m)};
}

}  // namespace

ParticleFrame particle_frame(const Packing& p, RigidityNetwork which) {
  const tools::PackingContacts pc = tools::analyse_contacts(p);
  Lobes lobes;
  place_lobes(p, lobes);
  const RigidityState rigidity = analyse_rigidity(p, lobes, pc.contacts, pc.network, which);
  const Box& box = p.box;
  const double L = box.L, shift = box.shear * box.L;

  ParticleFrame f;
  f.L = L;
  f.shear = box.shear;
  const std::size_t n = 2 * p.size();
  f.x.resize(n);
  f.y.resize(n);
  f.wrapped_x.resize(n);
  f.wrapped_y.resize(n);
  f.image_x.resize(n);
  f.image_y.resize(n);
  f.radius = lobes.R;
  f.id.resize(n);
  f.cluster.resize(n);
  f.rattler.resize(n);
  for (std::size_t lobe = 0; lobe < n; ++lobe) {
    const std::size_t cell = cell_of(lobe);
    const Image c = image_of(p.x(cell), p.y(cell), box);
    f.x[lobe] = lobes.x[lobe] - c.n * L - c.m * shift;
    f.y[lobe] = lobes.y[lobe] - c.m * L;
    const Image l = image_of(f.x[lobe], f.y[lobe], box);
    f.image_x[lobe] = l.n;
    f.image_y[lobe] = l.m;
    f.wrapped_x[lobe] = f.x[lobe] - l.n * L - l.m * shift;
    f.wrapped_y[lobe] = f.y[lobe] - l.m * L;
    f.id[lobe] = p.id[cell];
    f.cluster[lobe] = rigidity.cell_cluster[cell];
    f.rattler[lobe] = pc.network.rattler[cell];
  }

  // The force on a bud from its contacts, then the bar force that balances it.
  std::vector<double> bud_fx(p.size(), 0.0), bud_fy(p.size(), 0.0);
  for (const Contact& c : pc.contacts) {
    if (is_bud(c.i)) {
      bud_fx[cell_of(c.i)] += c.force() * c.nx;
      bud_fy[cell_of(c.i)] += c.force() * c.ny;
    }
    if (is_bud(c.j)) {
      bud_fx[cell_of(c.j)] -= c.force() * c.nx;
      bud_fy[cell_of(c.j)] -= c.force() * c.ny;
    }
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Axis n = axis(p.theta(i));
    const double link = -(bud_fx[i] * n.c + bud_fy[i] * n.s);
    f.bonds.push_back({static_cast<std::uint32_t>(mother_lobe(i)), static_cast<std::uint32_t>(bud_lobe(i)),
                       BondKind::link, link, false});
  }
  for (const Contact& c : pc.contacts) {
    // The contact joins the minimum images: it crosses the boundary when the unwrapped ends are
    // not those images of each other.
    double dx = f.x[c.i] - f.x[c.j], dy = f.y[c.i] - f.y[c.j];
    const double direct = dx * dx + dy * dy;
    box.minimum_image(dx, dy);
    const bool crosses = std::abs(direct - (dx * dx + dy * dy)) > 1e-9 * L * L;
    f.bonds.push_back({c.i, c.j, BondKind::contact, c.force(), crosses});
  }
  return f;
}

const std::vector<LobeField>& lobe_fields() {
  static const std::vector<LobeField> fields = {
      {"cell_id", "cell index in the packing file (0-based row)", false, "int", "int64",
       [](const ParticleFrame&, std::size_t k) { return static_cast<std::int64_t>(cell_of(k)); }},
      {"id", "lineage id: the packing's `id` column", false, "long", "int64",
       [](const ParticleFrame& f, std::size_t k) { return f.id[k]; }},
      {"rigid_cluster",
       "rigid cluster (pebble game, `--network`) of the cell's mother–bud bar, in the canonical order of "
       "docs/rigidity.md; −1: cell not analysed (a rattler of the load-bearing network)",
       false, "int", "int32", [](const ParticleFrame& f, std::size_t k) { return std::int64_t{f.cluster[k]}; }},
      {"rattler", "the cell is a rattler (iterative rule)", true, "int", "uint8",
       [](const ParticleFrame& f, std::size_t k) { return std::int64_t{f.rattler[k]}; }},
  };
  return fields;
}

ParticleFrame particle_frame(const PackingFile& file, RigidityNetwork which) {
  ParticleFrame f = particle_frame(file.packing, which);
  if (file.meta.has("step")) f.step = file.meta.integer("step");
  return f;
}

namespace {

// The columns of budjam's extended XYZ, as its header line declares them.
std::string extxyz_properties() {
  std::string p = "Properties=type:S:1:pos:R:3:radius:R:1";
  for (const LobeField& field : lobe_fields()) {
    p += ':';
    p += field.name;
    p += field.flag ? ":L:1" : ":I:1";
  }
  return p;
}

}  // namespace

std::string format_extxyz(const ParticleFrame& f) {
  std::ostringstream out;
  const std::string L = format_double(f.L);
  out << f.size() << '\n';
  out << "Lattice=\"" << L << " 0 0 " << format_double(f.shear * f.L) << ' ' << L << " 0 0 0 1\" "
      << extxyz_properties() << " pbc=\"T T F\" step=" << f.step << '\n';
  for (std::size_t k = 0; k < f.size(); ++k) {
    out << (is_bud(k) ? "bud" : "mother") << ' ' << format_double(f.wrapped_x[k]) << ' '
        << format_double(f.wrapped_y[k]) << " 0 " << format_double(f.radius[k]);
    for (const LobeField& field : lobe_fields()) {
      const std::int64_t v = field.value(f, k);
      out << ' ';
      if (field.flag)
        out << (v ? 'T' : 'F');
      else
        out << v;
    }
    out << '\n';
  }
  return out.str();
}

namespace {

// One line of a text read line by line, numbered from 1, for the messages of read_extxyz.
class XyzLines {
 public:
  XyzLines(const std::string& text, std::string source) : text_(text), source_(std::move(source)) {}
  bool done() const { return pos_ >= text_.size(); }
  std::string next() {
    if (done()) {
      ++line_;
      fail("the file ends inside a frame");
    }
    const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
    std::string line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++line_;
    return line;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(source_ + ":" + std::to_string(line_) + ": " + what);
  }

 private:
  const std::string& text_;
  std::string source_;
  std::size_t pos_ = 0, line_ = 0;
};

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The frame header "Lattice="L 0 0 γL L 0 0 0 1" Properties=... pbc="T T F" step=S".
void read_extxyz_header(const std::string& line, ParticleFrame& f, const XyzLines& lines) {
  const std::string lattice = "Lattice=\"", tail = "\" " + extxyz_properties() + " pbc=\"T T F\" step=";
  const std::size_t close = line.find(tail);
  if (line.rfind(lattice, 0) != 0 || close == std::string::npos)
    lines.fail("not a frame header of budjam's extended XYZ (Lattice=\"...\" " + extxyz_properties() +
               " pbc=\"T T F\" step=...)");
  const std::vector<std::string> v = words(line.substr(lattice.size(), close - lattice.size()));
  std::vector<double> a;
  for (const std::string& w : v)
    if (const auto d = parse_double(w)) a.push_back(*d);
  if (a.size() != 9 || v.size() != 9 || !(a[0] > 0) || a[0] != a[4] || a[1] != 0 || a[2] != 0 || a[5] != 0 ||
      a[6] != 0 || a[7] != 0 || a[8] != 1)
    lines.fail("Lattice: expected \"L 0 0 shear*L L 0 0 0 1\" with L > 0");
  const auto step = parse_int64(line.substr(close + tail.size()));
  if (!step || *step < 0) lines.fail("step: not a non-negative integer");
  f.L = a[0];
  f.shear = a[3] / a[0];
  f.step = *step;
}

// One lobe line: type x y z radius, then the lobe fields.
void read_extxyz_lobe(const std::string& line, std::size_t k, ParticleFrame& f, const XyzLines& lines) {
  const std::vector<std::string> v = words(line);
  const std::size_t columns = 5 + lobe_fields().size();
  if (v.size() != columns) lines.fail(std::to_string(v.size()) + " fields, a lobe line has " + std::to_string(columns));
  if (v[0] != (is_bud(k) ? "bud" : "mother"))
    lines.fail("type: lobe " + std::to_string(k) + " is a " + (is_bud(k) ? "bud" : "mother") + " (got " + v[0] + ")");
  double pos[4];
  for (int c = 0; c < 4; ++c) {
    const auto d = parse_double(v[1 + c]);
    if (!d || !std::isfinite(*d)) lines.fail("not a finite number (got " + v[1 + c] + ")");
    pos[c] = *d;
  }
  f.x.push_back(pos[0]), f.wrapped_x.push_back(pos[0]), f.image_x.push_back(0);
  f.y.push_back(pos[1]), f.wrapped_y.push_back(pos[1]), f.image_y.push_back(0);
  f.radius.push_back(pos[3]);
  for (std::size_t c = 0; c < lobe_fields().size(); ++c) {
    const LobeField& field = lobe_fields()[c];
    const std::string& w = v[5 + c];
    const auto n =
        field.flag ? (w == "T" || w == "F" ? std::optional<std::int64_t>(w == "T") : std::nullopt) : parse_int64(w);
    if (!n)
      lines.fail(std::string(field.name) + ": not " + (field.flag ? "T or F" : "an integer") + " (got " + w + ")");
    if (field.name == "cell_id" && *n != static_cast<std::int64_t>(cell_of(k)))
      lines.fail("cell_id: lobe " + std::to_string(k) + " belongs to cell " + std::to_string(cell_of(k)));
    if (field.name == "id") f.id.push_back(*n);
    if (field.name == "rigid_cluster") f.cluster.push_back(static_cast<int>(*n));
    if (field.name == "rattler") f.rattler.push_back(*n != 0);
  }
}

}  // namespace

std::vector<ParticleFrame> read_extxyz(const std::filesystem::path& path) {
  const std::string text = read_text_file(path);
  XyzLines lines(text, path.string());
  std::vector<ParticleFrame> frames;
  while (!lines.done()) {
    const std::string count = lines.next();
    const auto n = parse_int64(count);
    if (!n || *n < 0 || *n % 2 != 0) lines.fail("not a lobe count (an even number: two lobes a cell)");
    ParticleFrame f;
    read_extxyz_header(lines.next(), f, lines);
    for (std::int64_t k = 0; k < *n; ++k) read_extxyz_lobe(lines.next(), static_cast<std::size_t>(k), f, lines);
    frames.push_back(std::move(f));
  }
  if (frames.empty()) throw InputError(path.string() + ": no frame (an empty trajectory)");
  return frames;
}

std::string format_vtk(const ParticleFrame& f) {
  constexpr int kVtkLine = 3;
  std::ostringstream out;
  const std::size_t n = f.size(), nb = f.bonds.size();
  out << "# vtk DataFile Version 3.0\n"
      << "budjam packing: points = lobes, lines = bonds; L " << format_double(f.L) << " shear "
      << format_double(f.shear) << " step " << f.step << '\n'
      << "ASCII\nDATASET UNSTRUCTURED_GRID\n";
  out << "POINTS " << n << " double\n";
  for (std::size_t k = 0; k < n; ++k) out << format_double(f.x[k]) << ' ' << format_double(f.y[k]) << " 0\n";
  out << "CELLS " << nb << ' ' << 3 * nb << '\n';
  for (const Bond& b : f.bonds) out << "2 " << b.a << ' ' << b.b << '\n';
  out << "CELL_TYPES " << nb << '\n';
  for (std::size_t k = 0; k < nb; ++k) out << kVtkLine << '\n';

  const auto scalars = [&out](const char* name, const char* type, std::size_t count, auto value) {
    out << "SCALARS " << name << ' ' << type << " 1\nLOOKUP_TABLE default\n";
    for (std::size_t k = 0; k < count; ++k) out << value(k) << '\n';
  };
  out << "POINT_DATA " << n << '\n';
  scalars("radius", "double", n, [&](std::size_t k) { return format_double(f.radius[k]); });
  scalars("bud", "int", n, [](std::size_t k) { return static_cast<int>(is_bud(k)); });
  for (const LobeField& field : lobe_fields())
    scalars(std::string(field.name).c_str(), std::string(field.vtk_type).c_str(), n,
            [&](std::size_t k) { return field.value(f, k); });
  out << "CELL_DATA " << nb << '\n';
  scalars("contact", "int", nb, [&](std::size_t k) { return static_cast<int>(f.bonds[k].kind); });
  scalars(kBondForce.data(), "double", nb, [&](std::size_t k) { return format_double(f.bonds[k].force); });
  scalars(kBondCrossesBoundary.data(), "int", nb,
          [&](std::size_t k) { return static_cast<int>(f.bonds[k].crosses_boundary); });
  return out.str();
}

// HOOMD conventions: positions centred on the box, box = [Lx, Ly, Lz, xy, xz, yz], dimensions 2;
// quantities without a HOOMD field go under log/.
const char* const kGsdFrameSource = R"(import numpy as np
import gsd, gsd.hoomd
Frame = getattr(gsd.hoomd, 'Frame', None) or gsd.hoomd.Snapshot
def gsd_frame(j):
    s = Frame()
    s.configuration.step = j['step']
    s.configuration.dimensions = 2
    L, xy = j['L'], j['shear']
    s.configuration.box = [L, L, 1, xy, 0, 0]
    n = len(j['radius'])
    s.particles.N = n
    s.particles.types = ['mother', 'bud']
    s.particles.typeid = np.arange(n, dtype=np.uint32) % 2
    pos = np.zeros((n, 3))
    pos[:, 0] = np.array(j['x']) - 0.5 * L * (1 + xy)
    pos[:, 1] = np.array(j['y']) - 0.5 * L
    s.particles.position = pos
    s.particles.diameter = 2 * np.array(j['radius'])
    image = np.zeros((n, 3), dtype=np.int32)
    image[:, 0], image[:, 1] = j['image_x'], j['image_y']
    s.particles.image = image
    s.bonds.N = len(j['bond_kind'])
    s.bonds.types = ['link', 'contact']
    s.bonds.typeid = np.array(j['bond_kind'], dtype=np.uint32)
    s.bonds.group = np.array(j['bond_group'], dtype=np.uint32).reshape(-1, 2)
    # The cell index is not particles/body: HOOMD reads body >= 0 as constituents of its rigid
    # bodies.
    for entry in j['log']:
        s.log[entry['name']] = np.array(entry['values'], dtype=entry['dtype'])
    return s
)";

Json particle_frame_json(const ParticleFrame& f) {
  Json j;
  j["step"] = f.step;
  j["L"] = f.L;
  j["shear"] = f.shear;
  j["x"] = f.wrapped_x;
  j["y"] = f.wrapped_y;
  j["image_x"] = f.image_x;
  j["image_y"] = f.image_y;
  j["radius"] = f.radius;
  // Quantities without a HOOMD field, each under log/ with the name every format gives it.
  Json log = Json::array();
  for (const LobeField& field : lobe_fields()) {
    Json values = Json::array();
    for (std::size_t k = 0; k < f.size(); ++k) values.push_back(field.value(f, k));
    log.push_back({{"name", "particles/" + std::string(field.name)},
                   {"dtype", std::string(field.gsd_dtype)},
                   {"values", values}});
  }
  Json kind = Json::array(), group = Json::array(), force = Json::array(), crosses = Json::array();
  for (const Bond& b : f.bonds) {
    kind.push_back(static_cast<int>(b.kind));
    group.push_back(b.a);
    group.push_back(b.b);
    force.push_back(b.force);
    crosses.push_back(static_cast<int>(b.crosses_boundary));
  }
  log.push_back({{"name", "bonds/" + std::string(kBondForce)}, {"dtype", "float64"}, {"values", force}});
  log.push_back({{"name", "bonds/" + std::string(kBondCrossesBoundary)}, {"dtype", "uint8"}, {"values", crosses}});
  j["log"] = log;
  j["bond_kind"] = kind;
  j["bond_group"] = group;
  return j;
}

namespace {

// Reads the frames (JSON, argv[1]) and writes them as GSD (argv[2]); exit 4 without numpy or gsd.
constexpr int kNoGsdPackage = 4;
std::string gsd_writer() {
  return std::string(R"(import json, sys
try:
    import numpy, gsd.hoomd
except ImportError:
    sys.exit(4)
)") + kGsdFrameSource +
         R"(mode = 'w' if int(gsd.__version__.split('.')[0]) >= 3 else 'wb'
def write():
    with open(sys.argv[1]) as f:
        frames = json.load(f)
    with gsd.hoomd.open(sys.argv[2], mode) as out:
        for j in frames:
            out.append(gsd_frame(j))
# One line, no traceback: the caller reports the failure with its own context.
try:
    write()
except Exception as e:
    sys.stderr.write('gsd: %s: %s\n' % (type(e).__name__, e))
    sys.exit(5)
)";
}

}  // namespace

void write_gsd(const std::filesystem::path& path, const std::vector<ParticleFrame>& frames) {
  check_output_path("", path);
  write_gsd(Directory::open(path.parent_path(), true), path.filename().string(), frames);
}

// The first eight bytes of every GSD file (gsd.h, GSD_MAGIC_ID), little-endian as written.
constexpr std::uint64_t kGsdMagic = 0x65DF65DF65DF65DFULL;

void write_gsd(const Directory& dir, std::string_view name_view, const std::vector<ParticleFrame>& frames) {
  const std::filesystem::path path = dir / name_view;
  const std::string name(name_view);
  Json all = Json::array();
  for (const auto& f : frames) all.push_back(particle_frame_json(f));
  // Named for the output, so that a failure to write it names the file the user asked for; never
  // committed, it is removed on every way out.
  TempFile input(dir, name);
  input.write(all.dump());
  TempFile out(dir, name);
  const char* env = std::getenv("BUDJAM_PYTHON");
  const std::string python = env && *env ? env : BUDJAM_PYTHON_EXECUTABLE;
  const ProgramResult r =
      run_program({python, "-c", gsd_writer(), input.path().string(), out.path().string()}, "export --format gsd",
                  "GSD is written by the Python package gsd: install Debian's python3-gsd, or set BUDJAM_PYTHON");
  if (r.signal == 0 && r.status == kNoGsdPackage)
    throw IoError(one_line(path.string()) + ": " + one_line(python) +
                  " has no gsd package (install Debian's python3-gsd, or set BUDJAM_PYTHON)");
  if (!r.ok())
    throw IoError(one_line(path.string()) + ": the GSD writer (" + one_line(python) + ", package gsd) " + r.failure());
  // A writer that ends well having written no GSD file (an interpreter that is not Python) must not
  // replace the user's file with nothing: the file has to begin with GSD's magic number.
  std::uint64_t magic = 0;
  std::ifstream written(out.path(), std::ios::binary);
  if (!written.read(reinterpret_cast<char*>(&magic), sizeof magic) || magic != kGsdMagic)
    throw IoError(one_line(path.string()) + ": the GSD writer (" + one_line(python) +
                  ") ended without writing a GSD file (set BUDJAM_PYTHON to a Python with the gsd package)");
  out.commit();
}

const std::vector<ExportFormat>& export_formats() {
  static const std::vector<ExportFormat> formats = {
      {"xyz", "extended XYZ: OVITO, ASE",
       [](const std::filesystem::path& path, const ParticleFrame& f) { write_atomically(path, format_extxyz(f)); }},
      {"gsd", "GSD in the HOOMD schema: OVITO, gsd, HOOMD-blue",
       [](const std::filesystem::path& path, const ParticleFrame& f) { write_gsd(path, {f}); }},
      {"vtk", "legacy VTK: ParaView, meshio",
       [](const std::filesystem::path& path, const ParticleFrame& f) { write_atomically(path, format_vtk(f)); }},
  };
  return formats;
}

std::string export_formats_text() {
  std::vector<Choice> formats;
  for (const ExportFormat& f : export_formats()) formats.push_back({f.name, f.description});
  return describe_choices(formats);
}

const ExportFormat* find_export_format(std::string_view name) {
  for (const ExportFormat& format : export_formats())
    if (format.name == name) return &format;
  return nullptr;
}

void write_particles(const std::filesystem::path& path, const ParticleFrame& frame, const std::string& format) {
  const ExportFormat* f = find_export_format(format);
  if (!f) throw std::invalid_argument("write_particles: unknown format " + format);
  f->write(path, frame);
}

}  // namespace budjam::io
