#include "random_packing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace budjam::testing {

Packing random_packing(std::size_t n, double phi, std::uint64_t seed, double b_min, double b_max, int periods) {
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

Packing random_dumbbells(std::size_t n, double phi, double b_min, double b_max, std::uint64_t seed) {
  if (n == 0 || !(phi > 0 && phi < 0.6) || !(b_min >= 0) || !(b_max >= b_min) || b_max > 1.2 * kMotherDiameter)
    throw std::invalid_argument("random_dumbbells: need n > 0, 0 < phi < 0.6, 0 ≤ b_min ≤ b_max ≤ 1.2");
  std::mt19937_64 rng(seed);
  auto uni = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  std::vector<double> b(n);
  double area = 0;
  for (auto& bi : b) {
    bi = b_min + (b_max - b_min) * uni();
    area += 0.25 * std::numbers::pi * (kMotherDiameter * kMotherDiameter + bi * bi);
  }
  Packing p;
  p.box.L = std::sqrt(area / phi);
  const double L = p.box.L;
  // Random sequential addition: no overlaps, so FIRE never starts from interpenetrated cells
  // (a lobe trapped between the two lobes of another cell is a self-stressed local minimum).
  // Grid of centroids with cells of side ≥ 2 × the largest centroid-to-lobe-edge distance.
  const double reach = 0.5 * (kMotherDiameter + 1.2) + 0.6;
  const int g = std::max(1, static_cast<int>(L / (2 * reach)));
  const double cell = L / g;
  std::vector<std::vector<std::size_t>> grid(static_cast<std::size_t>(g * g));
  auto lobes_of = [&](double x, double y, double th, double bi, double out[2][3]) {
    const Dumbbell d = Dumbbell::of(bi);
    out[0][0] = x - d.mother_offset * std::cos(th), out[0][1] = y - d.mother_offset * std::sin(th),
    out[0][2] = 0.5 * d.D;
    out[1][0] = x + d.bud_offset * std::cos(th), out[1][1] = y + d.bud_offset * std::sin(th), out[1][2] = 0.5 * d.b;
  };
  std::vector<std::array<double, 6>> placed;  // lobe centres and radii of placed cells
  for (std::size_t i = 0; i < n; ++i) {
    bool ok = false;
    for (int attempt = 0; attempt < 100000 && !ok; ++attempt) {
      const double x = L * uni(), y = L * uni(), th = 2 * std::numbers::pi * (uni() - 0.5);
      double lo[2][3];
      lobes_of(x, y, th, b[i], lo);
      const int gx = std::min(g - 1, static_cast<int>(x / cell)), gy = std::min(g - 1, static_cast<int>(y / cell));
      ok = true;
      for (int dx = -1; dx <= 1 && ok; ++dx)
        for (int dy = -1; dy <= 1 && ok; ++dy) {
          if (g < 3 && (dx != 0 || dy != 0)) continue;  // tiny box: one cell holds everything
          const auto& bucket = grid[static_cast<std::size_t>(((gx + dx + g) % g) * g + (gy + dy + g) % g)];
          for (std::size_t k : bucket) {
            const auto& o = placed[k];
            for (int a = 0; a < 2 && ok; ++a)
              for (int c = 0; c < 2 && ok; ++c) {
                double ddx = lo[a][0] - o[3 * c], ddy = lo[a][1] - o[3 * c + 1];
                p.box.minimum_image(ddx, ddy);
                if (std::hypot(ddx, ddy) < lo[a][2] + o[3 * c + 2]) ok = false;
              }
            if (!ok) break;
          }
        }
      if (ok) {
        p.add_cell(x, y, th, b[i], 0.002, -1);
        placed.push_back({lo[0][0], lo[0][1], lo[0][2], lo[1][0], lo[1][1], lo[1][2]});
        grid[static_cast<std::size_t>(gx * g + gy)].push_back(i);
      }
    }
    if (!ok)
      throw std::invalid_argument("random_dumbbells: cannot place cell " + std::to_string(i) +
                                  " at phi = " + std::to_string(phi));
  }
  return p;
}

}  // namespace budjam::testing
