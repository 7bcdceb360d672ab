#include "budjam/growth_driver.hpp"

#include "budjam/continuation.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/jamming.hpp"
#include "budjam/packing_rules.hpp"
#include "budjam/saddle.hpp"
#include "budjam/stability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <utility>

namespace budjam {

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::unjammed: return "unjammed";
    case Phase::jammed: return "jammed";
  }
  return "?";
}

const char* to_string(TrialVerdict verdict) {
  switch (verdict) {
    case TrialVerdict::accepted: return "accepted";
    case TrialVerdict::rejected: return "rejected";
    case TrialVerdict::below_window: return "below_window";
    case TrialVerdict::deferred: return "deferred";
    case TrialVerdict::stop: return "stop";
  }
  return "?";
}

const char* to_string(RunStatus status) {
  switch (status) {
    case RunStatus::running: return "running";
    case RunStatus::finished: return "finished";
    case RunStatus::step_limit: return "step_limit";
    case RunStatus::dt_underflow: return "dt_underflow";
    case RunStatus::minimiser_failed: return "minimiser_failed";
    case RunStatus::overlap_bound: return "overlap_bound";
  }
  return "?";
}

namespace {

// Exact text round trip of a double.
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Δt of a step stored as `scaled` with `log_scale`, and its logarithm.
double unscaled_dt(double scaled, double log_scale) { return log_scale == 0.0 ? scaled : scaled * std::exp(log_scale); }
double log_dt(double scaled, double log_scale) { return std::log(scaled) + log_scale; }

// Buds with at least one contact.
std::size_t compressed_buds(std::size_t cells, const std::vector<Contact>& contacts) {
  std::vector<char> touched(cells, 0);
  for (const Contact& c : contacts) {
    if (is_bud(c.i)) touched[cell_of(c.i)] = 1;
    if (is_bud(c.j)) touched[cell_of(c.j)] = 1;
  }
  return static_cast<std::size_t>(std::ranges::count(touched, 1));
}

// Δt that the next step starts from (before any bisection halving), from the accepted state with
// its bud `pressures` (null below jamming or when not computed).
// The nominal growth.dt (docs/model.md, "Growth protocol"). With growth.adaptive_dt, above jamming with feedback:
// dt / max(g_max, adaptive_floor), g_max = max_i exp(−p_i/P0) = the factor of the least
// compressed bud, so that the fastest-growing cell gains γ0_i·dt of relative area, as in a
// nominal step. While every factor and that Δt are doubles it is stored as it is (log_scale 0);
// else the step is stored as dt, log_scale = −ln max(g_max, floor) and the rates are scaled by
// e^{log_scale}: the growth γ0_i·dt·exp(−p_i/P0)/max(g_max, floor) is then exact at any p/P0.
StepStart step_start(const Scene& scene, const std::vector<double>* pressures) {
  if (!(scene.adaptive_dt && scene.P0 && pressures) || pressures->empty()) return {scene.dt, 0.0};
  double g_max = 0.0, log_g_max = -std::numeric_limits<double>::infinity();
  bool underflow = false;  // the plain form would lose some bud's growth
  for (double p : *pressures) {
    const double log_g = log_growth_factor(p, scene.P0);
    const double g = factor_from_log(log_g);
    underflow = underflow || g == 0.0;
    g_max = std::max(g_max, g);
    log_g_max = std::max(log_g_max, log_g);
  }
  const double top = std::max(g_max, scene.adaptive_floor);
  if (!underflow && std::isfinite(scene.dt / top)) return {scene.dt / top, 0.0};
  return {scene.dt, -std::max(log_g_max, std::log(scene.adaptive_floor))};  // floor 0: log = −∞
}

// The record of target k (Δφ = dphi above φ_J = phi_J) landed by the accepted state `v`.
TargetRecord target_record(const StateView& v, std::size_t k, double dphi, double phi_J) {
  TargetRecord t;
  t.index = k;
  t.dphi = dphi;
  t.phi_target = phi_J + dphi;
  t.step = v.step;
  t.phi = v.phi;
  t.P = v.P;
  t.E_per_cell = v.E_per_cell;
  t.network = v.network->summary();
  t.chi_c = v.chi_c;
  t.divisions_since_jamming = v.divisions_since_jamming;
  return t;
}

// The record of the jamming point `v`, the jamming episode's index `episode`.
JammingRecord jamming_record(const StateView& v, int episode) {
  JammingRecord j;
  j.episode = episode;
  j.step = v.step;
  j.phi = v.phi;
  j.P = v.P;
  j.E_per_cell = v.E_per_cell;
  j.network = v.network->summary();
  const double L = v.packing->box.L;
  j.n_J = static_cast<double>(v.network->N_nr) / (L * L);
  return j;
}

// φ_2 at the accepted state `v`, with `still_unconstrained` tagged buds left.
DepletionRecord depletion_record(const StateView& v, std::size_t still_unconstrained) {
  DepletionRecord d;
  d.step = v.step;
  d.phi = v.phi;
  d.P = v.P;
  d.network = v.network->summary();
  d.still_unconstrained = still_unconstrained;
  d.divisions_since_jamming = v.divisions_since_jamming;
  return d;
}

// The observers' account of a relaxed trial made at attempt `attempt`, its step scaled by
// `log_scale`, and what it cost.
TrialRelaxed trial_relaxed(const Trial& t, long attempt, double log_scale, TrialVerdict verdict, long iterations,
                           long evaluations) {
  return TrialRelaxed{attempt,
                      unscaled_dt(t.dt, log_scale),
                      log_dt(t.dt, log_scale),
                      t.packing.size(),
                      t.packing.packing_fraction(),
                      t.E,
                      t.start,
                      verdict,
                      iterations,
                      evaluations,
                      nullptr,
                      {}};
}

// Whether `p` holds its energy in a rigid backbone: some cell is not a rattler. With every cell a
// rattler, E is what a relaxation of floppy cells stopped short of removing (a loose force_tol, or a
// window below what FIRE resolves), not the energy of a jammed minimum. Requires `field` to be current.
bool has_backbone(const Packing& p, const ForceField& field) {
  return analyse_network(p.size(), find_contacts(p, field.lobes(), field.neighbours())).N_nr > 0;
}

// Whether `p` is a minimum of U with a rigid backbone (no unstable mode of its non-rattler Hessian).
// Requires `field` to be current for `p` (freshly evaluated on it).
bool is_minimum(const Packing& p, const ForceField& field) {
  const std::vector<Contact> c = find_contacts(p, field.lobes(), field.neighbours());
  const ContactNetwork net = analyse_network(p.size(), c);
  return net.N_nr > 0 && stability(p, c, net).minimum();
}

// The lowest unstable mode of `p` (nullopt: none below the saddle test's −δ). Requires `field` to be
// current for `p`.
std::optional<UnstableMode> unstable_mode_of(const Packing& p, const ForceField& field) {
  const std::vector<Contact> c = find_contacts(p, field.lobes(), field.neighbours());
  return lowest_unstable_mode(p, c, analyse_network(p.size(), c));
}

// (φ, s, slope) of a relaxed trial above the jamming window. Requires `field` to be current for it.
JammingOvershoot overshoot_of(const Trial& t, const ForceField& field) {
  const std::vector<Contact> c = find_contacts(t.packing, field.lobes(), field.neighbours());
  return overshoot_line(t.packing.packing_fraction(), t.E, t.packing.size(), pressure(c, t.packing.box),
                        t.packing.box.L);
}

// The fields a checkpoint holds besides the seed and the search, from the driver to a GrowthState
// or back (moved out of a non-const source).
template <class To, class From>
void transfer(To& to, From& from) {
  to.rng = from.rng;
  to.phase = from.phase;
  to.dt = from.dt;
  to.last_dt = from.last_dt;
  to.last_log_scale = from.last_log_scale;
  to.step = from.step;
  to.attempts = from.attempts;
  to.next_target = from.next_target;
  to.divisions_since_jamming = from.divisions_since_jamming;
  to.episodes = from.episodes;
  to.result = std::move(from.result);
  to.buds = std::move(from.buds);
  to.packing = std::move(from.packing);
}

}  // namespace

