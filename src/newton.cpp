// Newton finish with the analytic Hessian (see newton.hpp).
#include "budjam/newton.hpp"

#include "budjam/cholmod_solver.hpp"
#include "budjam/contacts.hpp"
#include "budjam/hessian.hpp"

#include <algorithm>
#include <cmath>

namespace budjam {

namespace {

constexpr int kMaxHalvings = 6;

// |F| with the torque scaled to a force (τ / r_g), the norm the line search decreases.
double scaled_force_norm(const Packing& p, const Eigen::VectorXd& F) {
  double sum = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double t = F[3 * i + 2] / p.dumbbell(i).gyration;
    sum += F[3 * i] * F[3 * i] + F[3 * i + 1] * F[3 * i + 1] + t * t;
  }
  return std::sqrt(sum);
}

}  // namespace

const char* to_string(NewtonStop stop) {
  switch (stop) {
    case NewtonStop::converged: return "converged";
    case NewtonStop::indefinite: return "indefinite";
    case NewtonStop::line_search: return "line_search";
    case NewtonStop::iteration_cap: return "iteration_cap";
  }
  return "?";
}

double max_scaled_force(const Packing& p, const Eigen::VectorXd& F) {
  double fmax = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    fmax =
        std::max({fmax, std::abs(F[3 * i]), std::abs(F[3 * i + 1]), std::abs(F[3 * i + 2] / p.dumbbell(i).gyration)});
  return fmax;
}

void NewtonWorkspace::clear() {
  solver = CholmodSolver();
  network.clear();
  factored = false;
}

NewtonResult newton_finish(Packing& p, ForceField& field, const NewtonParams& prm, NewtonWorkspace& ws) {
  NewtonResult res;
  Eigen::VectorXd F, F_trial;
  double U = field.evaluate(p, F);
  ++res.evaluations;
  double fmax = max_scaled_force(p, F);
  double norm = scaled_force_norm(p, F);
  const auto finish = [&](NewtonStop stop) {
    res.stop = stop;
    res.energy = U;
    res.max_force = fmax;
    return res;
  };
  // Moves p to q0 + h·step; keeps it (true) if the force norm falls below `bound`.
  const auto try_step = [&](const Eigen::VectorXd& q0, const Eigen::VectorXd& step, double h, double bound) {
    p.q = q0 + h * step;
    const double U_trial = field.evaluate(p, F_trial);
    ++res.evaluations;
    const double norm_trial = scaled_force_norm(p, F_trial);
    if (!(norm_trial < bound)) return false;
    U = U_trial;
    F.swap(F_trial);
    norm = norm_trial;
    fmax = max_scaled_force(p, F);
    return true;
  };
  for (long it = 0;; ++it) {
    if (fmax < prm.force_tol || U < prm.energy_floor) return finish(NewtonStop::converged);
    if (it == prm.max_iterations) return finish(NewtonStop::iteration_cap);
    // The field is current for p: its neighbour list holds every contact of this configuration.
    const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
    std::vector<std::pair<std::uint32_t, std::uint32_t>> network(contacts.size());
    std::transform(contacts.begin(), contacts.end(), network.begin(),
                   [](const Contact& c) { return std::make_pair(c.i, c.j); });
    const Eigen::VectorXd q0 = p.q;
    if (prm.reuse_factor && ws.factored && ws.solver.rows() == F.size() && network == ws.network) {
      if (try_step(q0, ws.solver.solve(F), 1.0, prm.chord_contraction * norm)) {
        ++res.chord_steps;
        continue;
      }
      p.q = q0;  // too slow a contraction: refactor here (F, U and the contacts are still those of q0)
    }
    ++res.iterations;
    const double mu = prm.shift * fmax;
    ws.factored = ws.solver.factor(hessian(p, contacts), -mu, Eigen::VectorXd());
    ws.network = std::move(network);
    if (!ws.factored) return finish(NewtonStop::indefinite);
    const Eigen::VectorXd step = ws.solver.solve(F);
    bool accepted = false;
    double h = 1.0;
    for (int k = 0; k <= kMaxHalvings && !accepted; ++k, h *= 0.5) accepted = try_step(q0, step, h, norm);
    if (!accepted) {
      p.q = q0;
      U = field.evaluate(p, F);
      ++res.evaluations;
      return finish(NewtonStop::line_search);
    }
  }
}

NewtonResult newton_finish(Packing& p, ForceField& field, const NewtonParams& prm) {
  NewtonWorkspace fresh;
  return newton_finish(p, field, prm, fresh);
}

}  // namespace budjam
