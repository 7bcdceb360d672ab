// The `budjam` Python module (pybind11): packings as numpy arrays and the library's analyses of
// them, the same functions the command line calls (python/budjam/__init__.py adds load_run).
// Units everywhere: lengths in mother diameters D0, forces in k·D0, stresses and moduli in k
// (per unit area in 2D), eigenvalues λ in k/m (m = mother mass), angles in radians.
#include "analysis/dos_report.hpp"
#include "analysis/moduli_report.hpp"
#include "analysis/rigidity_report.hpp"
#include "analysis/survival_report.hpp"
#include "budjam/blas_threads.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/growth_driver.hpp"
#include "budjam/moduli.hpp"
#include "budjam/rigidity.hpp"
#include "budjam/spectrum.hpp"
#include "budjam/survival.hpp"
#include "io/atomic_file.hpp"
#include "io/export.hpp"
#include "io/packing_file.hpp"
#include "io/result_files.hpp"
#include "io/run_data.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <pybind11/eigen.h>
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace budjam;
using namespace py::literals;

namespace {

template <class T>
py::array_t<T> array(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}
py::array_t<bool> array(const std::vector<bool>& v) {
  py::array_t<bool> a(static_cast<py::ssize_t>(v.size()));
  auto m = a.mutable_unchecked<1>();
  for (std::size_t k = 0; k < v.size(); ++k) m(static_cast<py::ssize_t>(k)) = v[k];
  return a;
}
template <class T>
std::vector<T> vector_of(const py::array_t<T, py::array::c_style | py::array::forcecast>& a, std::size_t n,
                         const char* name) {
  if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n)
    throw InputError(std::string(name) + ": expected a 1-d array of length " + std::to_string(n));
  return std::vector<T>(a.data(), a.data() + n);
}

py::array_t<double> coordinate(const Packing& p, int k) {
  py::array_t<double> a(static_cast<py::ssize_t>(p.size()));
  auto m = a.mutable_unchecked<1>();
  for (std::size_t i = 0; i < p.size(); ++i) m(static_cast<py::ssize_t>(i)) = p.q[3 * i + k];
  return a;
}

RigidityNetwork network_of(const std::string& name) { return parse_rigidity_network(name, "network"); }

// Every contact and the network, from the packing as it is (nothing relaxed).
struct Analysed {
  tools::PackingContacts pc;
  Lobes lobes;
  explicit Analysed(const Packing& p) : pc(tools::analyse_contacts(p)) { place_lobes(p, lobes); }
};

py::dict contacts_dict(const Packing& p) {
  const tools::PackingContacts pc = tools::analyse_contacts(p);
  const std::size_t n = pc.contacts.size();
  std::vector<std::uint32_t> i(n), j(n);
  std::vector<double> nx(n), ny(n), r(n), sigma(n), force(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Contact& c = pc.contacts[k];
    i[k] = c.i, j[k] = c.j, nx[k] = c.nx, ny[k] = c.ny, r[k] = c.r, sigma[k] = c.sigma, force[k] = c.force();
  }
  const ContactNetwork& net = pc.network;
  return py::dict("i"_a = array(i), "j"_a = array(j), "nx"_a = array(nx), "ny"_a = array(ny), "r"_a = array(r),
                  "sigma"_a = array(sigma), "force"_a = array(force), "rattler"_a = array(net.rattler),
                  "lobe_contacts"_a = array(net.lobe_contacts), "bud_pressure"_a = array(pc.bud_pressures),
                  "P"_a = pc.P, "N"_a = net.N, "N_nr"_a = net.N_nr, "N_f"_a = net.N_f, "N_c"_a = net.N_c,
                  "N_u"_a = net.N_u, "N_u_buds"_a = net.N_u_buds, "Z"_a = net.Z, "Z_iso"_a = net.Z_iso, "dZ"_a = net.dZ,
                  "u"_a = net.u, "u_buds"_a = net.u_buds);
}