struct GrowthDriver::Impl {
  Scene scene;
  std::uint64_t seed = 0;
  std::vector<Observer*> observers;
  Needs needs;

  // The last accepted state and everything that a rejected step must not touch.
  Packing packing;
  Rng rng;
  Phase phase = Phase::unjammed;
  // Steps are stored scaled: an attempt of `dt` with `rates` grows as Δt = dt·e^{log_scale} with the
  // plain rates γ_i (StepStart; log_scale ≠ 0 only for an adaptive step out of the double range).
  double dt = 1.0;              // scaled Δt of the next attempt
  double last_dt = 0.0;         // scaled Δt of the step that produced the accepted state ...
  double last_log_scale = 0.0;  // ... and the log_scale it was taken with
  long step = 0, attempts = 0;
  bool started = false;
  RunResult result;
  std::size_t next_target = 0;
  long divisions_since_jamming = 0;
  int episodes = 0;  // jamming episodes begun
  BudTracker buds;
  JammingWindow window;
  std::unique_ptr<JammingSearcher> search;  // its state between accepted states is checkpointed

  // Derived from the accepted state (recomputed identically after a restore).
  double E = 0, P = 0, phi = 0;
  std::vector<Contact> contacts;
  bool have_contacts = false;
  ContactNetwork net;
  bool have_net = false;
  std::vector<double> pressures;
  bool have_pressures = false;
  std::size_t compressed = 0;
  CompressedFactor chi_c;     // χ_c and ln χ_c
  std::vector<double> rates;  // γ_i·e^{log_scale} of the next step, frozen from the accepted state
  StepStart next;             // where the next step starts, from the accepted state

