#pragma once
// The quasistatic growth loop (docs/model.md, "Growth protocol"):
//   growth step Δt → FIRE → classify E/N → accept / reject → emit events. The jamming window and
//   the searches that choose the next Δt (bisection, secant, bracket) are in jamming.hpp; the
//   driver keeps the protocol (docs/growth.md).
// Everything optional (logs, packings, moduli, spectra, rigidity) is an Observer that receives a
// read-only view of each accepted state. The driver computes contacts, the contact network and the
// bud pressures only when the protocol (feedback, depletion) or an observer needs them.
//
// Order of events for one accepted step (all see the same StateView, with the records of this
// state already in place), after the TrialRelaxed of the attempt that produced it:
//   Divided (one per division in the step) → BudEvent* (updates of the tagged buds, also of an
//   episode that unjammed, whose buds still unconstrained end `censored_unjam` at the next jamming)
//   → StepAccepted → Unjammed | Jammed → BudEvent* (`tagged`, at a jamming) → TargetReached* →
//   Depleted → then, at the end of the run, BudEvent* (censored_end) → Finished | Failed.
// The initial relaxed state is announced as StepAccepted with step 0.
// A rejected step emits only its TrialRelaxed (it is undone exactly, RNG included).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include "budjam/bud_events.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/fire.hpp"
#include "budjam/growth.hpp"
#include "budjam/jamming.hpp"
#include "budjam/packing.hpp"
#include "budjam/scene.hpp"

