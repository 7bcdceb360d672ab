// Observer "trials" (scene [observe] trials, off by default): every relaxed growth attempt, one row
// each in trials.csv, whatever its verdict: the search onto φ_J and the landing on the targets,
// which steps.csv (accepted states only) does not show (columns in docs/columns.md).
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "io/run_directory.hpp"

#include <cstdlib>

namespace budjam::tools::trials_observer {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kTrialColumns{"attempt", "dt",      "N",          "phi",        "E_per_cell",
                                             "start",   "verdict", "iterations", "evaluations"};

class TrialLog : public tools::CsvLogObserver {
 public:
  TrialLog(const io::Directory& dir, bool resuming)
      : CsvLogObserver(dir, {{std::string(io::run_files::trials), kTrialColumns}}, resuming) {}
  std::string name() const override { return "trials"; }
  void on_trial(const TrialRelaxed& t) override {
    log().row({t.attempt, tools::beyond_double_range(t.dt, t.log_dt), t.N, t.phi, t.E_per_cell, to_string(t.start),
               to_string(t.verdict), t.fire_iterations, t.force_evaluations});
  }
  // One row per relaxation of a growth attempt, numbered from 1 (a deferred trial resumed or a
  // bracket settled is a further row of its attempt): the last row is numbered with the
  // checkpoint's attempts, and the rows' evaluations add up to the checkpoint's evaluations of the
  // search and above jamming (each row has at least one, so no row can go missing unseen).
  void check_resumed(const GrowthState& s) const override {
    const std::vector<std::string> rows = resumed_rows(0);
    unsigned long long evaluations = 0;  // wraps on absurd input, which then disagrees
    std::string last = "none";
    for (const std::string& row : rows) {
      last = row.substr(0, row.find(','));
      evaluations += std::strtoull(row.c_str() + row.rfind(',') + 1, nullptr, 10);
    }
    const auto recorded =
        static_cast<unsigned long long>(s.result.force_evaluations_search + s.result.force_evaluations_above_jamming);
    if (last != (s.attempts ? std::to_string(s.attempts) : "none") || evaluations != recorded)
      refuse_resumed(0, std::to_string(rows.size()) + " rows up to the recorded length, the last of attempt " + last +
                            " with " + std::to_string(evaluations) +
                            " force evaluations in all, but the checkpoint records " + std::to_string(s.attempts) +
                            " growth attempts with " + std::to_string(recorded));
  }
};

const tools::ObserverRegistration registration{"trials",
                                               "observe.trials",
                                               {std::string(io::run_files::trials)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.trials) return nullptr;
                                                 return std::make_unique<TrialLog>(c.run_dir.root(), c.resuming);
                                               }};

}  // namespace
}  // namespace budjam::tools::trials_observer