  ForceField field;
  // The start of the latest trial's relaxation and its parameters (when an observer needs them).
  Packing trial_start;
  FireParams trial_params;
  std::optional<Packing> trial_branch;  // the relaxed state whose branch the trial lies on
  // The Newton factor kept from one minimisation to the next (arrested regime). Forgotten at every
  // checkpointed step, where a resumed run starts without one, so that it repeats the uninterrupted run.
  NewtonWorkspace newton;
  Eigen::VectorXd force;
  bool final_emitted = false;
  std::function<void()> checkpoint_hook;
  // Checkpoints inside relaxations (set_relaxation_checkpoints): the state before the attempt under
  // way (when it can be saved), which of its relaxations is running, and a relaxation in progress
  // restored from a checkpoint, for the next attempt to take up.
  long relaxation_every = 0;
  std::function<bool()> relaxation_requested;
  std::function<void(const GrowthState&)> relaxation_save;
  std::optional<GrowthState> before_attempt;
  int relaxation_index = 0;
  std::optional<RelaxationState> pending_relaxation;
  // Where a restored state came from (a checkpoint file), for the messages that refuse it; and
  // whether the observers are still to hear that the run resumed (announce_resume).
  std::string restored_from;
  bool resume_unannounced = false;

  Impl(const Scene& s, const DriverOptions& o) : scene(s), window(jamming_window(s)), field(s.skin, s.threads) {
    validate(scene);
    search = make_jamming_searcher(scene);
    seed = o.seed ? *o.seed : scene.seed;
    rng.seed(seed);
    dt = scene.dt;
  }

  GrowthState public_state() const {
    GrowthState s;
    s.seed = seed;
    transfer(s, *this);
    s.search = search->state();
    return s;
  }

  // U/N of `p` with a freshly built neighbour list, so that the list (and the order of the
  // contacts taken from it) depends only on the configuration, not on the history of rebuilds:
  // a resumed run then repeats an uninterrupted one bit for bit.
  double fresh_energy_per_cell(const Packing& p) {
    field.invalidate();
    const double U = field.evaluate(p, force);
    return p.size() ? U / static_cast<double>(p.size()) : 0.0;
  }

  // The cost of a minimisation (and of the evaluation that follows it), into the run's counters
  // and the stage's evaluations.
  void count(const FireResult& fr, long& stage_evaluations) {
    result.force_evaluations += fr.evaluations + 1;
    stage_evaluations += fr.evaluations + 1;
    result.fire_iterations += fr.iterations;
    result.newton_factorisations += fr.newton_iterations;
    result.newton_factor_reuses += fr.newton_chord_steps;
    result.active_set_steps += fr.active_set_steps;
    result.active_set_factorisations += fr.active_set_factorisations;
    result.active_set_updates += fr.active_set_updates;
  }

  // FIRE on a trial, counted; false (and the run failed) if it did not converge. With a `budget`
  // below params.max_iterations, FIRE stops there without failing the run: `*spent` tells.
  bool relax(Packing& p, const FireParams& params, const std::string& where, long budget = 0, bool* spent = nullptr) {
    field.invalidate();
    FireParams run = params;
    const bool budgeted = budget > 0 && budget < params.max_iterations;
    if (budgeted) run.max_iterations = budget;
    const int index = relaxation_index++;
    FireCheckpoints checkpoints;
    if (pending_relaxation && pending_relaxation->index == index) {
      const RelaxationState& r = *pending_relaxation;
      if (r.attempts != attempts || r.q.size() != p.q.size())
        throw InputError(restored_from + ": its relaxation in progress (growth attempt " + std::to_string(r.attempts) +
                         ", " + std::to_string(r.q.size() / 3) +
                         " cells) is not the one this run makes (growth attempt " + std::to_string(attempts) + ", " +
                         std::to_string(p.size()) + " cells)");
      p.q = r.q;
      Lobes lobes;
      place_lobes(p, lobes);
      if (const auto problem = field.neighbours().misfit(r.progress.neighbours, lobes))
        throw InputError(restored_from + ": its relaxation in progress does not fit its neighbour list: " + *problem);
      checkpoints.resume = &r.progress;
    }
    // The relaxations of a resumed attempt before the one it resumes are made again without
    // checkpoints: the checkpoint resumed from is further along (a signal waits for it).
    if (before_attempt && (!pending_relaxation || checkpoints.resume)) {
      checkpoints.every = relaxation_every;
      checkpoints.requested = relaxation_requested;
      checkpoints.save = [this, index](const Packing& at, const FireProgress& progress) {
        GrowthState s = *before_attempt;
        s.relaxation = RelaxationState{attempts, index, at.q, progress};
        announce_resume();
        relaxation_save(s);
      };
    }
    const FireResult fr = minimise(p, field, run, &newton, &checkpoints);
    if (checkpoints.resume) pending_relaxation.reset();
    count(fr, phase == Phase::unjammed ? result.force_evaluations_search : result.force_evaluations_above_jamming);
    if (spent) *spent = budgeted && !fr.converged;
    if (!fr.converged && !budgeted)
      fail(RunStatus::minimiser_failed, "FIRE did not converge within minimiser.max_iterations = " +
                                            std::to_string(params.max_iterations) + " (" + where + ")");
    return fr.converged || budgeted;
  }

