// Observer "rigidity": every change of the rigidity state of the load-bearing network along a
// growth run, one row per event in <run_dir>/rigidity_events.csv, only when the scene asks
// ([observe] rigidity_events = true). docs/rigidity.md.
//
// At every accepted state above jamming the pebble game is brought up to date by the tracker
// (contacts that appeared are inserted; contacts that disappeared are removed and their
// replacements re-tested) and its state is compared with the previous one. The first jammed state
// of an episode is the baseline: it logs the floppy-mode count (before = -1) and, if a rigid
// cluster already spans the box, first_spanning. An unjamming logs `unjammed` and ends the episode;
// the next jamming starts a new baseline.
#include "observers/csv_log_observer.hpp"
#include "observers/observers.hpp"

#include "budjam/rigidity.hpp"
#include "io/atomic_file.hpp"
#include "io/run_directory.hpp"

#include <istream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace budjam::tools::rigidity_observer {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kColumns{"step",           "phi",           "episode",
                                        "event",          "cell",          "before",
                                        "after",          "floppy_modes",  "floppy_modes_periodic",
                                        "redundant_bars", "largest_cells", "N_nr"};

class RigidityLog : public tools::CsvLogObserver {
 public:
  RigidityLog(const io::Directory& dir, bool resuming)
      : CsvLogObserver(dir, {{std::string(io::run_files::rigidity), kColumns}}, resuming) {}
  std::string name() const override { return "rigidity"; }
  Needs needs() const override { return Needs{.contacts = true, .network = true}; }

  void on_step_accepted(const StepAccepted& e) override {
    const StateView& s = e.state;
    if (s.phase != Phase::jammed || !s.jamming || !s.contacts || !s.network) return;
    if (!tracker_ || episode_ != s.jamming->episode) {
      tracker_.emplace(RigidityNetwork::load_bearing);
      episode_ = s.jamming->episode;
    }
    place_lobes(*s.packing, lobes_);
    const auto& events = tracker_->update(*s.packing, lobes_, *s.contacts, *s.network);
    const RigidityState& r = tracker_->state();
    for (const RigidityEvent& ev : events)
      log().row({s.step, s.phi, episode_, to_string(ev.kind), ev.cell, ev.before, ev.after, r.floppy_plane,
                 r.floppy_periodic, r.redundant_bars, r.largest_cells(), r.cells});
  }

  void on_unjammed(const Unjammed& e) override {
    if (tracker_) {
      const RigidityState& r = tracker_->state();
      log().row({e.state.step, e.state.phi, e.record.episode, "unjammed", -1, r.floppy_plane, -1, r.floppy_plane,
                 r.floppy_periodic, r.redundant_bars, r.largest_cells(), r.cells});
    }
    tracker_.reset();
  }

  // After the log length: the tracker's memory (the pebble game is rebuilt from it).
  void save_more(std::ostream& os) override {
    if (!tracker_) {
      os << "tracker none\n";
      return;
    }
    const RigidityMemory& m = tracker_->memory();
    os << "tracker " << episode_ << ' ' << m.has_state << ' ' << m.spanned << ' ' << m.floppy_plane << ' '
       << m.span_code << ' ' << m.cells.size() << '\n';
    for (const auto& [id, bits] : m.cells) os << id << ' ' << int{bits} << '\n';
  }

  void load_more(std::istream& is) override {
    const auto bad = [] { return InputError("checkpoint: bad rigidity state"); };
    std::string word, kind;
    if (!(is >> word) || word != "tracker") throw bad();
    tracker_.reset();
    if (!(is >> kind)) throw bad();
    if (kind == "none") return;
    RigidityMemory m;
    std::size_t n = 0;
    try {
      episode_ = std::stoi(kind);
    } catch (const std::exception&) {
      throw bad();
    }
    if (!(is >> m.has_state >> m.spanned >> m.floppy_plane >> m.span_code >> n)) throw bad();
    m.cells.resize(n);
    for (auto& [id, bits] : m.cells) {
      int b = 0;
      if (!(is >> id >> b) || b < 0 || b > 3) throw bad();
      bits = static_cast<std::uint8_t>(b);
    }
    tracker_.emplace(RigidityNetwork::load_bearing);
    try {
      tracker_->restore(m);
    } catch (const std::invalid_argument&) {
      throw bad();
    }
  }

 private:
  std::optional<RigidityTracker> tracker_;
  int episode_ = -1;
  Lobes lobes_;
};

const tools::ObserverRegistration registration{"rigidity",
                                               "observe.rigidity_events",
                                               {std::string(io::run_files::rigidity)},
                                               [](const tools::ObserverContext& c) -> std::unique_ptr<Observer> {
                                                 if (!c.scene.rigidity_events)
                                                   return nullptr;  // not asked: never built, costs nothing
                                                 return std::make_unique<RigidityLog>(c.run_dir.root(), c.resuming);
                                               }};

}  // namespace
}  // namespace budjam::tools::rigidity_observer
