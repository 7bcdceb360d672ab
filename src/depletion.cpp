#include "budjam/depletion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace budjam {

double lambert_w0(double x) {
  const double inv_e = std::exp(-1.0);
  if (std::isnan(x)) return x;
  if (x < -inv_e) {
    // Allow rounding of −1/e itself.
    if (x < -inv_e * (1.0 + 4 * std::numeric_limits<double>::epsilon()))
      throw std::domain_error("lambert_w0: argument below -1/e");
    return -1.0;
  }
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return x;
  // Starting guess: branch-point series near −1/e, log series for large x, x itself in between.
  double w;
  if (x < -0.25) {
    const double p = std::sqrt(std::max(0.0, 2.0 * (std::numbers::e * x + 1.0)));
    w = -1.0 + p - p * p / 3.0 + 11.0 / 72.0 * p * p * p;
  } else if (x < 3.0) {
    w = std::log1p(x);  // W(x) ≈ ln(1 + x) is within 30 % on (−1/4, 3)
  } else {
    const double l1 = std::log(x), l2 = std::log(l1);
    w = l1 - l2 + l2 / l1;
  }
  // Halley's iteration for f(w) = w e^w − x: cubic convergence.
  for (int it = 0; it < 64; ++it) {
    const double ew = std::exp(w);
    const double f = w * ew - x;
    const double wp1 = w + 1.0;
    if (wp1 == 0.0) break;  // at the branch point: w = −1 exactly
    const double denom = ew * wp1 - (w + 2.0) * f / (2.0 * wp1);
    const double dw = f / denom;
    w -= dw;
    if (std::abs(dw) <= 4 * std::numeric_limits<double>::epsilon() * (1.0 + std::abs(w))) break;
  }
  return w;
}

double u_J_mean_field() { return -0.5 * lambert_w0(-2.0 * std::exp(-2.0)); }

double lambda_c(double u, double chi_c) {
  const double num = (1.0 - u) * chi_c;
  const double den = u + num;
  if (den == 0.0) return std::numeric_limits<double>::quiet_NaN();  // u = 0 and χ_c = 0: undefined
  return num / den;
}

double phi2_excess(double n_J, double u_J, double chi_bar, double a_eps, double integral_S) {
  return n_J * (chi_bar * a_eps + (1.0 - chi_bar) * u_J * integral_S);
}

double phi2_excess_step(double n_J, double u_J, double chi_bar, double a_c) {
  return n_J * a_c * (u_J + (1.0 - u_J) * chi_bar);
}

Phi2Prediction predict_phi2(double n_J, double u_J, double chi_bar, double a_eps_d2, double integral_S_d2) {
  Phi2Prediction p;
  p.a_eps_d2 = a_eps_d2;
  p.integral_S_d2 = integral_S_d2;
  p.dphi2_diameter_sq = phi2_excess(n_J, u_J, chi_bar, a_eps_d2, integral_S_d2);
  p.dphi2_area =
      phi2_excess(n_J, u_J, chi_bar, kDiameterSquaredToArea * a_eps_d2, kDiameterSquaredToArea * integral_S_d2);
  return p;
}

double interval_average(std::span<const double> x, std::span<const double> y, double x0, double x1) {
  if (x.size() != y.size()) throw std::invalid_argument("interval_average: x and y differ in length");
  std::vector<std::pair<double, double>> in;
  for (std::size_t k = 0; k < x.size(); ++k)
    if (x[k] >= x0 && x[k] <= x1 && std::isfinite(y[k])) in.emplace_back(x[k], y[k]);
  if (in.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::stable_sort(in.begin(), in.end(), [](auto& a, auto& b) { return a.first < b.first; });
  const double span = in.back().first - in.front().first;
  if (in.size() == 1 || !(span > 0)) {
    double s = 0;
    for (auto& p : in) s += p.second;
    return s / static_cast<double>(in.size());
  }
  double area = 0;
  for (std::size_t k = 1; k < in.size(); ++k)
    area += 0.5 * (in[k].second + in[k - 1].second) * (in[k].first - in[k - 1].first);
  return area / span;
}

std::optional<BGrow> b_grow(std::span<const double> phi, std::span<const double> P, double phi_at, std::size_t window) {
  if (phi.size() != P.size()) throw std::invalid_argument("b_grow: phi and P differ in length");
  if (window < 2) throw std::invalid_argument("b_grow: window must be at least 2");
  // The last `window` states with φ ≤ φ_at, in the order they were visited.
  std::vector<double> xs, ys;
  for (std::size_t k = phi.size(); k-- > 0 && xs.size() < window;)
    if (phi[k] <= phi_at) {
      xs.push_back(phi[k]);
      ys.push_back(P[k]);
    }
  if (xs.size() < 2) return std::nullopt;
  if (*std::max_element(xs.begin(), xs.end()) == *std::min_element(xs.begin(), xs.end())) return std::nullopt;
  const LinearFit f = linear_fit(xs, ys);
  BGrow b;
  b.B = phi_at * f.slope;
  b.B_se = phi_at * f.slope_se;
  b.points = xs.size();
  return b;
}

PiecewiseLinear::PiecewiseLinear(std::vector<std::pair<double, double>> points) {
  std::stable_sort(points.begin(), points.end(), [](auto& a, auto& b) { return a.first < b.first; });
  for (std::size_t k = 0; k < points.size();) {
    if (!std::isfinite(points[k].first) || !std::isfinite(points[k].second))
      throw std::invalid_argument("PiecewiseLinear: non-finite point");
    std::size_t j = k;
    double s = 0;
    for (; j < points.size() && points[j].first == points[k].first; ++j) s += points[j].second;
    x_.push_back(points[k].first);
    y_.push_back(s / static_cast<double>(j - k));
    k = j;
  }
}

double PiecewiseLinear::operator()(double x) const {
  if (x_.empty()) throw std::logic_error("PiecewiseLinear: empty");
  if (x <= x_.front()) return y_.front();
  if (x >= x_.back()) return y_.back();
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  const std::size_t k = static_cast<std::size_t>(it - x_.begin());
  const double t = (x - x_[k - 1]) / (x_[k] - x_[k - 1]);
  return y_[k - 1] + t * (y_[k] - y_[k - 1]);
}

double growth_heterogeneity(std::span<const double> g) {
  if (g.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double m = mean(g);
  return population_variance(g) / (m * m);
}

double growth_heterogeneity_sectors(double u, double chi_c, double chi_c2) {
  const double m1 = u + (1.0 - u) * chi_c;
  const double m2 = u + (1.0 - u) * chi_c2;
  return (m2 - m1 * m1) / (m1 * m1);
}

std::vector<std::size_t> histogram(std::span<const double> values, std::span<const double> edges) {
  if (edges.size() < 2) throw std::invalid_argument("histogram: need at least two edges");
  for (std::size_t k = 1; k < edges.size(); ++k)
    if (!(edges[k] > edges[k - 1])) throw std::invalid_argument("histogram: edges must increase");
  std::vector<std::size_t> counts(edges.size() - 1, 0);
  for (double v : values) {
    if (!(v >= edges.front() && v <= edges.back())) continue;
    auto it = std::upper_bound(edges.begin(), edges.end(), v);
    std::size_t k = static_cast<std::size_t>(it - edges.begin());
    k = k == 0 ? 0 : k - 1;
    if (k >= counts.size()) k = counts.size() - 1;  // v == last edge
    ++counts[k];
  }
  return counts;
}

}  // namespace budjam
