// `budjam accuracy --reference DIR VARIANT_DIR... --out DIR`
// Accuracy against cost of the numerical knobs (issue 6): each VARIANT_DIR and the reference hold run
// directories seed<k>/ grown from the same scene and seeds, differing in one knob (the reference has
// every knob tight). For each variant: mean wall time per run (timing.json) and the mean absolute
// error against the reference on the same seed of φ_J, u_J, Z_J, φ_2 (absolute), and of P, G and ω*
// at the targets (relative; G and ω* from the .moduli.json / .dos.json beside the target packings
// when present). Writes DIR/accuracy.csv and DIR/accuracy.json.
#include "command.hpp"
#include "run_data.hpp"

#include "budjam/scene.hpp"
#include "budjam/statistics.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/text.hpp"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace budjam;
using io::Json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Options {
  std::string reference;
  std::vector<std::string> variants;
  std::string out;
};

// seed<k> subdirectories with a summary.json, by name.
std::map<std::string, fs::path> seeds_of(const fs::path& dir) {
  std::map<std::string, fs::path> m;
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": not a directory");
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && fs::exists(e.path() / "summary.json")) m[e.path().filename().string()] = e.path();
  if (m.empty()) throw InputError(dir.string() + ": holds no run directory (seed*/summary.json)");
  return m;
}

double sidecar_number(const fs::path& pack, const std::string& kind, const char* key) {
  const auto j = tools::sidecar(pack, kind);
  if (!j || !j->contains(key) || !(*j)[key].is_number()) return kNaN;
  return (*j)[key].get<double>();
}

struct Measured {
  double seconds = kNaN, phi_J = kNaN, u_J = kNaN, Z_J = kNaN, phi_2 = kNaN;
  std::map<double, double> P, G, omega;  // by Δφ
};

Measured measure(const fs::path& run) {
  const tools::RunData r = tools::load_run(run);
  Measured m;
  if (fs::exists(run / "timing.json")) m.seconds = io::read_json(run / "timing.json").value("wall_seconds", kNaN);
  m.phi_J = r.get("phi_J");
  m.u_J = r.get("u_J");
  m.Z_J = r.get("Z_J");
  m.phi_2 = r.get("phi_2");
  for (const auto& t : r.summary.at("targets")) {
    const double d = t.at("dphi").get<double>();
    m.P[d] = t.at("P").get<double>();
    const fs::path pack = run / "packings" / ("target_" + std::to_string(t.at("index").get<long>()) + ".pack");
    m.G[d] = sidecar_number(pack, "moduli", "G");
    m.omega[d] = sidecar_number(pack, "dos", "omega_star");
  }
  return m;
}

double rel_error(const std::map<double, double>& a, const std::map<double, double>& ref) {
  std::vector<double> e;
  for (const auto& [d, v] : a) {
    auto it = ref.find(d);
    if (it != ref.end() && std::isfinite(v) && std::isfinite(it->second) && it->second != 0)
      e.push_back(std::abs(v - it->second) / std::abs(it->second));
  }
  return e.empty() ? kNaN : mean(e);
}

void run(const Options& o) {
  const auto ref_runs = seeds_of(o.reference);
  std::map<std::string, Measured> ref;
  for (const auto& [s, d] : ref_runs) ref[s] = measure(d);

  const std::vector<std::string> cols{"seconds", "err_phi_J", "err_u_J", "err_Z_J", "err_phi_2", "err_P", "err_G", "err_omega_star"};
  std::vector<std::pair<std::string, std::vector<double>>> table;
  auto add = [&](const std::string& name, const fs::path& dir, bool is_ref) {
    std::vector<std::vector<double>> per(cols.size());
    for (const auto& [s, d] : seeds_of(dir)) {
      if (!ref.count(s)) throw InputError(d.string() + ": the reference has no run " + s);
      const Measured m = measure(d);
      const Measured& R = ref.at(s);
      per[0].push_back(m.seconds);
      if (is_ref) continue;
      per[1].push_back(std::abs(m.phi_J - R.phi_J));
      per[2].push_back(std::abs(m.u_J - R.u_J));
      per[3].push_back(std::abs(m.Z_J - R.Z_J));
      per[4].push_back(std::abs(m.phi_2 - R.phi_2));
      per[5].push_back(rel_error(m.P, R.P));
      per[6].push_back(rel_error(m.G, R.G));
      per[7].push_back(rel_error(m.omega, R.omega));
    }
    std::vector<double> row;
    for (auto& v : per) {
      std::vector<double> f;
      for (double x : v)
        if (std::isfinite(x)) f.push_back(x);
      row.push_back(f.empty() ? kNaN : mean(f));
    }
    table.emplace_back(name, row);
  };
  for (const auto& v : o.variants) add(fs::path(v).filename().string(), v, false);
  add("reference", o.reference, true);

  const fs::path out(o.out);
  fs::create_directories(out);
  Json j = Json::array();
  io::write_atomically(out / "accuracy.csv", [&](std::ostream& os) {
    os << "variant";
    for (const auto& c : cols) os << ',' << c;
    os << '\n';
    for (const auto& [name, row] : table) {
      os << name;
      Json x;
      x["variant"] = name;
      for (std::size_t k = 0; k < cols.size(); ++k) {
        os << ',' << (std::isfinite(row[k]) ? io::format_double(row[k]) : std::string());
        x[cols[k]] = io::number_or_null(row[k]);
      }
      os << '\n';
      j.push_back(x);
    }
  });
  io::write_json(out / "accuracy.json",
                 Json{{"note", "mean over seeds of |variant - reference| (phi_J, u_J, Z_J, phi_2) and of the mean relative "
                               "error over targets (P, G, omega_star); seconds = mean wall time per run"},
                      {"reference", o.reference},
                      {"variants", j}});
  std::cerr << "accuracy: " << table.size() << " variants -> " << (out / "accuracy.csv").string() << "\n";
}

const bool registered = budjam::cli::register_command(
    {"accuracy", "Accuracy against cost: errors of phi_J, u_J, Z_J, phi_2, P, G, omega* against a tight reference",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("--reference", o->reference, "folder of the reference runs (seed*/)")->required();
       sub.add_option("VARIANT", o->variants, "folders of variant runs (seed*/), one knob changed each")->required();
       sub.add_option("--out", o->out, "output directory")->required();
       sub.callback([o] { run(*o); });
     }});

}  // namespace
