#pragma once
// The cell count that the growth and division rules alone give at a packing fraction: below jamming
// every cell grows at its innate rate γ0_i and φ = Σ A_cell / L² depends on the cell areas only, so
// the number of cells at a given φ is a property of the growth process, with no mechanics in it.
// It is the baseline against which the cell count at jamming is read across box sizes: N/L² at
// fixed φ is not monotone in L (divisions come in waves from the two founders, and a box of a given
// size catches a wave at a given phase), so the cell density at jamming is compared with this
// expectation at each size instead of being fitted by q_∞ + c/N (docs/analysis.md, "Finite size").
#include "budjam/scene.hpp"

#include <cstddef>
#include <cstdint>

namespace budjam::tools {

struct GrowthOnlyCount {
  double mean = 0, se = 0;  // cells at the first nominal step with φ ≥ the target, over the samples
  std::size_t samples = 0;
};

// `samples` independent growth histories of `scene` (its box, cell parameters and initial state; the
// nominal step scene.dt, no feedback since feedback acts only above jamming) with seeds first_seed,
// first_seed + 1, …, each grown by nominal steps until φ ≥ `phi`. Throws InputError for φ outside
// (0, 1) or no samples.
GrowthOnlyCount growth_only_cells(const Scene& scene, double phi, std::size_t samples, std::uint64_t first_seed);

}  // namespace budjam::tools
