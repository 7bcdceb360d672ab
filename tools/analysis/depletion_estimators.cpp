#include "analysis/depletion_estimators.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace budjam::tools {

std::optional<std::size_t> depletion_state(std::span<const double> tagged_active, std::size_t from, double left) {
  for (std::size_t k = from; k < tagged_active.size(); ++k)
    if (tagged_active[k] <= left) return k;
  return std::nullopt;
}

double growth_coordinate_average(std::span<const double> y, std::size_t first, std::size_t last) {
  std::vector<double> in;
  for (std::size_t k = first; k <= last && k < y.size(); ++k)
    if (std::isfinite(y[k])) in.push_back(y[k]);
  return mean(in);
}

std::vector<bool> paper_admitted(std::span<const double> divisions_at_end, std::span<const double> G_2,
                                 double max_divisions) {
  std::vector<bool> keep(divisions_at_end.size());
  for (std::size_t k = 0; k < keep.size(); ++k) keep[k] = divisions_at_end[k] <= max_divisions && !(G_2[k] <= 0);
  return keep;
}

std::vector<double> tukey_inliers(std::span<const double> values, const std::vector<bool>& admitted, double k) {
  std::vector<double> in;
  for (std::size_t r = 0; r < values.size(); ++r)
    if (admitted[r] && std::isfinite(values[r])) in.push_back(values[r]);
  if (in.empty()) return in;
  const Fences f = tukey_fences(in, k);
  std::vector<double> out;
  for (double v : in)
    if (f.contains(v)) out.push_back(v);
  return out;
}

double crossover_pressure(double n_J, double u_J, double a_c_area) {
  return n_J * (6.0 + 2.0 * u_J) * a_c_area / (8.0 * std::log(10.0));
}

std::optional<GrowthBulkCheck> growth_bulk_check(std::span<const double> B_grow, std::span<const double> lambda_c,
                                                 std::span<const double> B_ext, const BootstrapOptions& options) {
  if (lambda_c.size() != B_grow.size() || B_ext.size() != B_grow.size())
    throw std::invalid_argument("growth_bulk_check: B_grow, lambda_c and B_ext differ in length");
  std::vector<double> ratio;
  GrowthBulkCheck c;
  for (std::size_t k = 0; k < B_grow.size(); ++k) {
    const double predicted = lambda_c[k] * B_ext[k];
    if (!std::isfinite(B_grow[k]) || !std::isfinite(predicted) || !(predicted > 0)) continue;
    ratio.push_back(B_grow[k] / predicted);
    if (B_grow[k] <= 0) ++c.nonpositive;
  }
  if (ratio.empty()) return std::nullopt;
  const auto log10_median = [](std::span<const double> x) {
    const double m = median(std::vector<double>(x.begin(), x.end()));
    return m > 0 ? std::log10(m) : -std::numeric_limits<double>::infinity();
  };
  c.log10_median = bootstrap(ratio, log10_median, options);
  return c;
}

}  // namespace budjam::tools
