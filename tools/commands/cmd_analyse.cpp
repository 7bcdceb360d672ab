// `budjam analyse RUNDIR... --out DIR [--main-L L] [--resamples N] [--seed S] [--require WHAT]`
// Ensemble analysis of finished growth runs (docs/analysis.md): every number behind the paper's
// figures and the reproduction report, as JSON and CSV tables. A RUNDIR may also be a folder that
// holds run directories (searched recursively for summary.json). Runs are grouped by (L, P0).
//
// Outputs in DIR:
//   analysis.json     per-group statistics and the headline numbers (mean ± SE, median ± bootstrap SE)
//   runs.csv          one row per run (φ_J, u_J, n_J, φ_2, predictions, P_2, G_2, divisions, h_γ ...)
//   targets.csv       one row per (run, Δφ target): P, Z, ΔZ, u, χ_c, λ_c, B_grow, ΔZ_0(P) + 2(u_J − u), B, G
//   survival.csv      pooled Kaplan–Meier S(a) per group with Greenwood band (Fig. 2B)
//   remaining.csv     fraction of the buds free at jamming still free against φ − φ_J (Fig. 2B)
//   division_curve.csv  cumulative post-jamming divisions / ⟨N_J⟩ against Δφ: median and quartiles (Fig. D1)
//   growth_rates.csv  Π(g) histograms at Δφ = 3·10⁻³ per group (Fig. E1)
//   trajectory.csv    mean (P, G) per (group, Δφ) below φ_2, and the endpoints (Fig. 4)
//   dos.csv           per packing with a DOS: ω*, ΔZ, Z − 6, N_zero, N_u (Fig. F1B–C)
// Moduli and spectra are read from packings/<name>.moduli.json / .dos.json (written by
// `budjam moduli` / `budjam dos` in the Makefile pipeline). --require moduli,dos makes their absence
// an error instead of empty columns.
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include "budjam/depletion.hpp"
#include "budjam/growth.hpp"
#include "budjam/errors.hpp"
#include "budjam/statistics.hpp"
#include "budjam/survival.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace budjam;
using io::Json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPmax = 0.1;      // confluence pressure scale (paper Eq. D22)
constexpr double kM4 = 0.125;      // ⟨n_x² n_y²⟩ of an isotropic network
constexpr double kDphiGrowth = 3e-3;  // Δφ of the growth-rate crossover (appendix E)

struct Options {
  std::vector<std::string> inputs;
  std::string out;
  double main_L = 0;  // 0: 15 if present, else the largest L
  int resamples = 2000;
  std::uint64_t seed = 1;
  std::vector<std::string> require;
};

std::string num(double v) { return io::format_double(v); }

// ---- per-run extraction ------------------------------------------------------------------------

struct TargetRow {
  double dphi = kNaN, phi = kNaN, P = kNaN, Z = kNaN, dZ = kNaN, Z_iso = kNaN, u = kNaN, u_lobes = kNaN;
  double chi_c = kNaN, lambda = kNaN, B_grow = kNaN, B_grow_se = kNaN, N_div = kNaN, N_nr = kNaN;
  double dZ_pred = kNaN;                   // ΔZ_0(P) + 2(u_J − u), filled once the branch is known
  double B = kNaN, G = kNaN, B_ext_mf = kNaN;  // from the moduli sidecar
  double G_min = kNaN;  // softest simple shear of the box (moduli sidecar "shear_stability"); < 0: unstable
  bool below_phi2 = false;
};

struct RunRow {
  fs::path dir;
  double L = kNaN;
  std::optional<double> P0;
  std::string P0_label;
  std::uint64_t seed = 0;
  std::string status;
  bool jammed = false, depleted = false;
  double phi_J = kNaN, u_J = kNaN, n_J = kNaN, N_J = kNaN, N_nr_J = kNaN, Z_J = kNaN, dZ_J = kNaN, P_J = kNaN;
  double tagged = kNaN, lc2_J = kNaN;
  double phi_2 = kNaN, dphi_2 = kNaN, P_2 = kNaN, Z_2 = kNaN, dZ_2 = kNaN, u_2 = kNaN, N_div_2 = kNaN;
  double chi_bar = kNaN, lambda_bar = kNaN;
  double a_eps = kNaN, int_S = kNaN, pred_area = kNaN, pred_d2 = kNaN;  // per-run KM, ε = 1/N_nr,J
  double G_2 = kNaN, B_2 = kNaN, G_min_2 = kNaN;
  double h_gamma = kNaN;
  std::vector<double> g;  // growth factors of the non-rattler cells at Δφ = 3·10⁻³
  std::vector<SurvivalRecord> survival;
  std::vector<TargetRow> targets;
  // curves on the Δφ grid
  std::vector<double> remaining;  // tagged_active / tagged (NaN beyond the run)
  std::vector<double> divisions;  // cumulative divisions after φ_J
};

struct DosRow {
  std::string run, packing;
  double L = kNaN;
  std::string P0_label;
  double dphi = kNaN, omega_star = kNaN, dZ = kNaN, Z = kNaN, N_zero = kNaN, N_u = kNaN, N_u_buds = kNaN;
};

Json fraction_json(std::size_t k, std::size_t n) {
  return Json{{"fraction", n ? Json(static_cast<double>(k) / static_cast<double>(n)) : Json(nullptr)}, {"packings", n}};
}

std::vector<double> dphi_grid() {
  std::vector<double> g;
  for (int k = 0; k <= 40; ++k) g.push_back(1e-4 * std::pow(10.0, 3.2 * k / 40.0));  // 1e-4 … ≈0.16
  return g;
}

// A number from a sidecar JSON: the first of `keys` present (top level, then under "moduli").
double json_number(const Json& j, std::initializer_list<const char*> keys) {
  for (const char* k : keys) {
    if (j.contains(k) && j[k].is_number()) return j[k].get<double>();
    if (j.contains("moduli") && j["moduli"].contains(k) && j["moduli"][k].is_number()) return j["moduli"][k].get<double>();
  }
  return kNaN;
}

