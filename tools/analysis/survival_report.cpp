#include "analysis/survival_report.hpp"

#include "analysis/jamming_states.hpp"
#include "analysis/run_protocol.hpp"
#include "budjam/depletion.hpp"
#include "budjam/errors.hpp"
#include "budjam/statistics.hpp"
#include "io/run_data.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

namespace budjam::tools {

using io::Json;

SurvivalReport survival_report(std::span<const std::filesystem::path> runs, std::optional<double> epsilon) {
  const DistinctRuns loaded = load_distinct_runs(runs);
  std::vector<std::filesystem::path> distinct;
  for (std::size_t k = 0; k < runs.size(); ++k)
    if (!loaded.later_copy[k]) distinct.push_back(runs[k]);
  require_one_protocol(distinct, "give them to survival apart");
  if (runs.empty()) throw InputError("survival: no run directories given");
  SurvivalReport report;
  report.duplicates = Json::array();
  for (const auto& group : loaded.copy_groups) report.duplicates.push_back(group);
  std::vector<SurvivalRecord> records;
  std::vector<double> uJ, nrJ;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    if (loaded.later_copy[k]) continue;
    const std::string d = runs[k].string();
    const RunData& r = loaded.runs[k];
    if (report.L.is_null()) {
      report.L = r.summary.value("L", Json());
      report.P0 = r.summary.value("P0", Json());
    }
    if (!r.jammed()) throw InputError(d + ": the run never jammed (phi_J is null)");
    if (!r.bud_events) throw InputError(d + ": no bud_events.csv (the scene turned observe.bud_events off)");
    for (auto rec : survival_records(*r.bud_events)) {
      rec.cluster = k;  // the run is the sample
      records.push_back(rec);
    }
    uJ.push_back(r.get("u_J"));
    nrJ.push_back(r.get("N_nr_J"));
  }
  report.runs = uJ.size();
  report.copies = runs.size() - report.runs;
  report.u_J = mean(uJ);
  report.N_nr_J = mean(nrJ);
  // The one check of ε (the command line and Python both pass it here): u_J S(a) lies in [0, 1]. The
  // default 1/<N_nr,J> is in (0, 1]: N_nr_J >= 1 in every jammed run (load_run checks it).
  if (epsilon && !(std::isfinite(*epsilon) && *epsilon >= 0 && *epsilon <= 1))
    throw InputError("epsilon: must be a finite number in [0, 1] (got " + io::format_double(*epsilon) + ")");
  report.epsilon = epsilon.value_or(1.0 / report.N_nr_J);
  report.km = kaplan_meier(records);
  if (report.u_J > 0) report.a_eps = a_epsilon(report.km, report.u_J, report.epsilon);
  return report;
}

Json survival_json(const SurvivalReport& r) {
  const KaplanMeierCurve& km = r.km;
  Json j;
  j["runs"] = r.runs;
  j["L"] = r.L;
  j["P0"] = r.P0;
  j["duplicates"] = r.duplicates;
  j["records"] = km.records();
  j["events"] = km.events();
  j["censored"] = km.records() - km.events();
  j["u_J"] = io::number_or_null(r.u_J);
  j["N_nr_J"] = io::number_or_null(r.N_nr_J);
  j["epsilon"] = r.epsilon;
  j["S_level"] = r.u_J > 0 ? Json(r.epsilon / r.u_J) : Json(nullptr);
  j["a_eps"] = io::number_or_null(r.a_eps);
  j["a_eps_area"] = r.a_eps ? Json(kDiameterSquaredToArea * *r.a_eps) : Json(nullptr);
  j["integral_S"] = r.a_eps ? Json(km.integral(*r.a_eps)) : Json(nullptr);
  j["integral_S_area"] = r.a_eps ? Json(kDiameterSquaredToArea * km.integral(*r.a_eps)) : Json(nullptr);
  j["a_last"] = km.last_observation();
  j["note"] = "a = b^2 - b_J^2 (diameter squared); *_area = pi/4 times it (true area)";
  return j;
}

std::array<std::string, 4> band_cells(const KaplanMeierStep& step, std::optional<std::size_t> runs) {
  if (!runs || *runs < kMinSamplesForError) return {};
  const auto band = survival_band(step, step.clustered_var);
  const auto independent = survival_band(step, step.greenwood_var);
  return {band ? io::format_double(band->se) : "", band ? io::format_double(band->lo) : "",
          band ? io::format_double(band->hi) : "", independent ? io::format_double(independent->se) : ""};
}

namespace {

std::string summary_line(const SurvivalReport& r) {
  const KaplanMeierCurve& km = r.km;
  std::string line = "survival: " + std::to_string(r.runs) + " runs";
  if (r.copies > 0) line += " (" + std::to_string(r.copies) + " duplicate copies left out)";
  line += ", " + std::to_string(km.records()) + " buds, " + std::to_string(km.events()) + " completed; a_eps = ";
  line += r.a_eps ? io::format_double(*r.a_eps) + ", integral of S = " + io::format_double(km.integral(*r.a_eps))
                  : std::string("not reached");
  return line + " (diameter squared)";
}

}  // namespace

io::CommandResult survival_result(const SurvivalReport& r) {
  io::CommandResult result{survival_json(r), {}, summary_line(r)};
  result.csv = [&km = r.km, runs = r.runs](std::ostream& os) {
    os << "a,a_area,S,se,lo,hi,se_greenwood,at_risk,events,censored\n";
    auto row = [&](const KaplanMeierStep& st) {
      const auto [se, lo, hi, se_greenwood] = band_cells(st, runs);
      os << io::format_double(st.a) << ',' << io::format_double(kDiameterSquaredToArea * st.a) << ','
         << io::format_double(st.S) << ',' << se << ',' << lo << ',' << hi << ',' << se_greenwood << ',' << st.at_risk
         << ',' << st.events << ',' << st.censored << '\n';
    };
    row(KaplanMeierStep{.a = 0, .at_risk = km.records()});
    for (const auto& st : km.steps()) row(st);
  };
  return result;
}

}  // namespace budjam::tools
