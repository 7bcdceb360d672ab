#pragma once
// The mean-field relations of the paper that turn measured inputs into predictions:
// bud depletion (Eqs. 12–16), flux partition λ_c (Eq. 19), the growth bulk response B_grow
// (Eq. 20), the no-feedback branch ΔZ_0(P) (Eq. 6), growth-rate heterogeneity h_γ (Eq. E4) and the
// mean-field estimate of u_J (Eq. A10, Lambert W).
#include <numbers>
#include <optional>
#include <span>
#include <utility>
#include <vector>
#include "budjam/statistics.hpp"

namespace budjam {

// a in the bud-event logs is diameter squared (b² − b_J²); the true added area is π a / 4.
inline constexpr double kDiameterSquaredToArea = std::numbers::pi / 4.0;

// Principal branch W_0 of the Lambert function, w e^w = x, for x ≥ −1/e (Halley iteration from a
// branch-point series near −1/e, log-based start for large x). Throws std::domain_error below −1/e.
double lambert_w0(double x);

// u_J = −W_0(−2 e⁻²)/2 ≈ 0.2032: the Poisson/mean-field solution of u_J = exp(−(2 − 2u_J)) other
// than the trivial root u = 1 (paper Eq. A10).
double u_J_mean_field();

// λ_c = (1 − u) χ_c / (u + (1 − u) χ_c): fraction of the density increment entering the compressed
// sector (Eq. 19). 0 when u = 1 or χ_c = 0 with u > 0.
double lambda_c(double u, double chi_c);

// φ_2 − φ_J = n_J [χ̄ a_ε + (1 − χ̄) u_J ∫_0^{a_ε} S da] (Eq. 14). `a_eps` and `integral_S` must be
// in the same units as the area that makes φ (true area π a/4 for the paper's meaning; diameter
// squared reproduces the reference analysis, larger by 4/π).
double phi2_excess(double n_J, double u_J, double chi_bar, double a_eps, double integral_S);

// Sharp threshold S(a) = Θ(a_c − a): φ_2 − φ_J = n_J a_c [u_J + (1 − u_J) χ̄] (Eq. 16).
double phi2_excess_step(double n_J, double u_J, double chi_bar, double a_c);

// Both readings of Eq. 14 from a survival curve measured in diameter squared.
struct Phi2Prediction {
  double a_eps_d2 = 0, integral_S_d2 = 0;  // diameter squared
  double dphi2_area = 0;                   // with a as true area (the paper's meaning; docs/model.md)
  double dphi2_diameter_sq = 0;            // with a as diameter squared (the reference analysis)
};
Phi2Prediction predict_phi2(double n_J, double u_J, double chi_bar, double a_eps_d2, double integral_S_d2);

// Average of y over x ∈ [x0, x1] by the trapezoid rule on the samples (x ascending): the
// "interval average" χ̄ or λ̄_c over the depletion interval [φ_J, φ_2]. Samples outside [x0, x1]
// are ignored; a single sample in range is returned as is; NaN with none.
double interval_average(std::span<const double> x, std::span<const double> y, double x0, double x1);

// B_grow = φ dP/dφ along growth (Eq. 20): slope of a linear fit of P(φ) over the last ≤ `window`
// accepted states with φ ≤ phi_at (the reference used 5), times phi_at. nullopt with < 2 states.
struct BGrow {
  double B = 0, B_se = 0;  // φ · slope, φ · slope error
  std::size_t points = 0;
};
std::optional<BGrow> b_grow(std::span<const double> phi, std::span<const double> P, double phi_at,
                            std::size_t window = 5);

// A piecewise-linear function through points sorted by x (equal x averaged), constant beyond the
// ends. Used for ΔZ_0(P), the no-feedback branch of mean (P, ΔZ) per Δφ (docs/model.md, "Observables").
class PiecewiseLinear {
 public:
  PiecewiseLinear() = default;
  explicit PiecewiseLinear(std::vector<std::pair<double, double>> points);
  double operator()(double x) const;
  bool empty() const { return x_.empty(); }
  double x_min() const { return x_.front(); }
  double x_max() const { return x_.back(); }
  const std::vector<double>& xs() const { return x_; }
  const std::vector<double>& ys() const { return y_; }

 private:
  std::vector<double> x_, y_;
};

// h_γ = Var(g)/⟨g⟩² with the population variance (Eq. E4). NaN for no data.
double growth_heterogeneity(std::span<const double> g);

// The same from the two-sector moments (Eqs. E5–E7): ⟨g⟩ = u + (1−u)χ_c, ⟨g²⟩ = u + (1−u)χ_c2.
double growth_heterogeneity_sectors(double u, double chi_c, double chi_c2);

// Counts of `values` in [edges[k], edges[k+1]) (the last bin closed), edges ascending.
std::vector<std::size_t> histogram(std::span<const double> values, std::span<const double> edges);

}  // namespace budjam