struct SidecarModuli {
  double B = kNaN, G = kNaN, B_ext_mf = kNaN, G_min = kNaN;
};

struct ModuliFiles {
  std::size_t found = 0;
  std::size_t saddles = 0;  // "energy_minimum": false — no relaxed B, G (NaN here, left out of every statistic)
};

SidecarModuli read_moduli(const fs::path& pack, bool required, ModuliFiles& files) {
  SidecarModuli m;
  const auto j = tools::sidecar(pack, "moduli");
  if (!j) {
    if (required && fs::exists(pack))
      throw InputError(pack.string() + ": no moduli (expected " + fs::path(pack).replace_extension(".moduli.json").string() +
                       "; run `make -f Makefile.analysis moduli`)");
    return m;
  }
  ++files.found;
  m.B_ext_mf = json_number(*j, {"B_ext_mean_field", "B_mf", "B_ext_mf"});
  if (j->contains("energy_minimum") && (*j)["energy_minimum"].is_boolean() && !(*j)["energy_minimum"].get<bool>()) {
    ++files.saddles;
    return m;
  }
  m.B = json_number(*j, {"B", "bulk_modulus"});
  m.G = json_number(*j, {"G", "shear_modulus"});
  if (j->contains("shear_stability")) m.G_min = json_number((*j)["shear_stability"], {"G_min"});
  if (!std::isfinite(m.G) || !std::isfinite(m.B))
    throw InputError(fs::path(pack).replace_extension(".moduli.json").string() + ": no numeric \"B\" and \"G\"");
  return m;
}

RunRow extract(const tools::RunData& r, bool need_moduli, ModuliFiles& moduli_found) {
  RunRow x;
  x.dir = r.dir;
  x.L = r.L();
  x.P0 = r.P0();
  x.P0_label = r.P0_label();
  x.seed = r.seed();
  x.status = r.status();
  x.jammed = r.jammed();
  if (!x.jammed) return x;
  x.phi_J = r.get("phi_J");
  x.u_J = r.get("u_J");
  x.n_J = r.get("n_J");
  x.N_J = r.get("N_J");
  x.N_nr_J = r.get("N_nr_J");
  x.Z_J = r.get("Z_J");
  x.dZ_J = r.get("dZ_J");
  x.P_J = r.get("P_J");
  x.tagged = r.get("tagged_J");
  const double step_J = r.get("step_J");
  x.phi_2 = r.get("phi_2");
  x.depleted = std::isfinite(x.phi_2);
  const double step_2 = r.get("step_2");
  if (x.depleted) {
    x.dphi_2 = x.phi_2 - x.phi_J;
    x.P_2 = r.get("P_2");
    x.Z_2 = r.get("Z_2");
    x.dZ_2 = r.get("dZ_2");
    x.N_div_2 = r.get("N_div_2");
  }

  // steps.csv above jamming (the current episode starts at step_J)
  const auto& S = r.steps;
  const std::size_t c_step = S.column("step"), c_phi = S.column("phi"), c_P = S.column("P"), c_N = S.column("N"),
                    c_Nf = S.column("N_f"), c_Nub = S.column("N_u_buds"), c_chi = S.column("chi_c"),
                    c_act = S.column("tagged_active");
  std::vector<double> st, phi, P, u, chi;
  std::vector<double> active;
  for (std::size_t k = 0; k < S.size(); ++k) {
    const double s = S.number(k, c_step);
    if (s < step_J) continue;
    st.push_back(s);
    phi.push_back(S.number(k, c_phi));
    P.push_back(S.number(k, c_P));
    const double N = S.number(k, c_N), Nf = S.number(k, c_Nf);
    u.push_back(S.number(k, c_Nub) / (N - Nf));
    chi.push_back(S.number(k, c_chi));
    active.push_back(S.number(k, c_act));
  }
  if (x.depleted) {
    std::vector<double> ph, ch, la;
    for (std::size_t k = 0; k < st.size(); ++k)
      if (st[k] <= step_2) {
        ph.push_back(phi[k]);
        ch.push_back(chi[k]);
        la.push_back(lambda_c(u[k], chi[k]));
        if (st[k] == step_2) x.u_2 = u[k];
      }
    x.chi_bar = interval_average(ph, ch, x.phi_J, x.phi_2);
    x.lambda_bar = interval_average(ph, la, x.phi_J, x.phi_2);
  }

  // Survival of the tagged buds: per-run a_ε with ε = 1/N_nr,J (at most one left = φ_2's definition)
  if (r.bud_events) {
    x.survival = tools::survival_records(*r.bud_events);
    if (!x.survival.empty() && x.u_J > 0) {
      const auto km = kaplan_meier(x.survival);
      if (const auto ae = a_epsilon(km, x.u_J, 1.0 / x.N_nr_J)) {
        x.a_eps = *ae;
        x.int_S = km.integral(*ae);
        if (std::isfinite(x.chi_bar)) {
          const auto p = predict_phi2(x.n_J, x.u_J, x.chi_bar, x.a_eps, x.int_S);
          x.pred_area = p.dphi2_area;
          x.pred_d2 = p.dphi2_diameter_sq;
        }
      }
    }
  }

  // Targets
  for (const auto& t : r.summary.at("targets")) {
    TargetRow y;
    y.dphi = t.at("dphi").get<double>();
    y.phi = t.at("phi").get<double>();
    y.P = t.at("P").get<double>();
    y.Z = t.at("Z").get<double>();
    y.dZ = t.at("dZ").get<double>();
    y.Z_iso = t.at("Z_iso").get<double>();
    y.u = t.at("u_buds").get<double>();
    y.u_lobes = t.at("u").get<double>();
    y.chi_c = t.at("chi_c").get<double>();
    y.N_div = t.at("N_div").get<double>();
    y.N_nr = t.at("N_nr").get<double>();
    y.lambda = lambda_c(y.u, y.chi_c);
    const long tstep = t.at("step").get<long>();
    std::vector<double> ph, pp;
    for (std::size_t k = 0; k < st.size(); ++k)
      if (st[k] <= tstep) {
        ph.push_back(phi[k]);
        pp.push_back(P[k]);
      }
    if (const auto b = b_grow(ph, pp, y.phi, 5)) {
      y.B_grow = b->B;
      y.B_grow_se = b->B_se;
    }
    y.below_phi2 = !x.depleted || y.phi <= x.phi_2;
    const fs::path pack = r.dir / "packings" / ("target_" + std::to_string(t.at("index").get<long>()) + ".pack");
    const SidecarModuli sm = read_moduli(pack, need_moduli, moduli_found);
    y.B = sm.B;
    y.G = sm.G;
    y.B_ext_mf = sm.B_ext_mf;
    y.G_min = sm.G_min;
    x.targets.push_back(y);

    // growth-rate distribution at Δφ = 3·10⁻³ (non-rattler cells; g = exp(−p/P0), 1 without feedback)
    if (std::abs(y.dphi - kDphiGrowth) < 1e-12 && fs::exists(pack)) {
      const io::PackingFile f = io::read_packing(pack);
      const auto pc = tools::analyse_contacts(f.packing);
      for (std::size_t i = 0; i < f.packing.size(); ++i)
        if (!pc.network.rattler[i]) x.g.push_back(growth_factor(pc.bud_pressures[i], x.P0));
      x.h_gamma = growth_heterogeneity(x.g);
    }
  }
  if (x.depleted) {
    const SidecarModuli sm = read_moduli(r.dir / "packings" / "phi2.pack", need_moduli, moduli_found);
    x.B_2 = sm.B;
    x.G_2 = sm.G;
    x.G_min_2 = sm.G_min;
  }
  {
    const fs::path jam = r.dir / "packings" / "jammed.pack";
    if (fs::exists(jam)) x.lc2_J = tools::analyse_contacts(io::read_packing(jam).packing).lc2;
  }

  // Curves on the Δφ grid
  const auto grid = dphi_grid();
  const double last = phi.empty() ? x.phi_J : phi.back();
  for (double d : grid) {
    double v = kNaN;
    if (x.phi_J + d <= last && x.tagged > 0)
      for (std::size_t k = 0; k < phi.size() && phi[k] - x.phi_J <= d; ++k) v = active[k] / x.tagged;
    x.remaining.push_back(v);
  }
  {
    const auto& D = r.divisions;
    const std::size_t c_s = D.column("step"), c_p = D.column("phi");
    std::vector<double> dd;
    for (std::size_t k = 0; k < D.size(); ++k)
      if (D.number(k, c_s) > step_J) dd.push_back(D.number(k, c_p) - x.phi_J);
    for (double d : grid) {
      if (x.phi_J + d > last) {
        x.divisions.push_back(kNaN);
        continue;
      }
      x.divisions.push_back(static_cast<double>(std::count_if(dd.begin(), dd.end(), [&](double v) { return v <= d; })));
    }
  }
  return x;
}

