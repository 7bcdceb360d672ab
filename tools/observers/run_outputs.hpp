#pragma once
// The files of a growth run directory (docs/growth.md, "Run directory"):
//   steps.csv, divisions.csv, packings/{jammed,phi2,target_<k>}.pack   (RunLog, always)
//   summary.json, timing.json                                         (write_summary, at the end)
// (bud_events.csv and the progress line are observers of their own: observe_bud_events.cpp,
// observe_progress.cpp).
#include "budjam/growth_driver.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "io/json.hpp"
#include "io/run_directory.hpp"
#include "observers/csv_log_observer.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace budjam::tools {

// steps.csv, divisions.csv and the packings at jamming, φ_2 and each target.
class RunLog : public CsvLogObserver {
 public:
  // resuming: the logs are reopened by load_state (cut back to the checkpoint) instead of created.
  RunLog(io::RunDirectory& run_dir, std::uint64_t seed, bool resuming);
  // The entries it writes: steps.csv, divisions.csv, the run packings and their sidecars (which
  // describe the packing and go with it).
  static io::OwnedEntries files();
  std::string name() const override { return "run_log"; }
  void on_step_accepted(const StepAccepted& e) override;
  void on_divided(const Divided& e) override;
  void on_jammed(const Jammed& e) override;
  void on_unjammed(const Unjammed& e) override;
  void on_target_reached(const TargetReached& e) override;
  void on_depleted(const Depleted& e) override;
  // Also removes the temporaries a killed writer left in the run directory.
  void on_resumed() override;

  static const std::vector<std::string>& step_columns();
  static const std::vector<std::string>& division_columns();

  // After load_state: InputError "<checkpoint>:<line>: ..." unless the checkpointed state `s`
  // agrees with what this log and the packings hold: the step and division counters with the
  // rows of steps.csv and divisions.csv up to their recorded lengths, the jamming and unjamming
  // records with the phase changes of those steps, each record (jamming point, targets, φ_2) with
  // its saved packing, the scene's P0 and the seed with every such packing,
  // and each tagged bud's size at jamming with the jammed packing.
  void check_resumed_state(const GrowthState& s, const Scene& scene, const io::CheckpointLines& at,
                           const std::string& checkpoint_file) const;

 private:
  // steps.csv up to its recorded length (after load_state).
  io::StepsLog resumed_steps() const;
  void write_pack(const std::string& stem, const StateView& s, const std::string& kind, std::optional<double> dphi);
  // Opened when used: a resume refused for another reason must not find packings/ created.
  io::Directory packings() const { return run_dir_.subdirectory(io::run_files::packings); }
  io::RunDirectory& run_dir_;
  std::uint64_t seed_;
  static constexpr std::size_t kSteps = 0, kDivisions = 1;  // log(k)
};

// The run's summary (deterministic: same scene and seed => same bytes) and timing.json (wall
// time and rates, not deterministic).
io::Json summary_json(const GrowthDriver& driver);
struct SessionTiming {
  double wall_seconds = 0;
  long attempts_at_start = 0;  // growth steps already done when this session started
  long force_evaluations_at_start = 0;
};
void write_summary(const io::Directory& run_dir, const GrowthDriver& driver, const SessionTiming& timing);

// Every entry a growth run may write (io::OwnedEntries): scene.toml, checkpoint.txt, summary.json,
// timing.json, RunLog::files() and what every registered observer declares.
io::OwnedEntries run_owned_entries();

}  // namespace budjam::tools
