#pragma once
// Random overlapping dumbbells at packing fraction φ, for the mechanics tests. `periods` > 0 puts
// centroids up to that many box lengths outside the box, to exercise the minimum image.
#include "budjam/packing.hpp"
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace budjam::testing {

inline Packing random_packing(std::size_t n, double phi, std::uint64_t seed, double b_min = 0.01,
                              double b_max = 1.02, int periods = 0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> b(n);
  double area = 0;
  for (auto& bi : b) {
    bi = b_min + (b_max - b_min) * u(rng);
    area += 0.25 * std::numbers::pi * (1 + bi * bi);
  }
  Packing p;
  p.box.L = std::sqrt(area / phi);
  std::uniform_int_distribution<int> period(-periods, periods);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = p.box.L * (u(rng) + (periods > 0 ? period(rng) : 0));
    const double y = p.box.L * (u(rng) + (periods > 0 ? period(rng) : 0));
    p.add_cell(x, y, std::numbers::pi * (2 * u(rng) - 1), b[i], 0.002, -1);
  }
  return p;
}

}  // namespace budjam::testing