  // Contacts, P, network, bud pressures, rates for the accepted state. Requires the field to be
  // current for `packing` (fresh_energy_per_cell just called on it).
  void derive() {
    phi = packing.packing_fraction();
    contacts = find_contacts(packing, field.lobes(), field.neighbours());
    have_contacts = true;
    P = pressure(contacts, packing.box);
    const bool jammed = phase == Phase::jammed;
    const bool observe_here = jammed || needs.before_jamming;
    // From the first jamming on, every state's network, χ_c and tags are logged, also while an
    // unjamming is searched through (the paper's analysis anchors at the first jamming).
    const bool followed = jammed || episodes > 0;
    have_net = followed || (observe_here && needs.network);
    if (have_net) net = analyse_network(packing.size(), contacts);
    const bool feedback = jammed && scene.P0.has_value();
    have_pressures = feedback || followed || (observe_here && needs.bud_pressures);
    if (have_pressures) pressures = bud_pressures(packing, contacts);
    compressed = compressed_buds(packing.size(), contacts);
    chi_c = have_pressures && scene.P0 ? mean_compressed_factor(pressures, scene.P0) : CompressedFactor{};
    next = step_start(scene, jammed && have_pressures ? &pressures : nullptr);
    rates = growth_rates(packing, feedback ? &pressures : nullptr, scene.P0, next.log_scale);
  }

  StateView view() const {
    StateView v;
    v.step = step;
    v.attempts = attempts;
    v.dt = unscaled_dt(last_dt, last_log_scale);
    v.log_dt = log_dt(last_dt, last_log_scale);
    v.phi = phi;
    v.P = P;
    v.E_per_cell = E;
    v.phase = phase;
    v.scene = &scene;
    v.packing = &packing;
    v.contacts = have_contacts ? &contacts : nullptr;
    v.network = have_net ? &net : nullptr;
    v.bud_pressures = have_pressures ? &pressures : nullptr;
    v.jamming = (phase == Phase::jammed && result.jamming) ? &*result.jamming : nullptr;
    v.buds = &buds;
    v.after_jamming = phase == Phase::jammed || episodes > 0;
    v.divisions_since_jamming = phase == Phase::jammed ? divisions_since_jamming : 0;
    v.compressed_buds = compressed;
    v.chi_c = chi_c.chi;
    v.log_chi_c = chi_c.log_chi;
    return v;
  }

  // Every event reaches the observers through here.
  template <class Event>
  void notify(const Event& event) {
    announce_resume();
    for (Observer* o : observers) event(*o);
  }

  // After a restore the observers' on_resumed() (which cuts their logs back to the checkpoint)
  // waits for the first event or checkpoint of the resumed run: by then its first attempt has taken
  // up the relaxation in progress, the last thing in a checkpoint that can disagree with the run,
  // so a resume refused on it leaves the run directory as it was.
  void announce_resume() {
    if (!resume_unannounced) return;
    resume_unannounced = false;
    for (Observer* o : observers) o->on_resumed();
  }

  void save_checkpoint() {
    if (!checkpoint_hook) return;
    announce_resume();
    checkpoint_hook();
  }

  void emit_bud_events(const StateView& v, const std::vector<BudEvent>& events) {
    for (const BudEvent& e : events) notify([&](Observer& o) { o.on_bud_event(BudEventHappened{v, e}); });
  }

  void start() {
    packing = initial_state(scene, rng);
    field.invalidate();
    const FireResult fr = minimise(packing, field, scene.fire);
    count(fr, result.force_evaluations_initial);
    started = true;
    if (!fr.converged) {
      E = fresh_energy_per_cell(packing);
      derive();
      return fail(RunStatus::minimiser_failed, "FIRE did not converge on the initial state");
    }
    E = fresh_energy_per_cell(packing);
    if (window.jammed(E)) throw InputError("init: the relaxed initial state is already jammed (E/N = " + num(E) + ")");
    derive();
    const StateView v = view();
    notify([&](Observer& o) { o.on_step_accepted(StepAccepted{v}); });
  }

  void fail(RunStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    finish_events();
  }

  void finish_events() {
    if (final_emitted) return;
    final_emitted = true;
    const StateView v = view();
    emit_bud_events(v, buds.close(BudEventKind::censored_end, step, phi, packing));
    notify([&](Observer& o) {
      if (result.status == RunStatus::finished)
        o.on_finished(Finished{v, result});
      else
        o.on_failed(Failed{v, result});
    });
  }

  // ---- choosing the growth step --------------------------------------------------------------
  // φ after a growth step Δt from the accepted state, divisions (and their draws) included. Known
  // before relaxing: relaxation moves cells but does not change their areas.
  double phi_after(double step) const {
    Packing p = packing;
    Rng r = rng;
    grow_step(p, rates, step, scene, r);
    return p.packing_fraction();
  }

  // The accepted state as the search plans from it.
  SearchFrom search_from() const {
    SearchFrom from{phase == Phase::unjammed, phi, dt, std::nullopt, scene.target_tolerance, {}};
    from.phi_after = [this](double by) { return phi_after(by); };
    if (phase == Phase::jammed && next_target < scene.targets.size())
      from.target_phi = result.jamming->phi + scene.targets[next_target];
    return from;
  }

