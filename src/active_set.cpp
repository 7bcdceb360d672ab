#include "budjam/active_set.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "budjam/cholmod_solver.hpp"
#include "budjam/contacts.hpp"
#include "budjam/hessian.hpp"
#include "budjam/newton.hpp"

namespace budjam {

const char* to_string(ActiveSetStop stop) {
  switch (stop) {
    case ActiveSetStop::converged: return "converged";
    case ActiveSetStop::energy_floor: return "energy_floor";
    case ActiveSetStop::stalled: return "stalled";
    case ActiveSetStop::step_cap: return "step_cap";
    case ActiveSetStop::long_step: return "long_step";
  }
  return "?";
}

long active_set_max_updates(long n) {
  return std::max(64L, static_cast<long>(std::sqrt(static_cast<double>(n)) / 3.0));
}

namespace {

// One listed pair linearised at the current q: δ = σ − r and g = ∂δ/∂q on the dofs
// (3 ci, 3 ci + 1, 3 ci + 2, 3 cj, 3 cj + 1, 3 cj + 2).
struct PairModel {
  Eigen::Index dof[6];
  double g[6];
  double delta;
};

std::vector<PairModel> linearise(const Packing& p, const ForceField& field) {
  const Lobes& lobes = field.lobes();
  std::vector<PairModel> pairs;
  pairs.reserve(field.neighbours().pairs().size());
  for (const auto& [a, b] : field.neighbours().pairs()) {
    double dx = lobes.x[a] - lobes.x[b], dy = lobes.y[a] - lobes.y[b];
    p.box.minimum_image(dx, dy);
    const double r = std::sqrt(dx * dx + dy * dy);
    Contact c{a, b, 0.0, 0.0, r, lobes.R[a] + lobes.R[b]};
    if (r > 0.0) {
      c.nx = dx / r;
      c.ny = dy / r;
    } else {
      coincident_normal(p, a, b, c.nx, c.ny);
    }
    const Eigen::Matrix<double, 1, 6> g = -(Eigen::RowVector2d(c.nx, c.ny) * contact_jacobian(p, c));
    PairModel m{};
    for (int k = 0; k < 3; ++k) {
      m.dof[k] = 3 * static_cast<Eigen::Index>(a / 2) + k;
      m.dof[3 + k] = 3 * static_cast<Eigen::Index>(b / 2) + k;
    }
    for (int k = 0; k < 6; ++k) m.g[k] = g[k];
    m.delta = c.overlap();
    pairs.push_back(m);
  }
  return pairs;
}

// An upper bound on how far a step u moves any lobe: |Δx| + lever |Δθ|.
double largest_lobe_move(const Eigen::VectorXd& u, double lever) {
  double moved = 0.0;
  for (Eigen::Index k = 0; k < u.size(); k += 3)
    moved = std::max(moved, std::hypot(u[k], u[k + 1]) + lever * std::abs(u[k + 2]));
  return moved;
}

double along(const PairModel& m, const Eigen::VectorXd& u) {
  double s = 0.0;
  for (int k = 0; k < 6; ++k) s += m.g[k] * u[m.dof[k]];
  return s;
}

// The model m(u) of one linearisation, minimised by semismooth Newton on its active set.
class ContactModel {
 public:
  // `solver` is kept from one linearisation to the next: every active set lies within the listed
  // pairs, so the ordering made for all of them serves until the neighbour list changes
  // (`new_list`: the pairs are not those of the last model).
  ContactModel(std::vector<PairModel> pairs, Eigen::VectorXd damping, CholmodSolver& solver, bool new_list)
      : pairs_(std::move(pairs)), D_(std::move(damping)), solver_(solver) {
    if (new_list) solver_.keep_ordering_for(assemble([](std::size_t) { return true; }));
  }