// A JSON document of the command line as Python objects (null -> None), so that a Python result
// has the keys and values of the CLI's --json output by construction.
py::object python_of(const io::Json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A column of a budjam table as the numpy array pandas reads from it: int64 where every field is
// an integer, bool where every field is true or false, float64 where every field is a number or
// empty (NaN), text otherwise (an empty field NaN).
py::object column_array(const tools::CsvTable& t, std::size_t c) {
  const std::size_t n = t.size();
  bool integers = n > 0, flags = n > 0, numbers = true;
  for (std::size_t r = 0; r < n; ++r) {
    const std::string& f = t.text(r, c);
    integers = integers && io::parse_int64(f).has_value();
    flags = flags && (f == "true" || f == "false");
    numbers = numbers && tools::csv_number(f).has_value();
  }
  if (integers) {
    std::vector<std::int64_t> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = *io::parse_int64(t.text(r, c));
    return array(v);
  }
  if (flags) {
    std::vector<bool> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = t.text(r, c) == "true";
    return array(v);
  }
  if (numbers) {
    std::vector<double> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = *tools::csv_number(t.text(r, c));
    return array(v);
  }
  py::list v;
  for (std::size_t r = 0; r < n; ++r) {
    const std::string& f = t.text(r, c);
    v.append(f.empty() ? py::object(py::float_(std::nan(""))) : py::object(py::str(f)));
  }
  return py::module_::import("numpy").attr("array")(v, "dtype"_a = "object");
}

// A table as {column: array}, in the order of its columns.
py::dict table_dict(const tools::CsvTable& t) {
  py::dict d;
  for (std::size_t c = 0; c < t.columns.size(); ++c) d[py::str(t.columns[c])] = column_array(t, c);
  return d;
}

// A result of the command line as Python objects: its JSON, and under "table" the columns of its
// CSV, read back from the text the command line writes, so that both have one name per quantity
// and the same values.
py::dict result_dict(const io::CommandResult& result) {
  py::dict d = python_of(result.json);
  if (result.csv) {
    std::ostringstream os;
    result.csv(os);
    d["table"] = table_dict(tools::parse_csv(os.str(), "table"));
  }
  return d;
}

py::dict rigidity_dict(const Packing& p, const std::string& network) {
  const Analysed a(p);
  const tools::RigidityReport r =
      tools::rigidity_report(p, a.lobes, a.pc.contacts, a.pc.network, network_of(network), "packing");
  const RigidityState& s = r.state;
  const Framework fw = build_framework(p, a.lobes, a.pc.contacts, a.pc.network, r.network);
  py::array_t<std::uint32_t> bars({static_cast<py::ssize_t>(fw.bars.size()), py::ssize_t{2}});
  auto b = bars.mutable_unchecked<2>();
  for (std::size_t k = 0; k < fw.bars.size(); ++k) {
    b(static_cast<py::ssize_t>(k), 0) = static_cast<std::uint32_t>(fw.bars[k].a);
    b(static_cast<py::ssize_t>(k), 1) = static_cast<std::uint32_t>(fw.bars[k].b);
  }
  std::vector<int> lobe_cluster(2 * p.size());
  for (std::size_t lobe = 0; lobe < lobe_cluster.size(); ++lobe) lobe_cluster[lobe] = s.cell_cluster[cell_of(lobe)];
  std::vector<std::size_t> cluster_cells, cluster_joints;
  for (const auto& c : s.clusters) {
    cluster_cells.push_back(c.cells);
    cluster_joints.push_back(c.joints);
  }
  py::dict d = result_dict(tools::rigidity_result(r));
  // What only the Python result has: per lobe, per bar and per cluster.
  d["lobe_cluster"] = array(lobe_cluster);
  d["bar_lobes"] = bars;
  d["cluster_cells"] = array(cluster_cells);
  d["cluster_joints"] = array(cluster_joints);
  d["largest_cluster"] = s.largest;
  return d;
}

py::object moduli_dict(const Packing& p, const std::string& solver) {
  const Analysed a(p);
  ModuliOptions options;
  options.solver = parse_moduli_solver(solver);
  const ElasticResponse e = elastic_response(p, a.pc.contacts, a.pc.network, options);
  require_relaxed_moduli(e, "packing");  // unstable modes: returned, flagged by stationary_point
  return python_of(tools::elastic_response_json(e));
}

// A metadata value as the Python type it reads as: an integer, a number, or text ("none", "jammed").
py::object typed_meta_value(const std::string& text) {
  if (const auto i = io::parse_int64(text)) return py::int_(*i);
  if (const auto d = io::parse_double(text)) return py::float_(*d);
  return py::str(text);
}

// A metadata value given from Python as the text a packing file holds (numbers round-trip).
std::string meta_text(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::float_>(value)) return io::format_double(value.cast<double>());
  return py::str(value);
}

