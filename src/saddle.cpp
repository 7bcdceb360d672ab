#include "budjam/saddle.hpp"

#include "budjam/cholmod_solver.hpp"
#include "budjam/fire.hpp"
#include "budjam/hessian.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace budjam {

namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

// Gershgorin: every eigenvalue of H is at least min_i (H_ii − Σ_{j≠i} |H_ij|).
double gershgorin_lower_bound(const Eigen::SparseMatrix<double>& H) {
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(H.rows()), off = Eigen::VectorXd::Zero(H.rows());
  for (Eigen::Index col = 0; col < H.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, col); it; ++it)
      (it.row() == it.col() ? diagonal : off)[it.row()] += it.row() == it.col() ? it.value() : std::abs(it.value());
  return (diagonal - off).minCoeff();
}

// A fixed start vector with no special relation to any mode: uniform in (−½, ½) from a seeded
// engine, converted by hand so that every standard library gives the same numbers.
Eigen::VectorXd start_vector(Eigen::Index n) {
  std::mt19937_64 engine(0x5add1e);
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = static_cast<double>(engine() >> 11) * 0x1p-53 - 0.5;
  return x.normalized();
}

}  // namespace

std::optional<UnstableMode> lowest_unstable_mode(const Eigen::SparseMatrix<double>& H, double relative_delta) {
  if (H.rows() == 0) return std::nullopt;
  UnstableMode mode;
  CholmodSolver ldl(Factorisation::ldlt);
  // #{eigenvalues of H below σ}, or −1 when σ is an eigenvalue to rounding (a zero pivot).
  const auto count_below = [&](double sigma) {
    ++mode.factorisations;
    return ldl.factor(H, sigma, Eigen::VectorXd()) ? ldl.negative_pivots() : -1L;
  };
  const double scale = H.diagonal().cwiseAbs().maxCoeff();
  double hi = -relative_delta * scale;
  if (count_below(hi) <= 0) return std::nullopt;
  double lo = std::min(gershgorin_lower_bound(H), 2 * hi) * 1.01;
  for (int widen = 0; count_below(lo) != 0; ++widen) {
    if (widen == 8) return std::nullopt;  // rounding beyond Gershgorin's margin: no usable bracket
    lo *= 2;
  }
  // λ_min ∈ [lo, hi): shrink the bracket in log|σ| until |lo| ≤ 1.25 |hi|.
  while (lo < 1.25 * hi) {
    double mid = -std::sqrt(lo * hi);
    long below = count_below(mid);
    if (below < 0) below = count_below(mid *= 1.001);
    if (below < 0) break;
    (below == 0 ? lo : hi) = mid;
  }
  if (!ldl.factor(H, lo, Eigen::VectorXd())) return std::nullopt;
  ++mode.factorisations;
  Eigen::VectorXd x = start_vector(H.rows());
  double rayleigh = 0;
  for (mode.iterations = 1; mode.iterations <= 200; ++mode.iterations) {
    x = ldl.solve(x).normalized();
    const Eigen::VectorXd Hx = H * x;
    rayleigh = x.dot(Hx);
    // Converged when the residual ‖Hx − ρx‖ is 10⁻⁴ of ρ, or at H's rounding (~ε‖H‖).
    if ((Hx - rayleigh * x).norm() <= 1e-4 * std::abs(rayleigh) + 64 * kEpsilon * scale) break;
  }
  mode.lambda = rayleigh;
  mode.v = std::move(x);
  return mode;
}

std::optional<UnstableMode> lowest_unstable_mode(const Packing& p, const std::vector<Contact>& contacts,
                                                 const ContactNetwork& net, double relative_delta) {
  const std::vector<Contact> lb = load_bearing(contacts, net);
  if (lb.empty()) return std::nullopt;
  const DofMap map = non_rattler_dofs(net);
  std::optional<UnstableMode> mode = lowest_unstable_mode(restrict_matrix(hessian(p, lb), map), relative_delta);
  if (mode) mode->v = expand_vector(mode->v, map);
  return mode;
}

SaddleStep step_off_saddle(Packing& p, ForceField& field, const UnstableMode& mode) {
  SaddleStep step;
  const Eigen::VectorXd q0 = p.q;
  const auto energy_at = [&](double s) {
    p.q = q0 + s * mode.v;
    ++step.evaluations;
    return field.energy(p);
  };
  step.U_before = energy_at(0);
  // U's own resolution: every overlap σ − r is the difference of numbers of order max(L, |q|),
  // known to force_resolution / k, and enters U weighted by its force.
  double total_force = 0;
  for (const Contact& c : find_contacts(p, field.lobes(), field.neighbours())) total_force += c.force();
  step.U_resolution = total_force * force_resolution(p) / kSpring;
  const double curvature = std::abs(mode.lambda);
  // A step is kept when U falls by half the quadratic prediction and by more than U resolves.
  // Steps too small to pass may still fail by the slope of the residual force FIRE stopped with:
  // the ladder goes on until a step passes, and ends at the first failure after one did.
  const double s0 = std::sqrt(4 * step.U_resolution / curvature);
  double best_U = step.U_before;
  for (const double sign : {1.0, -1.0}) {
    double kept = 0, kept_U = step.U_before;
    for (double s = s0; s < 1.0; s *= 2) {
      const double U = energy_at(sign * s);
      if (U < step.U_before - std::max(0.25 * curvature * s * s, step.U_resolution)) {
        kept = sign * s;
        kept_U = U;
      } else if (kept != 0) {
        break;
      }
    }
    if (kept != 0 && kept_U < best_U) {
      best_U = kept_U;
      step.s = kept;
    }
  }
  step.lowered = step.s != 0;
  p.q = step.lowered ? Eigen::VectorXd(q0 + step.s * mode.v) : q0;
  step.U_after = best_U;
  return step;
}

const char* to_string(StationaryPoint s) {
  switch (s) {
    case StationaryPoint::minimum: return "minimum";
    case StationaryPoint::saddle: return "saddle";
    case StationaryPoint::contact_bounded_minimum: return "contact-bounded minimum";
  }
  return "?";
}

StationaryPoint stationary_point(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                 std::size_t unstable_modes) {
  if (unstable_modes == 0) return StationaryPoint::minimum;
  if (unstable_modes > 1) return StationaryPoint::saddle;
  const std::optional<UnstableMode> mode = lowest_unstable_mode(p, contacts, net);
  if (!mode) return StationaryPoint::saddle;  // the two tests' δ differ by rounding: no mode to probe, no claim
  Packing probe = p;
  ForceField field;
  const SaddleStep step = step_off_saddle(probe, field, *mode);
  if (step.lowered) return StationaryPoint::saddle;
  // The mode alone is not the landscape: a state FIRE left short of its force resolution can still
  // go down another way. Relaxed on to that resolution, a minimum loses nothing U resolves.
  FireParams deep;
  deep.force_tol = 0;
  deep.newton_force = 0;
  const FireResult relaxed = minimise(probe, field, deep);
  const bool held = relaxed.converged && field.energy(probe) >= step.U_before - step.U_resolution;
  return held ? StationaryPoint::contact_bounded_minimum : StationaryPoint::saddle;
}

}  // namespace budjam
