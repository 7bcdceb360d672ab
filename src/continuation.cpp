// Continuation of a relaxed branch under growth (see continuation.hpp).
#include "budjam/continuation.hpp"

#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/fire.hpp"
#include "budjam/hessian.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

namespace budjam {

namespace {

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

double area_term(double b) { return kMotherDiameter * kMotherDiameter + b * b; }

// The lobe pairs in contact with a force above `tol`, sorted (the neighbour list's order depends on
// its rebuilds). A contact with a smaller force is no contact within the corrector's tolerance: a
// pair grazing along the branch would otherwise open and close at every step by rounding.
Pairs network(const std::vector<Contact>& contacts, double tol) {
  Pairs pairs;
  for (const Contact& c : contacts)
    if (c.force() > tol) pairs.emplace_back(c.i, c.j);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// The events between two consecutive points of the branch.
void record_events(const Pairs& before, const Pairs& after, double t, std::vector<BranchEvent>& events) {
  Pairs opened, closed;
  std::set_difference(before.begin(), before.end(), after.begin(), after.end(), std::back_inserter(opened));
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(), std::back_inserter(closed));
  for (const auto& [i, j] : opened) events.push_back({BranchEvent::Kind::opening, t, i, j});
  for (const auto& [i, j] : closed) events.push_back({BranchEvent::Kind::closing, t, i, j});
}

// d(mother_offset)/db and d(bud_offset)/db of Dumbbell::of.
std::pair<double, double> offset_derivatives(double b) {
  const double D2 = kMotherDiameter * kMotherDiameter, A = D2 + b * b;
  const double S = 0.5 * (kMotherDiameter + b), g = 2.0 * b * D2 / (A * A);
  return {0.5 * b * b / A + S * g, 0.5 * D2 / A - S * g};
}

}  // namespace

std::vector<double> BranchSizes::at(double t) const {
  if (t == 0.0) return from;
  if (t == 1.0) return to;
  std::vector<double> b(from.size());
  for (std::size_t i = 0; i < b.size(); ++i) {
    const double area = (1.0 - t) * area_term(from[i]) + t * area_term(to[i]);
    b[i] = std::sqrt(std::max(0.0, area - kMotherDiameter * kMotherDiameter));
  }
  return b;
}

std::vector<double> BranchSizes::rate(double t) const {
  const std::vector<double> b = at(t);
  std::vector<double> r(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) r[i] = (area_term(to[i]) - area_term(from[i])) / (2.0 * b[i]);
  return r;
}

Eigen::VectorXd force_rate(const Packing& p, const std::vector<Contact>& contacts, const std::vector<double>& b_rate) {
  Eigen::VectorXd rate = Eigen::VectorXd::Zero(p.q.size());
  // Per lobe: dR/dt and ds/dt of its signed offset s along n̂ (−mother_offset or +bud_offset).
  const auto lobe_rates = [&](std::size_t lobe) {
    const std::size_t cell = cell_of(lobe);
    const auto [d_mother, d_bud] = offset_derivatives(p.b[cell]);
    const double db = b_rate[cell];
    return is_bud(lobe) ? std::make_pair(0.5 * db, d_bud * db) : std::make_pair(0.0, -d_mother * db);
  };
  for (const Contact& c : contacts) {
    if (!(c.r > 0.0)) continue;  // coincident centres: no derivative of the normal
    const std::size_t ci = cell_of(c.i), cj = cell_of(c.j);
    const auto [dR_a, ds_a] = lobe_rates(c.i);
    const auto [dR_b, ds_b] = lobe_rates(c.j);
    const double s_a = lobe_offset(p, c.i), s_b = lobe_offset(p, c.j);
    const Eigen::Vector2d n(c.nx, c.ny);
    const Eigen::Vector2d e_i(std::cos(p.theta(ci)), std::sin(p.theta(ci)));
    const Eigen::Vector2d e_j(std::cos(p.theta(cj)), std::sin(p.theta(cj)));
    const Eigen::Vector2d perp_i(-e_i.y(), e_i.x()), perp_j(-e_j.y(), e_j.x());
    // d = r_a − r_b moves with the offsets; r and n follow.
    const Eigen::Vector2d dd = ds_a * e_i - ds_b * e_j;
    const double dr = n.dot(dd);
    const Eigen::Vector2d dn = (dd - dr * n) / c.r;
    const double f = c.force(), df = kSpring * (dR_a + dR_b - dr);
    const Eigen::Vector2d dF = df * n + f * dn;
    rate.segment<2>(3 * ci) += dF;
    rate.segment<2>(3 * cj) -= dF;
    rate[3 * ci + 2] += ds_a * f * perp_i.dot(n) + s_a * (df * perp_i.dot(n) + f * perp_i.dot(dn));
    rate[3 * cj + 2] -= ds_b * f * perp_j.dot(n) + s_b * (df * perp_j.dot(n) + f * perp_j.dot(dn));
  }
  return rate;
}

Eigen::VectorXd force_rate_difference(const Packing& p, ForceField& field, const BranchSizes& sizes, double t,
                                      double h) {
  Packing moved = p;
  Eigen::VectorXd up, down;
  moved.b = sizes.at(t + h);
  field.invalidate();
  field.evaluate(moved, up);
  moved.b = sizes.at(t - h);
  field.invalidate();
  field.evaluate(moved, down);
  field.invalidate();
  return (up - down) / (2.0 * h);
}

bool branch_tangent(const Packing& p, const std::vector<Contact>& contacts, const std::vector<double>& b_rate,
                    double shift, CholmodSolver& solver, Eigen::VectorXd& dq) {
  const DofMap map = non_rattler_dofs(analyse_network(p.size(), contacts));
  dq.setZero(p.q.size());
  if (map.size() == 0) return true;
  if (!solver.factor(restrict_matrix(hessian(p, contacts), map), -shift, Eigen::VectorXd())) return false;
  dq = expand_vector(solver.solve(restrict_vector(force_rate(p, contacts, b_rate), map)), map);
  return true;
}

const char* to_string(BranchEnd end) {
  switch (end) {
    case BranchEnd::reached: return "reached";
    case BranchEnd::energy_floor: return "energy_floor";
    case BranchEnd::stability_lost: return "stability_lost";
    case BranchEnd::step_underflow: return "step_underflow";
    case BranchEnd::step_cap: return "step_cap";
  }
  return "?";
}

ContinuationResult follow_branch(Packing& p, ForceField& field, const BranchSizes& sizes, const ContinuationParams& prm,
                                 double t0) {
  ContinuationResult res;
  res.t = t0;
  NewtonParams corrector;
  corrector.force_tol = std::max(prm.force_tol, force_resolution(p));
  corrector.max_iterations = prm.corrector_iterations;
  NewtonWorkspace workspace;
  CholmodSolver tangent_solver;
  Eigen::VectorXd F, dq;

  p.b = sizes.at(t0);
  field.invalidate();
  double U = field.evaluate(p, F);
  ++res.evaluations;
  std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  Pairs pairs = network(contacts, corrector.force_tol);
  const auto stable_tangent = [&] {
    ++res.factorisations;
    return branch_tangent(p, contacts, sizes.rate(res.t), prm.tangent_shift, tangent_solver, dq);
  };
  // The end of the branch at its last relaxed point, with the field current for it.
  const auto end = [&](BranchEnd why) {
    res.end = why;
    field.invalidate();
    res.energy = field.evaluate(p, F);
    ++res.evaluations;
    return res;
  };
  // Where the branch ends (the corrector fails down to min_step, or a point's tangent is not
  // stable), the rearrangement: the minimiser relaxes the packing crossing_step further along the
  // path, at fixed sizes, and the branch goes on from that minimum. nullopt: it does; else how the
  // branch ends.
  const auto cross = [&]() -> std::optional<BranchEnd> {
    do {
      res.t = std::min(1.0, res.t + prm.crossing_step);
      p.b = sizes.at(res.t);
      field.invalidate();
      FireParams fire = *prm.rearrangement;
      fire.energy_floor = prm.energy_floor / static_cast<double>(p.size());
      const FireResult fr = minimise(p, field, fire);
      ++res.rearrangements;
      res.rearrangement_evaluations += fr.evaluations;
      res.evaluations += fr.evaluations;
      res.factorisations += fr.newton_iterations;
      res.chord_steps += fr.newton_chord_steps;
      if (!fr.converged) return BranchEnd::step_underflow;  // FIRE's iteration cap
      if (fr.energy < prm.energy_floor) return BranchEnd::energy_floor;
      if (res.t >= 1.0) return BranchEnd::reached;
      contacts = find_contacts(p, field.lobes(), field.neighbours());
      pairs = network(contacts, corrector.force_tol);
      workspace.clear();
    } while (!stable_tangent());
    return std::nullopt;
  };
  // The branch ends at `why` unless a rearrangement crosses to where it goes on.
  const auto end_or_cross = [&](BranchEnd why) -> std::optional<ContinuationResult> {
    if (!prm.rearrangement) return end(why);
    if (const auto stop = cross()) return end(*stop);
    return std::nullopt;
  };
  if (U < prm.energy_floor) return end(BranchEnd::energy_floor);
  if (res.t >= 1.0) return end(BranchEnd::reached);
  if (!stable_tangent()) return end(BranchEnd::stability_lost);
  double h = std::min(prm.first_step, 1.0 - res.t);
  bool indefinite = false;  // why the corrector last failed
  while (true) {
    if (res.steps + res.rejected_steps >= prm.max_steps) return end(BranchEnd::step_cap);
    // A last sliver of the path shorter than min_step is taken with this step.
    const double t1 = 1.0 - (res.t + h) < prm.min_step ? 1.0 : res.t + h;
    const Eigen::VectorXd q0 = p.q;
    p.q += (t1 - res.t) * dq;
    p.b = sizes.at(t1);
    const NewtonResult nr = newton_finish(p, field, corrector, workspace);
    res.factorisations += nr.iterations;
    res.chord_steps += nr.chord_steps;
    res.evaluations += nr.evaluations;
    const bool converged = nr.stop == NewtonStop::converged;
    std::vector<Contact> next;
    Pairs next_pairs;
    if (converged) {
      next = find_contacts(p, field.lobes(), field.neighbours());
      next_pairs = network(next, corrector.force_tol);
    }
    const bool changed = converged && next_pairs != pairs;
    if (!converged || (changed && prm.event_tol > 0 && t1 - res.t > prm.event_tol)) {
      ++res.rejected_steps;
      if (!converged) indefinite = nr.stop == NewtonStop::indefinite;
      p.q = q0;
      p.b = sizes.at(res.t);
      h = 0.5 * (t1 - res.t);
      if (h < prm.min_step) {
        if (auto ended = end_or_cross(indefinite ? BranchEnd::stability_lost : BranchEnd::step_underflow))
          return *ended;
        h = std::min(prm.crossing_step, 1.0 - res.t);
      }
      continue;
    }
    ++res.steps;
    record_events(pairs, next_pairs, t1, res.events);
    const double taken = t1 - res.t;
    res.t = t1;
    contacts = std::move(next);
    pairs = std::move(next_pairs);
    if (nr.energy < prm.energy_floor) return end(BranchEnd::energy_floor);
    if (res.t >= 1.0) return end(BranchEnd::reached);
    if (!stable_tangent()) {
      if (auto ended = end_or_cross(BranchEnd::stability_lost)) return *ended;
      h = std::min(prm.crossing_step, 1.0 - res.t);
      continue;
    }
    // An easy step (no event, few corrector steps) doubles the next one.
    const bool easy = !changed && nr.iterations + nr.chord_steps <= 2;
    h = std::min(easy ? 2.0 * taken : taken, 1.0 - res.t);
  }
}

ContinuationResult start_on_branch(Packing& trial, const Packing& relaxed, ForceField& field,
                                   const ContinuationParams& params) {
  if (trial.size() != relaxed.size()) throw std::invalid_argument("start_on_branch: the packings differ in cells");
  Packing p = relaxed;
  const ContinuationResult res = follow_branch(p, field, BranchSizes{relaxed.b, trial.b}, params);
  trial.q = p.q;
  return res;
}

}  // namespace budjam
