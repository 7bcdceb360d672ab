#include "analysis/accuracy_sweep.hpp"

#include "analysis/accuracy_post.hpp"
#include "io/run_data.hpp"
#include "io/run_directory.hpp"

#include "budjam/errors.hpp"
#include "budjam/number_text.hpp"
#include "budjam/pareto.hpp"
#include "budjam/statistics.hpp"
#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <set>
#include <sstream>
#include <tuple>

namespace budjam::tools {

namespace fs = std::filesystem;
using io::Json;

namespace {

// Quantities in table order; which family can change which.
const std::vector<std::string> kQuantities{"phi_J", "u_J", "Z_J", "phi_2", "P", "B", "G", "omega_star", "band"};
const std::map<std::string, std::vector<std::string>> kFamilyQuantities{
    {"growth", {"phi_J", "u_J", "Z_J", "phi_2", "P", "B", "G", "omega_star"}},
    {"moduli", {"B", "G"}},
    {"spectrum", {"omega_star", "band"}}};
// Growth knobs by the <knob> of their variant directories (<knob>_<value>), then post-processing ones.
const std::map<std::string, std::string> kGrowthKnobLabel{{"ftol", "minimiser.force_tol"},
                                                          {"floor", "minimiser.energy_floor"},
                                                          {"epsU", "jamming.epsilon_U"},
                                                          {"tol", "jamming.target_tolerance"},
                                                          {"dt", "growth.dt"},
                                                          {"search", "jamming.search"},
                                                          {"newton", "minimiser.newton_force"},
                                                          {"adaptive", "growth.adaptive_dt"},
                                                          {"jump", "jamming.jump_factor"},
                                                          {"across", "jamming.start_across_divisions"},
                                                          {"budget", "jamming.trial_budget"},
                                                          {"continuation", "jamming.continuation"},
                                                          {"crossing", "jamming.crossing_step"},
                                                          {"activeset", "minimiser.active_set_after"},
                                                          {"activetry", "minimiser.active_set_try_after"}};
const std::map<std::string, std::string> kPostKnobLabel{
    {"solver", "moduli linear solver"}, {"arpack_tol", "ARPACK tol"}, {"arpack_ncv", "ARPACK ncv"}};

std::string knob_label(const std::string& knob) {
  for (const auto* labels : {&kGrowthKnobLabel, &kPostKnobLabel})
    if (const auto it = labels->find(knob); it != labels->end()) return it->second;
  return knob;
}
// Errors below which a family's settings tie, whatever --error-floor says: direct solvers, the dense
// reference included, differ by 1e-10–3e-9 in B and G on jammed packings (the Hessian's condition
// number near jamming times the rounding), so differences there measure the reference, not the setting.
double family_error_floor(const std::string& family, double floor) {
  return family == "moduli" ? std::max(floor, 1e-8) : floor;
}

// Knobs whose default is part of the model, not a numerical choice: the model defines the jamming
// point by E/N ∈ [ε_U, 2ε_U] with ε_U = 1e-16, the value the paper's numbers came from, so another
// ε_U moves φ_J by definition; where active-set steps take over a relaxation, they reach another
// minimum than FIRE (docs/minimiser.md, "Active-set steps"), a change of the protocol that per-seed
// errors do not measure and the ensembles do. Their fronts are measured and reported, but do not
// decide the verdict.
const std::string kJudgedByEnsembles =
    ": a change of the protocol, judged by the jamming ensembles (docs/minimiser.md, \"Active-set steps\"), not by "
    "per-seed errors";
const std::map<std::string, std::string> kPinnedByModel{
    {"epsU", "the model fixes epsilon_U = 1e-16 (the jamming criterion the paper's numbers came from)"},
    {"activeset", "where active-set steps take over they reach other minima than FIRE" + kJudgedByEnsembles},
    {"activetry", "a kept try of the active-set steps ends at another minimum than FIRE's" + kJudgedByEnsembles}};

// Quantities of the whole trajectory, judged over the ensemble of seeds (accuracy_sweep.hpp); from
// fewer than kMinSamplesForError seeds one has no resolution and takes no part in any front.
const std::set<std::string> kEnsembleQuantities{"phi_2"};

double error_of(const SweepRow& r, const std::string& q) {
  const auto it = r.err.find(q);
  return it == r.err.end() ? kNaN : it->second;
}

double resolution_of(const SweepRow& r, const std::string& q) {
  const auto it = r.resolution.find(q);
  return it == r.resolution.end() ? kNaN : it->second;
}

// ---- growth knobs ---------------------------------------------------------------------------

// seed<k> subdirectories with a summary.json, by name.
std::map<std::string, fs::path> seeds_of(const fs::path& dir) {
  std::map<std::string, fs::path> m;
  for (const auto& e : input_directory(dir, false))
    if (e.directory && input_exists(e.path / io::run_files::summary)) m[e.path.filename().string()] = e.path;
  if (m.empty()) throw InputError(dir.string() + ": holds no run directory (seed*/summary.json)");
  return m;
}

double sidecar_number(const fs::path& pack, const std::string& kind, const char* key) {
  const auto j = tools::sidecar(pack, kind);
  if (!j || !j->contains(key) || !(*j)[key].is_number()) return kNaN;
  return (*j)[key].get<double>();
}

struct Measured {
  double cpu = kNaN, wall = kNaN, evaluations = kNaN, factorisations = kNaN;
  double phi_J = kNaN, u_J = kNaN, Z_J = kNaN, phi_2 = kNaN;
  std::map<double, double> P, B, G, omega;  // by Δφ
};

Measured measure(const fs::path& run) {
  const tools::RunData r = tools::load_run(run);
  Measured m;
  if (input_exists(run / io::run_files::timing)) {
    const Json t = io::read_json(run / io::run_files::timing);
    m.wall = t.value("wall_seconds", kNaN);
    m.evaluations = t.value("force_evaluations", kNaN);
  }
  if (input_exists(run / "cpu_time.json")) {
    const Json t = io::read_json(run / "cpu_time.json");
    m.cpu = t.value("user_seconds", kNaN) + t.value("system_seconds", kNaN);
  }
  m.factorisations = r.summary.contains("newton_factorisations") ? r.get("newton_factorisations") : kNaN;
  m.phi_J = r.get("phi_J");
  m.u_J = r.get("u_J");
  m.Z_J = r.get("Z_J");
  m.phi_2 = r.get("phi_2");
  for (const auto& t : r.summary.at("targets")) {
    const double d = t.at("dphi").get<double>();
    m.P[d] = t.at("P").get<double>();
    const fs::path pack = run / io::run_files::packing(io::run_files::target_stem(t.at("index").get<std::size_t>()));
    m.B[d] = sidecar_number(pack, "moduli", "B");
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

double finite_mean(const std::vector<double>& v) {
  std::vector<double> f;
  for (double x : v)
    if (std::isfinite(x)) f.push_back(x);
  return f.empty() ? kNaN : mean(f);
}

}  // namespace

// The cost of a growth setting is its counted work at the sweep's CPU rates: force evaluations
// (FIRE) and factorisations (the Newton finish, the continuation), counts that the same seeds repeat
// exactly, while the CPU time of one ~1-s run on a shared machine varies by 15–30 % with the load.
// The two rates are the least-squares fit of every run's CPU time (rows weighted by their runs),
// kept non-negative: with too few factorisations to resolve their rate, it is 0 and the evaluations
// carry the whole CPU time.
GrowthCostRates growth_cost_rates(const std::vector<SweepRow>& rows) {
  double ee = 0, ef = 0, ff = 0, ec = 0, fc = 0;
  for (const SweepRow& r : rows) {
    if (!std::isfinite(r.seconds) || !std::isfinite(r.force_evaluations) || r.force_evaluations <= 0) continue;
    const double w = static_cast<double>(r.n), e = r.force_evaluations;
    const double f = std::isfinite(r.newton_factorisations) ? r.newton_factorisations : 0.0;
    ee += w * e * e;
    ef += w * e * f;
    ff += w * f * f;
    ec += w * e * r.seconds;
    fc += w * f * r.seconds;
  }
  GrowthCostRates rates;
  if (ee <= 0) return rates;
  const double det = ee * ff - ef * ef;
  if (det > 1e-12 * ee * ff) {
    rates.per_evaluation = (ec * ff - fc * ef) / det;
    rates.per_factorisation = (fc * ee - ec * ef) / det;
  }
  if (!(rates.per_evaluation > 0) || !(rates.per_factorisation > 0)) {
    rates.per_evaluation = ec / ee;  // the evaluations alone
    rates.per_factorisation = 0;
  }
  return rates;
}

std::vector<SweepRow> growth_rows(const SweepOptions& o) {
  const auto ref_runs = seeds_of(o.reference);
  std::map<std::string, Measured> ref;
  for (const auto& [s, d] : ref_runs) ref[s] = measure(d);

  std::vector<SweepRow> rows;
  auto add = [&](const std::string& name, const fs::path& dir, bool is_ref) {
    SweepRow row;
    row.family = "growth";
    row.set = o.growth_set;
    row.unit = "run";
    row.variant = name;
    row.is_reference = is_ref;
    row.is_default = name == "default";
    row.knob = is_ref ? "reference" : row.is_default ? "default" : name.substr(0, name.find('_'));
    if (!is_ref && !row.is_default && (name.find('_') == std::string::npos || !kGrowthKnobLabel.count(row.knob))) {
      std::string knobs;
      for (const auto& [knob, label] : kGrowthKnobLabel) knobs += (knobs.empty() ? "" : ", ") + knob;
      throw InputError(dir.string() + ": a variant directory is named <knob>_<value> with knob one of " + knobs +
                       ", or default");
    }
    std::map<std::string, std::vector<double>> per;
    std::vector<double> cpu, wall, evals, factorisations;
    for (const auto& [s, d] : seeds_of(dir)) {
      if (!ref.count(s)) throw InputError(d.string() + ": the reference has no run " + s);
      const Measured m = measure(d);
      const Measured& R = ref.at(s);
      cpu.push_back(m.cpu);
      wall.push_back(m.wall);
      evals.push_back(m.evaluations);
      factorisations.push_back(m.factorisations);
      ++row.n;
      if (is_ref) continue;
      per["phi_J"].push_back(std::abs(m.phi_J - R.phi_J));
      per["u_J"].push_back(std::abs(m.u_J - R.u_J));
      per["Z_J"].push_back(std::abs(m.Z_J - R.Z_J));
      per["phi_2"].push_back(m.phi_2 - R.phi_2);  // signed: an ensemble quantity
      per["P"].push_back(rel_error(m.P, R.P));
      per["B"].push_back(rel_error(m.B, R.B));
      per["G"].push_back(rel_error(m.G, R.G));
      per["omega_star"].push_back(rel_error(m.omega, R.omega));
    }
    row.wall_seconds = finite_mean(wall);
    row.force_evaluations = finite_mean(evals);
    row.newton_factorisations = finite_mean(factorisations);
    row.seconds = std::isfinite(finite_mean(cpu)) ? finite_mean(cpu) : row.wall_seconds;
    for (const auto& [q, v] : per) {
      row.err[q] = std::abs(finite_mean(v));
      if (!kEnsembleQuantities.count(q)) continue;
      std::vector<double> d;
      for (double x : v)
        if (std::isfinite(x)) d.push_back(x);
      row.resolution[q] = d.size() >= kMinSamplesForError ? 2 * standard_error(d) : kNaN;
    }
    rows.push_back(row);
  };
  for (const auto& v : o.variants) add(fs::path(v).filename().string(), v, false);
  add("reference", o.reference, true);
  const GrowthCostRates rates = growth_cost_rates(rows);
  for (SweepRow& r : rows)
    r.cost =
        std::isfinite(r.force_evaluations) && rates.per_evaluation > 0
            ? rates.per_evaluation * r.force_evaluations +
                  rates.per_factorisation * (std::isfinite(r.newton_factorisations) ? r.newton_factorisations : 0.0)
            : r.seconds;
  return rows;
}

// ---- post-processing knobs ------------------------------------------------------------------

namespace {

// NAME and DIR of a `--packings NAME=DIR`.
std::pair<std::string, std::string> packing_set(const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
    throw InputError("--packings: expected NAME=DIR, got '" + spec + "'");
  std::string name = spec.substr(0, eq);
  if (name.find_first_of(",\"\n") != std::string::npos)
    throw InputError("--packings: NAME must not contain , \" or a newline");
  return {std::move(name), spec.substr(eq + 1)};
}

}  // namespace

std::vector<SweepRow> post_rows(const SweepOptions& o) {
  std::vector<SweepRow> rows;
  tools::PostOptions po;
  po.min_seconds = o.min_seconds;
  for (const std::string& spec : o.packings) {
    const auto [name, dir] = packing_set(spec);
    const auto packs = tools::find_packings(dir);
    std::cerr << "accuracy: " << io::escape_control(name) << ": " << packs.size() << " packings\n";
    for (const tools::PostRow& p : tools::measure_postprocessing(name, packs, po)) {
      SweepRow r;
      r.family = p.family;
      r.knob = p.knob;
      r.variant = p.variant;
      r.set = p.set;
      r.unit = "computation";
      r.is_default = p.is_default;
      r.is_reference = p.is_reference;
      r.n = p.packings;
      r.failures = p.failures;
      r.seconds = p.seconds;
      r.cost = p.seconds;
      r.max_residual = p.max_residual;
      r.well_posed = p.all_well_posed;
      const std::pair<const char*, std::pair<double, double>> e[] = {
          {"B", {p.err_B, p.max_err_B}},
          {"G", {p.err_G, p.max_err_G}},
          {"omega_star", {p.err_omega_star, p.max_err_omega_star}},
          {"band", {p.err_band, p.max_err_band}}};
      for (const auto& [q, v] : e)
        if (!std::isnan(v.first) || !p.is_reference) {
          const auto& fam = kFamilyQuantities.at(r.family);
          if (std::find(fam.begin(), fam.end(), q) == fam.end()) continue;
          r.err[q] = v.first;
          r.max_err[q] = v.second;
        }
      rows.push_back(r);
    }
  }
  return rows;
}

namespace {

// ---- fronts ---------------------------------------------------------------------------------

struct Group {
  std::string family, set, knob;
  std::vector<std::size_t> members;  // row indices, the default first
};

std::vector<Group> groups_of(const std::vector<SweepRow>& rows) {
  std::vector<Group> groups;
  std::set<std::tuple<std::string, std::string, std::string>> seen;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const SweepRow& r = rows[k];
    if (r.is_default || r.is_reference || r.knob == "repeat" || !seen.insert({r.family, r.set, r.knob}).second)
      continue;
    Group g{r.family, r.set, r.knob, {}};
    for (std::size_t j = 0; j < rows.size(); ++j)
      if (rows[j].family == r.family && rows[j].set == r.set && rows[j].is_default) g.members.push_back(j);
    if (g.members.size() != 1)
      throw InputError("accuracy: knob " + r.knob + " of " + r.set + " needs exactly one default setting (found " +
                       std::to_string(g.members.size()) + ")");
    for (std::size_t j = 0; j < rows.size(); ++j)
      if (rows[j].family == r.family && rows[j].set == r.set && rows[j].knob == r.knob) g.members.push_back(j);
    groups.push_back(g);
  }
  return groups;
}

// An ensemble quantity without a resolution (fewer than kMinSamplesForError seeds) is not judged: its
// error is NaN here, which takes no part in a comparison (budjam/pareto.hpp).
CostErrors cost_errors(const SweepRow& r, const std::vector<std::string>& quantities) {
  CostErrors c{r.cost, {}, {}};
  for (const auto& q : quantities) {
    const double res = resolution_of(r, q);
    c.errors.push_back(kEnsembleQuantities.count(q) && std::isnan(res) ? kNaN : error_of(r, q));
    c.resolution.push_back(res);
  }
  return c;
}

// Joint front of a knob measured on several packing sets: a setting's cost is the geometric mean over
// the sets of its cost relative to that set's default (every size weighs alike), its error in each
// quantity the worst over the sets; ties as in the widest per-set band. Settings are matched across
// sets by name; only those measured on every set take part.
Json joint_fronts(const std::vector<SweepRow>& rows, const std::vector<Group>& groups,
                  const std::set<std::pair<std::string, std::string>>& knobs,
                  const std::map<std::string, double>& cost_tie_of_set, const ParetoTolerance& base) {
  Json out = Json::array();
  for (const auto& [family, knob] : knobs) {
    std::vector<const Group*> sets;
    for (const Group& g : groups)
      if (g.family == family && g.knob == knob) sets.push_back(&g);
    const auto& qs = kFamilyQuantities.at(family);
    ParetoTolerance tol = base;
    tol.error_floor = family_error_floor(family, tol.error_floor);
    // settings by name: per set, (relative cost, errors); the default is member 0 of every set
    std::vector<std::string> names;
    std::map<std::string, std::vector<std::pair<double, CostErrors>>> per;
    for (const Group* g : sets) {
      tol.cost_ratio = std::max(tol.cost_ratio, cost_tie_of_set.at(family + "\n" + g->set + "\n" + knob));
      const double c0 = rows[g->members[0]].cost;
      for (std::size_t m = 0; m < g->members.size(); ++m) {
        const SweepRow& r = rows[g->members[m]];
        const std::string name = m == 0 ? std::string("default") : r.variant;
        if (g == sets.front()) names.push_back(name);
        per[name].emplace_back(r.cost / c0, cost_errors(r, qs));
      }
    }
    std::vector<CostErrors> ce;
    std::vector<std::string> used;
    for (const auto& name : names) {
      const auto& v = per[name];
      if (v.size() != sets.size()) continue;
      CostErrors c{0.0, std::vector<double>(qs.size(), kNaN), std::vector<double>(qs.size(), kNaN)};
      for (const auto& [rc, one] : v) {
        c.cost += std::log(rc) / static_cast<double>(v.size());
        for (std::size_t q = 0; q < qs.size(); ++q)
          if (!std::isnan(one.errors[q]) && !(one.errors[q] <= c.errors[q])) {
            c.errors[q] = one.errors[q];
            c.resolution[q] = one.resolution[q];
          }
      }
      c.cost = std::exp(c.cost);
      ce.push_back(c);
      used.push_back(name);
    }
    const auto front = pareto_front(ce, tol);
    Json j{{"family", family}, {"knob", knob}, {"knob_label", knob_label(knob)}, {"cost_tie", tol.cost_ratio - 1}};
    Json jsets = Json::array(), jset = Json::array(), jfront = Json::array(), jby = Json::array();
    for (const Group* g : sets) jsets.push_back(g->set);
    for (std::size_t k = 0; k < used.size(); ++k)
      jset.push_back(Json{{"setting", used[k]}, {"relative_cost", ce[k].cost}});
    for (std::size_t f : front) jfront.push_back(used[f]);
    for (std::size_t b : dominated_by(ce, 0, tol)) jby.push_back(used[b]);
    j["sets"] = jsets;
    j["settings"] = jset;
    j["front"] = jfront;
    j["default_dominated_by"] = jby;
    j["default_on_front"] = std::find(front.begin(), front.end(), std::size_t{0}) != front.end();
    out.push_back(j);
  }
  return out;
}

std::string fmt(double v) {
  if (std::isnan(v)) return "";
  if (v == 0) return "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, std::abs(v) >= 0.01 && std::abs(v) < 1000 ? "%.3g" : "%.1e", v);
  return buf;
}

}  // namespace

void check_sweep_options(const SweepOptions& o) {
  if (o.reference.empty() != o.variants.empty())
    throw InputError(
        "--reference: growth variants and the reference go together (got " +
        std::string(o.reference.empty() ? "variants without --reference" : "--reference without variants") + ")");
  if (o.reference.empty() && o.packings.empty())
    throw InputError("accuracy: nothing to measure (give --reference DIR VARIANT_DIR... and/or --packings NAME=DIR)");
  const auto require = [](const char* option, double value, double lo) {
    if (!(std::isfinite(value) && value >= lo))
      throw InputError(std::string(option) + ": must be a finite number ≥ " + budjam::shortest_text(lo) + " (got " +
                       budjam::shortest_text(value) + ")");
  };
  require("--time-noise", o.time_noise, 0);
  require("--error-ratio", o.error_ratio, 1);
  require("--error-floor", o.error_floor, 0);
  require("--min-seconds", o.min_seconds, 0);
  std::set<std::string> names;
  for (const std::string& spec : o.packings)
    if (const std::string name = packing_set(spec).first; !names.insert(name).second)
      throw InputError("--packings: the name " + io::escape_control(name) + " is given twice (each set needs its own)");
  if (o.growth_set.empty() || o.growth_set.find_first_of(",\"\n") != std::string::npos)
    throw InputError("--growth-set: must be non-empty without , \" or a newline (a CSV field)");
}

namespace {

// Timing noise: the default of each post-processing family and set, timed twice in the same rounds.
// Returns (family, set) → relative difference of the two timings.
std::map<std::pair<std::string, std::string>, double> timing_noise(const std::vector<SweepRow>& rows,
                                                                   const SweepOptions& o, SweepVerdict& v) {
  std::ostringstream noise_md;
  std::map<std::pair<std::string, std::string>, double> noise_of;
  for (const SweepRow& r : rows) {
    if (r.knob != "repeat") continue;
    for (const SweepRow& d : rows)
      if (d.is_default && d.family == r.family && d.set == r.set) {
        const double diff = std::abs(r.cost - d.cost) / std::min(r.cost, d.cost);
        noise_of[{r.family, r.set}] = diff;
        const double band = std::max(o.time_noise, 3 * diff);
        v.timing_noise.push_back(Json{{"family", r.family},
                                      {"set", r.set},
                                      {"relative_difference", io::number_or_null(diff)},
                                      {"cost_tie", band}});
        noise_md << "- timing noise, " << r.set << " " << r.family << ": the default timed twice differs by "
                 << fmt(100 * diff) << " %; cost tie band " << fmt(100 * band) << " %\n";
      }
  }
  v.noise_md = noise_md.str();
  return noise_of;
}

// The front of one knob of one set: marks its rows on the front (a default stays off once any knob of
// its family and set has it off, unless the model pins that knob) and returns the group's JSON.
Json knob_front(std::vector<SweepRow>& rows, const Group& g, const ParetoTolerance& tol) {
  const auto& qs = kFamilyQuantities.at(g.family);
  std::vector<CostErrors> ce;
  for (std::size_t k : g.members) ce.push_back(cost_errors(rows[k], qs));
  const auto front = pareto_front(ce, tol);
  const auto by = dominated_by(ce, 0, tol);
  std::vector<bool> in_front(g.members.size(), false);
  for (std::size_t f : front) in_front[f] = true;
  for (std::size_t m = 0; m < g.members.size(); ++m) {
    SweepRow& r = rows[g.members[m]];
    r.on_front = m == 0 ? (r.on_front && (in_front[0] || kPinnedByModel.count(g.knob))) : in_front[m];
  }
  Json j;
  j["family"] = g.family;
  j["set"] = g.set;
  j["knob"] = g.knob;
  j["knob_label"] = knob_label(g.knob);
  j["cost_tie"] = tol.cost_ratio - 1;
  j["error_floor"] = tol.error_floor;
  j["default"] = rows[g.members[0]].variant;
  j["default_on_front"] = in_front[0];
  Json names = Json::array(), front_names = Json::array(), by_names = Json::array();
  for (std::size_t k : g.members) names.push_back(rows[k].variant);
  for (std::size_t f : front) front_names.push_back(rows[g.members[f]].variant);
  for (std::size_t b : by) by_names.push_back(rows[g.members[b]].variant);
  j["variants"] = names;
  j["front"] = front_names;
  j["default_dominated_by"] = by_names;
  // Per quantity (what the figure draws): the front of cost against that error alone.
  Json per = Json::object();
  for (std::size_t q = 0; q < qs.size(); ++q) {
    std::vector<CostErrors> one;
    for (const auto& c : ce) one.push_back(CostErrors{c.cost, {c.errors[q]}, {c.resolution[q]}});
    Json fq = Json::array();
    for (std::size_t f : pareto_front(one, tol)) fq.push_back(rows[g.members[f]].variant);
    per[qs[q]] = fq;
  }
  j["front_by_quantity"] = per;
  if (kPinnedByModel.count(g.knob)) j["pinned_by_model"] = kPinnedByModel.at(g.knob);
  return j;
}

}  // namespace

SweepVerdict judge_fronts(std::vector<SweepRow>& rows, const SweepOptions& o) {
  SweepVerdict v;
  const auto noise_of = timing_noise(rows, o, v);
  const ParetoTolerance base_tol{
      .cost_ratio = 1 + o.time_noise, .error_ratio = o.error_ratio, .error_floor = o.error_floor};
  const std::vector<Group> knob_groups = groups_of(rows);
  // A default serves every problem size: a knob measured on several packing sets is judged on its
  // joint front (joint_fronts); the per-set fronts are reported beside it.
  std::set<std::pair<std::string, std::string>> judged_jointly;
  for (const Group& g : knob_groups)
    for (const Group& h : knob_groups)
      if (g.family == h.family && g.knob == h.knob && g.set != h.set) judged_jointly.insert({g.family, g.knob});
  std::map<std::string, double> cost_tie_of_set;
  for (const Group& g : knob_groups) {
    // Costs within the tie band are equal: --time-noise, widened to 3× the measured timing noise of
    // the set (post-processing; the growth cost is a deterministic count).
    ParetoTolerance tol = base_tol;
    tol.error_floor = family_error_floor(g.family, tol.error_floor);
    if (const auto it = noise_of.find({g.family, g.set}); it != noise_of.end() && std::isfinite(it->second))
      tol.cost_ratio = 1 + std::max(o.time_noise, 3 * it->second);
    Json j = knob_front(rows, g, tol);
    cost_tie_of_set[g.family + "\n" + g.set + "\n" + g.knob] = tol.cost_ratio;
    if (!j["default_on_front"].get<bool>() && !judged_jointly.count({g.family, g.knob}) &&
        !kPinnedByModel.count(g.knob)) {
      v.all_on_front = false;
      v.off_front.push_back(g.set + ": " + g.knob);
    }
    v.groups.push_back(j);
  }
  v.joint_groups = joint_fronts(rows, knob_groups, judged_jointly, cost_tie_of_set, base_tol);
  std::ostringstream joint_md;
  for (const Json& j : v.joint_groups) {
    joint_md << "- " << j["knob_label"].get<std::string>() << ", all sets jointly (" << j["sets"].size()
             << "): default " << (j["default_on_front"].get<bool>() ? "on" : "NOT on") << " the front";
    if (!j["default_on_front"].get<bool>()) {
      v.all_on_front = false;
      v.off_front.push_back("all sets: " + j["knob"].get<std::string>());
    }
    joint_md << "; front: ";
    for (std::size_t k = 0; k < j["front"].size(); ++k) joint_md << (k ? ", " : "") << j["front"][k].get<std::string>();
    joint_md << '\n';
  }
  v.joint_md = joint_md.str();
  return v;
}

namespace {

bool judged(const SweepRow& r) { return !r.is_reference && r.knob != "repeat"; }

Json row_json(const SweepRow& r) {
  Json x{{"family", r.family},
         {"knob", r.knob},
         {"set", r.set},
         {"variant", r.variant},
         {"default", r.is_default},
         {"reference", r.is_reference},
         {"unit", r.unit},
         {"n", r.n},
         {"seconds", io::number_or_null(r.seconds)},
         {"cost", io::number_or_null(r.cost)}};
  for (const auto& q : kQuantities) {
    x["err_" + q] = io::number_or_null(error_of(r, q));
    if (r.max_err.count(q)) x["max_err_" + q] = io::number_or_null(r.max_err.at(q));
    if (r.resolution.count(q)) x["res_" + q] = io::number_or_null(r.resolution.at(q));
  }
  if (r.family == "growth") {
    x["wall_seconds"] = io::number_or_null(r.wall_seconds);
    x["force_evaluations"] = io::number_or_null(r.force_evaluations);
    x["newton_factorisations"] = io::number_or_null(r.newton_factorisations);
  } else {
    x["failures"] = r.failures;
  }
  if (r.family == "moduli") {
    x["max_residual"] = io::number_or_null(r.max_residual);
    x["well_posed"] = r.well_posed;
  }
  if (judged(r)) x["on_front"] = r.on_front;
  return x;
}

void write_csv(const fs::path& file, const std::vector<SweepRow>& rows) {
  const std::vector<std::string> head{"family", "knob", "set", "variant", "default", "unit", "n", "seconds", "cost"};
  const auto number = [](double v) { return std::isfinite(v) ? io::format_double(v) : ""; };
  io::write_atomically(file, [&](std::ostream& os) {
    for (const auto& h : head) os << h << ',';
    for (const auto& q : kQuantities) os << "err_" << q << ',';
    for (const auto& q : kEnsembleQuantities) os << "res_" << q << ',';
    os << "on_front\n";
    for (const SweepRow& r : rows) {
      os << r.family << ',' << r.knob << ',' << r.set << ',' << r.variant << ',' << (r.is_default ? "true" : "false")
         << ',' << r.unit << ',' << r.n << ',' << number(r.seconds) << ',' << number(r.cost);
      for (const auto& q : kQuantities) os << ',' << number(error_of(r, q));
      for (const auto& q : kEnsembleQuantities) os << ',' << number(resolution_of(r, q));
      os << ',' << (!judged(r) ? "" : r.on_front ? "true" : "false") << '\n';
    }
  });
}

// The table with 2–3 significant digits, for the documentation.
std::string markdown(const std::vector<SweepRow>& rows, const SweepVerdict& v) {
  std::ostringstream md;
  md << "| family | set | knob | setting | per | CPU s | cost s | φ_J | u_J | Z_J | φ_2 | P | B | G | ω* | band | on "
        "front |\n"
     << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const SweepRow& r : rows) {
    md << "| " << r.family << " | " << r.set << " | " << r.knob << " | "
       << (r.is_default ? "**" + r.variant + "**" : r.variant) << " | " << r.unit << " | " << fmt(r.seconds) << " | "
       << fmt(r.cost);
    for (const auto& q : kQuantities) {
      const double e = error_of(r, q);
      md << " | " << (r.err.count(q) ? (std::isnan(e) ? "n/a" : fmt(e)) : "");
      if (const double res = resolution_of(r, q); !std::isnan(res))
        md << " ± " << fmt(res);
      else if (kEnsembleQuantities.count(q) && r.err.count(q) && !std::isnan(e))
        md << " (" << r.n << " seeds < " << kMinSamplesForError << ": not judged)";
    }
    md << " | "
       << (r.is_reference       ? "reference"
           : r.knob == "repeat" ? "(noise probe)"
           : r.on_front         ? "yes"
                                : "**no**")
       << " |\n";
  }
  md << "\nKnobs measured on several packing sets, judged on their joint front (relative cost: geometric mean "
        "over the sets; errors: the worst set's):\n"
     << v.joint_md;
  for (const auto& [knob, why] : kPinnedByModel)
    md << "\nNot judged (default set by the model): " << knob << ": " << why << '\n';
  md << "\nDefaults on the front of every knob: " << (v.all_on_front ? "yes" : "no") << '\n';
  for (const auto& s : v.off_front) md << "- not on the front: " << s << '\n';
  md << v.noise_md;
  return md.str();
}

}  // namespace

void check_accuracy_out(const fs::path& dir) {
  io::check_output_directory("--out", dir, {"accuracy.csv", "accuracy.md", "accuracy.json"});
  // An earlier output: accuracy.json with the format tag, or (written before the tag) the keys
  // write_accuracy_tables writes.
  io::check_own_output_directory("--out", dir, "accuracy", "accuracy.json", [](const io::Json& j) {
    if (j.contains("format")) return j["format"] == "budjam-accuracy" && j.contains("version");
    return j.contains("front_rule") && j["front_rule"].is_object() && j.contains("rows") && j["rows"].is_array() &&
           j.contains("defaults_on_front");
  });
}

void write_accuracy_tables(const fs::path& dir, const SweepOptions& o, const std::vector<SweepRow>& rows,
                           const SweepVerdict& v) {
  write_csv(dir / "accuracy.csv", rows);
  io::write_atomically(dir / "accuracy.md", markdown(rows, v));
  Json jrows = Json::array();
  for (const SweepRow& r : rows) jrows.push_back(row_json(r));
  io::write_json(dir / "accuracy.json",
                 Json{{"format", "budjam-accuracy"},
                      {"version", 1},
                      {"note",
                       "errors: mean over seeds (growth) or packings (moduli, spectrum) of |variant - reference| "
                       "(phi_J, u_J, Z_J) or of the relative error (P, B, G, omega_star averaged over the "
                       "targets; band = the largest relative error of the n_band eigenvalues omega* averages); "
                       "phi_2 (a trajectory property): |mean over seeds of variant - reference|, res_phi_2 = 2 "
                       "standard errors of that mean, within which it ties (from 5 seeds or more; with fewer, no "
                       "res_phi_2 and phi_2 is not judged); "
                       "seconds: CPU seconds per run (growth) or per computation (best of interleaved repeats); "
                       "cost (what the front compares): the seconds, except for growth: force evaluations per run "
                       "times the sweep's mean CPU seconds per evaluation (deterministic); "
                       "docs/accuracy.md"},
                      {"reference", o.reference},
                      {"front_rule", Json{{"time_noise", o.time_noise},
                                          {"error_ratio", o.error_ratio},
                                          {"error_floor", o.error_floor},
                                          {"rule",
                                           "a setting dominates the default if it is at most cost_tie dearer, "
                                           "no error is worse (errors within error_ratio, or both <= error_floor, "
                                           "tie) and it is cheaper beyond cost_tie or better in one error; "
                                           "cost_tie = time_noise, for a post-processing set max(time_noise, 3 x "
                                           "the relative difference of the default timed twice)"}}},
                      {"defaults_on_front", v.all_on_front},
                      {"pinned_by_model",
                       [] {
                         Json p = Json::object();
                         for (const auto& [knob, why] : kPinnedByModel) p[knob] = why;
                         return p;
                       }()},
                      {"not_on_front", v.off_front},
                      {"timing_noise", v.timing_noise},
                      {"groups", v.groups},
                      {"joint_groups", v.joint_groups},
                      {"rows", jrows}});
}

}  // namespace budjam::tools
