// Observer "bud_events" (scene [observe] bud_events, on by default): the survival events of the
// buds tagged at jamming, one row each in bud_events.csv (columns in docs/growth.md).
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "io/run_directory.hpp"

namespace {

using namespace budjam;
namespace fs = std::filesystem;

const std::vector<std::string> kBudColumns{"episode", "cell_id", "event", "step", "phi", "a"};

class BudEventLog : public tools::CsvLogObserver {
 public:
  BudEventLog(const io::Directory& dir, bool resuming)
      : CsvLogObserver(dir, {{std::string(io::run_files::bud_events), kBudColumns}}, resuming) {}
  std::string name() const override { return "bud_events"; }
  void on_bud_event(const BudEventHappened& e) override {
    const BudEvent& b = e.event;
    log().row({b.episode, b.cell_id, to_string(b.kind), b.step, b.phi, b.a});
  }
};

const tools::ObserverRegistration registration{"bud_events",
                                               "observe.bud_events",
                                               {std::string(io::run_files::bud_events)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.bud_events) return nullptr;
                                                 return std::make_unique<BudEventLog>(c.run_dir.root(), c.resuming);
                                               }};

}  // namespace
