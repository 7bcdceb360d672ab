#include "analysis/ensemble_tables.hpp"

#include "analysis/jamming_states.hpp"
#include "budjam/scene.hpp"
#include "budjam/survival.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/run_data.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace budjam::tools {

namespace {

namespace fs = std::filesystem;

double number_or_nan(const CsvTable& t, const char* name, std::size_t row) {
  return t.has_column(name) ? t.number(row, t.column(name)) : kNaN;
}

// The column of runs.csv that holds `c`: its name, or the name of an earlier version; nullptr if none.
const char* run_column(const CsvTable& R, const RunColumn& c) {
  if (R.has_column(c.name)) return c.name;
  return c.legacy && R.has_column(c.legacy) ? c.legacy : nullptr;
}

std::string group_text(double L, const std::string& P0_label) {
  return "L = " + io::format_double(L) + ", P0 = " + P0_label;
}

// runs.csv's protocol and cells columns (run_protocol.hpp) held to the rule the run-directory reader
// applies to the scenes (check_one_protocol): one protocol within each (L, P0), one set of cells
// over the table. A column that is absent, or empty in every row (as an analysis of such tables writes
// it), comes from tables before it: nothing to check, and a notice says so. One filled in some rows
// and empty in others is refused: its rows were not written by one analysis.
void check_protocol_columns(const CsvTable& R, Ensemble& e) {
  std::vector<std::string> lacking;
  for (const auto& [column, field, in_group] :
       {std::tuple{"protocol", &RunRow::protocol, true}, std::tuple{"cells", &RunRow::cells, false},
        std::tuple{"jamming_model", &RunRow::jamming_model, true}}) {
    std::optional<std::size_t> filled, empty;  // first such rows
    for (std::size_t k = 0; k < e.rows.size(); ++k) {
      auto& first = (e.rows[k].*field).empty() ? empty : filled;
      if (!first) first = k;
    }
    if (!filled) {
      if (std::string_view(column) == "jamming_model")
        e.unchecked.push_back(R.source + " has no jamming_model column (tables from before it): whether a jamming " +
                              "ensemble is of these runs' model cannot be checked");
      else
        lacking.push_back(column);
      continue;
    }
    if (empty) {
      const std::size_t a = std::min(*filled, *empty), b = std::max(*filled, *empty);
      const bool later_empty = b == *empty;
      throw InputError(
          R.source + ":" + std::to_string(b + 2) + ": run " + e.rows[b].dir.string() +
          (later_empty ? " has no " + std::string(column) : " has " + std::string(column) + " " + e.rows[b].*field) +
          ", but run " + e.rows[a].dir.string() + " (line " + std::to_string(a + 2) + ") has " +
          (later_empty ? "one" : "none") + ": rows of tables of different formats");
    }
    std::map<std::pair<double, std::string>, std::size_t> first;  // group (or the whole table) → first row
    for (std::size_t k = 0; k < e.rows.size(); ++k) {
      const RunRow& r = e.rows[k];
      const auto at = first.try_emplace(in_group ? std::pair{r.L, r.P0_label} : std::pair{0.0, std::string()}, k);
      const RunRow& f = e.rows[at.first->second];
      if (r.*field == f.*field) continue;
      throw InputError(R.source + ":" + std::to_string(k + 2) + ": runs " + f.dir.string() + " and " + r.dir.string() +
                       " differ in " + column + " (" + f.*field + ", " + r.*field + "): " +
                       (in_group ? "the runs of one " + group_text(r.L, r.P0_label) +
                                       " are samples of one protocol; analyse them apart"
                                 : std::string("the runs of one analysis share their cells; analyse them apart")));
    }
  }
  if (!lacking.empty())
    e.unchecked.push_back(R.source + " has no " + lacking.front() + (lacking.size() > 1 ? " or " + lacking[1] : "") +
                          " column (tables from before it): whether the runs pooled per L and P0 are of one " +
                          "protocol cannot be checked");
}

void read_runs(const CsvTable& R, Ensemble& e, std::map<std::string, std::size_t>& index) {
  // Tables from before jamming.phi2_tagged_left hold budjam's φ_2 only, which is what the default says.
  for (const auto& c : kRunColumns)
    if (!run_column(R, c) && c.field != &RunRow::phi2_tagged_left && c.field != &RunRow::target_rows)
      e.unavailable[c.name] = R.source + " has no column " + c.name + " (it needs " + c.source + " of each run)";
  const std::size_t c_run = R.column("run"), c_L = R.column("L"), c_P0 = R.column("P0"), c_seed = R.column("seed"),
                    c_status = R.column("status");
  std::set<std::tuple<double, std::string, std::uint64_t>> samples;  // (L, P0, seed)
  for (std::size_t k = 0; k < R.size(); ++k) {
    RunRow x;
    x.dir = R.text(k, c_run);
    x.L = R.number(k, c_L);
    x.P0_label = P0_label_from_csv(R.text(k, c_P0));
    if (x.P0_label != "none") x.P0 = R.number(k, c_P0);
    x.seed = static_cast<std::uint64_t>(R.integer(k, c_seed, 0, std::numeric_limits<long long>::max()));
    x.status = R.text(k, c_status);
    if (R.has_column("protocol")) x.protocol = R.text(k, R.column("protocol"));
    if (R.has_column("cells")) x.cells = R.text(k, R.column("cells"));
    if (R.has_column("jamming_model")) x.jamming_model = R.text(k, R.column("jamming_model"));
    for (const auto& c : kRunColumns)
      if (const char* name = run_column(R, c)) x.*c.field = R.number(k, R.column(name));
    // Every run has a count, 0 included: an empty field would switch the check of its rows off.
    if (R.has_column("target_rows"))
      x.target_rows =
          static_cast<double>(R.integer(k, R.column("target_rows"), 0, std::numeric_limits<long long>::max()));
    x.depleted = std::isfinite(x.phi_2);
    if (!index.emplace(x.dir.string(), e.rows.size()).second)
      throw InputError(R.source + ":" + std::to_string(k + 2) + ": run " + x.dir.string() + " listed twice");
    // analyse writes one run per seed of a group: a seed listed twice would count one sample twice
    if (!samples.emplace(x.L, x.P0_label, x.seed).second)
      throw InputError(R.source + ":" + std::to_string(k + 2) + ": run " + x.dir.string() + " repeats seed " +
                       std::to_string(x.seed) + " of " + group_text(x.L, x.P0_label) + " (one seed is one sample)");
    if (x.status != "finished") e.failed.push_back(x.dir.string() + " (" + x.status + ")");
    e.rows.push_back(std::move(x));
  }
  if (e.rows.empty()) throw InputError(R.source + ": no runs");
  if (!R.has_column("target_rows"))
    e.unchecked.push_back(R.source +
                          " has no target_rows column (tables from before it): each run's rows of "
                          "targets.csv cannot be checked against the targets it landed");
  check_protocol_columns(R, e);
  if (e.unavailable.count("P_J"))
    e.unavailable["P_J"] +=
        "; ΔZ_0(P) + 2(u_J − u) is taken from targets.csv (dZ_pred) as the earlier analysis computed it";
  // The state a run jammed into: as the earlier analysis numbered it, else from its key (an earlier
  // format has no step_J: runs of one seed that jam with the same N_J at bit-identical φ_J are one state).
  if (R.has_column("jamming_state")) {
    const std::size_t c = R.column("jamming_state");
    for (std::size_t k = 0; k < R.size(); ++k)
      e.rows[k].state = static_cast<std::size_t>(R.integer(k, c, 0, std::numeric_limits<long long>::max()));
    return;
  }
  std::vector<JammingKey> keys;
  for (const auto& r : e.rows) keys.push_back({r.L, r.seed, std::isfinite(r.step_J) ? r.step_J : 0.0, r.N_J, r.phi_J});
  const auto states = jamming_state_ids(keys);
  for (std::size_t k = 0; k < e.rows.size(); ++k) e.rows[k].state = states[k];
}

RunRow& run_of(const CsvTable& t, std::size_t row, std::vector<RunRow>& rows,
               const std::map<std::string, std::size_t>& index) {
  const auto it = index.find(t.text(row, t.column("run")));
  if (it == index.end())
    throw InputError(t.source + ":" + std::to_string(row + 2) + ": run " + t.text(row, t.column("run")) +
                     " is not in runs.csv");
  return rows[it->second];
}

// N_nr of a packing from its Z_iso = 6 − 2u − 2/N_nr (paper Eq. 4), for tables that do not store it.
double nonrattlers_from_Z_iso(double u_lobes, double Z_iso) { return std::round(2.0 / (6.0 - 2.0 * u_lobes - Z_iso)); }

void read_targets(const CsvTable& T, Ensemble& e, const std::map<std::string, std::size_t>& index) {
  const std::size_t c_dphi = T.column("dphi"), c_below = T.column("below_phi2");
  for (std::size_t k = 0; k < T.size(); ++k) {
    TargetRow y;
    y.dphi = T.number(k, c_dphi);
    for (const auto& c : kTargetColumns) y.*c.field = number_or_nan(T, c.name, k);
    if (!T.has_column("N_nr")) y.N_nr = nonrattlers_from_Z_iso(y.u_lobes, y.Z_iso);
    y.below_phi2 = T.text(k, c_below) == "true";
    run_of(T, k, e.rows, index).targets.push_back(y);
  }
  for (const auto& c : kTargetColumns)
    if (!T.has_column(c.name) && std::string(c.name) != "N_nr")
      e.unavailable[std::string("targets.csv:") + c.name] = T.source + " has no column " + c.name;
}

// Each run's rows of targets.csv against the count runs.csv holds (target_rows): rows missing or
// added are refused. Tables from before the column cannot be checked (named under `unavailable`).
void check_target_rows(const Ensemble& e, const std::string& source) {
  for (const RunRow& r : e.rows) {
    if (!std::isfinite(r.target_rows) || static_cast<double>(r.targets.size()) == r.target_rows) continue;
    throw InputError(source + ": run " + r.dir.string() + " has " + std::to_string(r.targets.size()) +
                     " target rows where runs.csv says it landed " + io::format_double(r.target_rows) +
                     " (target_rows): rows are missing or added");
  }
}

// The target sets of finished runs of one group: a finished run lands every target of its protocol,
// so two that differ are not samples of one protocol (rows of targets.csv lost or added in transit;
// a run stopped early lands a subset, which is no evidence either way).
void check_target_sets(const Ensemble& e, const std::string& source) {
  std::map<std::tuple<double, std::string, std::string>, const RunRow*> first;  // (L, P0, protocol) → run
  for (const RunRow& r : e.rows) {
    if (r.status != "finished") continue;
    const auto [at, fresh] = first.try_emplace({r.L, r.P0_label, r.protocol}, &r);
    if (fresh) continue;
    const auto dphis = [](const RunRow& x) {
      std::vector<double> d;
      for (const auto& t : x.targets) d.push_back(t.dphi);
      std::sort(d.begin(), d.end());
      return d;
    };
    const RunRow& f = *at->second;
    if (dphis(r) == dphis(f)) continue;
    throw InputError(source + ": finished runs " + f.dir.string() + " and " + r.dir.string() + " of " +
                     group_text(r.L, r.P0_label) + " have different target rows (" + std::to_string(f.targets.size()) +
                     " and " + std::to_string(r.targets.size()) +
                     "): a finished run lands every target of its protocol, so rows are missing or added");
  }
}

// Two seeds of one box with one jamming state to the last bit (φ_J, N_J, its step) are one sample
// listed twice, under two labels: a seed's random stream makes its own history.
void check_distinct_samples(const Ensemble& e, const std::string& source) {
  std::map<std::tuple<double, double, double, double>, const RunRow*> state;  // (L, φ_J, N_J, step_J) → run
  for (const RunRow& r : e.rows) {
    // (tables from before step_J, and hand-made ones, have no state to compare)
    if (!std::isfinite(r.phi_J) || !std::isfinite(r.N_J) || !std::isfinite(r.step_J)) continue;
    const auto [at, fresh] = state.try_emplace({r.L, r.phi_J, r.N_J, r.step_J}, &r);
    if (fresh || at->second->seed == r.seed) continue;
    throw InputError(source + ": run " + r.dir.string() + " (seed " + std::to_string(r.seed) +
                     ") has the jamming state of run " + at->second->dir.string() + " (seed " +
                     std::to_string(at->second->seed) + ") to the last bit (phi_J " + io::format_double(r.phi_J) +
                     ", N_J " + io::format_double(r.N_J) + "): one sample under two seeds");
  }
}

// The tables against the digests their analysis recorded (analysis.json tables_written): a table
// edited since is analysed as given, and the report says so.
void check_table_digests(const fs::path& dir, Ensemble& e) {
  const fs::path aj = dir / "analysis.json";
  const io::Json j = fs::exists(aj) ? io::read_json(aj) : io::Json::object();
  const auto* written =
      j.contains("tables_written") && j["tables_written"].is_object() ? &j["tables_written"] : nullptr;
  if (!written) {
    e.unchecked.push_back((fs::exists(aj) ? aj.string() + " records no digests of its tables (tables_written; an "
                                                          "analysis from before them)"
                                          : dir.string() + " has no analysis.json") +
                          ": whether a table was edited after its analysis cannot be checked");
    return;
  }
  for (const auto& [name, digest] : written->items()) {
    const fs::path table = dir / name;
    if (!fs::exists(table)) continue;  // a table left out is named elsewhere
    if (digest.is_string() && digest.get<std::string>() == io::hex64(io::fnv1a64(io::read_text_file(table)))) continue;
    e.unchecked.push_back(table.string() + " is not the table its analysis wrote (its digest differs from " +
                          aj.string() +
                          "): edited since, its values are taken as given and an empty cell as "
                          "no value");
  }
}

// Integer contact counts of a spectrum row of a table that does not store them: N_nr from the
// target's Z_iso or the run's N_nr,J, N_c = Z N_nr. 0 where neither is known (the φ_2 packing).
void contact_counts(DosRow& q, const RunRow& run) {
  double N_nr = 0;
  if (q.packing == "jammed") N_nr = run.N_nr_J;
  for (const auto& t : run.targets)
    if (q.target && t.dphi == q.dphi) N_nr = t.N_nr;
  if (!(N_nr > 0)) return;
  q.N_nr = std::lround(N_nr);
  q.N_c = std::lround(q.Z * N_nr);
}

void read_spectra(const CsvTable& D, Ensemble& e, const std::map<std::string, std::size_t>& index) {
  const bool counts = D.has_column("N_c") && D.has_column("N_nr");
  if (!counts)
    e.unavailable["dos.csv:N_c,N_nr"] =
        D.source +
        " has no integer contact counts: taken from targets.csv (Z_iso) for "
        "the Δφ-target packings and from runs.csv (N_nr_J) for the jammed ones; 0 for others";
  const std::size_t c_pack = D.column("packing");
  for (std::size_t k = 0; k < D.size(); ++k) {
    RunRow& run = run_of(D, k, e.rows, index);
    DosRow q;
    q.run = run.dir.string();
    q.packing = D.text(k, c_pack);
    q.L = run.L;
    q.P0_label = run.P0_label;
    q.state = run.state;
    q.seed = run.seed;
    q.target = q.packing.rfind("target_", 0) == 0;
    q.dphi = number_or_nan(D, "dphi", k);
    q.omega_star = D.number(k, D.column("omega_star"));
    q.dZ = D.number(k, D.column("dZ"));
    q.Z = D.number(k, D.column("Z_minus_6")) + 6.0;
    q.N_zero = D.number(k, D.column("N_zero"));
    q.N_u = D.number(k, D.column("N_u"));
    q.N_u_buds = number_or_nan(D, "N_u_buds", k);
    if (counts) {
      q.N_c = static_cast<long>(D.integer(k, D.column("N_c"), 0, std::numeric_limits<long>::max()));
      q.N_nr = static_cast<long>(D.integer(k, D.column("N_nr"), 0, std::numeric_limits<long>::max()));
    } else {
      contact_counts(q, run);
    }
    // the contact-free lobes at jamming of a table without u_J_lobes: the jammed packing's N_u / N_nr,J
    if (q.packing == "jammed" && !std::isfinite(run.u_J_lobes)) run.u_J_lobes = q.N_u / run.N_nr_J;
    e.dos_rows.push_back(q);
  }
  e.dos_found = e.dos_rows.size();
  if (e.unavailable.erase("u_J_lobes"))
    e.unavailable["runs.csv:u_J_lobes"] = "taken from dos.csv: N_u of the jammed packing / N_nr_J";
}

// The pooled Kaplan–Meier curve of each group from survival.csv: per group a first row at a = 0 with
// the number of records at risk, then one row per step (a, Ŝ, at risk). The events at a step follow
// from Ŝ_k = Ŝ_{k−1} (1 − d_k / n_k), the censored from the drop of the risk set; the curve is made
// again from those records, so Ŝ and the Greenwood variance come back as the runs gave them; the
// variance clustered by run, which needs each record's run, is read from the table's se.
//
// Each group's `runs` (the runs it pools) and records are held to runs.csv: the runs of the group
// there that recorded bud events (bud_records, the rule of the run-directory reader) and the sum of
// their records; a group of such runs without a curve is refused too. Tables from before `runs`
// (absent, or empty in every row) or before bud_records cannot be checked: a notice says so.
void read_survival(const CsvTable& S, Ensemble& e, bool runs_have_bud_records) {
  struct Group {
    GroupKey key;
    std::size_t runs = 0;  // that recorded bud events
    double records = 0;
    bool has_curve = false;
  };
  std::map<std::pair<double, std::string>, Group> groups;
  for (const auto& r : e.rows) {
    auto& g = groups.try_emplace(std::pair{r.L, r.P0_label}, Group{GroupKey{r.L, r.P0}}).first->second;
    if (std::isfinite(r.bud_records)) ++g.runs, g.records += r.bud_records;
  }
  const std::size_t c_L = S.column("L"), c_P0 = S.column("P0"), c_a = S.column("a"), c_S = S.column("S"),
                    c_risk = S.column("at_risk");
  // The runs column, where the table has one filled in: filled in every row, or refused.
  std::optional<std::size_t> c_runs;
  if (S.has_column("runs")) {
    const std::size_t c = S.column("runs");
    std::optional<std::size_t> filled, empty;
    for (std::size_t k = 0; k < S.size(); ++k) {
      auto& first = S.text(k, c).empty() ? empty : filled;
      if (!first) first = k;
    }
    if (filled && empty)
      throw InputError(S.source + ":" + std::to_string(std::max(*filled, *empty) + 2) + ": runs " +
                       (*empty > *filled ? "empty, but filled in at line " : "filled in, but empty at line ") +
                       std::to_string(std::min(*filled, *empty) + 2) + ": rows of tables of different formats");
    if (filled) c_runs = c;
  }
  if (!c_runs)
    e.unchecked.push_back(S.source +
                          " has no runs column (tables from before it): whether its pooled curves are of the runs "
                          "in runs.csv cannot be checked");
  else if (!runs_have_bud_records)
    e.unchecked.push_back(S.source + "'s pooled curves cannot be checked against runs.csv: it has no bud_records " +
                          "column (tables from before it)");
  const bool check = c_runs && runs_have_bud_records;
  // se is clustered by run in tables that also give Greenwood's (se_greenwood); before, it was
  // Greenwood's alone, which would pass for a band it is not.
  const bool clustered = S.has_column("se_greenwood");
  if (!clustered)
    e.unavailable["survival.csv:se"] = S.source + " has no se_greenwood column (tables from before it): its se is " +
                                       "Greenwood's, which takes the buds of the pooled runs as independent; no band";
  const std::size_t c_se = S.column("se");
  std::size_t k = 0;
  while (k < S.size()) {
    const std::size_t first_row = k;
    const auto g = groups.find({S.number(k, c_L), P0_label_from_csv(S.text(k, c_P0))});
    if (g == groups.end())
      throw InputError(S.source + ":" + std::to_string(k + 2) + ": group L = " + S.text(k, c_L) +
                       ", P0 = " + S.text(k, c_P0) + " has no run in runs.csv");
    g->second.has_curve = true;
    const auto records = static_cast<std::size_t>(S.integer(k, c_risk, 0, std::numeric_limits<long long>::max()));
    const std::string group = group_text(g->first.first, g->first.second);
    if (c_runs) {
      const auto runs = static_cast<std::size_t>(S.integer(k, *c_runs, 0, std::numeric_limits<long long>::max()));
      e.survival_runs[g->second.key] = runs;
      if (check && runs != g->second.runs)
        throw InputError(S.source + ":" + std::to_string(k + 2) + ": group " + group + " pools " +
                         std::to_string(runs) + " runs, but runs.csv has " + std::to_string(g->second.runs) +
                         " of that group with bud events: the curve is not of these runs");
      if (check && static_cast<double>(records) != g->second.records)
        throw InputError(S.source + ":" + std::to_string(k + 2) + ": group " + group + " pools " +
                         std::to_string(records) + " bud records, but its runs in runs.csv recorded " +
                         io::format_double(g->second.records) + ": the curve is not of these runs");
    }
    std::vector<SurvivalRecord> kept;
    std::vector<double> se;  // per step, as the runs' analysis wrote it
    double S_prev = 1, a_prev = 0;
    std::size_t at_risk_prev = records, events_prev = 0;
    const auto censored_before = [&](std::size_t at_risk) { return at_risk_prev - events_prev - at_risk; };
    for (++k;
         k < S.size() && S.number(k, c_L) == g->first.first && P0_label_from_csv(S.text(k, c_P0)) == g->first.second;
         ++k) {
      if (c_runs && S.text(k, *c_runs) != S.text(first_row, *c_runs))
        throw InputError(S.source + ":" + std::to_string(k + 2) + ": group " + group + ": runs " + S.text(k, *c_runs) +
                         ", but " + S.text(first_row, *c_runs) + " in its first row (line " +
                         std::to_string(first_row + 2) + ")");
      const double a = S.number(k, c_a), S_k = S.number(k, c_S);
      const auto at_risk = static_cast<std::size_t>(S.integer(k, c_risk, 1, static_cast<long long>(at_risk_prev)));
      if (!(S_prev > 0 && S_k >= 0 && S_k <= S_prev && a >= a_prev) || at_risk + events_prev > at_risk_prev)
        throw InputError(S.source + ":" + std::to_string(k + 2) +
                         ": not a step of a Kaplan-Meier curve after the row before (a, S or at_risk)");
      if (k > first_row + 1) kept.insert(kept.end(), censored_before(at_risk), SurvivalRecord{a_prev, false});
      events_prev = static_cast<std::size_t>(std::lround(static_cast<double>(at_risk) * (1.0 - S_k / S_prev)));
      kept.insert(kept.end(), events_prev, SurvivalRecord{a, true});
      se.push_back(clustered && !S.text(k, c_se).empty() ? S.number(k, c_se) : kNaN);
      S_prev = S_k;
      a_prev = a;
      at_risk_prev = at_risk;
    }
    if (k > first_row + 1) kept.insert(kept.end(), at_risk_prev - events_prev, SurvivalRecord{a_prev, false});
    if (kept.size() != records)
      throw InputError(S.source + ":" + std::to_string(first_row + 2) + ": group L = " + S.text(first_row, c_L) +
                       ", P0 = " + S.text(first_row, c_P0) + ": its steps account for " + std::to_string(kept.size()) +
                       " records, its first row for " + std::to_string(records));
    // The records' runs are not in the table: the variance clustered by run is the one it holds.
    const KaplanMeierCurve rebuilt = kaplan_meier(kept);
    std::vector<KaplanMeierStep> steps = rebuilt.steps();
    if (steps.size() != se.size())
      throw InputError(S.source + ":" + std::to_string(first_row + 2) + ": group " + group + ": " +
                       std::to_string(se.size()) + " rows after the first, but they make " +
                       std::to_string(steps.size()) + " steps (rows of equal a)");
    for (std::size_t j = 0; j < steps.size(); ++j) steps[j].clustered_var = se[j] * se[j];
    e.survival[g->second.key] = KaplanMeierCurve(std::move(steps), rebuilt.records(), rebuilt.events(),
                                                 c_runs ? e.survival_runs[g->second.key] : 0);
  }
  if (check)
    for (const auto& [label, g] : groups)
      if (!g.has_curve && g.runs > 0)
        throw InputError(S.source + ": no curve of group " + group_text(label.first, label.second) + ", whose " +
                         std::to_string(g.runs) + " runs in runs.csv recorded bud events");
}

// Format 1 of the tables (analysis.json "version": 1) holds χ̄ and λ̄_c as trapezoids in φ, which weight
// the long steps, and the φ_2 predictions built on that χ̄: not today's plain means over the accepted
// states (docs/analysis.md, "Definitions"). They are left out rather than reported under a definition
// they do not have.
void drop_format1_averages(Ensemble& e) {
  for (auto& r : e.rows) r.chi_bar = r.lambda_bar = r.lambda_bar_lobes = r.pred_area = r.pred_d2 = kNaN;
  for (const char* c : {"chi_bar", "lambda_bar", "lambda_bar_lobes", "dphi_2_pred_area", "dphi_2_pred_diameter_sq"})
    e.unavailable[c] =
        std::string("runs.csv of format 1 holds it with χ̄ a trapezoid in φ (it needs steps.csv of each run ") +
        "for the plain mean over the accepted states)";
}

// runs.csv lists the runs that jammed: the runs left out (never jammed, later copies of one run) are
// named by the analysis.json the tables came with, and carried over so that a report from the tables
// counts the runs the analysis was given.
void read_left_out_runs(const fs::path& file, Ensemble& e) {
  const auto text = [](const io::Json& x) { return x.is_string(); };
  const auto copy_group = [&](const io::Json& x) {
    return x.is_array() && x.size() >= 2 && std::all_of(x.begin(), x.end(), text);
  };
  const auto list_of = [&](const io::Json& inputs, const char* key, auto is_item,
                           const char* items) -> std::optional<io::Json> {
    const auto it = inputs.find(key);
    if (it == inputs.end()) return std::nullopt;
    if (!it->is_array() || !std::all_of(it->begin(), it->end(), is_item))
      throw InputError(file.string() + ": inputs." + key + " is not a list of " + items);
    return *it;
  };
  std::optional<io::Json> never, copies;
  if (fs::exists(file)) {
    const io::Json j = io::read_json(file);
    const auto inputs = j.find("inputs");
    if (inputs != j.end() && !inputs->is_object()) throw InputError(file.string() + ": inputs is not an object");
    if (inputs != j.end()) {
      never = list_of(*inputs, "never_jammed", text, "run directories");
      copies = list_of(*inputs, "duplicates", copy_group, "groups of two or more run directories");
    }
  }
  if (never) {
    for (const io::Json& x : *never) e.never_jammed.push_back(x.get<std::string>());
    e.runs += e.never_jammed.size();
  } else {
    e.unavailable["never_jammed"] =
        file.string() + " does not name the runs that never jammed (runs.csv lists only those that did)";
  }
  if (copies) {
    for (const io::Json& group : *copies) {
      e.duplicates.push_back(group.get<std::vector<std::string>>());
      e.runs += e.duplicates.back().size() - 1;
    }
  } else {
    e.unavailable["duplicates"] =
        file.string() + " does not name the copies of a run it left out (runs.csv lists the copy it used)";
  }
}

}  // namespace