namespace budjam {

// unjammed: jamming not (yet, or no longer) found, every cell grows at γ0.
// jammed: at or above the jamming point φ_J; feedback (if P0 is set) is on.
enum class Phase { unjammed, jammed };
const char* to_string(Phase phase);

enum class RunStatus {
  running,
  finished,          // every target landed (and φ_2 found or φ_J + max_dphi reached if asked)
  step_limit,        // more than scene.max_steps growth steps (accepted + rejected)
  dt_underflow,      // a trial Δt below scene.dt_min (halved or solved for)
  minimiser_failed,  // FIRE hit its iteration limit, could not leave a saddle, or left a candidate without backbone
  overlap_bound,     // a relaxed state grown so deep that a pair of lobes reached the packing rules' r ≤ σ/2
};
const char* to_string(RunStatus status);

// What an observer wants computed at every accepted step. Contacts and the network are always
// available at accepted states above jamming (the driver needs them for φ_2 and the bud events)
// and at every event state (Jammed, TargetReached, Depleted, Finished/Failed if above jamming).
struct Needs {
  bool contacts = false;        // contact list
  bool network = false;         // ContactNetwork (implies contacts)
  bool bud_pressures = false;   // p_i per cell (implies contacts); feedback runs always have them
  bool before_jamming = false;  // also at accepted states in the unjammed phase
  bool trial_starts = false;    // TrialRelaxed::start_packing: where each trial's relaxation began
  Needs& operator|=(const Needs& o) {
    trial_starts |= o.trial_starts;
    contacts |= o.contacts;
    network |= o.network;
    bud_pressures |= o.bud_pressures;
    before_jamming |= o.before_jamming;
    return *this;
  }
};

// Data of the (latest) jamming point.
struct JammingRecord {
  int episode = 0;  // 0 for the first jamming, k after the k-th unjamming
  long step = 0;    // accepted-step index of the jammed state
  double phi = 0, P = 0, E_per_cell = 0;
  NetworkSummary network;
  double n_J = 0;          // N_nr / L²
  std::size_t tagged = 0;  // unconstrained buds tagged for the bud events and φ_2
};

struct TargetRecord {
  std::size_t index = 0;  // k: position in scene.targets
  double dphi = 0;        // requested Δφ
  double phi_target = 0;  // φ_J + Δφ
  long step = 0;
  double phi = 0, P = 0, E_per_cell = 0;
  NetworkSummary network;
  double chi_c = 1;  // ⟨exp(−p/P0)⟩ over compressed buds (1 with P0 = none or none compressed)
  long divisions_since_jamming = 0;
};

struct DepletionRecord {  // φ_2
  long step = 0;
  double phi = 0, P = 0;
  NetworkSummary network;
  std::size_t still_unconstrained = 0;  // tagged buds still unconstrained (≤ scene.phi2_tagged_left)
  long divisions_since_jamming = 0;
};

struct UnjamRecord {
  int episode = 0;  // the jamming episode that ended
  long step = 0;
  double phi = 0;
  double phi_J = 0;              // the φ_J that was lost
  std::size_t targets_lost = 0;  // targets landed in that episode (discarded: targets are re-visited)
};

struct RunResult {
  RunStatus status = RunStatus::running;
  std::string message;  // one line for failures
  std::optional<JammingRecord> jamming;
  std::vector<TargetRecord> targets;         // of the current jamming episode, in increasing Δφ
  std::optional<DepletionRecord> depletion;  // φ_2 of the current jamming episode
  std::vector<UnjamRecord> unjammings;
  long accepted = 0, rejected = 0;  // growth steps
  long force_evaluations = 0, fire_iterations = 0;
  long divisions = 0;        // all divisions in accepted steps
  long saddles_relaxed = 0;  // jamming candidates found to be saddles and relaxed on
  long saddle_escapes = 0;   // steps along an unstable mode where that relaxation stopped on a saddle again
  // Where the time goes (docs/speed.md). The force evaluations split by stage (the initial
  // relaxation, the trials of the unjammed phase, the trials above jamming) add up to
  // force_evaluations.
  long search_trials = 0;         // relaxed trials in the unjammed phase: the search onto φ_J
  long marginal_relaxations = 0;  // relaxed trials that cost more than kMarginalEvaluations
  long newton_factorisations = 0, newton_factor_reuses = 0;  // Newton steps with a fresh / a kept factor
  // Active-set steps (minimiser.active_set_after): linearisations, their factorisations and their
  // rank-1 factor changes.
  long active_set_steps = 0, active_set_factorisations = 0, active_set_updates = 0;
  long force_evaluations_initial = 0, force_evaluations_search = 0, force_evaluations_above_jamming = 0;
  // The relaxed branches followed before trials' relaxations (jamming.continuation): how many, how
  // many reached the trial's sizes and how many ended where the network lost stability, their
  // accepted steps and the contact events (openings and closings) found along them. Their
  // factorisations are among newton_factorisations; branch_rearrangements counts the stability losses
  // crossed by FIRE (jamming.crossing_step), whose evaluations are the branches'.
  long branches = 0, branches_reached = 0, branch_stability_losses = 0, branch_steps = 0, branch_events = 0;
  long branch_rearrangements = 0;
};

// A trial whose relaxation costs more force evaluations than this is a marginal relaxation: FIRE
// creeping near the jamming point, where the cost of a run concentrates.
inline constexpr long kMarginalEvaluations = 100000;
// Steps along a saddle's unstable mode (each followed by a relaxation) a jamming candidate may take,
// at most: a candidate that needs more is in a landscape of saddles FIRE cannot leave, and the run
// fails saying so.
inline constexpr long kSaddleEscapes = 8;

// Read-only view of an accepted state. Pointers are null when not computed for this state.
struct StateView {
  long step = 0;      // accepted steps so far; 0 = the initial state
  long attempts = 0;  // growth steps tried so far (accepted + rejected)
  double dt = 0;      // Δt of the step that produced this state (+∞ beyond the double range) ...
  double log_dt = 0;  // ... and ln Δt, exact at any size (−∞ for the initial state)
  double phi = 0, P = 0, E_per_cell = 0;
  Phase phase = Phase::unjammed;
  const Scene* scene = nullptr;
  const Packing* packing = nullptr;
  const std::vector<Contact>* contacts = nullptr;
  const ContactNetwork* network = nullptr;
  const std::vector<double>* bud_pressures = nullptr;
  const JammingRecord* jamming = nullptr;  // null in the unjammed phase
  const BudTracker* buds = nullptr;        // tags of the latest jamming episode (followed after an unjamming)
  bool after_jamming = false;              // jammed, or unjammed after a jamming: network, χ_c and tags known
  long divisions_since_jamming = 0;        // 0 in the unjammed phase
  std::size_t compressed_buds = 0;         // buds with ≥ 1 contact (valid when contacts != null)
  double chi_c = 1;                        // ⟨exp(−p/P0)⟩ over compressed buds (when pressures known) ...
  double log_chi_c = 0;                    // ... and ln χ_c, exact when every factor underflows
};

// What the decision table made of a relaxed trial: accepted; rejected (an overshoot of the jamming
// window, or a target passed); below the window, the bracket's new lower end; deferred (inside the
// bracket, jamming.trial_budget FIRE iterations spent with E/N still over 100 · 2ε_U: an upper end
// until it is resumed, when it is judged again under the same attempt); or the end of the run (φ_2 not found
// before φ_J + max_dphi).
enum class TrialVerdict { accepted, rejected, below_window, deferred, stop };
const char* to_string(TrialVerdict verdict);

// Every relaxed growth attempt, whatever its verdict: the log of the search onto φ_J and of the
// landing on targets, which the accepted states alone do not show. A settle, or the resumption of a
// deferred trial, continues the attempt of the trial it relaxes on (same `attempt`); its cost is its
// own.
struct TrialRelaxed {
  long attempt = 0;       // growth steps tried so far, this one included
  double dt = 0;          // Δt of the trial (+∞ beyond the double range) ...
  double log_dt = 0;      // ... and ln Δt, exact at any size
  std::size_t N = 0;      // cells after the trial's divisions
  double phi = 0;         // φ of the trial
  double E_per_cell = 0;  // E/N after its relaxation
  TrialStart start = TrialStart::accepted_state;
  TrialVerdict verdict = TrialVerdict::accepted;
  long fire_iterations = 0, force_evaluations = 0;  // spent on this trial (saddle relaxation included)
  // With Needs::trial_starts (else null): the packing its relaxation started from and the minimiser
  // parameters of that relaxation, which replay it (bench/bench_replay.cpp).
  const Packing* start_packing = nullptr;
  FireParams minimiser;
  // With Needs::trial_starts: the relaxed state whose branch the trial lies on (the bracket's lowest
  // overshoot, JammingSearcher::branch_start), from which jamming.continuation follows it; else null.
  const Packing* branch_start = nullptr;
};

struct StepAccepted {
  const StateView& state;
};
struct Jammed {
  const StateView& state;
  const JammingRecord& jamming;
};
struct Unjammed {
  const StateView& state;
  const UnjamRecord& record;
};
struct TargetReached {
  const StateView& state;
  const TargetRecord& target;
};
struct Depleted {
  const StateView& state;
  const DepletionRecord& depletion;
};
struct Divided {
  const StateView& state;
  const Division& division;
};  // state: after minimisation
struct BudEventHappened {
  const StateView& state;
  const BudEvent& event;
};
struct Failed {
  const StateView& state;
  const RunResult& result;
};  // state: last accepted
struct Finished {
  const StateView& state;
  const RunResult& result;
};

struct GrowthState;

class Observer {
 public:
  virtual ~Observer() = default;
  // Unique name; keys the observer's section in a checkpoint.
  virtual std::string name() const = 0;
  virtual Needs needs() const { return {}; }