  // `step` is scaled (a trial's dt): Δt < dt_min ⇔ step < dt_min·e^{−log_scale}.
  bool fail_below_dt_min(double step) {
    if (step >= scene.dt_min * std::exp(-next.log_scale)) return false;
    fail(RunStatus::dt_underflow, "growth step dt fell below growth.dt_min = " + num(scene.dt_min) + " (phase " +
                                      to_string(phase) + ", phi = " + num(phi) + ")");
    return true;
  }

  // ---- one growth attempt -------------------------------------------------------------------

  // Where a message is from, as the stop notices name it: the attempts made and the accepted step.
  std::string attempt_text() const {
    return "growth attempt " + std::to_string(attempts) + " (step " + std::to_string(step) + ")";
  }
  // The attempt the search asks for, relaxed; a jamming candidate that is a saddle is relaxed on.
  // nullopt if the run failed (minimiser or Δt below dt_min).
  std::optional<Trial> make_trial() {
    NextTrial plan = search->next_trial(search_from());
    switch (plan.kind) {
      case NextTrial::Kind::resume: return resume_deferred(std::move(plan.trial));
      case NextTrial::Kind::settle: return settle(std::move(plan.trial));
      case NextTrial::Kind::grow: break;
    }
    return grow_trial(plan.dt);
  }

  // Keeps where a trial's relaxation starts, for observers that replay it.
  void note_start(const Packing& p, const Packing* branch = nullptr) {
    if (!needs.trial_starts) return;
    trial_start = p;
    trial_params = trial_minimiser();
    trial_branch.reset();
    if (branch) trial_branch = *branch;
  }

  // A trial grown by `step` from the accepted state. One whose budget ran out far above the window
  // is set aside unrelaxed (deferred); near the window it is relaxed on: it may be the jamming point,
  // and a deferred trial there would only draw the next trials onto itself (docs/jamming.md).
  std::optional<Trial> grow_trial(double step) {
    Trial t{packing, rng, {}, step, 0};
    if (fail_below_dt_min(t.dt)) return std::nullopt;
    t.divisions = grow_step(t.packing, rates, t.dt, scene, t.rng);
    ++attempts;
    search->place(t);
    note_start(t.packing, search->branch_start(t));
    follow_branch_from(search->branch_start(t), t.packing);
    const std::string where = attempt_text() + ", dt = " + num(unscaled_dt(t.dt, next.log_scale));
    if (!relax(t.packing, trial_minimiser(), where, search->trial_budget(), &t.deferred)) return std::nullopt;
    t.E = fresh_energy_per_cell(t.packing);
    if (t.deferred && window.near(t.E)) {
      t.deferred = false;
      if (!relax(t.packing, trial_minimiser(), where)) return std::nullopt;
      t.E = fresh_energy_per_cell(t.packing);
    }
    if (t.deferred) return t;
    if (!relax_if_saddle(t)) return std::nullopt;
    return t;
  }

  // With jamming.continuation, a trial on the branch of a relaxed state (the bracket's lowest
  // overshoot) starts where the continuation along it ends: its relaxed state when the branch
  // reaches its sizes, else the last point before the network lost stability. Counted with the
  // trial's relaxation.
  void follow_branch_from(const Packing* relaxed, Packing& p) {
    if (!scene.continuation || !relaxed) return;
    ContinuationParams params;
    params.energy_floor = trial_minimiser().energy_floor * static_cast<double>(p.size());
    if (scene.crossing_step > 0) {
      params.rearrangement = trial_minimiser();
      params.crossing_step = scene.crossing_step;
    }
    const ContinuationResult r = start_on_branch(p, *relaxed, field, params);
    result.force_evaluations += r.evaluations;
    result.force_evaluations_search += r.evaluations;
    result.newton_factorisations += r.factorisations;
    result.newton_factor_reuses += r.chord_steps;
    ++result.branches;
    result.branches_reached += r.end == BranchEnd::reached;
    result.branch_stability_losses += r.end == BranchEnd::stability_lost;
    result.branch_steps += r.steps;
    result.branch_events += static_cast<long>(r.events.size());
    result.branch_rearrangements += r.rearrangements;
  }

  // A deferred trial, relaxed on to convergence from where its budget ended, is judged again as the
  // same attempt (counted rejected until then). nullopt if the run failed.
  std::optional<Trial> resume_deferred(Trial t) {
    --result.rejected;
    t.deferred = false;
    note_start(t.packing);
    if (!relax(t.packing, trial_minimiser(), "resuming a deferred trial, " + attempt_text())) return std::nullopt;
    t.E = fresh_energy_per_cell(t.packing);
    if (!relax_if_saddle(t)) return std::nullopt;
    return t;
  }