Ensemble read_ensemble_tables(const fs::path& dir) {
  Ensemble e;
  std::map<std::string, std::size_t> index;  // run → row
  read_runs(read_csv(dir / "runs.csv"), e, index);
  check_distinct_samples(e, (dir / "runs.csv").string());
  if (fs::exists(dir / "analysis.json") && io::read_json(dir / "analysis.json").value("version", 0) == 1)
    drop_format1_averages(e);
  e.runs = e.rows.size();
  read_left_out_runs(dir / "analysis.json", e);
  read_targets(read_csv(dir / "targets.csv"), e, index);
  check_target_rows(e, (dir / "targets.csv").string());
  check_target_sets(e, (dir / "targets.csv").string());
  check_table_digests(dir, e);
  if (fs::exists(dir / "dos.csv"))
    read_spectra(read_csv(dir / "dos.csv"), e, index);
  else
    e.unavailable["dos.csv"] = (dir / "dos.csv").string() + " absent: no spectra";
  for (const auto& r : e.rows) e.survival.emplace(GroupKey{r.L, r.P0}, KaplanMeierCurve{});
  if (fs::exists(dir / "survival.csv"))
    read_survival(read_csv(dir / "survival.csv"), e, !e.unavailable.count("bud_records"));
  else
    e.unavailable["survival.csv"] =
        (dir / "survival.csv").string() + " absent: no pooled survival (needs bud_events.csv)";
  const std::string steps = "needs steps.csv and divisions.csv of each run";
  const std::string cells = "needs the growth factor of each cell (the packing at Δφ = 3·10⁻³)";
  e.unavailable["remaining.csv"] = steps;
  e.unavailable["division_curve.csv"] = steps;
  e.unavailable["growth_rates.csv"] = cells;
  e.unavailable["g_peak_weight_at_1, g_compressed_*, h_gamma_pooled"] = cells;
  e.unavailable["moduli_saddles"] = "the tables do not say which packings were saddles";
  e.unavailable["moduli_contact_bounded"] = "the tables do not say which packings were contact-bounded minima";
  for (const auto& r : e.rows) {
    e.moduli.found += std::isfinite(r.G_2);
    for (const auto& t : r.targets) e.moduli.found += std::isfinite(t.G);
  }
  return e;
}

}  // namespace budjam::tools
