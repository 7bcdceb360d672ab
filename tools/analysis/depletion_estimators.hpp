#pragma once
// Per-run and per-group estimators of the depletion of the buds unconstrained at jamming (paper
// Eqs. 12–16 and appendix D) and of how the growth they leave to the compressed sector loads it
// (Eq. 20), each under budjam's definition and under the one the paper's own analysis used where
// the two differ (docs/analysis.md, "Definitions").
#include "budjam/statistics.hpp"

#include <cstddef>
#include <cstdint>
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

// The paper's run selection (its figure pipeline, where every target Δφ is a run of its own): a
// (P0, seed) enters the φ_2, P_2, λ̄_c, Eq. 14 and G_2 statistics when one of its target runs whose
// end lies at or beyond φ_2 had at most 10 divisions at its end (counted from its last jamming; its
// smallest such run represents it). One budjam run visits every target, so a target run is this run
// up to where it first lands on that target. `target_phi` and `target_divisions` are those ends (φ,
// divisions there; NaN φ for a target never landed); the fewest divisions of the runs that reach
// φ_2 decide, NaN when none does (the paper has no such run).
double selection_divisions(std::span<const double> target_phi, std::span<const double> target_divisions, double phi_2);

// A run whose selection divisions are at most 10 (a NaN is never admitted).
inline constexpr double kPaperMaxDivisions = 10;
inline bool paper_admits(double selection_divisions) { return selection_divisions <= kPaperMaxDivisions; }

// The paper's outlier rule, applied to G_2 only: of the admitted runs, those with a finite G_2 > 0,
// then Tukey's fences (k·IQR, quartiles interpolated linearly) on those G_2 — unless fewer than four
// remain or their IQR is zero (no fences), and never an empty result (then every positive G_2 stays).
// Returns the runs kept.
std::vector<bool> paper_G2_kept(std::span<const double> G_2, const std::vector<bool>& admitted, double k = 1.5);

// Crossover pressure of the growth-rate distribution P* = n_J (6 + 2u_J) a_c / (8 ln 10)
// (Eq. E12), with a_c the typical completion size as a true area.
double crossover_pressure(double n_J, double u_J, double a_c_area);

// The test of B_grow = λ_c B_ext (Eq. 20) over the (run, Δφ) targets: the median of the ratios
// B_grow/(λ_c B) over the targets with a finite B_grow and λ_c B > 0, quoted as log₁₀. A median, because
// the ratio has no scale where growth is arrested: once the compressed buds grow at exp(−p/P0) ~ 10⁻¹⁵⁰
// and one free bud takes all the growth, λ_c B ~ 10⁻¹⁵⁰ and the fitted B_grow is zero within its
// error, so log₁₀ of their ratio is ±100 and one such target outweighs hundreds of others in a mean.
// B_grow ≤ 0 (slope noise larger than the slope) ranks below every positive ratio instead of being
// dropped; a median ≤ 0 is log₁₀ = −∞. The targets of one run (and the runs of one seed, which share
// their growth up to jamming) are not independent: the error is a cluster bootstrap over `cluster`
// (SE and percentile interval of log₁₀ of the resampled medians), and n counts clusters.
struct GrowthBulkCheck {
  BootstrapResult log10_median;  // estimate, se, lo, hi of log₁₀ median(B_grow/(λ_c B)); n = clusters
  std::size_t targets = 0;       // the targets that qualify
  std::size_t nonpositive = 0;   // targets with B_grow ≤ 0 among them
};
// nullopt if no target qualifies. Throws std::invalid_argument for spans of different lengths.
std::optional<GrowthBulkCheck> growth_bulk_check(std::span<const double> B_grow, std::span<const double> lambda_c,
                                                 std::span<const double> B_ext, std::span<const std::uint64_t> cluster,
                                                 const BootstrapOptions& options = {});

}  // namespace budjam::tools
