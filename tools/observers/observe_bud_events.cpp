// Observer "bud_events" (scene [observe] bud_events, on by default): the survival events of the
// buds tagged at jamming, one row each in bud_events.csv (columns in docs/growth.md).
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "budjam/errors.hpp"
#include "io/run_directory.hpp"

#include <cstdlib>
#include <istream>
#include <map>
#include <ostream>

namespace budjam::tools::bud_events_observer {
namespace {

namespace fs = std::filesystem;

std::string joined(const std::vector<std::string>& words) {
  std::string s;
  for (const auto& w : words) s += (s.empty() ? "" : " ") + w;
  return s.empty() ? "none" : s;
}

const std::vector<std::string> kBudColumns{"episode", "cell_id", "event", "step", "phi", "a"};

class BudEventLog : public tools::CsvLogObserver {
 public:
  BudEventLog(const io::Directory& dir, bool resuming)
      : CsvLogObserver(dir, {{std::string(io::run_files::bud_events), kBudColumns}}, resuming) {}
  std::string name() const override { return "bud_events"; }
  void on_jammed(const Jammed&) override { episode_start_ = rows_; }  // its buds are tagged next
  void on_bud_event(const BudEventHappened& e) override {
    const BudEvent& b = e.event;
    log().row({b.episode, b.cell_id, to_string(b.kind), b.step, b.phi, b.a});
    ++rows_;
  }
  // The rows of the current jamming episode are the bud tracker's events, which the checkpoint
  // records on its own (its tags): as many, and bud by bud the same kinds in the same order.
  void check_resumed(const GrowthState& s) const override {
    const std::size_t rows = resumed_cut(0).rows;
    if (rows < episode_start_ || rows - episode_start_ != s.buds.events())
      refuse_resumed(
          0, std::to_string(rows) + " rows up to the recorded length, of which " +
                 (rows < episode_start_ ? std::string("none") : std::to_string(rows - episode_start_)) + " after row " +
                 std::to_string(episode_start_) + " where the current jamming episode began, " +
                 "but the checkpoint's tagged buds account for " + std::to_string(s.buds.events()) + " events");
    std::map<std::int64_t, std::vector<std::string>> logged;
    const std::vector<std::string> all = resumed_rows(0);
    for (std::size_t k = episode_start_; k < all.size(); ++k) {
      const std::string& row = all[k];  // episode,cell_id,event,...
      const std::size_t a = row.find(',') + 1, b = row.find(',', a), c = row.find(',', b + 1);
      std::string event = row.substr(b + 1, c - b - 1);
      if (event.starts_with("censored")) event = "censored";
      logged[std::strtoll(row.c_str() + a, nullptr, 10)].push_back(event);
    }
    for (const std::int64_t id : s.buds.tagged_ids())
      if (logged[id] != s.buds.events_of(id))
        refuse_resumed(0, "the rows of bud " + std::to_string(id) + " since the current jamming episode began (" +
                              joined(logged[id]) + ") are not the events of its tag in the checkpoint (" +
                              joined(s.buds.events_of(id)) + ")");
  }
  void on_resumed() override {
    CsvLogObserver::on_resumed();
    rows_ = resumed_cut(0).rows;
  }

 private:
  void save_more(std::ostream& os) override { os << episode_start_ << '\n'; }
  void load_more(std::istream& is) override {
    if (!(is >> episode_start_)) throw InputError("bad bud_events state (the row where the jamming episode began)");
  }
  std::size_t rows_ = 0;           // rows written
  std::size_t episode_start_ = 0;  // rows written before the current jamming episode
};

const tools::ObserverRegistration registration{"bud_events",
                                               "observe.bud_events",
                                               {std::string(io::run_files::bud_events)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.bud_events) return nullptr;
                                                 return std::make_unique<BudEventLog>(c.run_dir.root(), c.resuming);
                                               }};

}  // namespace
}  // namespace budjam::tools::bud_events_observer
