#include "budjam/packing_rules.hpp"

#include "budjam/number_text.hpp"
#include "budjam/scene_keys.hpp"  // kMaxBoxSide

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace budjam {

std::optional<std::string> cell_problem(const Packing& p, std::size_t i, double b_max) {
  const std::string cell = "cell " + std::to_string(i) + ": ";
  const double far = kMaxBoxesAway * p.box.L;
  if (!std::isfinite(p.x(i)) || !std::isfinite(p.y(i)) || !std::isfinite(p.theta(i)))
    return cell + "position or angle not finite";
  if (!(std::abs(p.x(i)) <= far && std::abs(p.y(i)) <= far))
    return cell + "position more than " + shortest_text(kMaxBoxesAway) + " box sides from the origin";
  if (!(p.b[i] >= 0 && p.b[i] <= b_max))
    return cell + "bud diameter b = " + shortest_text(p.b[i]) + " outside [0, " + shortest_text(b_max) + "]";
  if (!(std::isfinite(p.gamma0[i]) && p.gamma0[i] >= 0))
    return cell + "innate rate gamma0 = " + shortest_text(p.gamma0[i]) + " must be finite and not negative";
  return std::nullopt;
}

std::optional<std::string> box_problem(const Packing& p, double skin) {
  if (!(std::isfinite(p.box.L) && p.box.L > 0))
    return "box side L = " + shortest_text(p.box.L) + " must be finite and positive";
  if (!(p.box.L <= kMaxBoxSide))
    return "box side L = " + shortest_text(p.box.L) + " must be at most " + shortest_text(kMaxBoxSide) +
           " (the largest box.L of a scene)";
  if (!(std::abs(p.box.shear) <= kMaxBoxesAway))
    return "box shear = " + shortest_text(p.box.shear) + " must be finite and at most " + shortest_text(kMaxBoxesAway) +
           " in size";
  double sigma_max = kMotherDiameter;
  for (double b : p.b) sigma_max = std::max(sigma_max, b);
  const double L_min = 2.0 * (sigma_max + skin);
  if (!(p.box.L > L_min))
    return "box side L = " + shortest_text(p.box.L) +
           " must exceed 2 (largest lobe diameter + skin) = " + shortest_text(L_min) +
           " so that each neighbour pair has one periodic image";
  return std::nullopt;
}

std::optional<std::string> density_problem(const Packing& p) {
  const double phi = p.packing_fraction();
  if (!(phi < kMaxPackingFraction))
    return "packing fraction phi = " + shortest_text(phi) + " must be below " + shortest_text(kMaxPackingFraction) +
           " (the bound that lobes overlapping by less than half their contact distance allow)";
  return std::nullopt;
}

std::optional<std::string> overlap_problem(const Packing& p, std::pair<std::size_t, std::size_t>* first) {
  Lobes lobes;
  place_lobes(p, lobes);
  const std::size_t n = lobes.size();
  if (n == 0) return std::nullopt;
  // The lattice of shear γ is that of γ − round(γ); in the coordinates (x − γ y, y) it is square, so
  // lobes are binned there, with bins wide enough that a pair within reach is in adjacent ones.
  const double L = p.box.L;
  const Box box{L, p.box.shear - std::nearbyint(p.box.shear)};
  double reach = 0;  // largest σ of any pair
  for (double R : lobes.R) reach = std::max(reach, 2 * R);
  // At most about one bin per lobe a side: a huge box with few cells must not allocate empty bins.
  const double side_max = std::max(1.0, std::floor(std::sqrt(static_cast<double>(n))));
  const auto bins_along = [L, side_max](double width) {
    return static_cast<long>(std::clamp(std::floor(L / width), 1.0, side_max));
  };
  const long ns = bins_along(reach * (1 + std::abs(box.shear))), ny = bins_along(reach);
  const auto wrap = [L](double v) { return v - L * std::floor(v / L); };
  const auto bin_of = [](double v, double L_, long nb) { return std::min(nb - 1, static_cast<long>(v / L_ * nb)); };
  std::vector<long> bin(n);
  std::vector<std::uint32_t> start(static_cast<std::size_t>(ns * ny) + 1, 0), members(n);
  for (std::size_t a = 0; a < n; ++a) {
    const long bs = bin_of(wrap(lobes.x[a] - box.shear * lobes.y[a]), L, ns), by = bin_of(wrap(lobes.y[a]), L, ny);
    bin[a] = by * ns + bs;
    ++start[static_cast<std::size_t>(bin[a]) + 1];
  }
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t a = 0; a < n; ++a) members[fill[static_cast<std::size_t>(bin[a])]++] = static_cast<std::uint32_t>(a);

  std::vector<long> around;
  for (std::size_t a = 0; a < n; ++a) {
    const long bs = bin[a] % ns, by = bin[a] / ns;
    around.clear();
    for (long dy = -1; dy <= 1; ++dy)
      for (long ds = -1; ds <= 1; ++ds) around.push_back(((by + dy + ny) % ny) * ns + (bs + ds + ns) % ns);
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());  // fewer than 3 bins a side
    std::size_t worst = n;
    double r_worst = 0, sigma_worst = 0;
    for (long c : around)
      for (std::uint32_t k = start[static_cast<std::size_t>(c)]; k < start[static_cast<std::size_t>(c) + 1]; ++k) {
        const std::size_t b = members[k];
        if (b <= a || b >= worst || cell_of(b) == cell_of(a)) continue;
        double dx = lobes.x[b] - lobes.x[a], dy = lobes.y[b] - lobes.y[a];
        box.minimum_image(dx, dy);
        const double r = std::hypot(dx, dy), sigma = lobes.R[a] + lobes.R[b];
        if (r < sigma && r <= kMinContactRatio * sigma) {
          worst = b;
          r_worst = r;
          sigma_worst = sigma;
        }
      }
    if (worst == n) continue;
    const auto lobe = [](std::size_t l) {
      return std::string(is_bud(l) ? "bud" : "mother") + " of cell " + std::to_string(cell_of(l));
    };
    if (first) *first = {cell_of(a), cell_of(worst)};
    return "the " + lobe(a) + " and the " + lobe(worst) + " are r = " + shortest_text(r_worst) +
           " apart, not more than half their contact distance sigma = " + shortest_text(sigma_worst) +
           " (stacked or interpenetrating cells)";
  }
  return std::nullopt;
}

}  // namespace budjam