// ---- grouping and statistics ---------------------------------------------------------------------

struct GroupKey {
  double L;
  std::optional<double> P0;
  bool operator<(const GroupKey& o) const {
    if (L != o.L) return L < o.L;
    // none first, then decreasing P0 (weak → strong feedback), as in the paper's figures
    if (P0.has_value() != o.P0.has_value()) return !P0.has_value();
    return P0 && *P0 > *o.P0;
  }
};

std::vector<double> finite(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  return v;
}

Json mean_se_json(const std::vector<double>& v0) {
  const auto v = finite(v0);
  Json j;
  j["n"] = v.size();
  j["mean"] = io::number_or_null(mean(v));
  j["se"] = io::number_or_null(v.size() >= 2 ? standard_error(v) : kNaN);
  return j;
}

Json median_json(const std::vector<double>& v0, const BootstrapOptions& bo) {
  const auto v = finite(v0);
  Json j;
  j["n"] = v.size();
  if (v.empty()) {
    j["median"] = nullptr;
    j["se"] = nullptr;
    j["ci95"] = Json::array({nullptr, nullptr});
    return j;
  }
  const auto b = bootstrap_median(v, bo);
  j["median"] = b.estimate;
  j["se"] = b.se;  // bootstrap SE of the median
  j["ci95"] = Json::array({b.lo, b.hi});
  j["q25"] = quantile(v, 0.25);
  j["q75"] = quantile(v, 0.75);
  return j;
}

template <class F>
std::vector<double> collect(const std::vector<const RunRow*>& rs, F f) {
  std::vector<double> v;
  for (const auto* r : rs) v.push_back(f(*r));
  return v;
}

std::vector<fs::path> find_runs(const std::vector<std::string>& inputs) {
  std::set<fs::path> runs;
  for (const auto& in : inputs) {
    const fs::path p(in);
    if (!fs::exists(p)) throw InputError(in + ": no such run directory");
    if (fs::exists(p / "summary.json")) {
      runs.insert(p);
      continue;
    }
    if (!fs::is_directory(p)) throw InputError(in + ": not a directory");
    bool any = false;
    for (const auto& e : fs::recursive_directory_iterator(p))
      if (e.is_regular_file() && e.path().filename() == "summary.json") {
        runs.insert(e.path().parent_path());
        any = true;
      }
    if (!any) throw InputError(in + ": holds no finished run (no summary.json below it)");
  }
  return {runs.begin(), runs.end()};
}

void write_csv(const fs::path& path, const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  io::write_atomically(path, [&](std::ostream& os) {
    for (std::size_t k = 0; k < header.size(); ++k) os << (k ? "," : "") << header[k];
    os << '\n';
    for (const auto& r : rows) {
      for (std::size_t k = 0; k < r.size(); ++k) os << (k ? "," : "") << r[k];
      os << '\n';
    }
  });
}