py::dict spectrum_dict(const Packing& p, const std::string& method, int modes) {
  const Analysed a(p);
  tools::DosRequest request;
  request.spectrum.method = parse_spectrum_method(method);
  if (modes < 0) throw InputError("modes: must be ≥ 0 (0 = as many as omega_star needs), got " + std::to_string(modes));
  request.spectrum.modes = modes;
  const tools::DosReport report = tools::dos_report(p, a.pc.contacts, a.pc.network, request);
  const PackingSpectrum& ps = report.result;
  const Spectrum& s = ps.spectrum;
  Eigen::MatrixXd vectors(3 * ps.cells.size(), s.lambda.size());
  for (Eigen::Index k = 0; k < s.lambda.size(); ++k) vectors.col(k) = s.mode(k);
  py::dict d = result_dict(tools::dos_result(report, request));
  // What only the Python result has: the modes themselves.
  d["cells"] = array(ps.cells);
  d["eigenvectors"] = vectors;
  d["mass"] = mass_diagonal(p);
  return d;
}

// Kaplan–Meier survival of the buds free at jamming, pooled over runs, as `budjam survival`.
py::dict survival_dict(const std::vector<std::filesystem::path>& runs, std::optional<double> epsilon) {
  return result_dict(tools::survival_result(tools::survival_report(runs, epsilon)));
}

py::dict frame_dict(const io::ParticleFrame& f) {
  std::vector<std::uint32_t> a, b;
  std::vector<int> kind;
  std::vector<double> force;
  std::vector<bool> crosses;
  for (const auto& bond : f.bonds) {
    a.push_back(bond.a), b.push_back(bond.b), kind.push_back(static_cast<int>(bond.kind));
    force.push_back(bond.force), crosses.push_back(bond.crosses_boundary);
  }
  return py::dict("step"_a = f.step, "L"_a = f.L, "shear"_a = f.shear, "x"_a = array(f.x), "y"_a = array(f.y),
                  "wrapped_x"_a = array(f.wrapped_x), "wrapped_y"_a = array(f.wrapped_y),
                  "image_x"_a = array(f.image_x), "image_y"_a = array(f.image_y), "radius"_a = array(f.radius),
                  "id"_a = array(f.id), "rigid_cluster"_a = array(f.cluster), "rattler"_a = array(f.rattler),
                  "bond_a"_a = array(a), "bond_b"_a = array(b), "bond_kind"_a = array(kind),
                  "bond_force"_a = array(force), "bond_crosses_boundary"_a = array(crosses));
}

// The events of a growth run as Python dicts, in the order the driver emits them. Each carries the
// state it happened in (step, phi, P, N, phase) and a copy of the packing. Fields that summary.json
// also records have its names: the jamming's *_J keys, those of its targets, unjammings and φ_2.
class EventQueue : public Observer {
 public:
  std::string name() const override { return "python"; }
  void on_jammed(const Jammed& e) override {
    const JammingRecord& j = e.jamming;
    push("jammed", e.state,
         py::dict("episode"_a = j.episode, "phi_J"_a = j.phi, "Z_J"_a = j.network.Z, "Z_iso_J"_a = j.network.Z_iso,
                  "dZ_J"_a = j.network.dZ, "N_nr_J"_a = j.network.N_nr, "u_J"_a = j.network.u_buds,
                  "tagged_J"_a = j.tagged));
  }
  void on_unjammed(const Unjammed& e) override {
    const UnjamRecord& u = e.record;
    push("unjammed", e.state,
         py::dict("episode"_a = u.episode, "phi_J"_a = u.phi_J, "targets_lost"_a = u.targets_lost));
  }
  void on_target_reached(const TargetReached& e) override {
    const TargetRecord& t = e.target;
    push("target", e.state,
         py::dict("index"_a = t.index, "dphi"_a = t.dphi, "Z"_a = t.network.Z, "dZ"_a = t.network.dZ,
                  "N_nr"_a = t.network.N_nr, "chi_c"_a = t.chi_c));
  }
  void on_depleted(const Depleted& e) override {
    const DepletionRecord& d = e.depletion;
    push("phi2", e.state, py::dict("phi_2"_a = d.phi, "Z_2"_a = d.network.Z, "dZ_2"_a = d.network.dZ));
  }
  void on_divided(const Divided& e) override {
    const Division& d = e.division;
    push("division", e.state, py::dict("mother_id"_a = d.mother_id, "daughter_id"_a = d.daughter_id, "b"_a = d.b));
  }
  void on_bud_event(const BudEventHappened& e) override {
    push(std::string("bud_") + to_string(e.event.kind), e.state,
         py::dict("cell_id"_a = e.event.cell_id, "episode"_a = e.event.episode, "a"_a = e.event.a));
  }
  void on_finished(const Finished& e) override { push("finished", e.state, py::dict("status"_a = "finished")); }
  void on_failed(const Failed& e) override {
    // An expected early stop (step limit, ...) is an outcome of the run, not an exception.
    push("stopped", e.state, py::dict("status"_a = to_string(e.result.status), "message"_a = e.result.message));
  }

