// Ensemble analysis of finished growth runs. A run argument may also be a folder that holds run
// directories (searched recursively for summary.json). Runs are grouped by (L, P0). With --tables the
// records come from the tables of an earlier analysis instead (ensemble_tables.hpp) and the same
// estimators run on them; what those tables cannot give is listed in analysis.json "unavailable".
//
// Outputs (docs/analysis.md, "analyse outputs"):
//   analysis.json     per-group statistics and the headline numbers, under budjam's definitions
//                     and the paper's (key suffix _paper), errors over independent samples
//   runs.csv          one row per run (φ_J, u_J, n_J, φ_2 both ways, predictions, P_2, G_2, divisions, h_γ ...)
//   targets.csv       one row per (run, Δφ target): P, Z, ΔZ, u, χ_c, λ_c, B_grow, ΔZ_0(P) + 2(u_J − u), B, G
//   survival.csv      pooled Kaplan–Meier S(a) per group with its band clustered by run (Fig. 2B)
//   remaining.csv     fraction of the buds free at jamming still free against φ − φ_J (Fig. 2B)
//   division_curve.csv  cumulative post-jamming divisions / ⟨N_J⟩ against Δφ: median and quartiles (Fig. D1)
//   growth_rates.csv  Π(g) at Δφ = 3·10⁻³ per group on the paper's bins (Fig. E1)
//   trajectory.csv    mean (P, G) per (group, Δφ) below φ_2, and the endpoints (Fig. 4)
//   dos.csv           per packing with a DOS: ω*, ΔZ, Z − 6, integer contact counts, N_zero, N_u (Fig. F1)
// Moduli and spectra are read from packings/<name>.moduli.json / .dos.json (written by
// `budjam moduli` / `budjam dos` in the Makefile pipeline).
#include "analysis/ensemble_analysis.hpp"

#include "analysis/depletion_estimators.hpp"
#include "analysis/ensemble_records.hpp"
#include "analysis/ensemble_tables.hpp"
#include "analysis/finite_size.hpp"
#include "analysis/growth_only.hpp"
#include "analysis/jamming_states.hpp"
#include "analysis/run_protocol.hpp"
#include "analysis/structure_estimators.hpp"
#include "analysis/survival_report.hpp"
#include "io/run_data.hpp"
#include "io/run_directory.hpp"

#include "budjam/bud_events.hpp"  // BudEventKind of bud_events.csv rows
#include "budjam/depletion.hpp"
#include "budjam/growth.hpp"
#include "budjam/saddle.hpp"  // StationaryPoint of a moduli sidecar
#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"
#include "budjam/statistics.hpp"
#include "budjam/survival.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "io/result_files.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace budjam::tools {

namespace {

namespace fs = std::filesystem;
using io::Json;

constexpr double kPmax = 0.1;         // confluence pressure scale (paper Eq. D25)
constexpr double kM4 = 0.125;         // ⟨n_x² n_y²⟩ of an isotropic network
constexpr double kDphiGrowth = 3e-3;  // Δφ of the growth-rate crossover (appendix E)
// The growth-only baseline of the cell count (growth_only.hpp): enough histories for an SE of N/L² ten
// times below the jamming ensembles' (≈ 1e-4 at L = 15), their own seeds, and the large box of n_J,∞.
constexpr std::size_t kGrowthOnlySamples = 400;
constexpr std::uint64_t kGrowthOnlyFirstSeed = 1'000'000'000;
constexpr double kGrowthOnlyLargeL = 100;

std::string num(double v) { return io::format_double(v); }

// ---- per-run extraction ------------------------------------------------------------------------

Json fraction_json(std::size_t k, std::size_t n) {
  return Json{{"fraction", n ? Json(static_cast<double>(k) / static_cast<double>(n)) : Json(nullptr)}, {"packings", n}};
}

// ΔZ_J N_nr / 2 is a whole number of contacts (Z_iso = 6 − 2u − 2/N_nr), so the claim ΔZ_J ≈ 0 is
// that a jamming point is isostatic, and its packings are counted rather than averaged: a mean of
// counts that are all 0 but k has SE = mean/√k, z = √k whatever the excess. Each distinct jamming
// state counts once; "seeds" bounds the independent samples (a seed's runs share their growth).
Json isostatic_json(const std::vector<const RunRow*>& rs) {
  std::size_t isostatic = 0;
  std::set<std::size_t> states;
  std::set<std::uint64_t> seeds;
  long most = 0;  // the largest excess, in contacts, of a packing that is not isostatic
  for (const auto* r : rs) {
    if (!std::isfinite(r->dZ_J) || !std::isfinite(r->N_nr_J) || !states.insert(r->state).second) continue;
    seeds.insert(r->seed);
    const long excess = std::lround(r->dZ_J * r->N_nr_J / 2);
    if (excess == 0)
      ++isostatic;
    else if (std::abs(excess) > std::abs(most))
      most = excess;
  }
  Json j = fraction_json(isostatic, states.size());
  j["isostatic"] = isostatic;
  j["seeds"] = seeds.size();
  j["most_excess_contacts"] = most;
  return j;
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
    if (j.contains("moduli") && j["moduli"].contains(k) && j["moduli"][k].is_number())
      return j["moduli"][k].get<double>();
  }
  return kNaN;
}

// G is the lobe-centre stress response (the paper's); G_energy = (1/A) d²U/dγ² where `budjam
// moduli` writes it (docs/moduli.md): the two differ by the prestress term.
struct SidecarModuli {
  double B = kNaN, G = kNaN, G_energy = kNaN, B_ext_mf = kNaN, G_min = kNaN;
};

SidecarModuli read_moduli(const fs::path& pack, bool required, ModuliFiles& files) {
  SidecarModuli m;
  const auto j = tools::sidecar(pack, "moduli");
  if (!j) {
    if (required && fs::exists(pack))
      throw InputError(pack.string() + ": no moduli (expected " +
                       fs::path(pack).replace_extension(".moduli.json").string() +
                       "; run `make -f Makefile.analysis moduli`)");
    return m;
  }
  ++files.found;
  m.B_ext_mf = json_number(*j, {"B_ext_mean_field", "B_mf", "B_ext_mf"});
  if (j->contains("energy_minimum") && (*j)["energy_minimum"].is_boolean() && !(*j)["energy_minimum"].get<bool>()) {
    ++files.saddles;
    return m;
  }
  const auto sp = j->find("stationary_point");
  if (sp != j->end() && !sp->is_string())
    throw InputError(fs::path(pack).replace_extension(".moduli.json").string() + ": \"stationary_point\" is not text");
  if (sp != j->end() && sp->get<std::string>() == to_string(StationaryPoint::contact_bounded_minimum)) {
    ++files.contact_bounded;
    return m;
  }
  m.B = json_number(*j, {"B", "bulk_modulus"});
  m.G = json_number(*j, {"G", "shear_modulus"});
  m.G_energy = json_number(*j, {"G_energy"});
  if (j->contains("shear_stability")) m.G_min = json_number((*j)["shear_stability"], {"G_min"});
  if (!std::isfinite(m.G) || !std::isfinite(m.B))
    throw InputError(fs::path(pack).replace_extension(".moduli.json").string() + ": no numeric \"B\" and \"G\"");
  return m;
}

// The steps of the first-jamming φ_2 and none-left states (NaN where not reached).
struct FirstJammingStates {
  double phi_2 = kNaN, none_left = kNaN;
};

// The paper's anchor (RunRow::phi_J_first …): its first post-jamming row is the run's first jammed
// state, and every accepted state after it is a row of its φ_2 scan, with the tags its code follows.
// At a jamming after an unjamming its code writes two rows of the one state: the followed tags'
// (those still unconstrained there end censored_unjam, which bud_events.csv counts) and the new
// tags'; its scan and its means over [φ_J, φ_2] take both.
FirstJammingStates anchor_at_first_jamming(const tools::RunData& r, const Scene& scene, RunRow& x) {
  const auto& S = r.steps;
  const std::size_t c_step = S.column("step"), c_phase = S.column("phase"), c_phi = S.column("phi"),
                    c_P = S.column("P"), c_N = S.column("N"), c_Nf = S.column("N_f"), c_Nu = S.column("N_u"),
                    c_chi = S.column("chi_c"), c_act = S.column("tagged_active"),
                    c_div = S.column("divisions_since_jamming");
  std::map<double, double> followed_left;  // step of a jamming → earlier tags still active there
  if (r.bud_events) {
    const auto& E = *r.bud_events;
    const std::size_t c_ev = E.column("event"), c_es = E.column("step");
    for (std::size_t j = 0; j < E.size(); ++j)
      if (E.text(j, c_ev) == to_string(BudEventKind::censored_unjam)) followed_left[E.number(j, c_es)] += 1;
  }
  std::size_t first = 0;
  while (first < S.size() && S.text(first, c_phase) != "jammed") ++first;
  std::vector<double> st, phi, P, active, chi, lambda_lobes;
  // Each Δφ target is a run of its own there, which ends where the trajectory first lands on it (in
  // whichever episode) with the divisions counted from that episode's jamming.
  std::vector<double> target_end(scene.targets.size(), kNaN), target_divisions(scene.targets.size(), kNaN);
  double phi_J_episode = kNaN;
  bool old_logs = false;
  for (std::size_t k = first; k < S.size(); ++k) {
    const bool jammed = S.text(k, c_phase) == "jammed";
    const bool jamming = jammed && (k == first || S.text(k - 1, c_phase) != "jammed");
    const double N = S.number(k, c_N), Nf = S.number(k, c_Nf), c = S.number(k, c_chi);
    // a state with no non-rattler has no λ_c (its paper's code, with one-pass rattlers, divides by N_nr)
    const double lambda = N > Nf ? lambda_c(S.number(k, c_Nu) / (N - Nf), c) : kNaN;
    const auto row = [&](double tags) {
      st.push_back(S.number(k, c_step));
      phi.push_back(S.number(k, c_phi));
      P.push_back(S.number(k, c_P));
      active.push_back(tags);
      chi.push_back(c);
      lambda_lobes.push_back(lambda);
    };
    if (jamming && k > first) {
      const auto left = followed_left.find(S.number(k, c_step));
      row(!r.bud_events ? kNaN : left != followed_left.end() ? left->second : 0.0);
    }
    const double tags = S.number(k, c_act);
    old_logs = old_logs || std::isnan(tags);
    row(tags);
    if (jamming) phi_J_episode = phi.back();
    if (!jammed) continue;
    for (std::size_t t = 0; t < scene.targets.size(); ++t)
      if (std::isnan(target_end[t]) &&
          std::abs(phi.back() - (phi_J_episode + scene.targets[t])) <= scene.target_tolerance) {
        target_end[t] = phi.back();
        target_divisions[t] = S.number(k, c_div);
      }
  }
  // Logs from before the tags were followed through an unjamming leave those rows empty.
  if (st.empty() || old_logs) return {};
  x.step_J_first = st[0];
  x.phi_J_first = phi[0];
  x.N_J_first = S.number(first, c_N);
  x.N_nr_J_first = x.N_J_first - S.number(first, c_Nf);
  x.tagged_J_first = active[0];
  // Its means take every row with φ ≤ φ_2 (both rows of a state).
  const auto through = [&](std::size_t k) {
    while (k + 1 < st.size() && st[k + 1] == st[k]) ++k;
    return k;
  };
  // Its scan includes the jamming state itself (with at most one bud tagged there, φ_2 = φ_J).
  FirstJammingStates at;
  if (const auto k = depletion_state(active, 0, kBudjamTaggedLeft)) {
    at.phi_2 = st[*k];
    x.phi_2_first = phi[*k];
    x.dphi_2_first = phi[*k] - x.phi_J_first;
    x.P_2_first = P[*k];
    x.chi_bar_first = growth_coordinate_average(chi, 0, through(*k));
    x.lambda_bar_lobes = growth_coordinate_average(lambda_lobes, 0, through(*k));
    x.selection_divisions_first = selection_divisions(target_end, target_divisions, x.phi_2_first);
  }
  if (const auto k = depletion_state(active, 0, kNoneLeft)) {
    at.none_left = st[*k];
    x.phi_2_none_left = phi[*k];
    x.dphi_2_none_left = phi[*k] - x.phi_J_first;
    x.P_2_none_left = P[*k];
    const auto& D = r.divisions;
    const std::size_t c_s = D.column("step");
    // its count takes a division logged at the jamming step itself
    double n = 0;
    for (std::size_t j = 0; j < D.size(); ++j) n += D.number(j, c_s) >= x.step_J_first && D.number(j, c_s) <= st[*k];
    x.N_div_2_none_left = n;
  }
  return at;
}

