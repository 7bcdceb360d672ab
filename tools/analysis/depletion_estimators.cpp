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

double selection_divisions(std::span<const double> target_phi, std::span<const double> target_divisions, double phi_2) {
  if (target_phi.size() != target_divisions.size())
    throw std::invalid_argument("selection_divisions: target φ and divisions differ in length");
  double fewest = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < target_phi.size(); ++k)
    if (target_phi[k] >= phi_2 && !(target_divisions[k] >= fewest)) fewest = target_divisions[k];
  return fewest;
}

std::vector<bool> paper_G2_kept(std::span<const double> G_2, const std::vector<bool>& admitted, double k) {
  if (admitted.size() != G_2.size()) throw std::invalid_argument("paper_G2_kept: G_2 and admitted differ in length");
  std::vector<bool> kept(G_2.size());
  std::vector<double> positive;
  for (std::size_t r = 0; r < G_2.size(); ++r)
    if (admitted[r] && std::isfinite(G_2[r]) && G_2[r] > 0) {
      kept[r] = true;
      positive.push_back(G_2[r]);
    }
  if (positive.size() < 4) return kept;
  const Fences f = tukey_fences(positive, k);
  if (!(f.hi > f.lo)) return kept;  // zero IQR: no fences
  std::vector<bool> inside(kept);
  bool any = false;
  for (std::size_t r = 0; r < G_2.size(); ++r)
    if (kept[r]) any |= (inside[r] = f.contains(G_2[r]));
  return any ? inside : kept;
}

double crossover_pressure(double n_J, double u_J, double a_c_area) {
  return n_J * (6.0 + 2.0 * u_J) * a_c_area / (8.0 * std::log(10.0));
}

std::optional<GrowthBulkCheck> growth_bulk_check(std::span<const double> B_grow, std::span<const double> lambda_c,
                                                 std::span<const double> B_ext, std::span<const std::uint64_t> cluster,
                                                 const BootstrapOptions& options) {
  if (lambda_c.size() != B_grow.size() || B_ext.size() != B_grow.size() || cluster.size() != B_grow.size())
    throw std::invalid_argument("growth_bulk_check: B_grow, lambda_c, B_ext and clusters differ in length");
  std::vector<double> ratio;
  std::vector<std::uint64_t> of;
  GrowthBulkCheck c;
  for (std::size_t k = 0; k < B_grow.size(); ++k) {
    const double predicted = lambda_c[k] * B_ext[k];
    if (!std::isfinite(B_grow[k]) || !std::isfinite(predicted) || !(predicted > 0)) continue;
    ratio.push_back(B_grow[k] / predicted);
    of.push_back(cluster[k]);
    if (B_grow[k] <= 0) ++c.nonpositive;
  }
  if (ratio.empty()) return std::nullopt;
  const auto log10_median = [](std::span<const double> x) {
    const double m = median(std::vector<double>(x.begin(), x.end()));
    return m > 0 ? std::log10(m) : -std::numeric_limits<double>::infinity();
  };
  c.targets = ratio.size();
  c.log10_median = cluster_bootstrap(ratio, of, log10_median, options);
  return c;
}

}  // namespace budjam::tools