  std::deque<py::dict> events;

 private:
  void push(const std::string& kind, const StateView& s, py::dict fields) {
    io::PackingFile f;
    f.packing = *s.packing;
    // The metadata a run's packing file carries, so that the bridges (to_ase, to_gsd_frame, write)
    // see the state's step, φ and seed; a target's Δφ with it.
    const auto dphi = fields.contains("dphi") ? std::optional<double>(fields["dphi"].cast<double>()) : std::nullopt;
    f.meta = io::state_meta(s, kind, s.scene->seed, dphi);
    fields["kind"] = kind;
    fields["step"] = s.step;
    fields["phi"] = s.phi;
    fields["P"] = s.P;
    fields["N"] = s.packing->size();
    fields["phase"] = to_string(s.phase);
    fields["packing"] = std::move(f);
    events.push_back(std::move(fields));
  }
};

// The scene with `seed` as its run.seed, checked as `budjam grow --seed` checks it (a seed must fit
// a scene file, so that the run can be repeated from the command line).
Scene seeded(Scene scene, std::optional<std::uint64_t> seed) {
  if (seed) {
    scene.seed = *seed;
    validate(scene);
  }
  return scene;
}

// `for event in budjam.grow(...)`: advances the driver until it has something to report. Many growth
// steps, and relaxations of up to millions of force evaluations, pass between two events, so Python's
// signal handlers run between steps and inside relaxations (the hook of the command line's
// checkpoints): Ctrl-C raises KeyboardInterrupt at once, and the growth, left inside an attempt,
// cannot go on.
class Growth {
 public:
  Growth(const std::filesystem::path& scene, std::optional<std::uint64_t> seed, const std::vector<std::string>& set)
      : scene_(seeded(io::load_scene(scene, set), seed)), driver_(scene_) {
    driver_.add_observer(queue_);
    driver_.set_relaxation_checkpoints(
        0, [this] { return signal_raised(); }, [this](const GrowthState&) { end_interrupted(); });
  }
  py::dict next() {
    if (interrupted_) throw std::runtime_error("grow: interrupted inside a growth step: start a new budjam.grow");
    while (queue_.events.empty()) {
      if (driver_.result().status != RunStatus::running) throw py::stop_iteration();
      driver_.advance();
      if (signal_raised()) end_interrupted();
    }
    py::dict e = std::move(queue_.events.front());
    queue_.events.pop_front();
    return e;
  }
  const GrowthDriver& driver() const { return driver_; }

 private:
  // Runs Python's signal handlers; the exception one raised (KeyboardInterrupt) is kept for
  // end_interrupted, which throws it where the driver can be left.
  bool signal_raised() {
    if (!pending_ && PyErr_CheckSignals() != 0) pending_.emplace();
    return pending_.has_value();
  }
  [[noreturn]] void end_interrupted() {
    interrupted_ = true;
    py::error_already_set e = std::move(*pending_);
    pending_.reset();
    throw e;
  }