  // Minimises m from u = 0; returns the minimiser, or the first iterate that moves a lobe further
  // than give_up_move (> 0) when the caller gives such steps up. `result` counts the work.
  Eigen::VectorXd minimise(long max_inner, std::size_t max_updates, double give_up_move, double lever,
                           ActiveSetResult& result) {
    const Eigen::Index n = D_.size();
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    residual_.resize(pairs_.size());
    active_.assign(pairs_.size(), 0);
    for (std::size_t c = 0; c < pairs_.size(); ++c) residual_[c] = pairs_[c].delta;
    std::vector<std::size_t> changed;
    for (long it = 0; it < max_inner; ++it) {
      changed.clear();
      for (std::size_t c = 0; c < pairs_.size(); ++c)
        if ((residual_[c] > 0.0) != static_cast<bool>(active_[c])) changed.push_back(c);
      if (it > 0 && changed.empty()) break;
      ++result.inner;
      // A few changes: rank-1 updates of the factor; many: a fresh factorisation is cheaper.
      if (it == 0 || changed.size() > max_updates) {
        for (std::size_t c : changed) active_[c] ^= 1;
        factor();
        ++result.factorisations;
      } else {
        update(changed);
        result.updates += static_cast<long>(changed.size());
      }
      // Newton direction: the minimiser of the quadratic on the current active set.
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
      for (std::size_t c = 0; c < pairs_.size(); ++c)
        if (active_[c])
          for (int k = 0; k < 6; ++k) rhs[pairs_[c].dof[k]] -= kSpring * pairs_[c].delta * pairs_[c].g[k];
      const Eigen::VectorXd d = solver_.solve(rhs) - u;
      const double alpha = line_minimum(u, d);
      u += alpha * d;
      for (std::size_t c = 0; c < pairs_.size(); ++c) residual_[c] += alpha * rate_[c];
      if (give_up_move > 0.0 && largest_lobe_move(u, lever) > give_up_move) break;
    }
    return u;
  }

  double value(const Eigen::VectorXd& u) const {
    double m = 0.5 * u.dot(D_.asDiagonal() * u);
    for (const PairModel& pm : pairs_) {
      const double v = pm.delta + along(pm, u);
      if (v > 0.0) m += 0.5 * kSpring * v * v;
    }
    return m;
  }

 private:
  // μD + k Σ g gᵀ over the pairs that `in` selects.
  template <class Selected>
  SparseMatrix assemble(Selected in) const {
    const Eigen::Index n = D_.size();
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(static_cast<std::size_t>(n) + 36 * pairs_.size());
    for (Eigen::Index i = 0; i < n; ++i) t.emplace_back(i, i, D_[i]);
    for (std::size_t c = 0; c < pairs_.size(); ++c) {
      if (!in(c)) continue;
      const PairModel& m = pairs_[c];
      for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) t.emplace_back(m.dof[a], m.dof[b], kSpring * m.g[a] * m.g[b]);
    }
    SparseMatrix K(n, n);
    K.setFromTriplets(t.begin(), t.end());
    return K;
  }

  void factor() {
    // μD + k Σ g gᵀ is positive definite for μ > 0: a failure is a NaN, not a model property.
    if (!solver_.factor(assemble([&](std::size_t c) { return active_[c] != 0; })))
      throw CholmodError("active_set: the contact model's matrix could not be factored");
  }

  // ±√k g_c for each changed pair, up to eight columns per CHOLMOD call, additions and removals apart.
  void update(const std::vector<std::size_t>& changed) {
    const double root_k = std::sqrt(kSpring);
    for (int add = 0; add < 2; ++add) {
      std::vector<std::size_t> batch;
      for (std::size_t c : changed)
        if ((residual_[c] > 0.0) == static_cast<bool>(add)) batch.push_back(c);
      for (std::size_t start = 0; start < batch.size(); start += 8) {
        const std::size_t end = std::min(batch.size(), start + 8);
        std::vector<Eigen::Triplet<double>> t;
        for (std::size_t j = start; j < end; ++j)
          for (int k = 0; k < 6; ++k)
            t.emplace_back(pairs_[batch[j]].dof[k], static_cast<int>(j - start), root_k * pairs_[batch[j]].g[k]);
        SparseMatrix C(D_.size(), static_cast<Eigen::Index>(end - start));
        C.setFromTriplets(t.begin(), t.end());
        solver_.update(C, add == 1);
      }
      for (std::size_t c : batch) active_[c] = static_cast<char>(add);
    }
  }

  // argmin over α ∈ [0, 1] of m(u + α d). m is convex along d: its derivative
  // φ'(α) = μ dᵀD(u + α d) + k Σ_c [r_c + α s_c]₊ s_c is non-decreasing and linear between the
  // breakpoints α_c = −r_c / s_c where a pair enters or leaves the set. The breakpoints are
  // walked in order until φ' changes sign: the exact minimum, in O(pairs + crossings log crossings).
  double line_minimum(const Eigen::VectorXd& u, const Eigen::VectorXd& d) {
    double intercept = d.dot(D_.asDiagonal() * u), slope = d.dot(D_.asDiagonal() * d);  // φ' = intercept + α slope
    crossings_.clear();
    rate_.resize(pairs_.size());
    for (std::size_t c = 0; c < pairs_.size(); ++c) {
      const double r = residual_[c], s = rate_[c] = along(pairs_[c], d);
      const bool in = r > 0.0 || (r == 0.0 && s > 0.0);  // in the set just after α = 0
      if (in) {
        intercept += kSpring * r * s;
        slope += kSpring * s * s;
      }
      const double at = s != 0.0 ? -r / s : -1.0;
      if (at > 0.0 && at < 1.0 && in == (s < 0.0)) crossings_.push_back({at, c, s});
    }
    std::sort(crossings_.begin(), crossings_.end(),
              [](const Crossing& a, const Crossing& b) { return a.at < b.at || (a.at == b.at && a.pair < b.pair); });
    double from = 0.0;
    for (const Crossing& x : crossings_) {
      if (intercept + slope * x.at >= 0.0) return std::max(from, -intercept / slope);
      // The pair leaves the set (s < 0) or enters it (s > 0) at α = x.at.
      const double r = residual_[x.pair], sign = x.s < 0.0 ? -1.0 : 1.0;
      intercept += sign * kSpring * r * x.s;
      slope += sign * kSpring * x.s * x.s;
      from = x.at;
    }
    return intercept + slope >= 0.0 ? std::max(from, -intercept / slope) : 1.0;
  }

