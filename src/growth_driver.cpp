#include "budjam/growth_driver.hpp"

#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/stability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
  double dt = 1.0;       // Δt of the next attempt
  double last_dt = 0.0;  // Δt of the step that produced the accepted state
  long step = 0, attempts = 0;
  bool started = false;
  RunResult result;
  std::size_t next_target = 0;
  long divisions_since_jamming = 0;
  int episodes = 0;  // jamming episodes begun
  BudTracker buds;

  // Derived from the accepted state (recomputed identically after a restore).
  double E = 0, P = 0, phi = 0;
  std::vector<Contact> contacts;
  bool have_contacts = false;
  ContactNetwork net;
  bool have_net = false;
  std::vector<double> pressures;
  bool have_pressures = false;
  std::size_t compressed = 0;
  double chi_c = 1.0;
  std::vector<double> rates;  // γ_i of the next step, frozen from the accepted state

  ForceField field;
  Eigen::VectorXd force;
  bool final_emitted = false;
  std::function<void()> checkpoint_hook;

  Impl(const Scene& s, const DriverOptions& o) : scene(s), field(s.skin) {
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

  // FIRE on a trial, counted; false (and the run failed) if it did not converge.
  bool relax(Packing& p, const FireParams& params, const std::string& where) {
    field.invalidate();
    const FireResult fr = minimise(p, field, params);
    result.force_evaluations += fr.evaluations + 1;
    result.fire_iterations += fr.iterations;
    if (!fr.converged)
      fail(RunStatus::minimiser_failed, "FIRE did not converge within minimiser.max_iterations = " +
                                            std::to_string(params.max_iterations) + " (" + where + ")");
    return fr.converged;
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
    if (have_pressures && scene.P0) {
      double sum = 0;
      std::size_t n = 0;
      for (double p : pressures)
        if (p > 0) sum += growth_factor(p, scene.P0), ++n;
      if (n) chi_c = sum / static_cast<double>(n);
    }
    rates = growth_rates(packing, feedback ? &pressures : nullptr, scene.P0);
  }

  // Δt that the next step starts from (before any bisection halving), from the accepted state.
  // MODEL.md: the nominal growth.dt. With growth.adaptive_dt, above jamming with feedback:
  // dt / max(g_max, adaptive_floor), g_max = max_i exp(−p_i/P0) = the factor of the least
  // compressed bud, so that the fastest-growing cell gains γ0_i·dt of relative area, as in a
  // nominal step. Depends on the accepted state only (a checkpoint restores it with Δt anyway).
  double start_dt() const {
    if (!(scene.adaptive_dt && phase == Phase::jammed && scene.P0 && have_pressures)) return scene.dt;
    double g_max = 0.0;
    for (double p : pressures) g_max = std::max(g_max, growth_factor(p, scene.P0));
    return scene.dt / std::max(g_max, scene.adaptive_floor);
  }

  StateView view() const {
    StateView v;
    v.step = step;
    v.attempts = attempts;
    v.dt = last_dt;
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
      if (result.status == RunStatus::finished) o->on_finished(Finished{v, result});
      else o->on_failed(Failed{v, result});
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
    t.N = packing.size();
    t.N_nr = net.N_nr;
    t.N_f = net.N_f;
    t.N_f_single = net.N_f_single_pass;
    t.N_c = net.N_c;
    t.N_u = net.N_u;
    t.N_u_buds = net.N_u_buds;
    t.Z = net.Z;
    t.u = net.u;
    t.u_buds = net.u_buds;
    t.Z_iso = net.Z_iso;
    t.dZ = net.dZ;
    t.chi_c = chi_c;
    t.divisions_since_jamming = divisions_since_jamming;
    return t;
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

    // Trial step on copies: a rejection leaves the accepted packing and RNG untouched.
    Packing trial = packing;
    Rng trial_rng = rng;
    const std::vector<Division> divisions = grow_step(trial, rates, dt, scene, trial_rng);
    ++attempts;
    if (!relax(trial, scene.fire, "growth step " + std::to_string(attempts) + ", dt = " + num(dt))) return result.status;
    const double eps = scene.epsilon_U;
    double E_trial = fresh_energy_per_cell(trial);
    if (scene.check_minimum && phase == Phase::unjammed && E_trial >= eps && E_trial <= 2.0 * eps &&
        !is_minimum(trial)) {
      // FIRE stopped on a saddle: relax on to its force resolution; the energy usually falls to 0.
      FireParams deep = scene.fire;
      deep.force_tol = 0;
      ++result.saddles_relaxed;
      if (!relax(trial, deep, "relaxing a saddle, growth step " + std::to_string(attempts))) return result.status;
      E_trial = fresh_energy_per_cell(trial);
    }
    const double phi_trial = trial.packing_fraction();

    bool reject = false;
    if (phase == Phase::unjammed) {
      reject = E_trial > 2.0 * eps;  // overshot jamming: bisect
    } else if (E_trial >= eps) {
      if (next_target < scene.targets.size()) {
        reject = phi_trial > result.jamming->phi + scene.targets[next_target] + scene.target_tolerance;
      } else if (scene.continue_to_phi2 && !result.depletion &&
                 phi_trial > result.jamming->phi + scene.max_dphi) {
        // φ_2 not found before φ_J + max_dphi: the run ends at the last accepted state.
        field.invalidate();
        result.status = RunStatus::finished;
        finish_events();
        return result.status;
      }
    }
    if (reject) {
      ++result.rejected;
      dt *= 0.5;
      if (dt < scene.dt_min)
        fail(RunStatus::dt_underflow, "growth step dt fell below growth.dt_min = " + num(scene.dt_min) +
                                          " (phase " + to_string(phase) + ", phi = " + num(phi) + ")");
      return result.status;
    }

    // Accept.
    packing = std::move(trial);
    rng = trial_rng;
    E = E_trial;
    ++step;
    ++result.accepted;
    last_dt = dt;
    result.divisions += static_cast<long>(divisions.size());

    bool jammed_now = false, unjammed_now = false;
    if (phase == Phase::unjammed && E >= eps) {
      phase = Phase::jammed;
      jammed_now = true;
    } else if (phase == Phase::jammed && E < eps) {
      phase = Phase::unjammed;
      unjammed_now = true;
    } else if (phase == Phase::jammed) {
      divisions_since_jamming += static_cast<long>(divisions.size());
    }
    derive();
    dt = start_dt();

    // Records first, so that every event of this state sees the same, final view.
    std::vector<BudEvent> bud_events;
    if (phase == Phase::jammed && !jammed_now)
      bud_events = buds.update(step, phi, packing, contacts, net, divisions);
    if (unjammed_now) {
      UnjamRecord r;
      r.episode = result.jamming->episode;
      r.step = step;
      r.phi = phi;
      r.phi_J = result.jamming->phi;
      r.targets_lost = result.targets.size();
      result.unjammings.push_back(r);
      bud_events = buds.close(BudEventKind::censored_unjam, step, phi, packing);
      // The search for jamming restarts: φ_J, the targets and φ_2 belong to the next episode.
      result.jamming.reset();
      result.targets.clear();
      result.depletion.reset();
      next_target = 0;
      divisions_since_jamming = 0;
    }
    if (jammed_now) {
      JammingRecord j;
      j.episode = episodes++;
      j.step = step;
      j.phi = phi;
      j.P = P;
      j.E_per_cell = E;
      j.N = packing.size();
      j.N_nr = net.N_nr;
      j.N_f = net.N_f;
      j.N_u = net.N_u;
      j.N_u_buds = net.N_u_buds;
      j.N_c = net.N_c;
      j.Z = net.Z;
      j.Z_iso = net.Z_iso;
      j.dZ = net.dZ;
      j.u = net.u;
      j.u_buds = net.u_buds;
      j.n_J = static_cast<double>(net.N_nr) / (packing.box.L * packing.box.L);
      bud_events = buds.tag(j.episode, step, phi, packing, net);
      j.tagged = bud_events.size();
      result.jamming = j;
      result.targets.clear();
      result.depletion.reset();
      next_target = 0;
      divisions_since_jamming = 0;
    }

    const StateView v = view();
    for (const Division& d : divisions)
      for (Observer* o : observers) o->on_divided(Divided{v, d});
    emit_bud_events(v, bud_events);
    for (Observer* o : observers) o->on_step_accepted(StepAccepted{v});
    if (unjammed_now)
      for (Observer* o : observers) o->on_unjammed(Unjammed{v, result.unjammings.back()});
    if (jammed_now)
      for (Observer* o : observers) o->on_jammed(Jammed{v, *result.jamming});

    if (phase == Phase::jammed && !jammed_now) {
      while (next_target < scene.targets.size() &&
             std::abs(phi - (result.jamming->phi + scene.targets[next_target])) <= scene.target_tolerance) {
        result.targets.push_back(target_record(next_target));
        ++next_target;
        for (Observer* o : observers) o->on_target_reached(TargetReached{v, result.targets.back()});
      }
      if (!result.depletion && buds.active() <= 1) {
        DepletionRecord d;
        d.step = step;
        d.phi = phi;
        d.P = P;
        d.N = packing.size();
        d.N_nr = net.N_nr;
        d.Z = net.Z;
        d.u = net.u;
        d.u_buds = net.u_buds;
        d.Z_iso = net.Z_iso;
        d.dZ = net.dZ;
        d.still_unconstrained = buds.active();
        d.divisions_since_jamming = divisions_since_jamming;
        result.depletion = d;
        for (Observer* o : observers) o->on_depleted(Depleted{v, *result.depletion});
      }
    }

    if (phase == Phase::jammed && next_target == scene.targets.size() &&
        (!scene.continue_to_phi2 || result.depletion)) {
      result.status = RunStatus::finished;
      finish_events();
      return result.status;
    }
    if (checkpoint_hook) checkpoint_hook();
    return result.status;
  }

  // ---- checkpoints ---------------------------------------------------------------------------
  GrowthState state() const {
    if (!started) throw std::logic_error("GrowthDriver::state: the run has not started");
    return GrowthState{seed,  rng,         phase, dt,     last_dt, step, attempts, next_target, divisions_since_jamming,
                       episodes, result, buds,  packing};
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
    step = s.step;
    attempts = s.attempts;
    next_target = s.next_target;
    divisions_since_jamming = s.divisions_since_jamming;
    episodes = s.episodes;
    result = std::move(s.result);
    result.status = RunStatus::running;
    buds = std::move(s.buds);
    packing = std::move(s.packing);
    started = true;
    final_emitted = false;
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
  while (impl_->advance() == RunStatus::running) {
  }
  return impl_->result.status;
}

void GrowthDriver::set_checkpoint_hook(std::function<void()> hook) { impl_->checkpoint_hook = std::move(hook); }
GrowthState GrowthDriver::state() const { return impl_->state(); }
void GrowthDriver::restore(GrowthState state) { impl_->restore(std::move(state)); }

const Scene& GrowthDriver::scene() const { return impl_->scene; }
std::uint64_t GrowthDriver::seed() const { return impl_->seed; }
const Packing& GrowthDriver::packing() const { return impl_->packing; }
const RunResult& GrowthDriver::result() const { return impl_->result; }
Phase GrowthDriver::phase() const { return impl_->phase; }
double GrowthDriver::dt() const { return impl_->dt; }
StateView GrowthDriver::view() const { return impl_->view(); }

}  // namespace budjam