  Scene scene_;
  EventQueue queue_;
  GrowthDriver driver_;
  std::optional<py::error_already_set> pending_;
  bool interrupted_ = false;
};

}  // namespace

PYBIND11_MODULE(_budjam, m) {
  m.doc() = "budjam: growing budding-cell packings, jamming and rigidity (compiled core).";
  m.attr("__version__") = BUDJAM_VERSION;
  m.def("blas", &blas_library,
        "The BLAS this process computes with, as a run's summary.json records it (`blas`): results agree with "
        "the command line's to the last bit under the same one.");
  // Messages as the command line prints them: one line, control bytes escaped, bounded in length.
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<io::IoError> output_error(m, "OutputError", PyExc_OSError);
  static py::exception<NoResultError> no_result_error(m, "NoResultError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InputError& e) {
      input_error(io::one_line(e.what()).c_str());
    } catch (const io::IoError& e) {
      output_error(io::one_line(e.what()).c_str());
    } catch (const NoResultError& e) {
      no_result_error(io::one_line(e.what()).c_str());
    }
  });

  m.def("_one_line", &io::one_line, "text"_a, "A message as `budjam` prints it: one line, control bytes as \\xNN.");

  py::class_<io::PackingFile>(m, "Packing", R"(A packing of rigid mother–bud dumbbells in a periodic square box.

Units: lengths in mother diameters D0 = 1, angles in radians, growth rates per unit time.
Arrays are copies (numpy); build a modified packing with Packing(...).
Cell i has centroid (x[i], y[i]) (area-weighted, not wrapped into the box), orientation theta[i]
(mother → bud), bud diameter b[i], innate growth rate gamma0[i], lineage id[i] and parent[i]
(-1 for founders). Lobe 2i is the mother of cell i, lobe 2i+1 its bud.)")
      .def(py::init([](double L, const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                       const py::array_t<double, py::array::c_style | py::array::forcecast>& y,
                       const py::array_t<double, py::array::c_style | py::array::forcecast>& theta,
                       const py::array_t<double, py::array::c_style | py::array::forcecast>& b,
                       std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>> gamma0,
                       double shear, const py::dict& meta) {
             const std::size_t n = static_cast<std::size_t>(b.size());
             const auto xs = vector_of<double>(x, n, "x"), ys = vector_of<double>(y, n, "y"),
                        ts = vector_of<double>(theta, n, "theta"), bs = vector_of<double>(b, n, "b");
             const auto gs = gamma0 ? vector_of<double>(*gamma0, n, "gamma0") : std::vector<double>(n, 0.0);
             io::PackingFile f;
             f.packing.box.L = L;
             f.packing.box.shear = shear;
             for (std::size_t i = 0; i < n; ++i) f.packing.add_cell(xs[i], ys[i], ts[i], bs[i], gs[i], -1);
             for (const auto& [k, v] : meta) f.meta.values[py::str(k)] = meta_text(v);
             // What a file cannot hold, named by argument (L, x[i], meta[...]); then the file format's
             // checks (the box, b in range, overlaps, ...) apply to packings built here too.
             if (const auto problem = io::unwritable_problem(f.packing, f.meta)) throw InputError(*problem);
             return io::parse_packing(io::format_packing(f.packing, f.meta), "Packing(...)");
           }),
           "L"_a, "x"_a, "y"_a, "theta"_a, "b"_a, "gamma0"_a = py::none(), "shear"_a = 0.0,
           "meta"_a = py::dict(),
           "A packing of founder cells (ids 0..N-1, parent -1) from arrays; L and lengths in D0, theta in "
           "radians; gamma0 (innate growth rates) defaults to 0; meta: key/value metadata (numbers are "
           "written so that they read back equal; Packing(..., meta=p.meta) keeps p's).")
      .def_property_readonly("N", [](const io::PackingFile& f) { return f.packing.size(); }, "number of cells")
      .def_property_readonly("L", [](const io::PackingFile& f) { return f.packing.box.L; }, "box side, D0")
      .def_property_readonly("shear", [](const io::PackingFile& f) { return f.packing.box.shear; },
                             "Lees–Edwards shear strain γ (an image one box up is shifted by γL in x)")
      .def_property_readonly("phi", [](const io::PackingFile& f) { return f.packing.packing_fraction(); },
                             "packing fraction Σ cell areas / L² (overlaps not subtracted)")
      .def_property_readonly("x", [](const io::PackingFile& f) { return coordinate(f.packing, 0); },
                             "centroid x of every cell, D0 (not wrapped)")
      .def_property_readonly("y", [](const io::PackingFile& f) { return coordinate(f.packing, 1); },
                             "centroid y of every cell, D0 (not wrapped)")
      .def_property_readonly("theta", [](const io::PackingFile& f) { return coordinate(f.packing, 2); },
                             "orientation of every cell (mother → bud), radians")
      .def_property_readonly("b", [](const io::PackingFile& f) { return array(f.packing.b); }, "bud diameters, D0")
      .def_property_readonly("gamma0", [](const io::PackingFile& f) { return array(f.packing.gamma0); },
                             "innate growth rates γ0 (area growth per unit time)")
      .def_property_readonly("id", [](const io::PackingFile& f) { return array(f.packing.id); }, "lineage ids")
      .def_property_readonly("parent", [](const io::PackingFile& f) { return array(f.packing.parent); },
                             "id of each cell's mother cell, -1 for founders")
      .def_property_readonly(
          "meta",
          [](const io::PackingFile& f) {
            py::dict d;
            for (const auto& [k, v] : f.meta.values) d[py::str(k)] = typed_meta_value(v);
            return d;
          },
          "the file's metadata (phase, phi, P, step, seed, ...): integers as int, other numbers as float, "
          "the rest (phase, P0 'none') as str")
      .def("lobes", [](const io::PackingFile& f) {
             Lobes l;
             place_lobes(f.packing, l);
             return py::dict("x"_a = array(l.x), "y"_a = array(l.y), "radius"_a = array(l.R));
           },
           "Lobe centres and radii (D0): dict of arrays x, y, radius of length 2N; lobe 2i is the mother "
           "of cell i, 2i+1 its bud.")
      .def("write", [](const io::PackingFile& f, const std::filesystem::path& path) {
             io::check_output_file("", path);  // the command line's output-name rules
             const io::TemporariesRemovedOnStop stop;
             io::write_packing(path, f.packing, f.meta);
           },
           "path"_a, "Write the packing file (.pack), atomically; reads back bit-identically.")
      .def("__repr__", [](const io::PackingFile& f) {
        return "<budjam.Packing N=" + std::to_string(f.packing.size()) + " L=" + io::format_double(f.packing.box.L) + ">";
      });

  m.def("read_packing", &io::read_packing, "path"_a,
        "Read a packing file (.pack). InputError names the file and line.");
  m.def(
      "contacts", [](const io::PackingFile& f) { return contacts_dict(f.packing); }, "packing"_a,
      R"(Contacts of the packing as it is (nothing relaxed) and its contact network.

Per contact (arrays): lobes i < j, unit normal (nx, ny) from j to i, centre distance r and
sigma = R_i + R_j (D0), force = k (sigma - r) (k D0). Per cell: rattler (iterative rule); per
lobe: lobe_contacts (with non-rattlers); bud_pressure (force per unit bud perimeter, k).
Scalars: P (contact virial pressure, k), N, N_nr, N_f, N_c (counted twice), N_u, N_u_buds,
Z, Z_iso, dZ, u, u_buds (paper Eqs. 1-5; docs/rigidity.md).)");
  m.def(
      "rigidity",
      [](const io::PackingFile& f, const std::string& network) { return rigidity_dict(f.packing, network); },
      "packing"_a, "network"_a = "load-bearing",
      R"(Rigidity by the (2,3) pebble game: the result of `budjam rigidity` (docs/rigidity.md).

network: 'load-bearing' (rattlers removed) or 'raw'. The dict of its JSON, key for key (without
"file"): counts (joints, bars, independent_bars, redundant_bars, free_pebbles), floppy_modes in the
plane and periodic conventions, rigid_clusters, spans_x / spans_y, ...; under "table" the columns
of its CSV, per cell: cell, cluster (rigid cluster of the cell's mother-bud bar, -1 if not
analysed), bud_rigid. Only here: lobe_cluster (per lobe), bar_lobes (the bars as an (n, 2) array
of lobe pairs), cluster_cells / cluster_joints (per cluster), largest_cluster (its index, -1 for
none).)");
  m.def(
      "moduli", [](const io::PackingFile& f, const std::string& solver) { return moduli_dict(f.packing, solver); },
      "packing"_a, "solver"_a = "ldlt",
      R"(Linear elastic response of a relaxed packing: the dict of `budjam moduli --json` (same keys and
values, without "file"; docs/moduli.md, docs/files.md).