  // The fallback of a collapsed bracket: its highest trial below the window, relaxed on to the
  // ordinary stopping rule, is the next accepted (unjammed) state. nullopt if the run failed. The
  // trial was counted rejected when it narrowed the bracket; it is one attempt, now accepted
  // (accepted + rejected = attempts, which a checkpoint is checked against).
  std::optional<Trial> settle(Trial t) {
    note_start(t.packing);
    if (!relax(t.packing, trial_minimiser(), "settling the bracket, " + attempt_text())) return std::nullopt;
    --result.rejected;
    t.E = fresh_energy_per_cell(t.packing);
    t.start = TrialStart::settled;
    return t;
  }

  // A relaxed jamming candidate that is a saddle of U (FIRE stopped on it) is relaxed on to FIRE's
  // force resolution; the energy usually falls to 0. Where FIRE stops on a saddle again, a step
  // along its unstable mode (saddle.hpp) starts the next relaxation, until the state is a minimum or
  // below the window. A saddle along whose unstable mode U falls by nothing U resolves is bounded by
  // contacts at zero force, a minimum of U that the Hessian of the overlapping contacts does not
  // see: it is the jamming point. false if the run failed.
  bool relax_if_saddle(Trial& t) {
    if (!scene.check_minimum || phase != Phase::unjammed) return true;
    FireParams deep = scene.fire;
    deep.force_tol = 0;
    const std::string where = attempt_text();
    for (int escapes = 0; window.candidate(t.E) && !is_minimum(t.packing, field); ++escapes) {
      if (escapes == 0) {
        ++result.saddles_relaxed;
      } else {
        if (escapes > kSaddleEscapes) {
          fail(RunStatus::minimiser_failed, "a jamming candidate is still a saddle after " +
                                                std::to_string(kSaddleEscapes) +
                                                " steps along its unstable mode and relaxations (" + where + ")");
          return false;
        }
        if (!has_backbone(t.packing, field)) {
          fail(RunStatus::minimiser_failed,
               "a jamming candidate (E/N = " + num(t.E) + ") has no rigid backbone, every cell a rattler, after " +
                   "relaxing to FIRE's force resolution: jamming.epsilon_U = " + num(scene.epsilon_U) +
                   " is below what the minimiser resolves (" + where + ")");
          return false;
        }
        const std::optional<UnstableMode> mode = unstable_mode_of(t.packing, field);
        if (!mode) return true;
        const SaddleStep step = step_off_saddle(t.packing, field, *mode);
        result.force_evaluations += step.evaluations;
        result.force_evaluations_search += step.evaluations;
        if (!step.lowered) {  // the mode runs into contacts at zero force: a minimum to U's resolution
          t.E = fresh_energy_per_cell(t.packing);
          return true;
        }
        ++result.saddle_escapes;
      }
      if (!relax(t.packing, deep, "relaxing a saddle, " + where)) return false;
      t.E = fresh_energy_per_cell(t.packing);
    }
    return true;
  }

  // The Newton finish only above jamming: below it the trials are unjammed or marginal, their
  // Hessian is indefinite and Newton would cost a factorisation for nothing (docs/minimiser.md).
  // While the search only classifies trials, a relaxation stops as soon as it is below the window.
  FireParams trial_minimiser() const {
    FireParams params = scene.fire;
    if (phase == Phase::unjammed) params.newton_force = 0;
    if (search->classifying()) params.energy_floor = std::max(params.energy_floor, window.floor());
    return params;
  }

  // The decision table of docs/growth.md ("Protocol") for a relaxed trial.
  TrialVerdict judge(const Trial& t) const {
    if (t.deferred) return TrialVerdict::deferred;  // E/N ≥ ε_U (the floor did not stop it), still falling
    const WindowSide side = window.side(t.E);
    if (search->classifying() && side == WindowSide::below) return TrialVerdict::below_window;
    if (phase == Phase::unjammed)
      return side == WindowSide::above ? TrialVerdict::rejected : TrialVerdict::accepted;  // overshot jamming
    if (side == WindowSide::below) return TrialVerdict::accepted;                          // unjamming
    const double phi_trial = t.packing.packing_fraction();
    if (next_target < scene.targets.size())
      return phi_trial > result.jamming->phi + scene.targets[next_target] + scene.target_tolerance
                 ? TrialVerdict::rejected
                 : TrialVerdict::accepted;
    // φ_2 not found before φ_J + max_dphi: the run ends at the last accepted state.
    if (scene.continue_to_phi2 && !result.depletion && phi_trial > result.jamming->phi + scene.max_dphi)
      return TrialVerdict::stop;
    return TrialVerdict::accepted;
  }

  // Below jamming an overshoot goes to the search if it keeps them; otherwise (and above jamming,
  // a target passed) Δt is halved.
  void reject(Trial&& t) {
    ++result.rejected;
    if (phase == Phase::unjammed && search->keeps_overshoots()) {
      const JammingOvershoot line = overshoot_of(t, field);
      search->keep_overshoot(std::move(t), line);
      return;
    }
    dt *= 0.5;
    fail_below_dt_min(dt);
  }

