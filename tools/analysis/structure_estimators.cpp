#include "analysis/structure_estimators.hpp"

#include "budjam/depletion.hpp"

#include <cmath>
#include <map>
#include <stdexcept>

namespace budjam::tools {

long excess_contacts(long N_c, long N_nr, long N_u) { return N_c - (6 * N_nr - 2 * N_u - 2); }

OmegaCollapse omega_collapse(std::span<const CollapsePoint> packings) {
  if (packings.empty()) throw std::invalid_argument("omega_collapse: no packings");
  OmegaCollapse c;
  std::vector<double> w, dz, z6;
  for (const auto& p : packings) {
    const long excess = excess_contacts(p.N_c, p.N_nr, p.N_u);
    const long over_six = p.N_c - 6 * p.N_nr;
    const double n = static_cast<double>(p.N_nr);
    w.push_back(p.omega_star);
    dz.push_back(static_cast<double>(excess) / n);
    z6.push_back(static_cast<double>(over_six) / n);
    c.dZ_negative += excess < 0;
    c.Z_minus_6_negative += over_six < 0;
  }
  c.packings = packings.size();
  c.dZ = fit_through_origin(dz, w);
  c.Z_minus_6 = fit_through_origin(z6, w);
  return c;
}

std::vector<IdentityResidual> dz_identity_residuals(std::span<const IdentityPoint> points) {
  std::vector<double> order;
  std::map<double, std::vector<double>> by_P0;
  for (const auto& p : points) {
    if (!std::isfinite(p.residual)) continue;
    if (!by_P0.count(p.P0)) order.push_back(p.P0);
    by_P0[p.P0].push_back(p.residual);
  }
  std::vector<IdentityResidual> out;
  for (double P0 : order) {
    const auto& r = by_P0[P0];
    double sq = 0;
    for (double v : r) sq += v * v;
    out.push_back({P0, mean_se(r), std::sqrt(sq / static_cast<double>(r.size()))});
  }
  return out;
}

std::vector<double> paper_growth_rate_edges() {
  return {0, 0.03, 0.06, 0.10, 0.15, 0.22, 0.32, 0.45, 0.60, 0.78, 0.90, 0.97, 0.995};
}

GrowthRateDistribution growth_rate_distribution(std::span<const double> g, std::span<const double> edges) {
  if (g.empty()) throw std::invalid_argument("growth_rate_distribution: no cells");
  if (edges.size() < 2) throw std::invalid_argument("growth_rate_distribution: need at least 2 bin edges");
  GrowthRateDistribution d;
  d.cells = g.size();
  std::vector<double> below;
  std::size_t at_one = 0;
  for (double v : g) {
    if (v == 1.0)
      ++at_one;  // p = 0 exactly: the δ(g − 1) of Eq. E2
    else
      below.push_back(v);
  }
  const double total = static_cast<double>(g.size());
  d.weight_at_one = static_cast<double>(at_one) / total;
  const auto counts = histogram(below, edges);
  for (std::size_t k = 0; k < counts.size(); ++k)
    d.density.push_back(static_cast<double>(counts[k]) / total / (edges[k + 1] - edges[k]));
  d.median = median(below);
  d.q25 = quantile(below, 0.25);
  d.q75 = quantile(below, 0.75);
  return d;
}

}  // namespace budjam::tools