B and G (units k, 2D; G is the simple-shear modulus G_simple) from the contact-virial stress S
(the paper's convention), B_energy and G_energy from the relaxed energy; moduli, moduli_affine,
moduli_energy, moduli_energy_affine hold B, G_simple, G_pure, G_mean of each convention;
elastic_tensor is the Voigt stiffness C; response holds the 4x4 matrices dS_de, E, ... (order xx,
xy, yx, yy); shear_stability the softest and stiffest simple-shear directions (degrees).
An unjammed packing (N_nr = 0: no rigid backbone) or a relaxation that did not converge raises
NoResultError. A packing whose Hessian has unstable modes is returned flagged, the relaxed moduli
None: stationary_point "saddle" (energy_minimum False) or "contact-bounded minimum" (a minimum held
by a pair at zero force, energy_minimum True; docs/moduli.md, "Saddles").)");
  m.def(
      "spectrum",
      [](const io::PackingFile& f, const std::string& method, int modes) {
        return spectrum_dict(f.packing, method, modes);
      },
      "packing"_a, "method"_a = "auto", "modes"_a = 0,
      R"(Vibrational spectrum of the non-rattlers: the result of `budjam dos` (docs/spectrum.md).

The dict of its JSON, key for key: method, n_dof, N_zero (|lambda| < lambda_tol), omega_star (None if not
available), the counts N_u and floppy_modes, the histogram D(omega) under "dos", ...; under "table"
the columns of its CSV, per computed mode: mode, lambda (k/m, ascending), omega =
sign(lambda) sqrt|lambda|, participation, quasi_zero. Only here: eigenvectors as the orthonormal
columns of a (3n, k) array, the mass-weighted modes e = M^(1/2) u of the dynamical matrix
M^(-1/2) H M^(-1/2) over the (x, y, theta) of the kept cells `cells` (the displacement is
u = e / sqrt(mass[...]) with mass the (m, m, I) diagonal of every cell; the two uniform
translations are removed). method: auto | dense | arpack; modes: ARPACK modes (0: as many as
omega_star needs). An unjammed packing raises NoResultError (as budjam.moduli); method "arpack" on a
problem too small for it raises InputError; an eigensolver that does not converge raises NoResultError saying what to try. A saddle is
returned flagged: energy_minimum False, unstable_modes > 0, stationary_point "saddle" (as budjam.moduli;
"contact-bounded minimum" with energy_minimum True when its one unstable mode runs into a pair at zero
force).)");
  m.def("survival", &survival_dict, "runs"_a, "epsilon"_a = py::none(),
        R"(Kaplan-Meier survival of the buds free at jamming, pooled over finished run directories: the
result of `budjam survival` (each run's last jamming episode; completion is the event, division and
the end of the run censor; a run given twice is one sample). The dict of its JSON, key for key:
runs, records, events (completed buds), censored, u_J, N_nr_J, epsilon, a_eps, integral_S, ...,
and under "table" the columns of its CSV: a = b^2 - b_J^2 in D0^2 (diameter squared), a_area
(pi/4 times it), S, se (clustered by run), lo, hi (95 % band), se_greenwood (buds as independent),
at_risk, events, censored at each a.
epsilon: the cutoff of u_J S(a_eps) = epsilon (default 1/<N_nr,J>).)");
  m.def(
      "particle_frame",
      [](const io::PackingFile& f, const std::string& network) {
        return frame_dict(io::particle_frame(f, network_of(network)));
      },
      "packing"_a, "network"_a = "load-bearing",
      "The packing as particles (one per lobe) and bonds (links, then contacts), as `budjam export` "
      "writes it (docs/files.md, 'Export'): positions unwrapped (x, y) and wrapped with images, radius, "
      "lineage id, rigid_cluster, rattler; bonds a, b, kind (0 link, 1 contact), force (k D0, compressive).");
  m.def(
      "export",
      [](const io::PackingFile& f, const std::filesystem::path& path, const std::string& format,
         const std::string& network, const std::optional<std::filesystem::path>& source) {
        if (!io::find_export_format(format))
          throw InputError("format: must be one of " + io::export_formats_text() + " (got '" + format + "')");
        io::check_output_file("", path);  // the command line's output-name rules
        // Never over the file the packing was read from, given by path or as a Packing read from it.
        if (source || !f.source.empty()) io::check_not_an_input("path", path, {source.value_or(f.source)});
        const io::TemporariesRemovedOnStop stop;
        try {
          io::write_particles(path, io::particle_frame(f, network_of(network)), format);
        } catch (const std::exception&) {
          // Ctrl-C reaches the whole process group: the gsd writer it killed is this interrupt, not a failure.
          if (PyErr_CheckSignals() != 0) throw py::error_already_set();
          throw;
        }
      },
      "packing"_a, "path"_a, "format"_a, "network"_a = "load-bearing", "source"_a = py::none(),
      "Write the packing as `budjam export` does to `path` (the name is used as given): extended XYZ, "
      "GSD (HOOMD schema) or legacy VTK.");
  m.def(
      "gsd_frame",
      [](const io::PackingFile& f, const std::string& network) {
        py::dict scope;
        py::exec(io::kGsdFrameSource, scope);  // ImportError without numpy or gsd
        return scope["gsd_frame"](python_of(io::particle_frame_json(io::particle_frame(f, network_of(network)))));
      },
      "packing"_a, "network"_a = "load-bearing",
      "The packing as one gsd.hoomd.Frame, the frame `budjam export --format gsd` writes (needs the gsd "
      "package).");
  m.def(
      "read_run",
      [](const std::filesystem::path& dir) {
        const tools::RunData run = tools::load_run(dir);
        py::dict tables;
        for (const auto& [name, table] : tools::run_tables(run)) tables[py::str(name)] = table_dict(table);
        return py::make_tuple(python_of(run.summary), tables);
      },
      "directory"_a,
      "A finished run directory read and checked as `budjam analyse` reads it: (summary.json as a dict, "
      "{table name: {column: array}} of the CSV tables budjam wrote there). budjam.load_run builds on it.");

  py::class_<Growth>(m, "Growth", R"(A growth run as an iterator of events (`budjam.grow`).

Each event is a dict with kind ('jammed', 'unjammed', 'target', 'phi2', 'division', 'bud_tagged',
'bud_first_contact', 'bud_completed', ..., and last 'finished' or 'stopped' with the run's status:
'step_limit', or a failure such as 'minimiser_failed' or 'overlap_bound', which raises nothing), the state it happened in (step = accepted steps, phi,
P in k, N, phase) with a copy of the packing (its meta as a run's packing file has it), and the fields of that event under the names
summary.json gives them: jammed: episode, phi_J, Z_J, Z_iso_J, dZ_J, N_nr_J, u_J, tagged_J;
unjammed: episode, phi_J (the one lost), targets_lost; target: index, dphi, Z, dZ, N_nr, chi_c
(as an entry of its targets); phi2: phi_2, Z_2, dZ_2; division: mother_id, daughter_id, b (as
divisions.csv); bud_*: cell_id, episode, a (as bud_events.csv).)")
      .def(py::init<const std::filesystem::path&, std::optional<std::uint64_t>, const std::vector<std::string>&>(),
           "scene"_a, "seed"_a = py::none(), "set"_a = std::vector<std::string>{})
      .def("__iter__", [](Growth& g) -> Growth& { return g; })
      .def("__next__", &Growth::next)
      .def_property_readonly(
          "packing",
          [](const Growth& g) {
            return io::PackingFile{g.driver().packing(), {}, {}};
          },
          "the current (last accepted) packing")
      .def_property_readonly(
          "status", [](const Growth& g) { return std::string(to_string(g.driver().result().status)); },
          "'running', 'finished' or the reason of an early stop");
}
