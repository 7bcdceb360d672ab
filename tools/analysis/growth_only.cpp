#include "analysis/growth_only.hpp"

#include "budjam/errors.hpp"
#include "budjam/growth.hpp"
#include "budjam/statistics.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace budjam::tools {

GrowthOnlyCount growth_only_cells(const Scene& scene, double phi, std::size_t samples, std::uint64_t first_seed) {
  if (!(phi > 0 && phi < 1)) throw InputError("growth_only_cells: φ must lie in (0, 1), got " + std::to_string(phi));
  if (samples == 0) throw InputError("growth_only_cells: no samples");
  std::vector<double> cells;
  cells.reserve(samples);
  for (std::size_t s = 0; s < samples; ++s) {
    Rng rng(first_seed + s);
    Packing p = initial_state(scene, rng);
    while (p.packing_fraction() < phi) {
      const std::vector<double> rates = p.gamma0;  // a copy: the step appends the newborns' rates
      grow_step(p, rates, scene.dt, scene, rng);
    }
    cells.push_back(static_cast<double>(p.size()));
  }
  const MeanSE m = mean_se(cells);
  return {m.mean, m.se, samples};
}

}  // namespace budjam::tools
