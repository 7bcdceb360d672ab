#pragma once
// Per-run and per-group estimators of the depletion of the buds unconstrained at jamming (paper
// Eqs. 12–16 and appendix D), each under budjam's definition and under the one the paper's own
// analysis used where the two differ (docs/analysis.md, "Definitions").
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

}  // namespace budjam::tools
