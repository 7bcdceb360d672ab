#include "budjam/growth_driver.hpp"

#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
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

const char* to_string(TrialStart start) {
  switch (start) {
    case TrialStart::accepted_state: return "accepted_state";
    case TrialStart::lowest_overshoot: return "lowest_overshoot";
    case TrialStart::settled: return "settled";
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

using Overshoot = JammingOvershoot;

// √(E/N) in the middle of the jamming window [ε_U, 2ε_U].
double window_centre(double eps) { return 0.5 * (1.0 + std::sqrt(2.0)) * std::sqrt(eps); }

// Slope ds/dφ of s = √(E/N) at an overjammed minimum, from its energy and pressure alone. Near φ_J,
// U ≈ C (φ − φ_J)², so φ − φ_J = 2U / (dU/dφ); growing every length by λ at fixed centroids is
// dU/dλ = 2U + Σ f r = 2U + 2L²P and dφ/dλ = 2φ, so dU/dφ ≈ (U + L²P)/φ. Buds grow alone and at
// different rates, so this is an estimate; the second overshoot replaces it by a secant.
double overshoot_slope(double phi, double s, double U, double P, double L) {
  const double dphi = 2.0 * U * phi / (U + L * L * P);
  return dphi > 0 ? s / dphi : 0.0;
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
  // Secant search: the relaxed trials of this unjammed phase that overshot the jamming window.
  std::vector<Overshoot> overshoots;
  int slow_trials = 0;       // consecutive trials that did not halve the bracket around φ_J
  double bracket_width = 0;  // φ from the accepted state to the lowest overshoot at the last trial

  // Derived from the accepted state (recomputed identically after a restore).
  double E = 0, P = 0, phi = 0;
  std::vector<Contact> contacts;
  bool have_contacts = false;
  ContactNetwork net;
  bool have_net = false;
  std::vector<double> pressures;
  bool have_pressures = false;
  std::size_t compressed = 0;
  double chi_c = 1.0, log_chi_c = 0.0;
  std::vector<double> rates;  // γ_i·e^{log_scale} of the next step, frozen from the accepted state
  StepStart next;             // where the next step starts, from the accepted state

  ForceField field;
  // The Newton factor kept from one minimisation to the next (arrested regime). Forgotten at every
  // checkpointed step, where a resumed run starts without one, so that it repeats the uninterrupted run.
  NewtonWorkspace newton;
  Eigen::VectorXd force;
  bool final_emitted = false;
  std::function<void()> checkpoint_hook;

  Impl(const Scene& s, const DriverOptions& o) : scene(s), field(s.skin, s.threads) {
    validate(scene);
    seed = o.seed ? *o.seed : scene.seed;
    rng.seed(seed);
    dt = scene.dt;
  }

  // U/N of `p` with a freshly built neighbour list, so that the list (and the order of the
  // contacts taken from it) depends only on the configuration, not on the history of rebuilds:
  // a resumed run then repeats an uninterrupted one bit for bit.
  double fresh_energy_per_cell(const Packing& p) {
    field.invalidate();
    const double U = field.evaluate(p, force);
    return p.size() ? U / static_cast<double>(p.size()) : 0.0;
  }

  // FIRE on a trial, counted; false (and the run failed) if it did not converge. With a `budget`
  // below params.max_iterations, FIRE stops there without failing the run: `*spent` tells.
  bool relax(Packing& p, const FireParams& params, const std::string& where, long budget = 0, bool* spent = nullptr) {
    field.invalidate();
    FireParams run = params;
    const bool budgeted = budget > 0 && budget < params.max_iterations;
    if (budgeted) run.max_iterations = budget;
    const FireResult fr = minimise(p, field, run, &newton);
    result.force_evaluations += fr.evaluations + 1;
    result.fire_iterations += fr.iterations;
    if (spent) *spent = budgeted && !fr.converged;
    if (!fr.converged && !budgeted)
      fail(RunStatus::minimiser_failed, "FIRE did not converge within minimiser.max_iterations = " +
                                            std::to_string(params.max_iterations) + " (" + where + ")");
    return fr.converged || budgeted;
  }

  // Whether `p` is a minimum of U (no unstable mode of its Hessian). Requires the field to be current
  // for `p` (fresh_energy_per_cell just called on it).
  bool is_minimum(const Packing& p) {
    const std::vector<Contact> c = find_contacts(p, field.lobes(), field.neighbours());
    return stability(p, c, analyse_network(p.size(), c)).minimum();
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
    have_net = jammed || (observe_here && needs.network);
    if (have_net) net = analyse_network(packing.size(), contacts);
    const bool feedback = jammed && scene.P0.has_value();
    have_pressures = feedback || (observe_here && needs.bud_pressures);
    if (have_pressures) pressures = bud_pressures(packing, contacts);
    compressed = 0;
    std::vector<char> touched(packing.size(), 0);
    for (const Contact& c : contacts) {
      if (is_bud(c.i)) touched[cell_of(c.i)] = 1;
      if (is_bud(c.j)) touched[cell_of(c.j)] = 1;
    }
    for (char t : touched) compressed += t ? 1 : 0;
    chi_c = 1.0;
    log_chi_c = 0.0;
    if (have_pressures && scene.P0) mean_compressed_factor();
    next = step_start();
    rates = growth_rates(packing, feedback ? &pressures : nullptr, scene.P0, next.log_scale);
  }

  // χ_c = ⟨exp(−p/P0)⟩ over compressed buds, and ln χ_c by log-sum-exp about the largest factor, which
  // survives when every factor underflows.
  void mean_compressed_factor() {
    double sum = 0, log_top = -std::numeric_limits<double>::infinity();
    std::size_t n = 0;
    for (double p : pressures) {
      if (!(p > 0)) continue;
      sum += growth_factor(p, scene.P0);
      log_top = std::max(log_top, log_growth_factor(p, scene.P0));
      ++n;
    }
    if (!n) return;
    chi_c = sum / static_cast<double>(n);
    double relative = 0;  // Σ exp(ln g_i − ln g_top) ≥ 1
    for (double p : pressures)
      if (p > 0) relative += std::exp(log_growth_factor(p, scene.P0) - log_top);
    log_chi_c = log_top + std::log(relative / static_cast<double>(n));
  }

  // Δt that the next step starts from (before any bisection halving), from the accepted state.
  // The nominal growth.dt (docs/model.md, "Growth protocol"). With growth.adaptive_dt, above jamming with feedback:
  // dt / max(g_max, adaptive_floor), g_max = max_i exp(−p_i/P0) = the factor of the least
  // compressed bud, so that the fastest-growing cell gains γ0_i·dt of relative area, as in a
  // nominal step. While every factor and that Δt are doubles it is stored as it is (log_scale 0);
  // else the step is stored as dt, log_scale = −ln max(g_max, floor) and the rates are scaled by
  // e^{log_scale}: the growth γ0_i·dt·exp(−p_i/P0)/max(g_max, floor) is then exact at any p/P0.
  StepStart step_start() const {
    if (!(scene.adaptive_dt && phase == Phase::jammed && scene.P0 && have_pressures) || pressures.empty())
      return {scene.dt, 0.0};
    double g_max = 0.0, log_g_max = -std::numeric_limits<double>::infinity();
    bool underflow = false;  // the plain form would lose some bud's growth
    for (double p : pressures) {
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

  // Δt of a step stored as `scaled` with `log_scale`, and its logarithm.
  static double unscaled_dt(double scaled, double log_scale) {
    return log_scale == 0.0 ? scaled : scaled * std::exp(log_scale);
  }
  static double log_dt(double scaled, double log_scale) { return std::log(scaled) + log_scale; }

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
    v.divisions_since_jamming = phase == Phase::jammed ? divisions_since_jamming : 0;
    v.compressed_buds = compressed;
    v.chi_c = chi_c;
    v.log_chi_c = log_chi_c;
    return v;
  }

  void emit_bud_events(const StateView& v, const std::vector<BudEvent>& events) {
    for (const BudEvent& e : events)
      for (Observer* o : observers) o->on_bud_event(BudEventHappened{v, e});
  }

  void start() {
    packing = initial_state(scene, rng);
    field.invalidate();
    const FireResult fr = minimise(packing, field, scene.fire);
    result.force_evaluations += fr.evaluations + 1;
    result.fire_iterations += fr.iterations;
    started = true;
    if (!fr.converged) {
      E = fresh_energy_per_cell(packing);
      derive();
      return fail(RunStatus::minimiser_failed, "FIRE did not converge on the initial state");
    }
    E = fresh_energy_per_cell(packing);
    if (E >= scene.epsilon_U)
      throw InputError("init: the relaxed initial state is already jammed (E/N = " + num(E) + ")");
    derive();
    const StateView v = view();
    for (Observer* o : observers) o->on_step_accepted(StepAccepted{v});
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
    if (phase == Phase::jammed) emit_bud_events(v, buds.close(BudEventKind::censored_end, step, phi, packing));
    for (Observer* o : observers) {
      if (result.status == RunStatus::finished)
        o->on_finished(Finished{v, result});
      else
        o->on_failed(Failed{v, result});
    }
  }

  TargetRecord target_record(std::size_t k) const {
    TargetRecord t;
    t.index = k;
    t.dphi = scene.targets[k];
    t.phi_target = result.jamming->phi + scene.targets[k];
    t.step = step;
    t.phi = phi;
    t.P = P;
    t.E_per_cell = E;
    t.network = net.summary();
    t.chi_c = chi_c;
    t.divisions_since_jamming = divisions_since_jamming;
    return t;
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

  // A Δt in (dt_lo, dt_hi] with |φ(Δt) − goal| ≤ tol, by bisection from φ(dt_lo) < goal < φ(dt_hi).
  // φ rises continuously with Δt except at divisions, where it drops, so the bracket always closes
  // on a continuous crossing. Returns the lower end if the bracket shrinks to nothing first.
  double dt_for_phi(double goal, double dt_lo, double dt_hi, double tol) const {
    double lo = dt_lo, hi = dt_hi;
    while (true) {
      const double mid = 0.5 * (lo + hi);
      if (!(mid > lo && mid < hi)) return lo;
      const double miss = phi_after(mid) - goal;
      if (std::abs(miss) <= tol) return mid;
      (miss < 0 ? lo : hi) = mid;
    }
  }

  // s = √(E/N) on the line through the lowest overshoot: the secant through the two lowest, or the
  // virial slope of the lowest alone. Requires overshoots sorted by φ, not empty.
  double overshoot_line_slope() const {
    const Overshoot& a = overshoots[0];
    if (overshoots.size() >= 2 && overshoots[1].s > a.s) return (overshoots[1].s - a.s) / (overshoots[1].phi - a.phi);
    return a.slope;
  }

  // After an unjammed state was accepted: overshoots at or below it are gone, and an overshoot
  // found from an earlier accepted state whose line puts this unjammed state above the jamming
  // window does not hold on this path (φ_J depends on the path): dropped too.
  void prune_overshoots() {
    std::erase_if(overshoots, [&](const Overshoot& o) { return o.phi <= phi; });
    std::sort(overshoots.begin(), overshoots.end(),
              [](const Overshoot& a, const Overshoot& b) { return a.phi < b.phi; });
    const double s_top = std::sqrt(2.0 * scene.epsilon_U);
    while (!overshoots.empty() && overshoots[0].s - overshoot_line_slope() * (overshoots[0].phi - phi) > s_top)
      overshoots.erase(overshoots.begin());
  }

  // The φ the next trial of the secant search aims at: where s = √(E/N) reaches the middle of the
  // jamming window on the line through the lowest overshoot, kept strictly inside the bracket
  // (φ, lowest overshoot). Two trials in a row that do not halve the bracket make the next one a
  // bisection, so the search is never slower than halving. nullopt without an overshoot.
  std::optional<double> search_goal() {
    if (overshoots.empty()) return std::nullopt;
    std::sort(overshoots.begin(), overshoots.end(),
              [](const Overshoot& a, const Overshoot& b) { return a.phi < b.phi; });
    const Overshoot& a = overshoots.front();
    const double width = a.phi - phi;
    slow_trials = (bracket_width > 0 && width > 0.5 * bracket_width) ? slow_trials + 1 : 0;
    bracket_width = width;
    double goal = phi + 0.5 * width;
    const double slope = overshoot_line_slope();
    if (slow_trials >= 2)
      slow_trials = 0;
    else if (slope > 0)
      goal = a.phi - (a.s - window_centre(scene.epsilon_U)) / slope;
    return std::clamp(goal, phi + width / 32, a.phi - width / 32);
  }

  // Δt of the next trial: the nominal (or bisected) dt, or with the secant search, the Δt that
  // reaches the search's goal below jamming or lands the next target exactly above it.
  double trial_dt() {
    if (scene.search == JammingSearch::bisection) return dt;
    if (phase == Phase::unjammed && scene.search == JammingSearch::bracket) return bracket ? bracket_dt() : dt;
    if (phase == Phase::unjammed) {
      const std::optional<double> goal = search_goal();
      return goal ? dt_for_phi(*goal, 0, dt, 1e-3 * bracket_width) : dt;
    }
    if (next_target < scene.targets.size()) {
      const double goal = result.jamming->phi + scene.targets[next_target];
      if (phi_after(dt) > goal + scene.target_tolerance) return dt_for_phi(goal, 0, dt, 0.5 * scene.target_tolerance);
    }
    return dt;
  }

  // (φ, s, slope) of a relaxed trial above the jamming window. Requires the field to be current for
  // `trial`.
  Overshoot overshoot_of(const Packing& trial, double E_trial) const {
    const std::vector<Contact> c = find_contacts(trial, field.lobes(), field.neighbours());
    const double s = std::sqrt(E_trial), phi_trial = trial.packing_fraction();
    return {phi_trial, s,
            overshoot_slope(phi_trial, s, E_trial * static_cast<double>(trial.size()), pressure(c, trial.box),
                            trial.box.L)};
  }

  // `step` is scaled (a trial's dt): Δt < dt_min ⇔ step < dt_min·e^{−log_scale}.
  bool fail_below_dt_min(double step) {
    if (step >= scene.dt_min * std::exp(-next.log_scale)) return false;
    fail(RunStatus::dt_underflow, "growth step dt fell below growth.dt_min = " + num(scene.dt_min) + " (phase " +
                                      to_string(phase) + ", phi = " + num(phi) + ")");
    return true;
  }

  void reset_search() {
    overshoots.clear();
    slow_trials = 0;
    bracket_width = 0;
    bracket.reset();
  }

  // ---- one growth attempt -------------------------------------------------------------------
  // A relaxed trial step, made on copies: a rejection leaves the accepted packing and RNG untouched.
  struct Trial {
    Packing packing;
    Rng rng;
    std::vector<Division> divisions;
    double dt = 0, E = 0;
    TrialStart start = TrialStart::accepted_state;
    // Its relaxation spent jamming.trial_budget far above the window: an upper end of the bracket
    // until the bracket collapses onto it; then it is relaxed on (resume_top).
    bool deferred = false;
  };
  // A trial is deferred only with E/N above this many times the top of the window at its budget.
  static constexpr double kDeferAbove = 100.0;

  // ---- bracket search (jamming.search = bracket) ---------------------------------------------
  // From the fixed accepted state, φ_J lies between the largest Δt whose trial relaxed below the
  // jamming window and the smallest whose trial overshot it. Opened by the first overshoot, closed
  // by the next accepted state: never open at a checkpoint.
  struct BracketEnd {
    Trial trial;     // relaxed
    Overshoot line;  // its (φ, s = √(E/N), slope)
  };
  struct Bracket {
    std::optional<Trial> below;     // the highest trial below the window, relaxed only to E/N < ε_U
    std::vector<BracketEnd> above;  // the two relaxed overshoots of smallest Δt and the deferred trials
                                    // beneath them, smallest Δt first
    int slow_trials = 0;            // consecutive trials that did not halve the bracket
    double width = 0;               // Δt width of the bracket at the last trial
  };
  std::optional<Bracket> bracket;

  double bracket_lo() const { return bracket->below ? bracket->below->dt : 0.0; }
  double bracket_phi_lo() const { return bracket->below ? bracket->below->packing.packing_fraction() : phi; }

  // ds/dφ of the line through the lowest overshoot: the secant through the two lowest (same base,
  // so the same function s(Δt)), or the virial slope of the lowest alone (also when either is a
  // deferred trial, whose s is only an upper bound).
  double bracket_slope() const {
    const std::vector<BracketEnd>& above = bracket->above;
    const Overshoot& a = above[0].line;
    const bool relaxed = above.size() >= 2 && !above[0].trial.deferred && !above[1].trial.deferred;
    if (relaxed && above[1].line.s > a.s && above[1].line.phi > a.phi)
      return (above[1].line.s - a.s) / (above[1].line.phi - a.phi);
    return a.slope;
  }

  // Δt of the next trial in the bracket: where the line through the lowest overshoot reaches the
  // middle of the window (φ(Δt) solved for between the ends), at least 1/32 of the bracket from
  // either end; after two trials that did not halve the bracket, its middle.
  double bracket_dt() {
    Bracket& b = *bracket;
    const Overshoot& a = b.above[0].line;
    const double lo = bracket_lo(), hi = b.above[0].trial.dt, width = hi - lo;
    b.slow_trials = (b.width > 0 && width > 0.5 * b.width) ? b.slow_trials + 1 : 0;
    b.width = width;
    double step = lo + 0.5 * width;
    const double slope = bracket_slope();
    if (b.slow_trials >= 2) {
      b.slow_trials = 0;
    } else if (slope > 0) {
      const double goal = a.phi - (a.s - window_centre(scene.epsilon_U)) / slope, phi_lo = bracket_phi_lo();
      if (goal > phi_lo && goal < a.phi) step = dt_for_phi(goal, lo, hi, 1e-3 * (a.phi - phi_lo));
    }
    return std::clamp(step, lo + width / 32, hi - width / 32);
  }

  // Whether no trial can land in the window: the bracket, from a trial below it, has shrunk to an
  // eighth of the distance the line puts between its upper end and the middle of the window (or
  // below growth.dt_min), so s jumps across the window (a division, or the relaxation falling into
  // another basin); or s visibly jumps at the lower end (jumps_at_lower_end). Without a trial below,
  // the search goes on (to dt_underflow at worst).
  bool bracket_collapsed() const {
    if (!bracket->below) return false;
    if (bracket->above.empty()) return true;  // its only upper end, resumed, relaxed below the window
    const Overshoot& a = bracket->above[0].line;
    const double slope = bracket_slope();
    const double reach = slope > 0 ? (a.s - window_centre(scene.epsilon_U)) / slope : 0.0;
    return a.phi - bracket_phi_lo() < reach / 8 || bracket->above[0].trial.dt - bracket_lo() < scene.dt_min ||
           jumps_at_lower_end();
  }

  // Overshoots relaxed from the lowest one form one branch of minima, on which s = √(E/N) is nearly
  // linear in φ. When the two lowest lie on it close to the lower end (the farther at most
  // kNearLowerEnd times as far from it as the nearer, so the line is a local one) and their line
  // meets the lower end far above the window, the branch does not come down to the window before
  // the lower end: s jumps there. Without this test the bracket would halve towards the lower end
  // with overshoots whose E/N levels off above the window, each a marginal relaxation, until its
  // width decides (docs/growth.md, "Jamming search").
  bool jumps_at_lower_end() const {
    constexpr double kNearLowerEnd = 4.0;
    const std::vector<BracketEnd>& above = bracket->above;
    if (scene.jump_factor <= 0 || above.size() < 2) return false;
    if (above[0].trial.start != TrialStart::lowest_overshoot || above[1].trial.start != TrialStart::lowest_overshoot)
      return false;
    if (above[0].trial.deferred || above[1].trial.deferred) return false;  // their E/N is still falling
    const Overshoot &a = above[0].line, &b = above[1].line;
    const double lo = bracket_phi_lo();
    if (!(b.phi > a.phi && a.phi > lo) || b.phi - lo > kNearLowerEnd * (a.phi - lo)) return false;
    const double s_at_lo = a.s - (b.s - a.s) / (b.phi - a.phi) * (a.phi - lo);
    return s_at_lo > scene.jump_factor * std::sqrt(2.0 * scene.epsilon_U);
  }

  // The fallback of a collapsed bracket: its highest trial below the window, relaxed on to the
  // ordinary stopping rule, is the next accepted (unjammed) state. nullopt if the run failed. The
  // trial was counted rejected when it narrowed the bracket; it is one attempt, now accepted
  // (accepted + rejected = attempts, which a checkpoint is checked against).
  std::optional<Trial> settle_below() {
    Trial t = std::move(*bracket->below);
    bracket.reset();
    if (!relax(t.packing, trial_minimiser(), "settling the bracket, growth step " + std::to_string(attempts)))
      return std::nullopt;
    --result.rejected;
    t.E = fresh_energy_per_cell(t.packing);
    t.start = TrialStart::settled;
    return t;
  }

  // A trial inside the bracket starts from the relaxed positions of the lowest overshoot: they lie
  // next to the jammed configuration. The overshoot's larger step may have divided more cells; those
  // are put back together from their newborns (start_across_divisions; otherwise such a trial starts
  // from the accepted state). Shrunk back towards the accepted state's sizes, an overshoot's
  // configuration may however stay jammed where the accepted state's is not: until a trial has
  // relaxed below the window, an overshoot that was itself started so is not started from again (the
  // next trial starts from the accepted state), so that the bracket always closes.
  void start_from_overshoot(Trial& t) const {
    const Trial& top = bracket->above[0].trial;
    if (!bracket->below && top.start == TrialStart::lowest_overshoot) return;
    const auto same = [](const Division& a, const Division& b) { return a.mother_index == b.mother_index; };
    if (!scene.start_across_divisions && !std::ranges::equal(t.divisions, top.divisions, same)) return;
    std::optional<Eigen::VectorXd> q = coordinates_before_divisions(top.packing, top.divisions, t.divisions);
    if (!q) return;
    t.packing.q = std::move(*q);
    t.start = TrialStart::lowest_overshoot;
  }

  // A deferred upper end is worth its remaining relaxation only once the bracket has collapsed onto
  // it: trials beneath it are cheap (they relax below the window, or overshoot it and make it moot,
  // or land in it), its remaining creep is not.
  bool top_to_resume() const {
    return !bracket->above.empty() && bracket->above.front().trial.deferred && bracket_collapsed();
  }

  // The deferred upper end, relaxed on to convergence from where its budget ended, is judged again as
  // the same attempt (counted rejected until then). Whether it overshoots, lands in the window or
  // falls below it, the bracket stays consistent. nullopt if the run failed.
  std::optional<Trial> resume_top() {
    Trial t = std::move(bracket->above.front().trial);
    bracket->above.erase(bracket->above.begin());
    --result.rejected;
    t.deferred = false;
    if (!relax(t.packing, trial_minimiser(), "resuming a deferred trial, growth step " + std::to_string(attempts)))
      return std::nullopt;
    t.E = fresh_energy_per_cell(t.packing);
    if (!relax_if_saddle(t)) return std::nullopt;
    return t;
  }

  // A relaxed jamming candidate that is a saddle of U (FIRE stopped on it) is relaxed on to FIRE's
  // force resolution; the energy usually falls to 0. false if the run failed.
  bool relax_if_saddle(Trial& t) {
    const double eps = scene.epsilon_U;
    if (!scene.check_minimum || phase != Phase::unjammed || t.E < eps || t.E > 2.0 * eps || is_minimum(t.packing))
      return true;
    FireParams deep = scene.fire;
    deep.force_tol = 0;
    ++result.saddles_relaxed;
    if (!relax(t.packing, deep, "relaxing a saddle, growth step " + std::to_string(attempts))) return false;
    t.E = fresh_energy_per_cell(t.packing);
    return true;
  }

  // An overshoot is the new upper end of the bracket (trials lie inside it), opening it if needed.
  // Requires the field to be current for the trial.
  void lower_bracket_top(Trial&& t) {
    const Overshoot line = overshoot_of(t.packing, t.E);
    if (!bracket) bracket = Bracket{};
    std::vector<BracketEnd>& above = bracket->above;
    above.insert(above.begin(), BracketEnd{std::move(t), line});
    // The two lowest relaxed overshoots stay, and the deferred trials beneath them: a deferred trial
    // may yet relax below the window, and the bracket then still has its relaxed upper end.
    int relaxed = 0;
    const auto last =
        std::ranges::find_if(above, [&](const BracketEnd& e) { return !e.trial.deferred && ++relaxed == 2; });
    if (last != above.end()) above.erase(std::next(last), above.end());
  }

  // Grows and relaxes a trial from the accepted state; a jamming candidate that is a saddle is
  // relaxed on. nullopt if the run failed (minimiser or Δt below dt_min).
  std::optional<Trial> make_trial() {
    if (bracket && top_to_resume()) return resume_top();
    if (bracket && bracket_collapsed()) return settle_below();
    Trial t{packing, rng, {}, trial_dt(), 0};
    if (fail_below_dt_min(t.dt)) return std::nullopt;
    t.divisions = grow_step(t.packing, rates, t.dt, scene, t.rng);
    ++attempts;
    if (bracket) start_from_overshoot(t);
    // Inside an open bracket a trial only has to be placed above or below the window: one that
    // creeps on past the budget far above the window is set aside as a deferred upper end. Near the
    // window it is relaxed on: it may be the jamming point, and a deferred trial there would only
    // draw the next trials onto itself (docs/growth.md, "Jamming search").
    const std::string where =
        "growth step " + std::to_string(attempts) + ", dt = " + num(unscaled_dt(t.dt, next.log_scale));
    const long budget = bracket ? scene.trial_budget : 0;
    if (!relax(t.packing, trial_minimiser(), where, budget, &t.deferred)) return std::nullopt;
    t.E = fresh_energy_per_cell(t.packing);
    if (t.deferred && t.E <= kDeferAbove * 2.0 * scene.epsilon_U) {
      t.deferred = false;
      if (!relax(t.packing, trial_minimiser(), where)) return std::nullopt;
      t.E = fresh_energy_per_cell(t.packing);
    }
    if (t.deferred) return t;
    if (!relax_if_saddle(t)) return std::nullopt;
    return t;
  }

  // The Newton finish only above jamming: below it the trials are unjammed or marginal, their
  // Hessian is indefinite and Newton would cost a factorisation for nothing (docs/minimiser.md).
  // Inside an open bracket a trial is only classified, so its relaxation stops as soon as E/N < ε_U:
  // the energy only falls, so it is certainly below the window.
  FireParams trial_minimiser() const {
    FireParams params = scene.fire;
    if (phase == Phase::unjammed) params.newton_force = 0;
    if (bracket) params.energy_floor = std::max(params.energy_floor, scene.epsilon_U);
    return params;
  }

  // The decision table of docs/growth.md ("Protocol") for a relaxed trial.
  TrialVerdict judge(const Trial& t) const {
    const double eps = scene.epsilon_U, phi_trial = t.packing.packing_fraction();
    if (t.deferred) return TrialVerdict::deferred;  // E/N ≥ ε_U (the floor did not stop it), still falling
    if (bracket && t.E < eps) return TrialVerdict::below_window;  // below the window: the bracket's new lower end
    if (phase == Phase::unjammed)
      return t.E > 2.0 * eps ? TrialVerdict::rejected : TrialVerdict::accepted;  // overshot jamming
    if (t.E < eps) return TrialVerdict::accepted;                                // unjamming
    if (next_target < scene.targets.size())
      return phi_trial > result.jamming->phi + scene.targets[next_target] + scene.target_tolerance
                 ? TrialVerdict::rejected
                 : TrialVerdict::accepted;
    // φ_2 not found before φ_J + max_dphi: the run ends at the last accepted state.
    if (scene.continue_to_phi2 && !result.depletion && phi_trial > result.jamming->phi + scene.max_dphi)
      return TrialVerdict::stop;
    return TrialVerdict::accepted;
  }

  void reject(Trial&& t) {
    ++result.rejected;
    if (phase == Phase::unjammed && scene.search == JammingSearch::secant) {
      overshoots.push_back(overshoot_of(t.packing, t.E));
      return;
    }
    if (phase == Phase::unjammed && scene.search == JammingSearch::bracket) {
      lower_bracket_top(std::move(t));
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
    Change change = Change::none;
    if (phase == Phase::unjammed && E >= scene.epsilon_U) {
      phase = Phase::jammed;
      change = Change::jammed;
      reset_search();
    } else if (phase == Phase::jammed && E < scene.epsilon_U) {
      phase = Phase::unjammed;
      change = Change::unjammed;
      reset_search();
    } else if (phase == Phase::jammed) {
      divisions_since_jamming += static_cast<long>(t.divisions.size());
    }
    derive();
    if (phase == Phase::unjammed) prune_overshoots();
    dt = next.dt;
    return change;
  }

  // The jamming episode ends: φ_J, the targets and φ_2 belong to the next one.
  std::vector<BudEvent> record_unjamming() {
    UnjamRecord r;
    r.episode = result.jamming->episode;
    r.step = step;
    r.phi = phi;
    r.phi_J = result.jamming->phi;
    r.targets_lost = result.targets.size();
    result.unjammings.push_back(r);
    std::vector<BudEvent> events = buds.close(BudEventKind::censored_unjam, step, phi, packing);
    start_episode(std::nullopt);
    return events;
  }

  std::vector<BudEvent> record_jamming() {
    JammingRecord j;
    j.episode = episodes++;
    j.step = step;
    j.phi = phi;
    j.P = P;
    j.E_per_cell = E;
    j.network = net.summary();
    j.n_J = static_cast<double>(net.N_nr) / (packing.box.L * packing.box.L);
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
      result.targets.push_back(target_record(next_target));
      ++next_target;
      for (Observer* o : observers) o->on_target_reached(TargetReached{v, result.targets.back()});
    }
    if (result.depletion || buds.active() > scene.phi2_tagged_left) return;
    DepletionRecord d;
    d.step = step;
    d.phi = phi;
    d.P = P;
    d.network = net.summary();
    d.still_unconstrained = buds.active();
    d.divisions_since_jamming = divisions_since_jamming;
    result.depletion = d;
    for (Observer* o : observers) o->on_depleted(Depleted{v, *result.depletion});
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
    std::optional<Trial> trial = make_trial();
    if (!trial) return result.status;
    const TrialVerdict verdict = judge(*trial);
    if (!observers.empty()) {
      const TrialRelaxed relaxed{attempts,
                                 unscaled_dt(trial->dt, next.log_scale),
                                 log_dt(trial->dt, next.log_scale),
                                 trial->packing.size(),
                                 trial->packing.packing_fraction(),
                                 trial->E,
                                 trial->start,
                                 verdict,
                                 result.fire_iterations - iterations,
                                 result.force_evaluations - evaluations};
      for (Observer* o : observers) o->on_trial(relaxed);
    }
    switch (verdict) {
      case TrialVerdict::rejected:
      case TrialVerdict::deferred: reject(std::move(*trial)); return result.status;
      case TrialVerdict::below_window:
        ++result.rejected;
        bracket->below = std::move(*trial);
        return result.status;
      case TrialVerdict::stop:
        field.invalidate();
        result.status = RunStatus::finished;
        finish_events();
        return result.status;
      case TrialVerdict::accepted: break;
    }
    const std::vector<Division> divisions = trial->divisions;
    const Change change = accept(std::move(*trial));

    // Records first, so that every event of this state sees the same, final view.
    std::vector<BudEvent> bud_events;
    if (phase == Phase::jammed && change == Change::none)
      bud_events = buds.update(step, phi, packing, contacts, net, divisions);
    if (change == Change::unjammed) bud_events = record_unjamming();
    if (change == Change::jammed) bud_events = record_jamming();

    const StateView v = view();
    for (const Division& d : divisions)
      for (Observer* o : observers) o->on_divided(Divided{v, d});
    // Events in physical order: the buds tagged at a jamming follow the jamming they belong to.
    if (change != Change::jammed) emit_bud_events(v, bud_events);
    for (Observer* o : observers) o->on_step_accepted(StepAccepted{v});
    if (change == Change::unjammed)
      for (Observer* o : observers) o->on_unjammed(Unjammed{v, result.unjammings.back()});
    if (change == Change::jammed) {
      for (Observer* o : observers) o->on_jammed(Jammed{v, *result.jamming});
      emit_bud_events(v, bud_events);
    }
    if (phase == Phase::jammed && change == Change::none) land_targets_and_depletion(v);

    if (phase == Phase::jammed && next_target == scene.targets.size() &&
        (!scene.continue_to_phi2 || result.depletion)) {
      result.status = RunStatus::finished;
      finish_events();
      return result.status;
    }
    if (scene.checkpoint_every > 0 && step % scene.checkpoint_every == 0) newton.clear();
    if (checkpoint_hook) checkpoint_hook();
    return result.status;
  }

  // ---- checkpoints ---------------------------------------------------------------------------
  GrowthState state() const {
    if (!started) throw std::logic_error("GrowthDriver::state: the run has not started");
    return GrowthState{
        .seed = seed,
        .rng = rng,
        .phase = phase,
        .dt = dt,
        .last_dt = last_dt,
        .last_log_scale = last_log_scale,
        .step = step,
        .attempts = attempts,
        .next_target = next_target,
        .divisions_since_jamming = divisions_since_jamming,
        .episodes = episodes,
        .result = result,
        .buds = buds,
        .packing = packing,
        .search = JammingSearchState{overshoots, slow_trials, bracket_width},
    };
  }

  void restore(GrowthState s) {
    if (s.seed != seed)
      throw InputError("checkpoint: seed " + std::to_string(s.seed) + " does not match the run's seed " +
                       std::to_string(seed));
    if (s.packing.box.L != scene.L) throw InputError("checkpoint: box side does not match the scene");
    rng = s.rng;
    phase = s.phase;
    dt = s.dt;
    last_dt = s.last_dt;
    last_log_scale = s.last_log_scale;
    step = s.step;
    attempts = s.attempts;
    next_target = s.next_target;
    divisions_since_jamming = s.divisions_since_jamming;
    episodes = s.episodes;
    result = std::move(s.result);
    result.status = RunStatus::running;
    buds = std::move(s.buds);
    packing = std::move(s.packing);
    overshoots = std::move(s.search.overshoots);
    slow_trials = s.search.slow_trials;
    bracket_width = s.search.bracket_width;
    started = true;
    final_emitted = false;
    newton.clear();
    E = fresh_energy_per_cell(packing);
    derive();
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
GrowthState GrowthDriver::state() const { return impl_->state(); }
bool GrowthDriver::state_is_complete() const { return !impl_->newton.factored; }
void GrowthDriver::restore(GrowthState state) { impl_->restore(std::move(state)); }

const Scene& GrowthDriver::scene() const { return impl_->scene; }
std::uint64_t GrowthDriver::seed() const { return impl_->seed; }
const Packing& GrowthDriver::packing() const { return impl_->packing; }
const RunResult& GrowthDriver::result() const { return impl_->result; }
Phase GrowthDriver::phase() const { return impl_->phase; }
double GrowthDriver::dt() const { return impl_->dt; }
StateView GrowthDriver::view() const { return impl_->view(); }

}  // namespace budjam
