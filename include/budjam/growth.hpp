#pragma once
// Cell growth, the growth law, division and initial states (docs/model.md, "Growth").
// One random stream per run, std::mt19937_64, drawn in a fixed documented order (docs/growth.md).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>
#include "budjam/packing.hpp"
#include "budjam/scene.hpp"

namespace budjam {

using Rng = std::mt19937_64;

// U uniform in [0, 1) from the top 53 bits: the same on every platform and library
// (std::uniform_real_distribution is not specified bit for bit).
inline double uniform01(Rng& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// γ0 = r0 (1 + δ (U − 1/2)); one draw.
double draw_innate_rate(const Scene& scene, Rng& rng);

// Bud diameter of a newborn cell: b = (α0 − 1) D.
inline double newborn_bud(double alpha0) { return (alpha0 - 1.0) * kMotherDiameter; }
// A cell divides when α = 1 + b/D > 2 α0.
inline bool ready_to_divide(double b, double alpha0) { return 1.0 + b / kMotherDiameter > 2.0 * alpha0; }

// b after a step: b² ← (1 + γΔt)(D² + b²) − D² (all new area goes into the bud).
double grown_bud(double b, double gamma, double dt);

// ln exp(−p/P0) = −p/P0, exact far beyond where the factor itself underflows: 0 without feedback
// (nullopt) or for p ≤ 0, −∞ for p = +∞. Throws InputError for P0 ≤ 0, std::domain_error for a NaN
// pressure.
double log_growth_factor(double bud_pressure, std::optional<double> P0);

// exp(log_factor), exactly 0 when it would fall below DBL_MIN (never a denormal, never NaN).
double factor_from_log(double log_factor);

// exp(−p/P0): 1 without feedback (nullopt) or for p ≤ 0; exactly 0 when it would fall below DBL_MIN
// (never a denormal, never NaN, also for p = +∞). Errors as log_growth_factor.
double growth_factor(double bud_pressure, std::optional<double> P0);

// χ_c = ⟨exp(−p/P0)⟩ over the compressed buds (p > 0), and ln χ_c by log-sum-exp about the largest
// factor, which survives when every factor underflows. (1, 0) when no bud is compressed.
struct CompressedFactor {
  double chi = 1.0, log_chi = 0.0;
};
CompressedFactor mean_compressed_factor(const std::vector<double>& bud_pressures, std::optional<double> P0);

// γ_i·e^{log_scale} for the next step: γ0_i, times exp(−p_i/P0) when `bud_pressures` is given
// (feedback on: above jamming and P0 set; one entry per cell), each factor taken in log space as
// exp(log_scale − p_i/P0). A step of Δt·e^{−log_scale} with these rates grows every cell as Δt with
// the plain rates; log_scale > 0 keeps the factors of strongly compressed buds in the double range
// (docs/growth.md, "Adaptive growth step"). log_scale = 0: the plain rates, bit for bit.
std::vector<double> growth_rates(const Packing& p, const std::vector<double>* bud_pressures, std::optional<double> P0,
                                 double log_scale = 0.0);

// One division as it happened (cell indices refer to the packing after the step).
struct Division {
  std::size_t mother_index = 0;    // index of the cell that kept the identity (unchanged)
  std::size_t daughter_index = 0;  // index of the new cell (appended)
  std::int64_t mother_id = -1, daughter_id = -1;
  double x = 0, y = 0, theta = 0;  // centroid and orientation of the dividing cell
  double b = 0;                    // its bud diameter at division
};

// Splits cell i: newborns at (x,y) ∓ (α0/2) n̂; the bud-side one is the daughter
// (new id, parent = id of i, appended at the end), the mother-side one keeps index and id of i.
// Draw order: mother side γ0, θ, noise; then daughter γ0, θ, noise.
Division divide(Packing& p, std::size_t i, const Scene& scene, Rng& rng);

// Grows every cell present at the start by b² ← (1 + γ_i Δt)(D² + b²) − D², in index order,
// dividing a cell as soon as α > 2α0. Cells born in the step do not grow in it.
// `rates` holds γ_i for the cells present at the start.
std::vector<Division> grow_step(Packing& p, const std::vector<double>& rates, double dt, const Scene& scene, Rng& rng);
// Coordinates for a packing grown from the same state as `further`, with the same rates and random
// stream, by a smaller step: `divisions` is what that step divided, `further_divisions` what the
// larger one did. The larger step divides a superset of cells, in the same index order, so every
// cell is in `further`: a cell divided in neither or in both steps takes its coordinates (and its
// daughter's) from there; a cell divided by the larger step only is put back together from its two
// newborns as divide() split it, centroid midway between them and axis from the mother side to the
// daughter. Used to start a relaxation next to `further`'s relaxed configuration. nullopt if a
// division of the smaller step is not in `further_divisions`; throws std::invalid_argument if the
// two do not start from the same number of cells (a daughter index out of place).
std::optional<Eigen::VectorXd> coordinates_before_divisions(const Packing& further,
                                                            const std::vector<Division>& further_divisions,
                                                            const std::vector<Division>& divisions);

// The paper's start: two cells at (L/2, L/2 ∓ 0.5), α = α0 and α = 1 + √(2.5α0 − (α0−1)² − 2).
// Draw order per cell: γ0, then θ uniform in [−π, π).
Packing two_cell_start(const Scene& scene, Rng& rng);

// scene.n_seeds newborn cells at uniformly random, pairwise non-overlapping positions with
// uniform orientations (per cell, draws x, y, θ until it fits, then γ0). Throws InputError if the
// box is too crowded to place them.
Packing random_seeds(const Scene& scene, Rng& rng);

// Either of the above, as the scene asks.
Packing initial_state(const Scene& scene, Rng& rng);

}  // namespace budjam