std::string cell(double v) { return std::isfinite(v) ? num(v) : std::string(); }

void run(const Options& o) {
  if (o.out.empty()) throw InputError("--out: an output directory is required");
  if (o.resamples < 2) throw InputError("--resamples: must be at least 2");
  bool need_moduli = false, need_dos = false;
  for (const auto& w : o.require) {
    if (w == "moduli") need_moduli = true;
    else if (w == "dos") need_dos = true;
    else throw InputError("--require: unknown item '" + w + "' (known: moduli, dos)");
  }
  BootstrapOptions bo;
  bo.resamples = o.resamples;
  bo.seed = o.seed;

  const auto dirs = find_runs(o.inputs);
  std::vector<RunRow> rows;
  std::vector<DosRow> dos_rows;
  std::vector<std::string> failed;
  ModuliFiles moduli_found;
  std::size_t dos_found = 0;
  for (const auto& d : dirs) {
    const tools::RunData r = tools::load_run(d);
    // A run that stopped early (step limit, say) still landed every state it recorded: its jamming
    // point, targets and φ_2 are used; it is listed so that the report can say so. One that never
    // jammed has nothing to contribute.
    if (r.status() != "finished") failed.push_back(d.string() + " (" + r.status() + ")");
    if (!r.jammed()) continue;
    rows.push_back(extract(r, need_moduli, moduli_found));
    // spectra beside any packing of the run
    for (const auto& e : fs::directory_iterator(d / "packings")) {
      if (e.path().extension() != ".pack") continue;
      const auto j = tools::sidecar(e.path(), "dos");
      if (!j) {
        if (need_dos) throw InputError(e.path().string() + ": no spectrum (run `make -f Makefile.analysis dos`)");
        continue;
      }
      ++dos_found;
      DosRow q;
      q.run = d.string();
      q.packing = e.path().stem().string();
      q.L = rows.back().L;
      q.P0_label = rows.back().P0_label;
      const io::PackingFile f = io::read_packing(e.path());
      q.dphi = f.meta.has("dphi") ? f.meta.number("dphi") : (f.meta.has("phi_J") ? f.meta.number("phi") - f.meta.number("phi_J") : kNaN);
      q.omega_star = json_number(*j, {"omega_star"});
      q.N_zero = json_number(*j, {"N_zero"});
      const auto pc = tools::analyse_contacts(f.packing);
      q.Z = pc.network.Z;
      q.dZ = pc.network.dZ;
      q.N_u = static_cast<double>(pc.network.N_u);
      q.N_u_buds = static_cast<double>(pc.network.N_u_buds);
      if (!std::isfinite(q.omega_star) || !std::isfinite(q.N_zero))
        throw InputError(e.path().string() + ": its .dos.json has no numeric \"omega_star\" and \"N_zero\"");
      dos_rows.push_back(q);
    }
  }
  if (rows.empty()) throw InputError("analyse: no run among the inputs reached jamming");

  std::map<GroupKey, std::vector<const RunRow*>> groups;
  std::set<double> lengths;
  for (const auto& r : rows) {
    groups[{r.L, r.P0}].push_back(&r);
    lengths.insert(r.L);
  }
  const double main_L = o.main_L > 0 ? o.main_L : (lengths.count(15.0) ? 15.0 : *lengths.rbegin());
  if (!lengths.count(main_L)) throw InputError("--main-L: no runs with L = " + num(main_L));

  // ΔZ_0(P): no-feedback branch per L — mean (P, ΔZ) at jamming and at each Δφ target.
  std::map<double, PiecewiseLinear> branch;
  for (double L : lengths) {
    auto it = groups.find({L, std::nullopt});
    if (it == groups.end()) continue;
    std::map<double, std::pair<std::vector<double>, std::vector<double>>> by_dphi;
    std::vector<double> PJ, dZJ;
    for (const auto* r : it->second) {
      if (!r->jammed) continue;
      PJ.push_back(r->P_J);
      dZJ.push_back(r->dZ_J);
      for (const auto& t : r->targets) {
        by_dphi[t.dphi].first.push_back(t.P);
        by_dphi[t.dphi].second.push_back(t.dZ);
      }
    }
    std::vector<std::pair<double, double>> pts;
    if (!PJ.empty()) pts.emplace_back(mean(PJ), mean(dZJ));
    for (auto& [d, v] : by_dphi) pts.emplace_back(mean(v.first), mean(v.second));
    if (!pts.empty()) branch.emplace(L, PiecewiseLinear(pts));
  }
  for (auto& r : rows) {
    auto b = branch.find(r.L);
    if (b == branch.end()) continue;
    for (auto& t : r.targets) t.dZ_pred = b->second(t.P) + 2.0 * (r.u_J - t.u);
  }

  const fs::path out(o.out);
  fs::create_directories(out);
  const auto grid = dphi_grid();

  // ---- per-group statistics -----------------------------------------------------------------
  Json jgroups = Json::array();
  std::vector<std::vector<std::string>> surv_rows, rem_rows, div_rows, g_rows, traj_rows;
  const std::vector<double> g_edges = [] {
    std::vector<double> e;
    for (int k = 0; k <= 20; ++k) e.push_back(k / 20.0);
    return e;
  }();
  for (const auto& [key, rs] : groups) {
    const std::string P0s = key.P0 ? num(*key.P0) : "none";
    std::vector<const RunRow*> jam, dep;
    for (const auto* r : rs) {
      if (r->jammed) jam.push_back(r);
      if (r->depleted) dep.push_back(r);
    }
    Json g;
    g["L"] = key.L;
    g["P0"] = key.P0 ? Json(*key.P0) : Json(nullptr);
    g["P0_label"] = P0s;
    g["runs"] = rs.size();
    g["jammed"] = jam.size();
    g["depleted"] = dep.size();
    g["phi_J"] = mean_se_json(collect(jam, [](auto& r) { return r.phi_J; }));
    g["u_J"] = mean_se_json(collect(jam, [](auto& r) { return r.u_J; }));
    g["n_J"] = mean_se_json(collect(jam, [](auto& r) { return r.n_J; }));
    g["N_J"] = mean_se_json(collect(jam, [](auto& r) { return r.N_J; }));
    g["N_nr_J"] = mean_se_json(collect(jam, [](auto& r) { return r.N_nr_J; }));
    g["Z_J"] = mean_se_json(collect(jam, [](auto& r) { return r.Z_J; }));
    g["dZ_J"] = mean_se_json(collect(jam, [](auto& r) { return r.dZ_J; }));
    g["lc2_J"] = mean_se_json(collect(jam, [](auto& r) { return r.lc2_J; }));
    g["dphi_2"] = mean_se_json(collect(dep, [](auto& r) { return r.dphi_2; }));
    g["phi_2"] = mean_se_json(collect(dep, [](auto& r) { return r.phi_2; }));
    g["dphi_2_pred_area"] = mean_se_json(collect(dep, [](auto& r) { return r.pred_area; }));
    g["dphi_2_pred_diameter_sq"] = mean_se_json(collect(dep, [](auto& r) { return r.pred_d2; }));
    g["a_eps"] = mean_se_json(collect(dep, [](auto& r) { return r.a_eps; }));
    g["chi_bar"] = mean_se_json(collect(dep, [](auto& r) { return r.chi_bar; }));
    g["lambda_bar"] = mean_se_json(collect(dep, [](auto& r) { return r.lambda_bar; }));
    g["P_2"] = mean_se_json(collect(dep, [](auto& r) { return r.P_2; }));
    g["P_2_over_Pmax"] = mean_se_json(collect(dep, [](auto& r) { return r.P_2 / kPmax; }));
    g["P_2_median"] = median_json(collect(dep, [](auto& r) { return r.P_2; }), bo);
    g["a_eps_area"] = mean_se_json(collect(dep, [](auto& r) { return kDiameterSquaredToArea * r.a_eps; }));
    g["dZ_2"] = mean_se_json(collect(dep, [](auto& r) { return r.dZ_2; }));
    g["u_2"] = mean_se_json(collect(dep, [](auto& r) { return r.u_2; }));
    g["G_2"] = median_json(collect(dep, [](auto& r) { return r.G_2; }), bo);
    g["G_2_mean"] = mean_se_json(collect(dep, [](auto& r) { return r.G_2; }));
    g["G_2_over_Pmax"] = median_json(collect(dep, [](auto& r) { return r.G_2 / kPmax; }), bo);
    g["G_2_over_P_2"] = median_json(collect(dep, [](auto& r) { return r.G_2 / r.P_2; }), bo);
    {
      // Packings unstable to some simple shear of the box (G_min < 0; moduli.hpp, ShearStability).
      std::size_t n = 0, k = 0, n2 = 0, k2 = 0;
      for (const auto* r : jam) {
        for (const auto& t : r->targets)
          if (std::isfinite(t.G_min)) ++n, k += t.G_min < 0;
        if (r->depleted && std::isfinite(r->G_min_2)) ++n2, k2 += r->G_min_2 < 0;
      }
      g["shear_unstable_targets"] = fraction_json(k, n);
      g["shear_unstable_phi2"] = fraction_json(k2, n2);
    }
    {
      // Divisions by φ_2 normalised by the mean number of cells at jamming (Fig. D1B)
      const double NJ = mean(finite(collect(jam, [](auto& r) { return r.N_J; })));
      g["N_div_2_over_N_J"] = median_json(collect(dep, [NJ](auto& r) { return r.N_div_2 / NJ; }), bo);
    }
    g["h_gamma"] = median_json(collect(jam, [](auto& r) { return r.h_gamma; }), bo);

    // pooled Kaplan–Meier and the pooled prediction
    std::vector<SurvivalRecord> pool;
    for (const auto* r : jam) pool.insert(pool.end(), r->survival.begin(), r->survival.end());
    const auto km = kaplan_meier(pool);
    const double uJ = mean(finite(collect(jam, [](auto& r) { return r.u_J; })));
    const double nJ = mean(finite(collect(jam, [](auto& r) { return r.n_J; })));
    const double NnrJ = mean(finite(collect(jam, [](auto& r) { return r.N_nr_J; })));
    const double chib = mean(finite(collect(dep, [](auto& r) { return r.chi_bar; })));
    Json pooled;
    pooled["records"] = km.records();
    pooled["events"] = km.events();
    pooled["epsilon"] = io::number_or_null(1.0 / NnrJ);
    std::optional<double> ae;
    if (uJ > 0 && std::isfinite(NnrJ)) ae = a_epsilon(km, uJ, 1.0 / NnrJ);
    pooled["a_eps"] = io::number_or_null(ae);
    if (ae) {
      const auto p = predict_phi2(nJ, uJ, chib, *ae, km.integral(*ae));
      pooled["integral_S"] = p.integral_S_d2;
      pooled["dphi_2_pred_area"] = io::number_or_null(p.dphi2_area);
      pooled["dphi_2_pred_diameter_sq"] = io::number_or_null(p.dphi2_diameter_sq);
    }
    // mean completion size a_c = ∫_0^∞ S da (restricted to the last completion), as a true area
    {
      double last_event = 0;
      for (const auto& st : km.steps())
        if (st.events > 0) last_event = st.a;
      pooled["a_c_mean_area"] = km.events() ? Json(kDiameterSquaredToArea * km.integral(last_event)) : Json(nullptr);
    }
    g["pooled_survival"] = pooled;
    surv_rows.push_back({num(key.L), P0s, "0", "1", "0", "1", "1", std::to_string(km.records())});
    for (const auto& st : km.steps()) {
      const double se = std::sqrt(st.greenwood_var);
      surv_rows.push_back({num(key.L), P0s, num(st.a), num(st.S), num(se), num(std::max(0.0, st.S - 1.96 * se)),
                           num(std::min(1.0, st.S + 1.96 * se)), std::to_string(st.at_risk)});
    }

    // Fig. 2B and D1A curves
    const double NJ = mean(finite(collect(jam, [](auto& r) { return r.N_J; })));
    for (std::size_t k = 0; k < grid.size(); ++k) {
      std::vector<double> rem, dv;
      for (const auto* r : jam) {
        if (std::isfinite(r->remaining[k])) rem.push_back(r->remaining[k]);
        if (std::isfinite(r->divisions[k])) dv.push_back(r->divisions[k] / NJ);
      }
      if (!rem.empty())
        rem_rows.push_back({num(key.L), P0s, num(grid[k]), num(mean(rem)), cell(rem.size() >= 2 ? standard_error(rem) : kNaN),
                            std::to_string(rem.size())});
      if (!dv.empty())
        div_rows.push_back({num(key.L), P0s, num(grid[k]), num(median(dv)), num(quantile(dv, 0.25)),
                            num(quantile(dv, 0.75)), std::to_string(dv.size())});
    }
    g["dphi_2_median"] = median_json(collect(dep, [](auto& r) { return r.dphi_2; }), bo);

    // Fig. E1: Π(g) pooled over the group's runs
    std::vector<double> gall;
    for (const auto* r : jam) gall.insert(gall.end(), r->g.begin(), r->g.end());
    if (!gall.empty()) {
      std::vector<double> lower;
      std::size_t at_one = 0;
      for (double v : gall) {
        if (v == 1.0) ++at_one;  // a bud without contact: p = 0 exactly (the δ(g − 1) of Eq. E5)
        else lower.push_back(v);
      }
      const auto counts = histogram(lower, g_edges);
      const double total = static_cast<double>(gall.size());
      std::size_t mode = 0;
      for (std::size_t k = 1; k < counts.size(); ++k)
        if (counts[k] > counts[mode]) mode = k;
      g["g_cells"] = gall.size();
      g["g_peak_weight_at_1"] = at_one / total;
      g["g_compressed_peak"] = lower.empty() ? Json(nullptr) : Json(0.5 * (g_edges[mode] + g_edges[mode + 1]));
      g["g_mean"] = mean(gall);
      g["h_gamma_pooled"] = growth_heterogeneity(gall);
      for (std::size_t k = 0; k < counts.size(); ++k)
        g_rows.push_back({num(key.L), P0s, num(g_edges[k]), num(g_edges[k + 1]),
                          num(counts[k] / total / (g_edges[k + 1] - g_edges[k])), "false"});
      g_rows.push_back({num(key.L), P0s, "1", "1", num(at_one / total), "true"});
    }

    // Fig. 4: mean trajectory in (P, G) over the targets below φ_2, and the endpoint
    std::map<double, std::pair<std::vector<double>, std::vector<double>>> traj;
    for (const auto* r : jam)
      for (const auto& t : r->targets)
        if (t.below_phi2) {
          traj[t.dphi].first.push_back(t.P);
          traj[t.dphi].second.push_back(t.G);
        }
    // Means as in the paper's caption, and medians: one packing near a shear instability of the box
    // (G ≪ 0, docs/moduli.md) can dominate the mean of a few runs.
    auto med = [](const std::vector<double>& v) { return v.empty() ? kNaN : median(v); };
    for (auto& [d, v] : traj)
      traj_rows.push_back({num(key.L), P0s, num(d), cell(mean(v.first)), cell(mean(finite(v.second))),
                           cell(med(v.first)), cell(med(finite(v.second))), std::to_string(v.first.size()), "false"});
    {
      const auto P2 = finite(collect(dep, [](auto& r) { return r.P_2; }));
      const auto G2 = finite(collect(dep, [](auto& r) { return r.G_2; }));
      traj_rows.push_back({num(key.L), P0s, cell(mean(finite(collect(dep, [](auto& r) { return r.dphi_2; })))),
                           cell(mean(P2)), cell(mean(G2)), cell(med(P2)), cell(med(G2)), std::to_string(dep.size()), "true"});
    }
    jgroups.push_back(g);
  }

  // ---- headline numbers ---------------------------------------------------------------------
  Json J;
  J["format"] = "budjam-analysis";
  J["version"] = 1;
  J["inputs"] = Json{{"runs", dirs.size()},
                     {"used", rows.size()},
                     {"not_finished", failed},
                     {"moduli_files", moduli_found.found},
                     {"moduli_saddles", moduli_found.saddles},
                     {"dos_files", dos_found}};
  J["main_L"] = main_L;
  J["bootstrap"] = Json{{"resamples", bo.resamples}, {"seed", bo.seed}};
  J["constants"] = Json{{"P_max", kPmax},
                        {"P_max_formula_phiJ_0.84", 2.0 / std::numbers::pi * (1.0 - 0.84)},
                        {"M4", kM4},
                        {"u_J_lambert_w", u_J_mean_field()},
                        {"lambert_w0_of_minus_2_e_minus_2", lambert_w0(-2.0 * std::exp(-2.0))}};
  {
    // u_J, n_J, φ_J over every run of the main L (all P0: feedback acts only above jamming)
    std::vector<const RunRow*> m;
    for (const auto& r : rows)
      if (r.L == main_L && r.jammed) m.push_back(&r);
    Json h;
    h["u_J"] = mean_se_json(collect(m, [](auto& r) { return r.u_J; }));
    h["n_J"] = mean_se_json(collect(m, [](auto& r) { return r.n_J; }));
    h["phi_J"] = mean_se_json(collect(m, [](auto& r) { return r.phi_J; }));
    h["N_J"] = mean_se_json(collect(m, [](auto& r) { return r.N_J; }));
    h["P_max_formula_measured_phiJ"] = 2.0 / std::numbers::pi * (1.0 - mean(collect(m, [](auto& r) { return r.phi_J; })));
    // ΔZ identity: RMS of measured − predicted over all targets of the main L
    std::vector<double> res, rel_b;
    for (const auto* r : m)
      for (const auto& t : r->targets) {
        if (std::isfinite(t.dZ_pred)) res.push_back(t.dZ - t.dZ_pred);
        if (std::isfinite(t.B) && std::isfinite(t.B_grow) && t.lambda * t.B > 0)
          rel_b.push_back(std::log10(t.B_grow / (t.lambda * t.B)));
      }
    h["dZ_identity_residual"] = mean_se_json(res);
    h["dZ_identity_rms"] = res.empty() ? Json(nullptr) : Json(std::sqrt(mean([&] {
      std::vector<double> sq;
      for (double v : res) sq.push_back(v * v);
      return sq;
    }())));
    h["B_grow_over_lambda_B_log10"] = mean_se_json(rel_b);
    // Fraction of packings (targets and φ_2, all P0) unstable to some simple shear of the box, in
    // decades of P N_J²: finite packings jammed at fixed box shape lose that instability as P N²
    // grows (Dagois-Bohy et al. 2012; Goodrich et al. 2012).
    {
      std::map<int, std::pair<std::size_t, std::size_t>> bins;  // decade → (packings, unstable)
      auto add = [&](double P, double N, double G_min) {
        if (!std::isfinite(G_min) || !(P > 0) || !(N > 0)) return;
        auto& b = bins[static_cast<int>(std::floor(std::log10(P * N * N)))];
        ++b.first;
        b.second += G_min < 0;
      };
      for (const auto* r : m) {
        for (const auto& t : r->targets) add(t.P, r->N_J, t.G_min);
        if (r->depleted) add(r->P_2, r->N_J, r->G_min_2);
      }
      Json sb = Json::array();
      for (const auto& [d, c] : bins) {
        Json b = fraction_json(c.second, c.first);
        b["PN2_lo"] = std::pow(10.0, d);
        b["PN2_hi"] = std::pow(10.0, d + 1);
        sb.push_back(b);
      }
      h["shear_unstable_by_PN2"] = sb;
    }
    // plateau G_2(0+) = n_J k ℓ_c² M_4 u_J from the strongest-feedback jammed packings
    std::optional<double> strongest;
    for (const auto& [key, rs] : groups)
      if (key.L == main_L && key.P0 && (!strongest || *key.P0 < *strongest)) strongest = key.P0;
    if (strongest) {
      const auto& rs = groups.at({main_L, strongest});
      const double nJ = mean(finite(collect(rs, [](auto& r) { return r.n_J; })));
      const double lc2 = mean(finite(collect(rs, [](auto& r) { return r.lc2_J; })));
      const double uJ = mean(finite(collect(rs, [](auto& r) { return r.u_J; })));
      h["plateau_P0"] = *strongest;
      h["G2_plateau"] = io::number_or_null(nJ * lc2 * kM4 * uJ);
      h["G2_plateau_over_Pmax"] = io::number_or_null(nJ * lc2 * kM4 * uJ / kPmax);
      h["lc2_J"] = io::number_or_null(lc2);
    }
    // P_2 ∝ exp(−P†/P0) (Eq. 22, D11): slope of ln P_2 against 1/P0 over the feedback groups with
    // P0 ≤ 10⁻², and the crossover estimate P* = n_J (6 + 2u_J) a_c / (8 ln 10) (Eq. E13) with a_c the
    // mean completion size ∫S da (true area) of the pooled survival curve of those groups.
    {
      std::vector<double> x, y, ac;
      for (const auto& [key, rs] : groups) {
        if (key.L != main_L || !key.P0 || *key.P0 > 1e-2 + 1e-15) continue;
        std::vector<double> p2;
        std::vector<SurvivalRecord> pool;
        for (const auto* r : rs) {
          if (r->depleted) p2.push_back(r->P_2);
          pool.insert(pool.end(), r->survival.begin(), r->survival.end());
        }
        p2 = finite(p2);
        if (!p2.empty() && mean(p2) > 0) {
          x.push_back(1.0 / *key.P0);
          y.push_back(std::log(mean(p2)));
        }
        const auto km = kaplan_meier(pool);
        double last_event = 0;
        for (const auto& st : km.steps())
          if (st.events > 0) last_event = st.a;
        if (km.events() > 0) ac.push_back(kDiameterSquaredToArea * km.integral(last_event));
      }
      if (x.size() >= 2) {
        const auto f = linear_fit(x, y);
        h["P_dagger"] = -f.slope;
        h["P_dagger_se"] = f.slope_se;
        h["P_dagger_points"] = x.size();
      }
      const double nJ = mean(collect(m, [](auto& r) { return r.n_J; }));
      const double uJ = mean(collect(m, [](auto& r) { return r.u_J; }));
      if (!ac.empty()) {
        const auto [lo, hi] = std::minmax_element(ac.begin(), ac.end());
        h["a_c_range_area"] = Json::array({*lo, *hi});
        const double k = nJ * (6.0 + 2.0 * uJ) / (8.0 * std::log(10.0));
        h["P_star_range"] = Json::array({k * *lo, k * *hi});
      }
    }
    // Spectrum: N_zero against N_u, and how well ω* follows ΔZ compared with the naive Z − 6.
    {
      std::vector<double> w, dz, z6, diff;
      std::size_t equal = 0, neg_dz = 0, neg_z6 = 0;
      for (const auto& q : dos_rows) {
        if (q.L != main_L) continue;
        w.push_back(q.omega_star);
        dz.push_back(q.dZ);
        z6.push_back(q.Z - 6.0);
        diff.push_back(std::abs(q.N_zero - q.N_u));
        equal += q.N_zero == q.N_u;
        neg_dz += q.dZ < 0;
        neg_z6 += q.Z - 6.0 < 0;
      }
      if (w.size() >= 3) {
        const double n = static_cast<double>(w.size());
        const auto fd = linear_fit(dz, w);
        const auto f6 = linear_fit(z6, w);
        h["dos"] = Json{{"packings", w.size()},
                        {"N_zero_equals_N_u", equal / n},
                        {"N_zero_minus_N_u_abs", mean(diff)},
                        {"omega_star_vs_dZ", Json{{"slope", fd.slope}, {"slope_se", fd.slope_se}, {"intercept", fd.intercept}}},
                        {"r2_dZ", fd.r2},
                        {"r2_Z_minus_6", f6.r2},
                        {"fraction_dZ_negative", neg_dz / n},
                        {"fraction_Z_minus_6_negative", neg_z6 / n}};
      }
    }
    J["main"] = h;
  }
  J["groups"] = jgroups;
  {
    Json br = Json::array();
    for (const auto& [L, f] : branch) {
      Json pts = Json::array();
      for (std::size_t k = 0; k < f.xs().size(); ++k) pts.push_back(Json::array({f.xs()[k], f.ys()[k]}));
      br.push_back(Json{{"L", L}, {"points_P_dZ", pts}});
    }
    J["dZ0_branch"] = br;
  }
  io::write_json(out / "analysis.json", J);

  // ---- tables ----------------------------------------------------------------------------------
  std::vector<std::vector<std::string>> run_rows, tgt_rows, dos_out;
  for (const auto& r : rows) {
    run_rows.push_back({r.dir.string(), num(r.L), r.P0_label, std::to_string(r.seed), r.status, cell(r.phi_J), cell(r.u_J),
                        cell(r.n_J), cell(r.N_J), cell(r.N_nr_J), cell(r.Z_J), cell(r.dZ_J), cell(r.phi_2), cell(r.dphi_2),
                        cell(r.P_2), cell(r.Z_2), cell(r.dZ_2), cell(r.u_2), cell(r.N_div_2), cell(r.chi_bar),
                        cell(r.lambda_bar), cell(r.a_eps), cell(r.int_S), cell(r.pred_area), cell(r.pred_d2), cell(r.B_2),
                        cell(r.G_2), cell(r.G_min_2), cell(r.h_gamma), cell(r.lc2_J)});
    for (const auto& t : r.targets)
      tgt_rows.push_back({r.dir.string(), num(r.L), r.P0_label, std::to_string(r.seed), num(t.dphi), cell(t.phi), cell(t.P),
                          cell(t.Z), cell(t.Z_iso), cell(t.dZ), cell(t.dZ_pred), cell(t.u), cell(t.u_lobes), cell(t.chi_c),
                          cell(t.lambda), cell(t.B_grow), cell(t.B_grow_se), cell(t.B), cell(t.G), cell(t.G_min), cell(t.B_ext_mf),
                          cell(t.N_div), t.below_phi2 ? "true" : "false"});
  }
  for (const auto& q : dos_rows)
    dos_out.push_back({q.run, q.packing, num(q.L), q.P0_label, cell(q.dphi), cell(q.omega_star), cell(q.dZ),
                       cell(q.Z - 6.0), cell(q.N_zero), cell(q.N_u), cell(q.N_u_buds)});
  write_csv(out / "runs.csv",
            {"run", "L", "P0", "seed", "status", "phi_J", "u_J", "n_J", "N_J", "N_nr_J", "Z_J", "dZ_J", "phi_2", "dphi_2",
             "P_2", "Z_2", "dZ_2", "u_2", "N_div_2", "chi_bar", "lambda_bar", "a_eps", "integral_S", "dphi_2_pred_area",
             "dphi_2_pred_diameter_sq", "B_2", "G_2", "G_min_2", "h_gamma", "lc2_J"},
            run_rows);
  write_csv(out / "targets.csv",
            {"run", "L", "P0", "seed", "dphi", "phi", "P", "Z", "Z_iso", "dZ", "dZ_pred", "u", "u_lobes", "chi_c",
             "lambda_c", "B_grow", "B_grow_se", "B", "G", "G_min", "B_ext_mean_field", "N_div", "below_phi2"},
            tgt_rows);
  write_csv(out / "survival.csv", {"L", "P0", "a", "S", "se", "lo", "hi", "at_risk"}, surv_rows);
  write_csv(out / "remaining.csv", {"L", "P0", "dphi", "mean", "se", "runs"}, rem_rows);
  write_csv(out / "division_curve.csv", {"L", "P0", "dphi", "median", "q25", "q75", "runs"}, div_rows);
  write_csv(out / "growth_rates.csv", {"L", "P0", "g_lo", "g_hi", "density", "delta_at_1"}, g_rows);
  write_csv(out / "trajectory.csv", {"L", "P0", "dphi", "P", "G", "P_median", "G_median", "runs", "endpoint"}, traj_rows);
  write_csv(out / "dos.csv", {"run", "packing", "L", "P0", "dphi", "omega_star", "dZ", "Z_minus_6", "N_zero", "N_u", "N_u_buds"},
            dos_out);
  std::cerr << "analyse: " << rows.size() << " runs used (" << failed.size() << " not finished) in " << groups.size()
            << " groups; moduli files " << moduli_found.found << " (" << moduli_found.saddles << " saddles), spectra " << dos_found << " -> " << out.string() << "\n";
}

const bool registered = budjam::cli::register_command(
    {"analyse", "Ensemble analysis of finished runs: JSON/CSV tables behind every figure and number of the paper",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("RUNDIR", o->inputs, "run directories, or folders holding them")->required();
       sub.add_option("--out", o->out, "output directory")->required();
       sub.add_option("--main-L", o->main_L, "system size of the main figures (default 15 if present, else the largest)");
       sub.add_option("--resamples", o->resamples, "bootstrap resamples (default 2000)");
       sub.add_option("--seed", o->seed, "bootstrap seed (default 1)");
       sub.add_option("--require", o->require, "fail if these per-packing results are missing: moduli, dos")
           ->delimiter(',');
       sub.callback([o] { run(*o); });
     }});

}  // namespace
