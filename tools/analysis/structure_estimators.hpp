#pragma once
// Estimators of the contact structure and the growth-rate field above jamming: the ΔZ identity
// (Eq. 6), the collapse of ω* on ΔZ (Eq. F5) and the growth-rate distribution Π(g) (appendix E).
#include "budjam/statistics.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace budjam::tools {

// Contacts above the modified isostatic count, N_c − N_c,iso with N_c,iso = 6 N_nr − 2 N_u − 2
// (N_c counted twice): an integer whose sign is the sign of ΔZ = (N_c − N_c,iso)/N_nr, free of the
// rounding that puts a marginal packing's floating-point ΔZ at ±1e-16.
long excess_contacts(long N_c, long N_nr, long N_u);

// One packing's spectrum and integer contact counts.
struct CollapsePoint {
  double omega_star = 0;
  long N_c = 0, N_nr = 0, N_u = 0;
};

// ω* against ΔZ and against the naive Z − 6, each fitted through the origin (a proportionality), and
// how many packings have ΔZ < 0 and Z − 6 < 0 counted from the integer counts. A proportionality
// to Z − 6 cannot hold where Z − 6 < 0 while ω* > 0.
struct OmegaCollapse {
  OriginFit dZ, Z_minus_6;
  std::size_t packings = 0, dZ_negative = 0, Z_minus_6_negative = 0;
};
// Throws std::invalid_argument for no packings.
OmegaCollapse omega_collapse(std::span<const CollapsePoint> packings);

// Residual ΔZ − [ΔZ_0(P) + 2(u_J − u)] of one packing of a run with feedback (P0). No-feedback
// runs define ΔZ_0(P) and are not tests of it.
struct IdentityPoint {
  double P0 = 0;
  double residual = 0;
};
struct IdentityResidual {
  double P0 = 0;
  MeanSE residual;
  double rms = 0;
};
// Per P0, in the order P0 first appears.
std::vector<IdentityResidual> dz_identity_residuals(std::span<const IdentityPoint> points);

// The bin edges of the paper's Π(g) figure, dense near g = 1 where weak feedback puts the cells.
std::vector<double> paper_growth_rate_edges();

// Π(g) of one group: the weight of the δ(g − 1) peak (cells with no bud pressure, g = 1 exactly),
// the density of the g < 1 cells on `edges` (per unit g, normalised by all cells), and the median
// and quartiles of the g < 1 cells (a nearly flat density has no meaningful peak).
struct GrowthRateDistribution {
  std::size_t cells = 0;
  double weight_at_one = 0;
  std::vector<double> density;          // one per bin of edges
  double median = 0, q25 = 0, q75 = 0;  // of g < 1; NaN if none
};
// Throws std::invalid_argument for no cells or fewer than 2 edges.
GrowthRateDistribution growth_rate_distribution(std::span<const double> g, std::span<const double> edges);

}  // namespace budjam::tools
