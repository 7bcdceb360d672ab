#pragma once
// Finite-size study (docs/analysis.md, "Finite size").
//
// Model: q(N) = q_∞ + c/N, the leading correction of the finite-size counting (the +2 of the
// isostatic count and the discreteness of u = N_u/N_nr are O(1/N)), fitted by weighted least squares
// on the per-size values with their standard errors. It is fitted only where at least five sizes have
// an error bar: with three the fit has one degree of freedom and cannot test the form. The fit
// reports χ²/dof and each size's residual in units of its SE, so the form is checked, not assumed.
// χ² assumes independent sizes, so the fit is made only where no seed was grown at two of the sizes
// it uses: a seed's random stream does not depend on L, and its runs at two sizes are correlated.
//
// Two tables: the quantities fixed at jamming, from ensembles whose sizes have independent seeds
// (one measurement per jamming state: feedback acts only above jamming), and the quantities of the
// depletion point per feedback strength. The cell density at jamming is not fitted by q_∞ + c/N:
// N/L² from the growth process alone is not monotone in L (growth_only.hpp), so it is compared at
// each size with that growth-only expectation, and n_J = (N_J/L²)(1 − rattler fraction) is
// extrapolated as the growth-only density in a large box times the fitted non-rattler fraction.
#include "analysis/growth_only.hpp"
#include "io/json.hpp"

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>

namespace budjam::tools {

inline constexpr std::size_t kMinSizesToExtrapolate = 5;

// The seeds of the runs at each box side L.
using SeedsBySize = std::map<double, std::set<std::uint64_t>>;

// `groups`: the "groups" array that analyse writes to analysis.json, one entry per (L, P0); `seeds`:
// the seeds of each group's runs, by P0_label and L (every group must be there). Returns one entry per
// P0 present at two sizes or more: its per-size rows of the depletion-point quantities and, with
// kMinSizesToExtrapolate sizes or more of pairwise disjoint seeds, their extrapolation.
io::Json finite_size_json(const io::Json& groups, const std::map<std::string, SeedsBySize>& seeds);

// The cell count of the growth process alone at a box side and packing fraction.
using GrowthOnly = std::function<GrowthOnlyCount(double L, double phi)>;

// `sizes`: the "sizes" array that analyse writes (one entry per L, quantities fixed at jamming over
// distinct jamming states), `seeds` the seeds of the runs of each (every size must be there). Per-size rows of u_J, u_J
// (lobes), φ_J, Z_J, the rattler fraction, N_J/L² beside the growth-only density at ⟨φ_J⟩, and n_J; the 1/N
// extrapolations; and n_J,∞ from the growth-only density averaged over boxes of sides `large_L` … √2 `large_L` (one
// period of its phase) at the ⟨φ_J⟩ of the largest size. Null when fewer than two sizes.
io::Json jamming_finite_size_json(const io::Json& sizes, const SeedsBySize& seeds, const GrowthOnly& growth_only,
                                  double large_L);

}  // namespace budjam::tools