  struct Crossing {
    double at;
    std::size_t pair;
    double s;
  };

  std::vector<PairModel> pairs_;
  Eigen::VectorXd D_;
  CholmodSolver& solver_;
  std::vector<double> residual_;  // δ_c + g_cᵀu
  std::vector<double> rate_;      // g_cᵀd along the last Newton direction d
  std::vector<Crossing> crossings_;
  std::vector<char> active_;
};

}  // namespace

// Below this μ the damping of the exact zero modes (rattlers, global translations) would let
// rounding noise in the right-hand side move them by more than the step bound.
constexpr double kMinDamping = 1e-12 * kSpring;

ActiveSetResult active_set_minimise(Packing& p, ForceField& field, const ActiveSetParams& prm) {
  ActiveSetResult res;
  const std::size_t n = p.size();
  Eigen::VectorXd F, Ft;
  double U = field.evaluate(p, F);
  ++res.evaluations;
  double fmax = max_scaled_force(p, F);
  Eigen::VectorXd D(3 * static_cast<Eigen::Index>(n));
  double lever = 0.0;  // largest centroid-to-lobe distance: a lobe moves by ≤ |Δx| + lever |Δθ|
  for (std::size_t i = 0; i < n; ++i) {
    const Dumbbell db = p.dumbbell(i);
    D.segment<3>(3 * static_cast<Eigen::Index>(i)) << 1.0, 1.0, db.gyration * db.gyration;
    lever = std::max({lever, db.mother_offset, db.bud_offset});
  }
  const double max_move = 0.25 * field.neighbours().skin();
  const auto max_updates =
      static_cast<std::size_t>(prm.max_updates < 0 ? active_set_max_updates(D.size()) : prm.max_updates);
  CholmodSolver solver(Factorisation::updatable);
  long listed = -1;  // the neighbour list's build that the kept ordering was made for
  double mu = prm.damping * kSpring;
  int refused = 0;
  while (true) {
    if (U < prm.energy_floor) {
      res.stop = ActiveSetStop::energy_floor;
      break;
    }
    if (fmax < prm.force_tol) {
      res.stop = ActiveSetStop::converged;
      break;
    }
    if (refused >= prm.max_refused) {
      res.stop = ActiveSetStop::stalled;
      break;
    }
    if (res.steps >= prm.max_steps) break;
    ++res.steps;
    const bool new_list = field.neighbours().rebuilds() != listed;
    listed = field.neighbours().rebuilds();
    ContactModel model(linearise(p, field), mu * D, solver, new_list);
    Eigen::VectorXd u = model.minimise(prm.max_inner, max_updates, prm.give_up_move, lever, res);
    const double moved = largest_lobe_move(u, lever);
    if (prm.give_up_move > 0.0 && moved > prm.give_up_move) {
      res.stop = ActiveSetStop::long_step;
      break;
    }
    // m is convex, so the shortened step still lowers it: m(s u) ≤ (1 − s) m(0) + s m(u).
    if (moved > max_move) u *= max_move / moved;
    const double predicted = U - model.value(u);
    Packing trial = p;
    trial.q += u;
    const double Ut = field.evaluate(trial, Ft);
    ++res.evaluations;
    if (Ut < U) {
      const double rho = (U - Ut) / predicted;
      p.q = trial.q;  // into p's own buffer: a caller (FIRE) may hold pointers into it
      U = Ut;
      F.swap(Ft);
      fmax = max_scaled_force(p, F);
      refused = 0;
      if (rho > 0.75) mu = std::max(0.25 * mu, kMinDamping);
      if (rho < 0.25) mu *= 4.0;
    } else {
      ++refused;
      mu *= 8.0;
      field.evaluate(p, F);  // the field is linearised at p next
      ++res.evaluations;
    }
  }
  field.evaluate(p, F);
  ++res.evaluations;
  res.energy = U;
  res.max_force = fmax;
  return res;
}

}  // namespace budjam