  // Every relaxed attempt, before the events of the state it produces (if accepted).
  virtual void on_trial(const TrialRelaxed&) {}
  virtual void on_step_accepted(const StepAccepted&) {}
  virtual void on_jammed(const Jammed&) {}
  virtual void on_unjammed(const Unjammed&) {}
  virtual void on_target_reached(const TargetReached&) {}
  virtual void on_depleted(const Depleted&) {}
  virtual void on_divided(const Divided&) {}
  virtual void on_bud_event(const BudEventHappened&) {}
  virtual void on_failed(const Failed&) {}
  virtual void on_finished(const Finished&) {}

  // Checkpoints (tools/io/checkpoint.hpp): whatever the observer needs to continue after --resume
  // (e.g. the byte length of the files it appends to, so that rows written after the checkpoint
  // can be cut off; make them durable first, CsvLog::sync). save_state is called after all events
  // of a checkpointed growth attempt (GrowthDriver::set_checkpoint_hook); load_state gets exactly
  // what it wrote (any text) and throws InputError if it does not fit. A `stateful` observer must
  // find its section in a checkpoint (else the resume is refused); a stateless one (a progress
  // display) may come and go. load_state only reads and checks: it changes nothing outside the
  // observer, because the resume may still be refused; on_resumed() follows once the whole resume
  // was accepted (before the resumed run's first event or checkpoint, GrowthDriver::restore), and
  // may then change what the observer keeps outside (cut its logs back).
  virtual bool stateful() const { return false; }
  virtual void save_state(std::ostream&) {}
  virtual void load_state(std::istream&) {}
  // After every load_state passed: throws InputError naming the file if what the observer wrote
  // outside the checkpoint (a log's rows) disagrees with the state the run resumes from, which
  // the checkpoint records independently (its attempts, its tagged buds). Changes nothing.
  virtual void check_resumed(const GrowthState&) const {}
  virtual void on_resumed() {}
};

// Where a growth step starts from the accepted state: Δt = dt·e^{log_scale}, with the rates scaled
// by e^{log_scale} to match. log_scale is 0 except for an adaptive step out of the double range
// (docs/growth.md, "Adaptive growth step").
struct StepStart {
  double dt = 1;
  double log_scale = 0;
};

// A growth attempt's relaxation in progress: where the minimisation stood, saved with the state
// before the attempt (GrowthState::relaxation). The resumed run makes the attempt again from that
// state (the same Δt, divisions and random draws) and goes on with this relaxation from here.
struct RelaxationState {
  long attempts = 0;  // GrowthState::attempts while it ran (the attempt's own number)
  int index = 0;      // which relaxation of the attempt: 0 the trial's, then one on a deferred trial near the
                      // window or on a saddle
  Eigen::VectorXd q;  // the packing's coordinates
  FireProgress progress;
};

// Everything that determines the rest of a run, besides the scene: a checkpoint
// (tools/io/checkpoint.hpp) stores it, and the quantities derived from it (contacts, network,
// pressures, rates) are recomputed identically after restore(), so that a resumed run repeats an
// uninterrupted one bit for bit.
struct GrowthState {
  std::uint64_t seed = 0;
  Rng rng;
  Phase phase = Phase::unjammed;
  // Steps as the driver stores them, scaled (StepStart): the next attempt's log_scale follows from
  // the accepted state (like the rates), the last step's is kept.
  double dt = 0;                           // the next attempt
  double last_dt = 0, last_log_scale = 0;  // the step that produced the accepted state
  long step = 0, attempts = 0;             // accepted steps; growth steps tried
  std::size_t next_target = 0;             // index in scene.targets of the next target to land
  long divisions_since_jamming = 0;
  int episodes = 0;  // jamming episodes begun
  RunResult result;  // status `running`
  BudTracker buds;
  Packing packing;            // the last accepted state
  JammingSearchState search;  // with the trials of an open bracket, between the trials of a search
  // Inside a growth attempt: its relaxation in progress (the rest of the state is from before the
  // attempt).
  std::optional<RelaxationState> relaxation;
};

// Extra knobs that are not part of a scene (tests use them).
struct DriverOptions {
  std::optional<std::uint64_t> seed;  // overrides scene.seed
};

class GrowthDriver {
 public:
  explicit GrowthDriver(const Scene& scene, const DriverOptions& options = {});
  ~GrowthDriver();
  GrowthDriver(const GrowthDriver&) = delete;
  GrowthDriver& operator=(const GrowthDriver&) = delete;

