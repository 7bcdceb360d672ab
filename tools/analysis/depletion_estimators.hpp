#pragma once
// Per-run and per-group estimators of the depletion of the buds unconstrained at jamming (paper
// Eqs. 12–16 and appendix D) and of how the growth they leave to the compressed sector loads it
// (Eq. 20), each under budjam's definition and under the one the paper's own analysis used where
// the two differ (docs/analysis.md, "Definitions").
#include "budjam/statistics.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace budjam::tools {

// The depletion point: the first state from `from` on at which at most `left` of the buds tagged at
// jamming are still unconstrained. budjam's φ_2 is left = 1 ("at most one", ε ~ 1/N_nr,J); the
// paper's division figure takes left = 0 (no tagged bud left). nullopt if never reached.
std::optional<std::size_t> depletion_state(std::span<const double> tagged_active, std::size_t from, double left);

// An interval average over the depletion interval as Eq. 13 defines it, an average over the growth
// coordinate a: the plain mean of y over the accepted states first..last (inclusive), which are the
// samples of a (one growth step each). NaN for an empty interval or no finite value.
double growth_coordinate_average(std::span<const double> y, std::size_t first, std::size_t last);

// The paper's run selection for φ_2, P_2, G_2 and λ̄_c: runs with at most `max_divisions`
// divisions after φ_J at the end of the run and G_2 > 0 (a NaN G_2 — no moduli — does not exclude).
std::vector<bool> paper_admitted(std::span<const double> divisions_at_end, std::span<const double> G_2,
                                 double max_divisions = 10);

// The finite values of the admitted runs that lie within the Tukey fences (k·IQR) of those values:
// the per-P0 outlier rule that follows paper_admitted.
std::vector<double> tukey_inliers(std::span<const double> values, const std::vector<bool>& admitted, double k = 1.5);

// Crossover pressure of the growth-rate distribution P* = n_J (6 + 2u_J) a_c / (8 ln 10)
// (Eq. E12), with a_c the typical completion size as a true area.
double crossover_pressure(double n_J, double u_J, double a_c_area);

// The test of B_grow = λ_c B_ext (Eq. 20) over the (run, Δφ) targets: the median of the ratios
// B_grow/(λ_c B) over the targets with a finite B_grow and λ_c B > 0, quoted as log₁₀ (bootstrap SE
// and percentile interval of log₁₀ of the resampled medians). A median, because the ratio has no
// scale where growth is arrested: once the compressed buds grow at exp(−p/P0) ~ 10⁻¹⁵⁰ and one free
// bud takes all the growth, λ_c B ~ 10⁻¹⁵⁰ and the fitted B_grow is zero within its error, so
// log₁₀ of their ratio is ±100 and one such target outweighs hundreds of others in a mean. B_grow ≤ 0
// (slope noise larger than the slope) ranks below every positive ratio instead of being dropped; a
// median ≤ 0 is log₁₀ = −∞.
struct GrowthBulkCheck {
  BootstrapResult log10_median;  // estimate, se, lo, hi of log₁₀ median(B_grow/(λ_c B)); n = targets
  std::size_t nonpositive = 0;   // targets with B_grow ≤ 0 among them
};
// nullopt if no target qualifies. Throws std::invalid_argument for spans of different lengths.
std::optional<GrowthBulkCheck> growth_bulk_check(std::span<const double> B_grow, std::span<const double> lambda_c,
                                                 std::span<const double> B_ext, const BootstrapOptions& options = {});

}  // namespace budjam::tools