  // Makes the trial the accepted state and moves the phase; returns the phase change.
  enum class Change { none, jammed, unjammed };
  Change accept(Trial&& t) {
    packing = std::move(t.packing);
    rng = t.rng;
    E = t.E;
    ++step;
    ++result.accepted;
    last_dt = t.dt;
    last_log_scale = next.log_scale;
    result.divisions += static_cast<long>(t.divisions.size());
    const bool jammed = window.jammed(E);
    Change change = Change::none;
    if (phase == Phase::unjammed && jammed) {
      phase = Phase::jammed;
      change = Change::jammed;
    } else if (phase == Phase::jammed && !jammed) {
      phase = Phase::unjammed;
      change = Change::unjammed;
    } else if (phase == Phase::jammed) {
      divisions_since_jamming += static_cast<long>(t.divisions.size());
    }
    derive();
    search->accepted(phi, phase == Phase::unjammed, change != Change::none);
    dt = next.dt;
    return change;
  }

  // The jamming episode ends: φ_J, the targets and φ_2 belong to the next one. Its tagged buds are
  // followed on until the next jamming tags others, as the paper's code follows them.
  void record_unjamming() {
    result.unjammings.push_back(
        UnjamRecord{result.jamming->episode, step, phi, result.jamming->phi, result.targets.size()});
    start_episode(std::nullopt);
  }

  // The tags still active from an episode that unjammed end here, censored; then the new tags.
  std::vector<BudEvent> record_jamming(std::vector<BudEvent>& ended) {
    const std::vector<BudEvent> closed = buds.close(BudEventKind::censored_unjam, step, phi, packing);
    ended.insert(ended.end(), closed.begin(), closed.end());
    JammingRecord j = jamming_record(view(), episodes++);
    std::vector<BudEvent> events = buds.tag(j.episode, step, phi, packing, net);
    j.tagged = events.size();
    start_episode(j);
    return events;
  }

  void start_episode(std::optional<JammingRecord> jamming) {
    result.jamming = std::move(jamming);
    result.targets.clear();
    result.depletion.reset();
    next_target = 0;
    divisions_since_jamming = 0;
  }

  // Every target landed by the accepted state (in order), then φ_2 if it is the first state with at
  // most scene.phi2_tagged_left tagged buds unconstrained.
  void land_targets_and_depletion(const StateView& v) {
    while (next_target < scene.targets.size() &&
           std::abs(phi - (result.jamming->phi + scene.targets[next_target])) <= scene.target_tolerance) {
      result.targets.push_back(target_record(v, next_target, scene.targets[next_target], result.jamming->phi));
      ++next_target;
      notify([&](Observer& o) { o.on_target_reached(TargetReached{v, result.targets.back()}); });
    }
    if (result.depletion || buds.active() > scene.phi2_tagged_left) return;
    result.depletion = depletion_record(v, buds.active());
    notify([&](Observer& o) { o.on_depleted(Depleted{v, *result.depletion}); });
  }

  RunStatus advance() {
    if (result.status != RunStatus::running) return result.status;
    if (!started) {
      start();
      return result.status;
    }
    if (attempts >= scene.max_steps) {
      fail(RunStatus::step_limit, "more than growth.max_steps = " + std::to_string(scene.max_steps) +
                                      " growth steps without reaching the end of the run");
      return result.status;
    }
    const long evaluations = result.force_evaluations, iterations = result.fire_iterations;
    const bool searching = phase == Phase::unjammed;
    relaxation_index = 0;
    before_attempt.reset();
    if (relaxation_save && step > 0 && !newton.factored) before_attempt = public_state();
    std::optional<Trial> trial = make_trial();
    before_attempt.reset();
    if (pending_relaxation)
      throw InputError(restored_from + ": growth attempt " + std::to_string(pending_relaxation->attempts) +
                       " made no relaxation " + std::to_string(pending_relaxation->index) +
                       " to resume (was the checkpoint written by another build?)");
    if (!trial) return result.status;
    if (searching) ++result.search_trials;
    if (result.force_evaluations - evaluations > kMarginalEvaluations) ++result.marginal_relaxations;
    const TrialVerdict verdict = judge(*trial);
    if (!observers.empty()) {
      TrialRelaxed relaxed = trial_relaxed(*trial, attempts, next.log_scale, verdict,
                                           result.fire_iterations - iterations, result.force_evaluations - evaluations);
      if (needs.trial_starts) {
        relaxed.start_packing = &trial_start;
        relaxed.minimiser = trial_params;
        relaxed.branch_start = trial_branch ? &*trial_branch : nullptr;
      }
      notify([&](Observer& o) { o.on_trial(relaxed); });
    }
    switch (verdict) {
      case TrialVerdict::rejected:
      case TrialVerdict::deferred: reject(std::move(*trial)); break;
      case TrialVerdict::below_window:
        ++result.rejected;
        search->keep_below(std::move(*trial));
        break;
      case TrialVerdict::stop:
        field.invalidate();
        result.status = RunStatus::finished;
        finish_events();
        return result.status;
      case TrialVerdict::accepted: take(std::move(*trial)); return result.status;
    }
    // The next attempt starts from the same accepted state, with the search's state (its open
    // bracket) and Δt: a complete state too, so a long search can be checkpointed between trials.
    if (result.status == RunStatus::running) save_checkpoint();
    return result.status;
  }