  // Non-owning; add all observers before the first advance() (and in the same order, by name,
  // before restore()).
  void add_observer(Observer& observer);

  // One growth attempt (accepted or rejected). Returns the status after it.
  RunStatus advance();
  // Runs until the status is no longer `running`; emits Finished or Failed once.
  RunStatus run();

  // Called after every growth attempt that does not end the run, after its events: after an
  // accepted step, and after a rejected trial (an overshoot, a trial below the window or a deferred
  // one), from whose search state the next attempt goes on. These are the moments at which state()
  // (with the observers' save_state) is a complete checkpoint. The caller decides which of them to
  // keep (every k steps, after a costly trial, on a signal).
  void set_checkpoint_hook(std::function<void()> hook);
  // Checkpoints inside a growth attempt's relaxations (FireCheckpoints: every `every` force
  // evaluations of one relaxation, 0 = never, and whenever `requested()`), from the first accepted
  // step on and while state_is_complete() holds: `save` receives state() as it was before the
  // attempt, with the relaxation in progress. `save` may throw to end the run.
  void set_relaxation_checkpoints(long every, std::function<bool()> requested,
                                  std::function<void(const GrowthState&)> save);
  // The state a checkpoint holds (after the first advance()).
  GrowthState state() const;
  // Whether state() holds everything the rest of the run depends on. Not while a Newton factor is
  // kept from an earlier minimisation (minimiser.newton_reuse): the checkpoint does not hold it, and
  // the run goes on with chord steps where a resumed one would factor afresh. It is dropped at
  // every step that is a multiple of observe.checkpoint_every, so periodic checkpoints always are.
  bool state_is_complete() const;
  // Continues from `state` (taken from a driver of the same scene and seed; `source` names where it
  // came from, for the messages). Throws InputError if the seed or the box differs; everything
  // else is the checkpoint reader's to check. A relaxation in progress is taken up by the next
  // attempt (InputError if that attempt does not make it: another number of cells, or no such
  // relaxation). The observers' on_resumed() comes just before the resumed run's first event or
  // checkpoint, after that attempt took up its relaxation: a resume refused on it changes nothing
  // an observer keeps.
  void restore(GrowthState state, std::string source = "checkpoint");

  const Scene& scene() const;
  std::uint64_t seed() const;
  const Packing& packing() const;
  const RunResult& result() const;
  Phase phase() const;
  double dt() const;  // scaled Δt of the next attempt (StepStart)
  // View of the current (last accepted) state.
  StateView view() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace budjam
