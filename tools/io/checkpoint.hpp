#pragma once
// The checkpoint of a growth run (docs/growth.md, "Checkpoints and resume"): a text file that
// holds the driver's GrowthState and every observer's section, written atomically.
//
// A checkpoint is trusted only if all of these hold (else InputError "<file>:<line>: <problem>",
// exit 2, nothing changed):
//  - its first line `budjam-checkpoint <kCheckpointVersion>`, its last line
//    `checksum <FNV-1a 64 of everything before>`;
//  - the hash of the effective scene it was written with equals that of the scene resuming it
//    (an edited scene.toml — growth.P0, a target, an observer — is refused);
//  - every number is finite and in range, every counter consistent with the others and with
//    the scene (next target within the targets, attempts within growth.max_steps, ...), the
//    packing obeys the physical rules (packing_rules.hpp), ids are unique;
//  - every stateful observer of the resuming run has its section, and every section with
//    content belongs to one of them.
#include "budjam/growth_driver.hpp"
#include "budjam/scene.hpp"
#include "io/atomic_file.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

inline constexpr int kCheckpointVersion = 14;

// When `budjam grow` saves its state, asked after every growth attempt the driver's checkpoint hook
// follows (docs/growth.md, "Checkpoints and resume"): at every `every`-th accepted step; after an
// attempt that cost more than kMarginalEvaluations force evaluations (a marginal relaxation, hours
// at 10⁵ cells and not worth repeating, inside a search that may have no accepted state for hours);
// and on a signal. The last two only when the state is complete (GrowthDriver::state_is_complete:
// the periodic steps always are). Never at the initial state (step 0), which no step produced.
class CheckpointSchedule {
 public:
  // `every`: observe.checkpoint_every (0 = no periodic checkpoints); `step`, `evaluations`: as
  // for due(), where the run starts (or resumes).
  CheckpointSchedule(long every, long step, long evaluations) : every_(every), step_(step), evaluations_(evaluations) {}
  // After a growth attempt: the accepted steps and the force evaluations of all growth attempts
  // so far (not the initial relaxation's), whether a signal came, whether the state is complete.
  bool due(long step, long evaluations, bool signal, bool complete);

 private:
  long every_, step_, evaluations_;
};

// Where parse_checkpoint found the records that other files can confirm (1-based lines), so that
// a disagreement names the checkpoint's line; and the BLAS the checkpoint was computed with
// (checkpoint_blas), which a resume compares with its own.
struct CheckpointLines {
  std::string blas;
  std::size_t state = 0, counters = 0, jamming = 0, depletion = 0;
  std::vector<std::size_t> targets;     // one per target record
  std::vector<std::size_t> unjammings;  // one per unjamming record
  struct Tag {
    std::int64_t id = 0;
    double b2_J = 0;  // its bud's b² at jamming
    std::size_t line = 0;
  };
  std::vector<Tag> buds;
};

// The BLAS of this process (blas_library) as a checkpoint records it: one line, its words separated by
// one space. A run resumed under another BLAS continues correctly, but not in the bits an
// uninterrupted run would have had.
std::string checkpoint_blas();

// The hash a checkpoint records of the effective scene: FNV-1a of scene_to_toml, every key
// included but minimiser.threads (a run resumed on another number of threads continues
// identically).
std::uint64_t scene_hash(const Scene& scene);

// The checkpoint text of `state` of a run of `scene`, with the sections of `observers`
// (save_state of each is called, in order).
std::string format_checkpoint(const Scene& scene, const GrowthState& state, const std::vector<Observer*>& observers);

// format_checkpoint, written atomically as `name` in `dir`.
void write_checkpoint(const Directory& dir, std::string_view name, const Scene& scene, const GrowthState& state,
                      const std::vector<Observer*>& observers);

// Checks `text` (named `file` in messages) against the resuming run (`scene`, `seed`,
// `observers`), then hands each observer its section (load_state) and returns the state for
// GrowthDriver::restore. Observers' load_state is called only after the whole text was checked.
// `lines` (if given) receives where the records were found.
GrowthState parse_checkpoint(std::string_view text, const std::string& file, const Scene& scene, std::uint64_t seed,
                             const std::vector<Observer*>& observers, CheckpointLines* lines = nullptr);

// A row of steps.csv as resume checks it (χ_c NaN before jamming).
struct StepRow {
  long step = 0;
  std::size_t N = 0;
  double phi = 0, P = 0, chi_c = 0;
  Phase phase = Phase::unjammed;
};
// steps.csv up to a checkpoint's length: its rows, and those that begin a new phase.
struct StepsLog {
  std::vector<StepRow> rows, changes;
};

// steps.csv's text (its header, then rows; `file` names it in messages): InputError
// "<file>:<line>: ..." for a row without a step, N, φ, P, phase and χ_c.
StepsLog read_steps(std::string_view steps_text, const std::string& file);

// InputError "<file>:<line>: ..." (`file` the checkpoint, `at` where parse_checkpoint found its
// records) unless the checkpointed state `s` agrees with what the run's other files hold: the
// step and division counters with the rows of steps.csv and divisions.csv up to their recorded
// lengths (`steps`, `divisions`: CsvLog::check_resumable), the packing with the last of those rows
// (N, φ, P), the jamming and unjamming records and the phase with the phase changes of `log`, each
// target's χ_c with its row and its φ_target with φ_J + Δφ, each record (jamming point, targets, φ_2)
// with the packing saved with it in `packings` (its meta lines and its cells), the scene's P0 and the
// seed with each of those packings, and each tagged bud's size at jamming with packings/jammed.pack.
void check_against_run(const GrowthState& s, const Scene& scene, const CheckpointLines& at, const std::string& file,
                       const CsvLog::Cut& steps, const StepsLog& log, const CsvLog::Cut& divisions,
                       const Directory& packings);

// parse_checkpoint of the file `name` in `dir` (a link is not followed).
GrowthState read_checkpoint(const Directory& dir, std::string_view name, const Scene& scene, std::uint64_t seed,
                            const std::vector<Observer*>& observers, CheckpointLines* lines = nullptr);

}  // namespace budjam::io
