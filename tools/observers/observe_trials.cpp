// Observer "trials" (scene [observe] trials, off by default): every relaxed growth attempt, one row
// each in trials.csv, whatever its verdict: the search onto φ_J and the landing on the targets,
// which steps.csv (accepted states only) does not show (columns in docs/columns.md).
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "io/run_directory.hpp"

namespace {

using namespace budjam;
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
};

const tools::ObserverRegistration registration{"trials",
                                               "observe.trials",
                                               {std::string(io::run_files::trials)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.trials) return nullptr;
                                                 return std::make_unique<TrialLog>(c.run_dir.root(), c.resuming);
                                               }};

}  // namespace