// The numbers summary.json records at jamming and at budjam's φ_2, under their runs.csv names.
constexpr std::string_view kSummaryKeys[] = {"phi_J", "u_J", "n_J",      "N_J",    "N_nr_J",    "Z_J",
                                             "dZ_J",  "P_J", "tagged_J", "step_J", "u_J_lobes", "phi_2",
                                             "P_2",   "Z_2", "dZ_2",     "N_div_2"};

// One jammed run's row (the caller skips runs that never jammed).
RunRow extract(const tools::RunData& r, bool need_moduli, ModuliFiles& moduli_found) {
  RunRow x;
  x.dir = r.dir;
  x.L = r.L();
  x.P0 = r.P0();
  x.P0_label = r.P0_label();
  x.seed = r.seed();
  x.status = r.status();
  for (const auto& c : kRunColumns)
    if (std::find(std::begin(kSummaryKeys), std::end(kSummaryKeys), std::string_view(c.name)) != std::end(kSummaryKeys))
      x.*c.field = r.get(c.name);
  if (const double left = r.get("phi_2_tagged_left"); std::isfinite(left)) x.phi2_tagged_left = left;
  const double saved_step_2 = r.get("step_2");  // the φ_2 packing the run saved, under its definition
  double step_2 = saved_step_2;

  // steps.csv from jamming on (the current episode starts at step_J)
  const auto& S = r.steps;
  const std::size_t c_step = S.column("step"), c_phi = S.column("phi"), c_P = S.column("P"), c_N = S.column("N"),
                    c_Nf = S.column("N_f"), c_Nub = S.column("N_u_buds"), c_chi = S.column("chi_c"),
                    c_act = S.column("tagged_active"), c_div = S.column("divisions_since_jamming"), c_Z = S.column("Z"),
                    c_dZ = S.column("dZ");
  std::vector<double> st, phi, P, Z, dZ, u, chi, lambda, active, divisions;
  for (std::size_t k = 0; k < S.size(); ++k) {
    const double s = S.number(k, c_step);
    if (s < x.step_J) continue;
    st.push_back(s);
    phi.push_back(S.number(k, c_phi));
    P.push_back(S.number(k, c_P));
    Z.push_back(S.number(k, c_Z));
    dZ.push_back(S.number(k, c_dZ));
    const double N = S.number(k, c_N), Nf = S.number(k, c_Nf);
    u.push_back(S.number(k, c_Nub) / (N - Nf));
    chi.push_back(S.number(k, c_chi));
    lambda.push_back(lambda_c(u.back(), chi.back()));
    active.push_back(S.number(k, c_act));
    divisions.push_back(S.number(k, c_div));
  }
  if (!divisions.empty()) x.N_div_end = divisions.back();
  // A run that saved another definition's φ_2 (jamming.phi2_tagged_left) has budjam's in its log only.
  if (x.phi2_tagged_left != kBudjamTaggedLeft) {
    x.phi_2 = x.P_2 = x.Z_2 = x.dZ_2 = x.N_div_2 = step_2 = kNaN;
    if (const auto k = depletion_state(active, 1, kBudjamTaggedLeft)) {
      x.phi_2 = phi[*k];
      x.P_2 = P[*k];
      x.Z_2 = Z[*k];
      x.dZ_2 = dZ[*k];
      x.N_div_2 = divisions[*k];
      step_2 = st[*k];
    }
  }
  x.depleted = std::isfinite(x.phi_2);
  if (x.depleted) x.dphi_2 = x.phi_2 - x.phi_J;
  if (x.depleted) {
    const auto k2 = static_cast<std::size_t>(std::find(st.begin(), st.end(), step_2) - st.begin());
    if (k2 < st.size()) {
      x.u_2 = u[k2];
      x.chi_bar = growth_coordinate_average(chi, 0, k2);
      x.lambda_bar = growth_coordinate_average(lambda, 0, k2);
    }
  }
  const FirstJammingStates first = anchor_at_first_jamming(r, io::load_scene(r.dir / io::run_files::scene), x);

  // Survival of the tagged buds: per-run a_ε with ε = 1/N_nr,J (at most one left = φ_2's definition)
  if (r.bud_events) {
    x.survival = tools::survival_records(*r.bud_events);
    x.bud_records = static_cast<double>(x.survival.size());
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
      const auto ae_paper = km.quantile_point(1.0 / x.tagged_J_first, 0.0);
      if (ae_paper && std::isfinite(x.chi_bar_first))
        x.pred_paper = predict_phi2(x.N_nr_J_first / (x.L * x.L), x.tagged_J_first / x.N_nr_J_first, x.chi_bar_first,
                                    *ae_paper, km.integral(*ae_paper))
                           .dphi2_diameter_sq;
    }
  }

  // Targets
  const fs::path summary = r.dir / io::run_files::summary;
  const auto targets = r.summary.find("targets");
  if (targets == r.summary.end() || !targets->is_array()) throw InputError(summary.string() + ": targets: not a list");
  x.target_rows = static_cast<double>(targets->size());
  for (std::size_t k = 0; k < targets->size(); ++k) {
    const io::Json& t = (*targets)[k];
    if (!t.is_object()) throw InputError(summary.string() + ": targets[" + std::to_string(k) + "]: not an object");
    const auto number = [&](const char* key) {
      return tools::json_double(t, key, summary, "targets[" + std::to_string(k) + "]." + key);
    };
    TargetRow y;
    y.dphi = number("dphi");
    y.phi = number("phi");
    y.P = number("P");
    y.Z = number("Z");
    y.dZ = number("dZ");
    y.Z_iso = number("Z_iso");
    y.u = number("u_buds");
    y.u_lobes = number("u");
    y.chi_c = number("chi_c");
    y.N_div = number("N_div");
    y.N_nr = number("N_nr");
    y.lambda = lambda_c(y.u, y.chi_c);
    const long long tstep = json_integer(t, "step", summary);
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
    const fs::path pack =
        r.dir /
        io::run_files::packing(io::run_files::target_stem(static_cast<std::size_t>(json_integer(t, "index", summary))));
    const SidecarModuli sm = read_moduli(pack, need_moduli, moduli_found);
    y.B = sm.B;
    y.G = sm.G;
    y.G_energy = sm.G_energy;
    y.B_ext_mf = sm.B_ext_mf;
    y.G_min = sm.G_min;
    x.targets.push_back(y);

    // growth-rate distribution at Δφ = 3·10⁻³ (g = exp(−p/P0), 1 without feedback): budjam's over
    // the non-rattler cells, the paper's over every cell
    if (std::abs(y.dphi - kDphiGrowth) < 1e-12 && fs::exists(pack)) {
      const io::PackingFile f = io::read_packing(pack);
      const auto pc = tools::analyse_contacts(f.packing);
      std::vector<double> g_all;
      for (std::size_t i = 0; i < f.packing.size(); ++i) {
        g_all.push_back(growth_factor(pc.bud_pressures[i], x.P0));
        if (!pc.network.rattler[i]) x.g.push_back(g_all.back());
      }
      x.h_gamma = growth_heterogeneity(x.g);
      x.h_gamma_all_cells = growth_heterogeneity(g_all);
      if (!g_all.empty())
        x.g1_fraction_all_cells =
            static_cast<double>(std::count(g_all.begin(), g_all.end(), 1.0)) / static_cast<double>(g_all.size());
    }
  }
  // The saved φ_2 packing serves each definition whose φ_2 it is (both where they fall on one state).
  if (std::isfinite(saved_step_2)) {
    const SidecarModuli sm =
        read_moduli(r.dir / io::run_files::packing(io::run_files::phi2), need_moduli, moduli_found);
    if (saved_step_2 == step_2) {
      x.B_2 = sm.B;
      x.G_2 = sm.G;
      x.G_2_energy = sm.G_energy;
      x.G_min_2 = sm.G_min;
    }
    if (saved_step_2 == first.phi_2) x.G_2_first = sm.G;
    if (saved_step_2 == first.none_left) x.G_2_none_left = sm.G;
  }
  {
    const fs::path jam = r.dir / io::run_files::packing(io::run_files::jammed);
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
      if (D.number(k, c_s) > x.step_J) dd.push_back(D.number(k, c_p) - x.phi_J);
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

std::vector<double> finite(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  return v;
}

// A state a run reaches at a time of its own (φ_2, the first state with no tagged bud left) is
// right-censored in the runs that stopped before it (at their last target or step limit): they are
// the runs that would have reached it latest, so a statistic over the runs that did reach it is
// biased (Δφ_2 low). Such statistics of a group are kept only where every run reached the state;
// else their values are null and "censored" counts the runs that stopped first.
constexpr const char* kAtPhi2[] = {"dphi_2",
                                   "phi_2",
                                   "dphi_2_pred_area",
                                   "dphi_2_pred_diameter_sq",
                                   "dphi_2_pred_minus_sim_area",
                                   "a_eps",
                                   "chi_bar",
                                   "lambda_bar",
                                   "P_2",
                                   "P_2_over_Pmax",
                                   "P_2_median",
                                   "a_eps_area",
                                   "dZ_2",
                                   "u_2",
                                   "G_2",
                                   "G_2_mean",
                                   "G_2_energy",
                                   "G_2_over_Pmax",
                                   "G_2_over_P_2",
                                   "N_div_2_over_N_J"};
constexpr const char* kAtNoneLeft[] = {"dphi_2_none_left", "G_2_over_Pmax_none_left", "N_div_2_over_N_J_paper"};
// The paper's φ_2, scanned from the first jamming (its selection admits only runs that reached it).
constexpr const char* kAtPaperPhi2[] = {"dphi_2_paper",        "dphi_2_pred_paper", "dphi_2_pred_minus_sim_paper",
                                        "P_2_over_Pmax_paper", "lambda_bar_paper",  "G_2_over_Pmax_paper",
                                        "G_2_over_P_2_paper"};

template <std::size_t K>
void censor_unreached(Json& group, const char* const (&keys)[K], std::size_t reached, std::size_t runs) {
  if (reached == runs) return;
  for (const char* key : keys) {
    Json& stat = group[key];
    for (const char* value : {"mean", "median", "se", "q25", "q75"})
      if (stat.contains(value)) stat[value] = nullptr;
    if (stat.contains("ci95")) stat["ci95"] = Json::array({nullptr, nullptr});
    stat.erase("by_seed");  // a trend must not pair the runs that reached it either
    stat["censored"] = runs - reached;
  }
}

Json mean_se_json(const std::vector<double>& v0) {
  const auto v = finite(v0);
  Json j;
  j["n"] = v.size();
  j["mean"] = io::number_or_null(mean(v));
  j["se"] = io::number_or_null(v.size() >= kMinSamplesForError ? standard_error(v) : kNaN);
  return j;
}

// The mean of values that come in clusters (the targets of a run, the runs of one seed): n counts
// clusters, the SE is a bootstrap over them, "values" counts the values.
Json clustered_mean_json(const std::vector<double>& v, const std::vector<std::uint64_t>& cluster,
                         const BootstrapOptions& bo) {
  std::vector<double> x;
  std::vector<std::uint64_t> c;
  for (std::size_t k = 0; k < v.size(); ++k)
    if (std::isfinite(v[k])) {
      x.push_back(v[k]);
      c.push_back(cluster[k]);
    }
  Json j;
  j["values"] = x.size();
  j["n"] = std::set<std::uint64_t>(c.begin(), c.end()).size();
  j["mean"] = io::number_or_null(mean(x));
  j["se"] = nullptr;
  if (j["n"].get<std::size_t>() >= kMinSamplesForError)
    j["se"] = io::number_or_null(cluster_bootstrap(
                                     x, c, [](std::span<const double> s) { return mean(s); }, bo)
                                     .se);
  return j;
}

// The SE of a statistic of items that come in clusters (the packings of one seed, which share their
// growth up to jamming): a bootstrap over clusters, with the options of every other error. `of(items)`
// takes the indices of the drawn items; a resample where it is undefined (throws
// std::invalid_argument: a fit with all x equal) leaves the SE undefined. Null from fewer than
// kMinSamplesForError clusters.
template <class Of>
Json se_by_cluster(const std::vector<std::uint64_t>& cluster, Of of, const BootstrapOptions& bo) {
  if (std::set<std::uint64_t>(cluster.begin(), cluster.end()).size() < kMinSamplesForError) return nullptr;
  std::vector<double> index(cluster.size());
  for (std::size_t k = 0; k < index.size(); ++k) index[k] = static_cast<double>(k);
  std::vector<std::size_t> items;
  const auto b = cluster_bootstrap(
      index, cluster,
      [&](std::span<const double> drawn) {
        items.clear();
        for (double i : drawn) items.push_back(static_cast<std::size_t>(i));
        try {
          return of(items);
        } catch (const std::invalid_argument&) {
          return kNaN;
        }
      },
      bo);
  return io::number_or_null(b.se);
}

// The items of `v` at `items`.
template <class T>
std::vector<T> pick(const std::vector<T>& v, const std::vector<std::size_t>& items) {
  std::vector<T> out;
  out.reserve(items.size());
  for (std::size_t i : items) out.push_back(v[i]);
  return out;
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
  j["median"] = median(v);
  if (v.size() < kMinSamplesForError) {
    j["se"] = nullptr;
    j["ci95"] = Json::array({nullptr, nullptr});
    j["q25"] = quantile(v, 0.25);
    j["q75"] = quantile(v, 0.75);
    return j;
  }
  const auto b = bootstrap_median(v, bo);
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

// `stat` with the values it was computed from, by seed ("by_seed": seed → the mean of that seed's
// finite values): groups grown from the same seeds are compared seed by seed (a trend over P0 is a
// paired test, docs/analysis.md "Verdicts").
template <class F>
Json with_values_by_seed(Json stat, const std::vector<const RunRow*>& rs, F f) {
  std::map<std::uint64_t, std::vector<double>> by_seed;
  for (const auto* r : rs)
    if (const double x = f(*r); std::isfinite(x)) by_seed[r->seed].push_back(x);
  Json values = Json::object();
  for (const auto& [seed, v] : by_seed) values[std::to_string(seed)] = mean(v);
  stat["by_seed"] = std::move(values);
  return stat;
}

// mean ± SE of f over the runs, with its values by seed
template <class F>
Json mean_se_by_seed(const std::vector<const RunRow*>& rs, F f) {
  return with_values_by_seed(mean_se_json(collect(rs, f)), rs, f);
}

// median of f over the runs (bootstrap error), with its values by seed
template <class F>
Json median_by_seed(const std::vector<const RunRow*>& rs, F f, const BootstrapOptions& bo) {
  return with_values_by_seed(median_json(collect(rs, f), bo), rs, f);
}

std::vector<fs::path> find_runs(const std::vector<std::string>& inputs) {
  std::set<fs::path> runs;
  for (const auto& in : inputs) {
    const fs::path p(in);
    if (!input_exists(p)) throw InputError(in + ": no such run directory");
    if (input_exists(p / io::run_files::summary)) {
      runs.insert(p);
      continue;
    }
    bool any = false;
    for (const auto& e : input_directory(p, true))
      if (e.regular_file && e.path.filename() == io::run_files::summary) {
        runs.insert(e.path.parent_path());
        any = true;
      }
    if (!any) throw InputError(in + ": holds no finished run (no summary.json below it)");
  }
  return {runs.begin(), runs.end()};
}

std::string csv_text(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::ostringstream os;
  for (std::size_t k = 0; k < header.size(); ++k) os << (k ? "," : "") << header[k];
  os << '\n';
  for (const auto& r : rows) {
    for (std::size_t k = 0; k < r.size(); ++k) os << (k ? "," : "") << r[k];
    os << '\n';
  }
  return std::move(os).str();
}

std::string cell(double v) { return std::isfinite(v) ? num(v) : std::string(); }

// ---- reading ---------------------------------------------------------------------------------------

DosRow read_spectrum(const fs::path& pack, const io::Json& dos, const RunRow& run) {
  DosRow q;
  q.run = run.dir.string();
  q.packing = pack.stem().string();
  q.L = run.L;
  q.P0_label = run.P0_label;
  q.state = run.state;
  q.seed = run.seed;
  q.target = q.packing.rfind("target_", 0) == 0;
  const io::PackingFile f = io::read_packing(pack);
  q.dphi = f.meta.has("dphi") ? f.meta.number("dphi")
                              : (f.meta.has("phi_J") ? f.meta.number("phi") - f.meta.number("phi_J") : kNaN);
  q.omega_star = json_number(dos, {"omega_star"});
  q.N_zero = json_number(dos, {"N_zero"});
  if (!std::isfinite(q.omega_star) || !std::isfinite(q.N_zero))
    throw InputError(pack.string() + ": its .dos.json has no numeric \"omega_star\" and \"N_zero\"");
  const auto pc = analyse_contacts(f.packing);
  q.Z = pc.network.Z;
  q.dZ = pc.network.dZ;
  q.N_u = static_cast<double>(pc.network.N_u);
  q.N_u_buds = static_cast<double>(pc.network.N_u_buds);
  q.N_c = static_cast<long>(pc.network.N_c);
  q.N_nr = static_cast<long>(pc.network.N_nr);
  return q;
}

// The runs of a group (L, P0) are pooled as samples of one protocol, and the growth-only baseline
// takes the cell parameters of the first run for every group: InputError naming the first scene that
// breaks either, its key and both values. Each run's protocol and cells hashes go to runs.csv, so
// that `analyse --tables` can hold the tables to the same rule without the scenes.
void check_one_protocol(std::vector<RunRow>& rows) {
  std::map<GroupKey, RunScene> first_of_group;
  std::optional<RunScene> first;
  for (RunRow& r : rows) {
    const fs::path file = r.dir / io::run_files::scene;
    const RunScene run{file, io::load_scene(file)};
    if (!first) first = run;
    const RunScene& group_first = first_of_group.try_emplace(GroupKey{r.L, r.P0}, run).first->second;
    require_same_keys(run, group_first, group_protocol_key, "the runs of one L and P0 are samples of one protocol",
                      "analyse them apart");
    require_same_keys(run, *first, cells_key, "the runs of one analysis share their cells", "analyse them apart");
    r.protocol = protocol_hash(run.scene, group_protocol_key);
    r.cells = protocol_hash(run.scene, cells_key);
    r.jamming_model = protocol_hash(run.scene, jamming_model_key);
  }
}

Ensemble read_ensemble(const EnsembleOptions& o) {
  Ensemble e;
  const auto dirs = find_runs(o.inputs);
  e.runs = dirs.size();
  // A run directory copied elsewhere is one run, not two samples: keep the first copy.
  const DistinctRuns loaded = load_distinct_runs(dirs);
  e.duplicates = loaded.copy_groups;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const RunData& r = loaded.runs[k];
    if (loaded.later_copy[k]) continue;
    // A run that stopped early (step limit, say) still landed every state it recorded: its jamming
    // point, targets and φ_2 are used; it is listed so that the report can say so. One that never
    // jammed has nothing to contribute.
    try {
      if (!r.jammed()) {
        e.never_jammed.push_back(dirs[k].string() + " (" + r.status() + ")");
        continue;
      }
      if (r.status() != "finished") e.failed.push_back(dirs[k].string() + " (" + r.status() + ")");
      e.rows.push_back(extract(r, o.require_moduli, e.moduli));
    } catch (const nlohmann::json::exception& x) {
      // A value of the wrong type or a missing key in the run's summary: name the file.
      throw InputError((dirs[k] / io::run_files::summary).string() + ": " + x.what());
    }
  }
  {
    const auto unknown =
        std::count_if(e.rows.begin(), e.rows.end(), [](const RunRow& r) { return std::isnan(r.phi_J_first); });
    if (unknown > 0)
      e.unchecked.push_back(std::to_string(unknown) +
                            " run(s) unjammed after a jamming and have logs from before the tagged buds were followed "
                            "through an unjamming: the paper's columns anchored at the first jamming (*_first, "
                            "none_left, lambda_bar_lobes, dphi_2_pred_paper) are empty for them; grow them again");
  }
  // The growth parameters of the runs, for the growth-only baseline (the first run stands for all:
  // check_one_protocol holds every run to its cell parameters).
  check_one_protocol(e.rows);
  if (!e.rows.empty()) e.growth_scene = io::load_scene(e.rows.front().dir / io::run_files::scene);
  std::vector<JammingKey> keys;
  for (const auto& r : e.rows) keys.push_back({r.L, r.seed, r.step_J, r.N_J, r.phi_J});
  const auto states = jamming_state_ids(keys);
  for (std::size_t k = 0; k < e.rows.size(); ++k) e.rows[k].state = states[k];

  for (const auto& run : e.rows) {
    // in name order: the tables do not depend on the directory order
    for (const auto& f : input_directory(run.dir / io::run_files::packings, false)) {
      const fs::path& pack = f.path;
      if (pack.extension() != ".pack") continue;
      const auto j = sidecar(pack, "dos");
      if (!j) {
        if (o.require_dos) throw InputError(pack.string() + ": no spectrum (run `make -f Makefile.analysis dos`)");
        continue;
      }
      ++e.dos_found;
      e.dos_rows.push_back(read_spectrum(pack, *j, run));
    }
  }
  if (e.rows.empty()) throw InputError("analyse: no run among the inputs reached jamming");
  std::map<GroupKey, std::vector<SurvivalRecord>> pools;
  for (std::size_t k = 0; k < e.rows.size(); ++k) {
    const RunRow& r = e.rows[k];
    const GroupKey key{r.L, r.P0};
    auto& pool = pools[key];
    for (SurvivalRecord rec : r.survival) {
      rec.cluster = k;  // the run is the sample
      pool.push_back(rec);
    }
    e.survival_runs[key] += std::isfinite(r.bud_records);  // a run without bud events adds no run to the pool
  }
  for (const auto& [key, pool] : pools) e.survival.emplace(key, kaplan_meier(pool));
  return e;
}

// ΔZ_0(P): the no-feedback branch per L — mean (P, ΔZ) at each Δφ target and, in budjam's branch,
// at jamming (the paper's analysis draws it through the targets alone, constant beyond their
// pressures) — and the SE of its ΔZ means (the scatter of the mean P along the branch is not
// propagated). A point is a mean of kMinSamplesForError runs or more, so that every value read off
// the branch has an error of its own; runs with a missing P or ΔZ at a point are left out of it.
struct NoFeedbackBranch {
  PiecewiseLinear dZ0, se;
};
std::map<double, NoFeedbackBranch> no_feedback_branch(const std::map<GroupKey, std::vector<const RunRow*>>& groups,
                                                      bool with_jamming_point) {
  std::map<double, NoFeedbackBranch> branch;
  for (const auto& [key, rs] : groups) {
    if (key.P0) continue;
    // Tables without P_J (an earlier format) give budjam no branch: their stored ΔZ_0(P) + 2(u_J − u) stands.
    if (with_jamming_point && std::none_of(rs.begin(), rs.end(), [](const RunRow* r) { return std::isfinite(r->P_J); }))
      continue;
    std::map<double, std::pair<std::vector<double>, std::vector<double>>> at;  // Δφ (−1: jamming) → P, ΔZ
    const auto add = [&](double dphi, double P, double dZ) {
      if (!std::isfinite(P) || !std::isfinite(dZ)) return;
      at[dphi].first.push_back(P);
      at[dphi].second.push_back(dZ);
    };
    for (const auto* r : rs) {
      if (with_jamming_point) add(-1.0, r->P_J, r->dZ_J);
      for (const auto& t : r->targets) add(t.dphi, t.P, t.dZ);
    }
    std::vector<std::pair<double, double>> mean_pts, se_pts;
    for (const auto& [d, v] : at)
      if (v.second.size() >= kMinSamplesForError) {
        mean_pts.emplace_back(mean(v.first), mean(v.second));
        se_pts.emplace_back(mean(v.first), standard_error(v.second));
      }
    if (!mean_pts.empty()) branch.emplace(key.L, NoFeedbackBranch{PiecewiseLinear(mean_pts), PiecewiseLinear(se_pts)});
  }
  return branch;
}

// ---- statistics ------------------------------------------------------------------------------------

// A quantity fixed at jamming: one sample per distinct jamming state, and the SE of a bootstrap
// that resamples seeds (runs of one seed share their growth up to jamming).
template <class F>
Json states_json(const std::vector<const RunRow*>& rs, F f, const BootstrapOptions& bo) {
  std::vector<double> v;
  std::vector<std::size_t> st;
  std::vector<std::uint64_t> seed;
  for (const auto* r : rs) {
    v.push_back(f(*r));
    st.push_back(r->state);
    seed.push_back(r->seed);
  }
  const MeanSE m = mean_over_states(v, st);
  // the runs of one seed share their growth up to the first jamming: its states are not independent,
  // so the seeds are the samples, and "se" is over states only where each state has a seed of its own
  const std::size_t seeds = std::set<std::uint64_t>(seed.begin(), seed.end()).size();
  const bool error_bar = seeds >= kMinSamplesForError && m.n >= kMinSamplesForError;
  const Json by_seed = error_bar ? Json(cluster_bootstrap_mean(v, st, seed, bo).se) : Json(nullptr);
  Json j;
  j["runs"] = rs.size();
  j["n"] = m.n;  // distinct jamming states
  j["seeds"] = seeds;
  j["mean"] = io::number_or_null(m.mean);
  j["se"] = !error_bar ? Json(nullptr) : seeds == m.n ? io::number_or_null(m.se) : by_seed;
  j["bootstrap_se_by_seed"] = by_seed;
  return j;
}

// The statistics of the paper's analysis over the depleted runs of a group (docs/analysis.md,
// "Definitions"): φ_2 at most one tagged bud left, as budjam's, but anchored at the run's first
// jamming; the runs its selection admits; Eq. 14 with a as diameter squared; G_2 > 0 and Tukey's
// fences on G_2 alone, the G_2 ratios over the runs those keep. Each statistic says how many runs the
// group has and how many the selection admitted.
void paper_analysis_json(Json& g, const std::vector<const RunRow*>& rs, const BootstrapOptions& bo) {
  std::vector<const RunRow*> admitted, kept;
  for (const auto* r : rs)
    if (std::isfinite(r->phi_2_first) && paper_admits(r->selection_divisions_first)) admitted.push_back(r);
  const auto keep =
      paper_G2_kept(collect(admitted, [](auto& r) { return r.G_2_first; }), std::vector<bool>(admitted.size(), true));
  for (std::size_t k = 0; k < admitted.size(); ++k)
    if (keep[k]) kept.push_back(admitted[k]);
  const auto selected = [&](Json j) {
    j["runs"] = rs.size();
    j["admitted"] = admitted.size();
    return j;
  };
  // Its φ_2 summary (Δφ_2 and P_2, beside Eq. 14) keeps only the admitted runs with a prediction.
  std::vector<const RunRow*> predicted;
  for (const auto* r : admitted)
    if (std::isfinite(r->pred_paper)) predicted.push_back(r);
  const auto with_predicted = [&](Json j) {
    j = selected(std::move(j));
    j["predicted"] = predicted.size();
    return j;
  };
  const auto dphi_2 = [](auto& r) { return r.dphi_2_first; };
  g["dphi_2_paper"] = with_predicted(mean_se_by_seed(predicted, dphi_2));
  g["dphi_2_pred_paper"] = with_predicted(mean_se_json(collect(predicted, [](auto& r) { return r.pred_paper; })));
  // Eq. 14 against the simulation run by run (the same runs on both sides: a paired difference)
  g["dphi_2_pred_minus_sim_paper"] =
      with_predicted(mean_se_json(collect(predicted, [](auto& r) { return r.pred_paper - r.dphi_2_first; })));
  const auto P_2 = [](auto& r) { return r.P_2_first / kPmax; };
  g["P_2_over_Pmax_paper"] = with_predicted(mean_se_by_seed(predicted, P_2));
  const auto lambda_bar = [](auto& r) { return r.lambda_bar_lobes; };
  g["lambda_bar_paper"] = selected(mean_se_by_seed(admitted, lambda_bar));
  g["G_2_over_Pmax_paper"] = selected(median_json(collect(kept, [](auto& r) { return r.G_2_first / kPmax; }), bo));
  const auto G_2_over_P_2 = [](auto& r) { return r.G_2_first / r.P_2_first; };
  g["G_2_over_P_2_paper"] = selected(median_by_seed(kept, G_2_over_P_2, bo));
}

// The test of B_grow = λ_c B_ext over the targets of the runs: log₁₀ of the median ratio, its error a
// bootstrap over seeds (a run's targets, and runs of one seed, are one sample).
Json growth_bulk_json(const std::vector<const RunRow*>& rs, const BootstrapOptions& bo) {
  std::vector<double> b_grow, lambda, b_ext;
  std::vector<std::uint64_t> seed;
  for (const auto* r : rs)
    for (const auto& t : r->targets) {
      b_grow.push_back(t.B_grow);
      lambda.push_back(t.lambda);
      b_ext.push_back(t.B);
      seed.push_back(r->seed);
    }
  Json j;
  j["n"] = 0;
  j["median"] = nullptr;
  if (const auto c = growth_bulk_check(b_grow, lambda, b_ext, seed, bo)) {
    const auto& b = c->log10_median;
    const bool error_bar = b.n >= kMinSamplesForError;
    j["n"] = b.n;  // seeds
    j["targets"] = c->targets;
    j["median"] = io::number_or_null(b.estimate);
    j["se"] = error_bar ? io::number_or_null(b.se) : Json(nullptr);
    j["ci95"] =
        error_bar ? Json::array({io::number_or_null(b.lo), io::number_or_null(b.hi)}) : Json::array({nullptr, nullptr});
    j["nonpositive_B_grow"] = c->nonpositive;
  }
  return j;
}

struct Tables {
  std::vector<std::vector<std::string>> survival, remaining, divisions, growth_rates, trajectory;
};

// `pooled_runs`: how many runs `km` pools, where known (survival.csv's `runs`). `N_J_first_size`:
// the mean N at the first jamming over every run of the group's box, every P0 (the paper's ⟨N_J⟩).
Json group_json(const GroupKey& key, const std::vector<const RunRow*>& rs, const KaplanMeierCurve& km,
                std::optional<std::size_t> pooled_runs, double N_J_first_size, const BootstrapOptions& bo, Tables& t) {
  const std::string P0_label = key.P0 ? num(*key.P0) : "none", P0s = P0_csv(P0_label);
  std::vector<const RunRow*> dep;
  for (const auto* r : rs)
    if (r->depleted) dep.push_back(r);
  Json g;
  g["L"] = key.L;
  g["P0"] = key.P0 ? Json(*key.P0) : Json(nullptr);
  g["P0_label"] = P0_label;
  g["runs"] = rs.size();
  g["jammed"] = rs.size();
  g["depleted"] = dep.size();
  g["depleted_none_left"] =
      std::count_if(rs.begin(), rs.end(), [](auto* r) { return std::isfinite(r->phi_2_none_left); });
  g["phi_J"] = mean_se_json(collect(rs, [](auto& r) { return r.phi_J; }));
  g["u_J"] = mean_se_json(collect(rs, [](auto& r) { return r.u_J; }));
  g["u_J_lobes"] = mean_se_json(collect(rs, [](auto& r) { return r.u_J_lobes; }));
  g["n_J"] = mean_se_json(collect(rs, [](auto& r) { return r.n_J; }));
  g["N_J"] = mean_se_json(collect(rs, [](auto& r) { return r.N_J; }));
  g["N_nr_J"] = mean_se_json(collect(rs, [](auto& r) { return r.N_nr_J; }));
  g["Z_J"] = mean_se_json(collect(rs, [](auto& r) { return r.Z_J; }));
  g["dZ_J"] = mean_se_json(collect(rs, [](auto& r) { return r.dZ_J; }));
  g["isostatic_J"] = isostatic_json(rs);
  g["lc2_J"] = mean_se_json(collect(rs, [](auto& r) { return r.lc2_J; }));
  g["dphi_2"] = mean_se_json(collect(dep, [](auto& r) { return r.dphi_2; }));
  g["phi_2"] = mean_se_json(collect(dep, [](auto& r) { return r.phi_2; }));
  g["dphi_2_pred_area"] = mean_se_json(collect(dep, [](auto& r) { return r.pred_area; }));
  g["dphi_2_pred_diameter_sq"] = mean_se_json(collect(dep, [](auto& r) { return r.pred_d2; }));
  g["dphi_2_pred_minus_sim_area"] = mean_se_json(collect(dep, [](auto& r) { return r.pred_area - r.dphi_2; }));
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
  g["G_2_energy"] = median_json(collect(dep, [](auto& r) { return r.G_2_energy; }), bo);
  g["G_2_over_Pmax"] = median_json(collect(dep, [](auto& r) { return r.G_2 / kPmax; }), bo);
  g["G_2_over_P_2"] = median_json(collect(dep, [](auto& r) { return r.G_2 / r.P_2; }), bo);
  paper_analysis_json(g, rs, bo);
  // The first state with no tagged bud left, in every run that reached it, and G there where the run
  // saved it.
  g["dphi_2_none_left"] = mean_se_json(collect(rs, [](auto& r) { return r.dphi_2_none_left; }));
  g["G_2_over_Pmax_none_left"] = median_json(collect(rs, [](auto& r) { return r.G_2_none_left / kPmax; }), bo);
  {
    // Packings unstable to some simple shear of the box (G_min < 0; moduli.hpp, ShearStability).
    std::size_t n = 0, k = 0, n2 = 0, k2 = 0;
    for (const auto* r : rs) {
      for (const auto& x : r->targets)
        if (std::isfinite(x.G_min)) ++n, k += x.G_min < 0;
      if (r->depleted && std::isfinite(r->G_min_2)) ++n2, k2 += r->G_min_2 < 0;
    }
    g["shear_unstable_targets"] = fraction_json(k, n);
    g["shear_unstable_phi2"] = fraction_json(k2, n2);
  }
  // Divisions by φ_2 normalised by the mean number of cells at jamming (Fig. D1B), by budjam's φ_2
  // (summary N_div_2) and as the paper's division figure counts them (every division from the first
  // jamming up to the first state with no tagged bud left, over the box's mean N at the first jamming)
  const double NJ = mean(finite(collect(rs, [](auto& r) { return r.N_J; })));
  g["N_div_2_over_N_J"] = median_json(collect(dep, [NJ](auto& r) { return r.N_div_2 / NJ; }), bo);
  g["N_div_2_over_N_J_paper"] =
      median_json(collect(rs, [N_J_first_size](auto& r) { return r.N_div_2_none_left / N_J_first_size; }), bo);
  censor_unreached(g, kAtPhi2, dep.size(), rs.size());
  censor_unreached(g, kAtNoneLeft, g["depleted_none_left"].get<std::size_t>(), rs.size());
  censor_unreached(g, kAtPaperPhi2,
                   static_cast<std::size_t>(
                       std::count_if(rs.begin(), rs.end(), [](auto* r) { return std::isfinite(r->phi_2_first); })),
                   rs.size());
  g["N_div_end"] = median_json(collect(rs, [](auto& r) { return r.N_div_end; }), bo);
  g["h_gamma"] = median_json(collect(rs, [](auto& r) { return r.h_gamma; }), bo);
  // the paper's figure: mean ± SE over runs, every cell of a run
  const auto h_gamma = [](auto& r) { return r.h_gamma_all_cells; };
  g["h_gamma_paper"] = mean_se_by_seed(rs, h_gamma);
  g["B_grow_over_lambda_B_log10"] = growth_bulk_json(rs, bo);

  // pooled Kaplan–Meier and the pooled prediction
  const double uJ = mean(finite(collect(rs, [](auto& r) { return r.u_J; })));
  const double nJ = mean(finite(collect(rs, [](auto& r) { return r.n_J; })));
  const double NnrJ = mean(finite(collect(rs, [](auto& r) { return r.N_nr_J; })));
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
  // typical completion size a_c as a true area: budjam's mean ∫S da, the paper's median of S
  pooled["a_c_mean_area"] = km.events() ? Json(kDiameterSquaredToArea * mean_completion_size(km)) : Json(nullptr);
  const auto a_med = median_completion_size(km);
  pooled["a_c_median_area"] = a_med ? Json(kDiameterSquaredToArea * *a_med) : Json(nullptr);
  g["pooled_survival"] = pooled;
  const std::string runs_cell = pooled_runs ? std::to_string(*pooled_runs) : std::string();
  const auto survival_row = [&](const KaplanMeierStep& st) {
    const auto [se, lo, hi, se_greenwood] = band_cells(st, pooled_runs);
    t.survival.push_back(
        {num(key.L), P0s, num(st.a), num(st.S), se, lo, hi, se_greenwood, std::to_string(st.at_risk), runs_cell});
  };
  survival_row(KaplanMeierStep{.a = 0, .at_risk = km.records()});
  for (const auto& st : km.steps()) survival_row(st);

  // Fig. 2B and D1A curves
  const auto grid = dphi_grid();
  for (std::size_t k = 0; k < grid.size(); ++k) {
    std::vector<double> rem, dv;
    for (const auto* r : rs) {
      if (k < r->remaining.size() && std::isfinite(r->remaining[k])) rem.push_back(r->remaining[k]);
      if (k < r->divisions.size() && std::isfinite(r->divisions[k])) dv.push_back(r->divisions[k] / NJ);
    }
    if (!rem.empty())
      t.remaining.push_back({num(key.L), P0s, num(grid[k]), num(mean(rem)),
                             cell(rem.size() >= kMinSamplesForError ? standard_error(rem) : kNaN),
                             std::to_string(rem.size())});
    if (!dv.empty())
      t.divisions.push_back({num(key.L), P0s, num(grid[k]), num(median(dv)), num(quantile(dv, 0.25)),
                             num(quantile(dv, 0.75)), std::to_string(dv.size())});
  }
  g["dphi_2_median"] = median_json(collect(dep, [](auto& r) { return r.dphi_2; }), bo);

  // Fig. E1: Π(g) pooled over the group's runs, on the paper's bins; the paper's weight at g = 1 is
  // the mean over runs of the fraction of all cells growing at g = 1
  g["g_peak_weight_at_1_paper"] = mean_se_json(collect(rs, [](auto& r) { return r.g1_fraction_all_cells; }));
  std::vector<double> gall;
  for (const auto* r : rs) gall.insert(gall.end(), r->g.begin(), r->g.end());
  if (!gall.empty()) {
    const auto edges = paper_growth_rate_edges();
    const auto d = growth_rate_distribution(gall, edges);
    g["g_cells"] = d.cells;
    g["g_peak_weight_at_1"] = d.weight_at_one;
    g["g_compressed_median"] = io::number_or_null(d.median);
    g["g_compressed_q25"] = io::number_or_null(d.q25);
    g["g_compressed_q75"] = io::number_or_null(d.q75);
    g["g_mean"] = mean(gall);
    g["h_gamma_pooled"] = growth_heterogeneity(gall);
    for (std::size_t k = 0; k < d.density.size(); ++k)
      t.growth_rates.push_back({num(key.L), P0s, num(edges[k]), num(edges[k + 1]), num(d.density[k]), "false"});
    t.growth_rates.push_back({num(key.L), P0s, "1", "1", num(d.weight_at_one), "true"});
  }

  // Fig. 4: mean trajectory in (P, G) over the targets below φ_2, and the endpoint
  std::map<double, std::pair<std::vector<double>, std::vector<double>>> traj;
  for (const auto* r : rs)
    for (const auto& x : r->targets)
      if (x.below_phi2) {
        traj[x.dphi].first.push_back(x.P);
        traj[x.dphi].second.push_back(x.G);
      }
  // Means as in the paper's caption, and medians: one packing near a shear instability of the box
  // (G ≪ 0, docs/moduli.md) can dominate the mean of a few runs.
  auto med = [](const std::vector<double>& v) { return v.empty() ? kNaN : median(v); };
  for (auto& [d, v] : traj)
    t.trajectory.push_back({num(key.L), P0s, num(d), cell(mean(v.first)), cell(mean(finite(v.second))),
                            cell(med(v.first)), cell(med(finite(v.second))), std::to_string(v.first.size()), "false"});
  const auto P2 = finite(collect(dep, [](auto& r) { return r.P_2; }));
  const auto G2 = finite(collect(dep, [](auto& r) { return r.G_2; }));
  t.trajectory.push_back({num(key.L), P0s, cell(mean(finite(collect(dep, [](auto& r) { return r.dphi_2; })))),
                          cell(mean(P2)), cell(mean(G2)), cell(med(P2)), cell(med(G2)), std::to_string(dep.size()),
                          "true"});
  return g;
}

// Fraction of packings (targets and φ_2, all P0) unstable to some simple shear of the box, in
// decades of P N_J²: finite packings jammed at fixed box shape lose that instability as P N² grows
// (Dagois-Bohy et al. 2012; Goodrich et al. 2012).
Json shear_instability_by_PN2(const std::vector<const RunRow*>& m) {
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
  return sb;
}

// ΔZ = ΔZ_0(P) + 2(u_J − u) (Eq. 6): budjam's residual over every target of the main L, and the
// paper's test per P0 over the feedback runs only (the no-feedback runs define ΔZ_0(P)). The targets
// of one run, and the runs of one seed, are one sample: pooled residuals are clustered by seed.
Json dz_identity_json(const std::vector<const RunRow*>& m, const BootstrapOptions& bo) {
  std::vector<double> res, res_fed;
  std::vector<std::uint64_t> seed, seed_fed;
  std::vector<IdentityPoint> fed;
  for (const auto* r : m)
    for (const auto& t : r->targets) {
      if (!std::isfinite(t.dZ_pred)) continue;
      res.push_back(t.dZ - t.dZ_pred);
      seed.push_back(r->seed);
      if (!r->P0) continue;
      fed.push_back({*r->P0, t.dZ - t.dZ_pred});
      res_fed.push_back(t.dZ - t.dZ_pred);
      seed_fed.push_back(r->seed);
    }
  double sq = 0;
  for (double v : res) sq += v * v;
  Json j;
  j["all_targets"] = clustered_mean_json(res, seed, bo);
  j["all_targets"]["rms"] = res.empty() ? Json(nullptr) : Json(std::sqrt(sq / static_cast<double>(res.size())));
  Json per = Json::array();
  for (const auto& x : dz_identity_residuals(fed))
    per.push_back(
        Json{{"P0", x.P0}, {"targets", x.residual.n}, {"mean", io::number_or_null(x.residual.mean)}, {"rms", x.rms}});
  j["per_P0_feedback"] = per;
  j["feedback_targets"] = clustered_mean_json(res_fed, seed_fed, bo);
  // The identity assumes that the buds free at jamming are not repopulated by divisions: over the
  // targets a run reached with at most kPaperMaxDivisions divisions after φ_J (the paper's own bound
  // for that), one mean residual per run — the targets of one run are not independent — and per P0
  // the mean over runs. Its error adds to the SE over runs that of the branch ΔZ_0(P) at those
  // targets, which every run of the group shares (so it does not average down over runs).
  std::map<double, std::pair<std::vector<double>, std::vector<double>>> by_P0;  // run means, branch SEs
  for (const auto* r : m) {
    if (!r->P0) continue;
    std::vector<double> v;
    for (const auto& t : r->targets)
      if (std::isfinite(t.dZ_pred) && paper_admits(t.N_div)) {
        v.push_back(t.dZ - t.dZ_pred);
        by_P0[*r->P0].second.push_back(t.dZ_pred_se);
      }
    if (!v.empty()) by_P0[*r->P0].first.push_back(mean(v));
  }
  Json unrep = Json::array();
  for (auto it = by_P0.rbegin(); it != by_P0.rend(); ++it) {
    Json p = mean_se_json(it->second.first);
    const double se_runs = p["se"].is_number() ? p["se"].get<double>() : kNaN;
    const double se_branch = mean(it->second.second);  // NaN when the branch has no error bar there
    p["se_runs"] = p["se"];
    p["se_branch"] = io::number_or_null(se_branch);
    p["se"] = io::number_or_null(std::hypot(se_runs, se_branch));
    p["P0"] = it->first;
    unrep.push_back(p);
  }
  j["per_P0_unrepopulated_by_run"] = unrep;
  return j;
}

// The paper's figures of an identity "measured = predicted" over (P0, Δφ): per cell the means ± SE
// over its runs of both sides, with no test; its no-feedback runs are cells too where
// `with_no_feedback` (B_grow; the ΔZ identity takes its ΔZ_0(P) from them). The whole counts the cells with
// kMinSamplesForError runs or more and those whose two means lie more than 2 combined SE apart, √(SE_m² + SE_p²) — what
// a reader of the figure sees as error bars that do not meet; about 1 in 20 by chance where the identity holds.
template <class Measured, class Predicted>
Json paper_cells_json(const std::vector<const RunRow*>& m, bool with_no_feedback, Measured measured,
                      Predicted predicted) {
  // (P0, −Δφ) → both sides; no feedback as P0 = ∞, the weakest: read backwards, weak to strong
  // feedback and each group's targets in increasing Δφ
  std::map<std::pair<double, double>, std::array<std::vector<double>, 2>> cells;
  for (const auto* r : m) {
    if (!r->P0 && !with_no_feedback) continue;
    const double P0 = r->P0.value_or(std::numeric_limits<double>::infinity());
    for (const auto& t : r->targets) {
      const double a = measured(t), b = predicted(t);
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      auto& c = cells[{P0, -t.dphi}];
      c[0].push_back(a);
      c[1].push_back(b);
    }
  }
  Json list = Json::array();
  std::size_t tested = 0, apart = 0;
  for (auto it = cells.rbegin(); it != cells.rend(); ++it) {
    const auto& [P0, minus_dphi] = it->first;
    const Json a = mean_se_json(it->second[0]), b = mean_se_json(it->second[1]);
    if (a["se"].is_number() && b["se"].is_number()) {
      ++tested;
      const double gap = std::abs(a["mean"].get<double>() - b["mean"].get<double>());
      apart += gap > 2.0 * std::hypot(a["se"].get<double>(), b["se"].get<double>());
    }
    list.push_back(Json{{"P0", std::isfinite(P0) ? Json(P0) : Json(nullptr)},
                        {"dphi", -minus_dphi},
                        {"measured", a},
                        {"predicted", b}});
  }
  return Json{{"cells", list}, {"cells_tested", tested}, {"cells_apart_2se", apart}};
}

// Spectrum: N_zero against N_u over distinct packings (a jammed packing shared by the runs of one
// jamming state counts once), and ω* against ΔZ and Z − 6: budjam's free linear fit over every
// packing, the paper's proportionality through the origin on the Δφ-target packings. The packings of
// one seed (its runs' targets at every P0) are one sample for the errors: n counts seeds.
Json spectrum_json(const std::vector<const DosRow*>& rows, const BootstrapOptions& bo) {
  std::vector<double> w, dz, z6, diff, signed_diff, target_below_six, target_N_u, target_N_zero;
  std::vector<std::uint64_t> seed, target_seed;
  std::size_t equal = 0;
  std::set<std::size_t> jammed_seen;
  std::vector<CollapsePoint> targets;
  for (const auto* q : rows) {
    if (q->packing == "jammed" && !jammed_seen.insert(q->state).second) continue;
    w.push_back(q->omega_star);
    dz.push_back(q->dZ);
    z6.push_back(q->Z - 6.0);
    diff.push_back(std::abs(q->N_zero - q->N_u));
    signed_diff.push_back(q->N_zero - q->N_u);
    seed.push_back(q->seed);
    equal += q->N_zero == q->N_u;
    if (!q->target) continue;
    targets.push_back({q->omega_star, q->N_c, q->N_nr, static_cast<long>(q->N_u)});
    target_N_u.push_back(q->N_u);
    target_N_zero.push_back(q->N_zero);
    target_below_six.push_back(q->N_c - 6 * q->N_nr < 0 ? 1.0 : 0.0);
    target_seed.push_back(q->seed);
  }
  if (w.size() < 3) return nullptr;
  const double n = static_cast<double>(w.size());
  const auto fd = linear_fit(dz, w);
  const auto f6 = linear_fit(z6, w);
  // The SEs of the slopes are bootstraps over seeds: the fits' own SEs would count every packing of a
  // seed as an independent sample.
  const Json fd_se = se_by_cluster(
      seed, [&](const auto& k) { return linear_fit(pick(dz, k), pick(w, k)).slope; }, bo);
  Json j{{"packings", w.size()},
         {"seeds", std::set<std::uint64_t>(seed.begin(), seed.end()).size()},
         {"N_zero_equals_N_u", equal / n},
         {"N_zero_minus_N_u_abs", mean(diff)},
         {"N_zero_minus_N_u", clustered_mean_json(signed_diff, seed, bo)},
         {"omega_star_vs_dZ", Json{{"slope", fd.slope}, {"slope_se", fd_se}, {"intercept", fd.intercept}}},
         {"r2_dZ", fd.r2},
         {"r2_Z_minus_6", f6.r2}};
  if (!targets.empty()) {
    const auto c = omega_collapse(targets);
    const auto fit = [&](const OriginFit& f, OriginFit OmegaCollapse::*which) {
      const Json se = se_by_cluster(
          target_seed, [&](const auto& k) { return (omega_collapse(pick(targets, k)).*which).slope; }, bo);
      return Json{{"slope", f.slope}, {"slope_se", se}, {"r2_uncentred", f.r2}, {"rms", f.rms}};
    };
    const double nt = static_cast<double>(c.packings);
    const Json below_six = clustered_mean_json(target_below_six, target_seed, bo);
    j["paper"] = Json{{"packings", c.packings},
                      {"seeds", below_six["n"]},
                      {"through_origin_dZ", fit(c.dZ, &OmegaCollapse::dZ)},
                      {"through_origin_Z_minus_6", fit(c.Z_minus_6, &OmegaCollapse::Z_minus_6)},
                      {"fraction_dZ_negative", c.dZ_negative / nt},
                      {"fraction_Z_minus_6_negative", c.Z_minus_6_negative / nt},
                      {"fraction_Z_minus_6_negative_se", below_six["se"]}};
    // its N_zero panel: the packings with N_zero = N_u exactly, and the slope of N_zero on N_u through 0
    std::size_t same = 0;
    for (std::size_t k = 0; k < target_N_u.size(); ++k) same += target_N_zero[k] == target_N_u[k];
    Json nz{{"packings", target_N_u.size()},
            {"seeds", std::set<std::uint64_t>(target_seed.begin(), target_seed.end()).size()},
            {"N_zero_equals_N_u", same}};
    if (std::any_of(target_N_u.begin(), target_N_u.end(), [](double x) { return x != 0; })) {
      nz["slope_through_origin"] = fit_through_origin(target_N_u, target_N_zero).slope;
      nz["slope_se"] = se_by_cluster(
          target_seed,
          [&](const auto& k) { return fit_through_origin(pick(target_N_u, k), pick(target_N_zero, k)).slope; }, bo);
    }
    j["paper"]["N_zero_vs_N_u"] = nz;
  }
  return j;
}

// P† of ln ⟨P_2⟩ against 1/P0 over the groups of `runs` (their depleted runs; `items` picks which,
// with repeats): −slope of the line, and the number of groups it runs through.
std::pair<double, std::size_t> p_dagger_fit(const std::vector<const RunRow*>& runs,
                                            const std::vector<std::size_t>& items) {
  std::map<double, std::vector<double>> p2;  // 1/P0 → P_2
  for (const std::size_t k : items)
    if (std::isfinite(runs[k]->P_2)) p2[1.0 / *runs[k]->P0].push_back(runs[k]->P_2);
  std::vector<double> x, y;
  for (const auto& [inv_P0, v] : p2)
    if (mean(v) > 0) {
      x.push_back(inv_P0);
      y.push_back(std::log(mean(v)));
    }
  if (x.size() < 2) throw std::invalid_argument("P†: fewer than two groups");
  return {-linear_fit(x, y).slope, x.size()};
}

// P_2 ∝ exp(−P†/P0) (Eq. D19): slope of ln P_2 against 1/P0 over the feedback groups with
// P0 ≤ 10⁻², and the crossover P* (Eq. E12) over the a_c of those groups: budjam's mean completion
// size, the paper's median (both as true areas). The groups are grown from the same seeds, so P†'s
// error is a bootstrap over seeds, each draw refitted, not the scatter about one line of groups
// taken as independent.
void feedback_scales(Json& h, const std::map<GroupKey, std::vector<const RunRow*>>& groups,
                     const std::map<GroupKey, KaplanMeierCurve>& survival, double main_L, double nJ, double uJ,
                     const BootstrapOptions& bo) {
  std::vector<double> ac_mean, ac_median;
  std::vector<const RunRow*> depleted;
  std::vector<std::uint64_t> seeds;
  for (const auto& [key, rs] : groups) {
    if (key.L != main_L || !key.P0 || *key.P0 > 1e-2 + 1e-15) continue;
    for (const auto* r : rs)
      if (r->depleted && std::isfinite(r->P_2)) {
        depleted.push_back(r);
        seeds.push_back(r->seed);
      }
    const auto& km = survival.at(key);
    if (km.events() > 0) ac_mean.push_back(kDiameterSquaredToArea * mean_completion_size(km));
    if (const auto a = median_completion_size(km)) ac_median.push_back(kDiameterSquaredToArea * *a);
  }
  std::vector<std::size_t> all(depleted.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  try {
    const auto [p_dagger, points] = p_dagger_fit(depleted, all);
    h["P_dagger"] = p_dagger;
    h["P_dagger_points"] = points;
    h["P_dagger_seeds"] = std::set<std::uint64_t>(seeds.begin(), seeds.end()).size();
    h["P_dagger_se"] =
        points >= kMinSamplesForError
            ? se_by_cluster(
                  seeds, [&](const std::vector<std::size_t>& items) { return p_dagger_fit(depleted, items).first; }, bo)
            : Json(nullptr);
  } catch (const std::invalid_argument&) {
    // fewer than two groups: no line
  }
  auto range = [&](const std::vector<double>& ac, const char* a_key, const char* p_key) {
    if (ac.empty()) return;
    const auto [lo, hi] = std::minmax_element(ac.begin(), ac.end());
    h[a_key] = Json::array({*lo, *hi});
    h[p_key] = Json::array({crossover_pressure(nJ, uJ, *lo), crossover_pressure(nJ, uJ, *hi)});
  };
  range(ac_mean, "a_c_range_area", "P_star_range");
  range(ac_median, "a_c_median_range_area", "P_star_range_paper");
}

// The numbers the size-effects figure compares across L, from the runs of one size: quantities
// fixed at jamming (over distinct states), the ΔZ identity and B_grow = λ_c B_ext.
Json size_json(const std::vector<const RunRow*>& m, const BootstrapOptions& bo) {
  Json h;
  h["runs"] = m.size();
  // budjam's u_J counts contact-free buds; the lobe count includes contact-free mothers
  h["u_J"] = states_json(
      m, [](auto& r) { return r.u_J; }, bo);
  h["u_J_lobes"] = states_json(
      m, [](auto& r) { return r.u_J_lobes; }, bo);
  h["n_J"] = states_json(
      m, [](auto& r) { return r.n_J; }, bo);
  h["phi_J"] = states_json(
      m, [](auto& r) { return r.phi_J; }, bo);
  h["N_J"] = states_json(
      m, [](auto& r) { return r.N_J; }, bo);
  h["Z_J"] = states_json(
      m, [](auto& r) { return r.Z_J; }, bo);
  h["rattler_fraction"] = states_json(
      m, [](auto& r) { return 1.0 - r.N_nr_J / r.N_J; }, bo);
  h["cells_per_area"] = states_json(
      m, [](auto& r) { return r.N_J / (r.L * r.L); }, bo);
  h["dZ_J"] = states_json(
      m, [](auto& r) { return r.dZ_J; }, bo);
  h["isostatic_J"] = isostatic_json(m);
  h["jamming_states"] = h["u_J"]["n"];
  h["dZ_identity"] = dz_identity_json(m, bo);
  h["dZ_identity"]["paper_cells"] = paper_cells_json(
      m, false, [](const TargetRow& t) { return t.dZ; }, [](const TargetRow& t) { return t.dZ_pred_paper; });
  h["B_grow_over_lambda_B_log10"] = growth_bulk_json(m, bo);
  h["B_grow_over_lambda_B_log10"]["paper_cells"] = paper_cells_json(
      m, true, [](const TargetRow& t) { return t.B_grow; },
      // the paper's λ_c counts the contact-free lobes in u, as its Eq. 13 reads u
      [](const TargetRow& t) { return lambda_c(t.u_lobes, t.chi_c) * t.B; });
  return h;
}

Json headline_json(double main_L, const Ensemble& e, const std::map<GroupKey, std::vector<const RunRow*>>& groups,
                   const BootstrapOptions& bo) {
  std::vector<const RunRow*> m;
  for (const auto& r : e.rows)
    if (r.L == main_L) m.push_back(&r);
  // Quantities fixed at jamming over every run of the main L (feedback acts only above jamming), one
  // sample per distinct jamming state; the paper's u_J, on the strongest-feedback packings, is its
  // own analysis' tagged (contact-free) buds over N_nr, budjam's u_J.
  Json h = size_json(m, bo);
  std::optional<double> strongest;
  for (const auto& [key, rs] : groups)
    if (key.L == main_L && key.P0 && (!strongest || *key.P0 < *strongest)) strongest = key.P0;
  if (strongest) {
    const auto& rs = groups.at({main_L, strongest});
    h["paper_P0"] = *strongest;
    h["u_J_paper"] = states_json(
        rs, [](auto& r) { return r.u_J; }, bo);
    h["n_J_paper"] = states_json(
        rs, [](auto& r) { return r.n_J; }, bo);
  }
  const double phiJ = h["phi_J"]["mean"].is_number() ? h["phi_J"]["mean"].get<double>() : kNaN;
  h["P_max_formula_measured_phiJ"] = io::number_or_null(2.0 / std::numbers::pi * (1.0 - phiJ));
  h["shear_unstable_by_PN2"] = shear_instability_by_PN2(m);
  // plateau G_2(0+) = n_J k ℓ_c² M_4 u_J from the strongest-feedback jammed packings
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
  feedback_scales(h, groups, e.survival, main_L, h["n_J"]["mean"].get<double>(), h["u_J"]["mean"].get<double>(), bo);
  std::vector<const DosRow*> dm;
  for (const auto& q : e.dos_rows)
    if (q.L == main_L) dm.push_back(&q);
  h["dos"] = spectrum_json(dm, bo);
  return h;
}

// The files analyse writes in --out, all replaced at once (analysis.json marks them as analyse's).
const std::vector<std::string_view> kOutputFiles{"analysis.json",    "runs.csv",       "targets.csv",
                                                 "survival.csv",     "remaining.csv",  "division_curve.csv",
                                                 "growth_rates.csv", "trajectory.csv", "dos.csv"};

// The tables as (file name, content). A table the inputs could not give (Ensemble::unavailable names
// it) is left out: an empty file would read as "measured, nothing there".
std::vector<std::pair<std::string, std::string>> table_files(const Ensemble& e, const Tables& t) {
  std::vector<std::string> run_header{"run",           "L",        "P0",    "seed",         "status",
                                      "jamming_state", "protocol", "cells", "jamming_model"};
  std::vector<std::string> tgt_header{"run", "L", "P0", "seed", "dphi"};
  for (const auto& c : kRunColumns) run_header.push_back(c.name);
  for (const auto& c : kTargetColumns) tgt_header.push_back(c.name);
  tgt_header.push_back("below_phi2");
  std::vector<std::vector<std::string>> run_rows, tgt_rows, dos_out;
  for (const auto& r : e.rows) {
    std::vector<std::string> row{
        r.dir.string(), num(r.L), P0_csv(r.P0_label), std::to_string(r.seed), r.status, std::to_string(r.state),
        r.protocol,     r.cells,  r.jamming_model};
    for (const auto& c : kRunColumns) row.push_back(cell(r.*c.field));
    run_rows.push_back(row);
    for (const auto& x : r.targets) {
      std::vector<std::string> trow{r.dir.string(), num(r.L), P0_csv(r.P0_label), std::to_string(r.seed), num(x.dphi)};
      for (const auto& c : kTargetColumns) trow.push_back(cell(x.*c.field));
      trow.push_back(x.below_phi2 ? "true" : "false");
      tgt_rows.push_back(trow);
    }
  }
  for (const auto& q : e.dos_rows)
    dos_out.push_back({q.run, q.packing, num(q.L), P0_csv(q.P0_label), std::to_string(q.state), cell(q.dphi),
                       cell(q.omega_star), cell(q.dZ), cell(q.Z - 6.0), std::to_string(q.N_c), std::to_string(q.N_nr),
                       cell(q.N_zero), cell(q.N_u), cell(q.N_u_buds)});
  std::vector<std::pair<std::string, std::string>> files;
  auto write = [&](const char* name, const std::vector<std::string>& header,
                   const std::vector<std::vector<std::string>>& rows) {
    if (std::find(kOutputFiles.begin(), kOutputFiles.end(), name) == kOutputFiles.end())
      throw std::logic_error(std::string("analyse: ") + name + " is not in kOutputFiles");
    if (!e.unavailable.count(name)) files.emplace_back(name, csv_text(header, rows));
  };
  write("runs.csv", run_header, run_rows);
  write("targets.csv", tgt_header, tgt_rows);
  write("survival.csv", {"L", "P0", "a", "S", "se", "lo", "hi", "se_greenwood", "at_risk", "runs"}, t.survival);
  write("remaining.csv", {"L", "P0", "dphi", "mean", "se", "runs"}, t.remaining);
  write("division_curve.csv", {"L", "P0", "dphi", "median", "q25", "q75", "runs"}, t.divisions);
  write("growth_rates.csv", {"L", "P0", "g_lo", "g_hi", "density", "delta_at_1"}, t.growth_rates);
  write("trajectory.csv", {"L", "P0", "dphi", "P", "G", "P_median", "G_median", "runs", "endpoint"}, t.trajectory);
  write("dos.csv",
        {"run", "packing", "L", "P0", "jamming_state", "dphi", "omega_star", "dZ", "Z_minus_6", "N_c", "N_nr", "N_zero",
         "N_u", "N_u_buds"},
        dos_out);
  return files;
}

}  // namespace

EnsembleAccount analyse_ensemble(const EnsembleOptions& o) {
  if (o.out.empty()) throw InputError("--out: an output directory is required");
  io::check_output_directory("--out", o.out, kOutputFiles);  // before the work, not after it
  // An earlier output: analysis.json with the format tag and the keys analyse writes (any version).
  io::check_own_output_directory("--out", o.out, "analyse", "analysis.json", [](const io::Json& j) {
    return j.value("format", io::Json()) == "budjam-analysis" && j.contains("version") && j.contains("groups");
  });
  if (o.tables.empty() == o.inputs.empty()) throw InputError("analyse: give either run directories or --tables DIR");
  if (!o.tables.empty() && fs::exists(o.out) && fs::equivalent(o.tables, o.out))
    throw InputError("--out: " + o.out + " is the --tables directory; its tables would be overwritten");
  // A table may share a run file's name (dos.csv): --out in a run directory must not replace it.
  if (o.tables.empty()) {
    std::vector<fs::path> inputs;
    for (const fs::path& dir : find_runs(o.inputs))
      for (auto& file : run_input_files(dir)) inputs.push_back(std::move(file));
    for (const std::string_view name : kOutputFiles) io::check_not_an_input("--out", fs::path(o.out) / name, inputs);
  }
  if (!(o.main_L >= 0)) throw InputError("--main-L: must be a box side > 0 (got " + num(o.main_L) + ")");
  Ensemble e = o.tables.empty() ? read_ensemble(o) : read_ensemble_tables(o.tables);

  std::map<GroupKey, std::vector<const RunRow*>> groups;
  std::set<double> lengths;
  for (const auto& r : e.rows) {
    groups[{r.L, r.P0}].push_back(&r);
    lengths.insert(r.L);
  }
  const double main_L = o.main_L > 0 ? o.main_L : (lengths.count(15.0) ? 15.0 : *lengths.rbegin());
  if (!lengths.count(main_L)) throw InputError("--main-L: no runs with L = " + num(main_L));

  const auto branch = no_feedback_branch(groups, true), paper_branch = no_feedback_branch(groups, false);
  for (auto& r : e.rows) {
    const auto b = branch.find(r.L), pb = paper_branch.find(r.L);
    for (auto& t : r.targets) {
      if (b != branch.end()) {
        t.dZ_pred = b->second.dZ0(t.P) + 2.0 * (r.u_J - t.u);
        t.dZ_pred_se = b->second.se.empty() ? kNaN : b->second.se(t.P);
      }
      if (pb != paper_branch.end()) t.dZ_pred_paper = pb->second.dZ0(t.P) + 2.0 * (r.tagged / t.N_nr - t.u_lobes);
    }
  }

  const fs::path out(o.out);
  Tables tables;
  Json jgroups = Json::array();
  std::map<double, std::vector<double>> N_J_first_by_L;
  for (const auto& r : e.rows) N_J_first_by_L[r.L].push_back(r.N_J_first);
  for (const auto& [key, rs] : groups) {
    const auto pooled = e.survival_runs.find(key);
    jgroups.push_back(group_json(key, rs, e.survival.at(key),
                                 pooled != e.survival_runs.end() ? std::optional(pooled->second) : std::nullopt,
                                 mean(finite(N_J_first_by_L.at(key.L))), o.bootstrap, tables));
  }

  Json J;
  J["format"] = "budjam-analysis";
  // 3: B_grow = λ_c B_ext as the median ratio; 4: errors of pooled targets by seed; 5: the SEs of the
  // spectrum's slopes by seed, finite-size fits only over sizes of disjoint seeds
  J["version"] = 7;
  J["inputs"] = Json{{"runs", e.runs},
                     {"used", e.rows.size()},
                     {"not_finished", e.failed},
                     {"never_jammed", e.never_jammed},
                     {"duplicates", e.duplicates},
                     {"moduli_files", e.moduli.found},
                     {"moduli_saddles", e.moduli.saddles},
                     {"moduli_contact_bounded", e.moduli.contact_bounded},
                     {"dos_files", e.dos_found}};
  if (!o.tables.empty()) {
    J["inputs"]["tables"] = o.tables;
    // which packings had no linear response the tables do not say (e.unavailable): unknown, not 0
    J["inputs"]["moduli_saddles"] = J["inputs"]["moduli_contact_bounded"] = nullptr;
  }
  J["inputs"]["unchecked"] = e.unchecked;
  J["unavailable"] = e.unavailable;
  J["main_L"] = main_L;
  J["bootstrap"] = Json{{"resamples", o.bootstrap.resamples}, {"seed", o.bootstrap.seed}};
  J["constants"] = Json{{"P_max", kPmax},
                        {"P_max_formula_phiJ_0.84", 2.0 / std::numbers::pi * (1.0 - 0.84)},
                        {"M4", kM4},
                        {"u_J_lambert_w", u_J_mean_field()},
                        {"lambert_w0_of_minus_2_e_minus_2", lambert_w0(-2.0 * std::exp(-2.0))}};
  J["main"] = headline_json(main_L, e, groups, o.bootstrap);
  {
    // Which jamming model the runs are of (empty for tables from before the column).
    std::set<std::string> models;
    for (const auto& r : e.rows)
      if (!r.jamming_model.empty()) models.insert(r.jamming_model);
    J["jamming_models"] = models;
  }
  J["groups"] = jgroups;
  {
    Json sizes = Json::array();
    for (double L : lengths) {
      std::vector<const RunRow*> m;
      for (const auto& r : e.rows)
        if (r.L == L) m.push_back(&r);
      Json x = size_json(m, o.bootstrap);
      x["L"] = L;
      sizes.push_back(x);
    }
    J["sizes"] = sizes;
  }
  // The seeds behind each size, so that the 1/N fits use only sizes that are independent samples.
  std::map<std::string, SeedsBySize> group_seeds;
  SeedsBySize size_seeds;
  for (const auto& r : e.rows) {
    group_seeds[r.P0 ? num(*r.P0) : "none"][r.L].insert(r.seed);  // the P0_label of group_json
    size_seeds[r.L].insert(r.seed);
  }
  J["finite_size"] = finite_size_json(J["groups"], group_seeds);
  {
    // The growth-only baseline with the growth parameters of the runs (every run of an ensemble shares
    // them; tables carry none, so there the scene defaults, which are the paper's, stand in).
    Scene scene = e.growth_scene;
    const GrowthOnly growth_only = [&scene](double L, double phi) {
      scene.L = L;
      return growth_only_cells(scene, phi, kGrowthOnlySamples, kGrowthOnlyFirstSeed);
    };
    J["finite_size_jamming"] = jamming_finite_size_json(J["sizes"], size_seeds, growth_only, kGrowthOnlyLargeL);
  }
  {
    Json br = Json::array();
    for (const auto& [L, b] : branch) {
      Json pts = Json::array(), se = Json::array();
      for (std::size_t k = 0; k < b.dZ0.xs().size(); ++k) pts.push_back(Json::array({b.dZ0.xs()[k], b.dZ0.ys()[k]}));
      for (std::size_t k = 0; k < b.se.xs().size(); ++k) se.push_back(Json::array({b.se.xs()[k], b.se.ys()[k]}));
      br.push_back(Json{{"L", L}, {"points_P_dZ", pts}, {"points_P_se", se}});
    }
    J["dZ0_branch"] = br;
  }
  // Every file is complete before any replaces its predecessor (a full disk leaves the earlier
  // output whole), and a table this ensemble cannot give does not survive from an earlier one.
  auto files = table_files(e, tables);
  // Each table's digest, by which a later `analyse --tables` tells a table edited since.
  J["tables_written"] = Json::object();
  for (const auto& [name, text] : files) J["tables_written"][name] = io::hex64(io::fnv1a64(text));
  files.emplace_back("analysis.json", io::json_text(J));
  const io::Directory dir = io::Directory::open(out, true);
  io::write_atomically(dir, files);
  for (const std::string_view name : kOutputFiles)
    if (e.unavailable.count(std::string(name))) dir.remove(name);

  std::ostringstream msg;
  msg << e.rows.size() << " runs used (" << e.failed.size() << " not finished";
  if (!e.never_jammed.empty()) msg << "; " << e.never_jammed.size() << " never jammed, left out";
  if (!e.duplicates.empty()) {
    msg << "; duplicate copies left out:";
    for (const auto& d : e.duplicates)
      for (std::size_t k = 1; k < d.size(); ++k) msg << " " << d[k] << " (= " << d[0] << ")";
  }
  msg << ") in " << groups.size() << " groups; moduli files " << e.moduli.found;
  if (o.tables.empty())
    msg << " (" << e.moduli.saddles << " saddles, " << e.moduli.contact_bounded << " contact-bounded minima)";
  msg << ", spectra " << e.dos_found << " -> " << out.string();
  return {msg.str(), e.unchecked};
}

}  // namespace budjam::tools
