// `budjam survival RUNDIR... [-o|--out BASE] [--json] [--quiet] [--epsilon E]`
// Kaplan–Meier survival S(a) of the buds unconstrained at jamming, pooled over the given finished
// runs (each run's last jamming episode): completion is the event, division and the end of the run
// censor. The output convention (io/result_files.hpp): BASE.csv is the curve (a in diameter squared
// and as true area, Ŝ, Greenwood SE and a 95 % band), BASE.json the summary: a_ε with
// u_J S(a_ε) = ε (ε = 1/⟨N_nr,J⟩ unless given) and ∫_0^{a_ε} S da, in both units (paper Eq. 14).
#include "analysis/jamming_states.hpp"
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include "budjam/depletion.hpp"
#include "budjam/errors.hpp"
#include "budjam/statistics.hpp"
#include "budjam/survival.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace budjam;

struct Options {
  std::vector<std::string> runs;
  io::OutputRequest output;
  std::optional<double> epsilon;
};

std::string summary_line(std::size_t runs, std::size_t copies, const KaplanMeierCurve& km,
                         std::optional<double> a_eps) {
  std::string line = "survival: " + std::to_string(runs) + " runs";
  if (copies > 0) line += " (" + std::to_string(copies) + " duplicate copies left out)";
  line += ", " + std::to_string(km.records()) + " buds, " + std::to_string(km.events()) + " completed; a_eps = ";
  line += a_eps ? io::format_double(*a_eps) + ", integral of S = " + io::format_double(km.integral(*a_eps))
                : std::string("not reached");
  return line + " (diameter squared)";
}

void run(const Options& o) {
  // A run given twice, or copied into another directory, is one sample, as in `budjam analyse`:
  // its first copy is used.
  const std::vector<std::filesystem::path> dirs(o.runs.begin(), o.runs.end());
  const tools::DistinctRuns loaded = tools::load_distinct_runs(dirs);
  io::Json duplicates = io::Json::array();
  for (const auto& group : loaded.copy_groups) duplicates.push_back(group);
  std::vector<SurvivalRecord> records;
  std::vector<double> uJ, nrJ;
  for (std::size_t k = 0; k < o.runs.size(); ++k) {
    if (loaded.later_copy[k]) continue;
    const std::string& d = o.runs[k];
    const tools::RunData& r = loaded.runs[k];
    if (!r.jammed()) throw InputError(d + ": the run never jammed (phi_J is null)");
    if (!r.bud_events) throw InputError(d + ": no bud_events.csv (the scene turned observe.bud_events off)");
    const auto rec = tools::survival_records(*r.bud_events);
    records.insert(records.end(), rec.begin(), rec.end());
    uJ.push_back(r.get("u_J"));
    nrJ.push_back(r.get("N_nr_J"));
  }
  const double u_J = mean(uJ), N_nr = mean(nrJ);
  const double eps = o.epsilon.value_or(1.0 / N_nr);
  if (!(eps >= 0)) throw InputError("--epsilon: must be >= 0");
  const KaplanMeierCurve km = kaplan_meier(records);
  const auto a_eps = u_J > 0 ? a_epsilon(km, u_J, eps) : std::nullopt;

  io::Json j;
  const auto used = static_cast<std::size_t>(std::count(loaded.later_copy.begin(), loaded.later_copy.end(), false));
  j["runs"] = used;
  j["duplicates"] = duplicates;
  j["records"] = km.records();
  j["events"] = km.events();
  j["censored"] = km.records() - km.events();
  j["u_J"] = io::number_or_null(u_J);
  j["N_nr_J"] = io::number_or_null(N_nr);
  j["epsilon"] = eps;
  j["S_level"] = u_J > 0 ? io::Json(eps / u_J) : io::Json(nullptr);
  j["a_eps"] = io::number_or_null(a_eps);
  j["a_eps_area"] = a_eps ? io::Json(kDiameterSquaredToArea * *a_eps) : io::Json(nullptr);
  j["integral_S"] = a_eps ? io::Json(km.integral(*a_eps)) : io::Json(nullptr);
  j["integral_S_area"] = a_eps ? io::Json(kDiameterSquaredToArea * km.integral(*a_eps)) : io::Json(nullptr);
  j["a_last"] = km.last_observation();
  j["note"] = "a = b^2 - b_J^2 (diameter squared); *_area = pi/4 times it (true area)";
  io::CommandResult result{j, {}, summary_line(used, o.runs.size() - used, km, a_eps)};
  result.csv = [&km](std::ostream& os) {
    os << "a,a_area,S,se,lo,hi,at_risk,events,censored\n";
    auto row = [&](double a, double S, double var, std::size_t n, std::size_t d, std::size_t c) {
      const double se = std::sqrt(var);
      os << io::format_double(a) << ',' << io::format_double(kDiameterSquaredToArea * a) << ',' << io::format_double(S)
         << ',' << io::format_double(se) << ',' << io::format_double(std::max(0.0, S - 1.96 * se)) << ','
         << io::format_double(std::min(1.0, S + 1.96 * se)) << ',' << n << ',' << d << ',' << c << '\n';
    };
    row(0.0, 1.0, 0.0, km.records(), 0, 0);
    for (const auto& st : km.steps()) row(st.a, st.S, st.greenwood_var, st.at_risk, st.events, st.censored);
  };
  io::emit(o.output, result, std::cout);
}

const bool registered = budjam::cli::register_command(
    {"survival", "Kaplan-Meier survival S(a) of the buds free at jamming, a_eps and the integral of S",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("RUNDIR", o->runs, "finished run directories (pooled)")->required();
       budjam::cli::add_output_options(sub, o->output, "BASE.json (a_eps, the integral of S) and BASE.csv (the curve)",
                                       true);
       sub.add_option("--epsilon", o->epsilon, "cutoff eps of u_J S(a_eps) = eps (default 1/<N_nr,J>)");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