  // An accepted trial: the new accepted state, its records and events; then the end of the run or
  // a checkpoint.
  void take(Trial&& trial) {
    // The packing rules refuse lobes of different cells at r ≤ σ/2 (docs/model.md, "Degenerate
    // packings"): a run grown that deep ends at its last readable state instead of writing a packing
    // no reader takes.
    if (const auto problem = overlap_problem(trial.packing)) {
      fail(RunStatus::overlap_bound,
           attempt_text() + ": the relaxed state at phi = " + num(trial.packing.packing_fraction()) +
               " passes the packing rules' overlap bound (" + *problem + "); lower jamming.max_dphi or the targets");
      return;
    }
    const std::vector<Division> divisions = trial.divisions;
    const Change change = accept(std::move(trial));

    // Records first, so that every event of this state sees the same, final view.
    // The tags of this state's episode (or of the episode an unjamming ended) see the state first.
    std::vector<BudEvent> bud_events = buds.update(step, phi, packing, contacts, net, divisions), tagged;
    if (change == Change::unjammed) record_unjamming();
    if (change == Change::jammed) tagged = record_jamming(bud_events);

    const StateView v = view();
    for (const Division& d : divisions) notify([&](Observer& o) { o.on_divided(Divided{v, d}); });
    // Events in physical order: the buds tagged at a jamming follow the jamming they belong to.
    emit_bud_events(v, bud_events);
    notify([&](Observer& o) { o.on_step_accepted(StepAccepted{v}); });
    if (change == Change::unjammed) notify([&](Observer& o) { o.on_unjammed(Unjammed{v, result.unjammings.back()}); });
    if (change == Change::jammed) {
      notify([&](Observer& o) { o.on_jammed(Jammed{v, *result.jamming}); });
      emit_bud_events(v, tagged);
    }
    if (phase == Phase::jammed && change == Change::none) land_targets_and_depletion(v);

    if (phase == Phase::jammed && next_target == scene.targets.size() &&
        (!scene.continue_to_phi2 || result.depletion)) {
      result.status = RunStatus::finished;
      return finish_events();
    }
    if (scene.checkpoint_every > 0 && step % scene.checkpoint_every == 0) newton.clear();
    save_checkpoint();
  }
};

GrowthDriver::GrowthDriver(const Scene& scene, const DriverOptions& options)
    : impl_(std::make_unique<Impl>(scene, options)) {}
GrowthDriver::~GrowthDriver() = default;

void GrowthDriver::add_observer(Observer& observer) {
  impl_->observers.push_back(&observer);
  Needs n = observer.needs();
  if (n.network || n.bud_pressures) n.contacts = true;
  impl_->needs |= n;
}

RunStatus GrowthDriver::advance() { return impl_->advance(); }

RunStatus GrowthDriver::run() {
  while (impl_->advance() == RunStatus::running) {}
  return impl_->result.status;
}

void GrowthDriver::set_checkpoint_hook(std::function<void()> hook) { impl_->checkpoint_hook = std::move(hook); }
void GrowthDriver::set_relaxation_checkpoints(long every, std::function<bool()> requested,
                                              std::function<void(const GrowthState&)> save) {
  impl_->relaxation_every = every;
  impl_->relaxation_requested = std::move(requested);
  impl_->relaxation_save = std::move(save);
}
bool GrowthDriver::state_is_complete() const { return !impl_->newton.factored; }

// ---- checkpoints ---------------------------------------------------------------------------------

GrowthState GrowthDriver::state() const {
  if (!impl_->started) throw std::logic_error("GrowthDriver::state: the run has not started");
  return impl_->public_state();
}

void GrowthDriver::restore(GrowthState s, std::string source) {
  Impl& d = *impl_;
  if (s.seed != d.seed)
    throw InputError(source + ": seed " + std::to_string(s.seed) + " does not match the run's seed " +
                     std::to_string(d.seed));
  if (s.packing.box.L != d.scene.L) throw InputError(source + ": box side does not match the scene");
  d.restored_from = std::move(source);
  d.resume_unannounced = true;
  transfer(d, s);
  d.result.status = RunStatus::running;
  d.search->restore(std::move(s.search));
  d.pending_relaxation = std::move(s.relaxation);
  d.started = true;
  d.final_emitted = false;
  d.newton.clear();
  d.E = d.fresh_energy_per_cell(d.packing);
  d.derive();
}

const Scene& GrowthDriver::scene() const { return impl_->scene; }
std::uint64_t GrowthDriver::seed() const { return impl_->seed; }
const Packing& GrowthDriver::packing() const { return impl_->packing; }
const RunResult& GrowthDriver::result() const { return impl_->result; }
Phase GrowthDriver::phase() const { return impl_->phase; }
double GrowthDriver::dt() const { return impl_->dt; }
StateView GrowthDriver::view() const { return impl_->view(); }

}  // namespace budjam
