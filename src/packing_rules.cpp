#include "budjam/packing_rules.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace budjam {

namespace {
// Shortest text that reads back to v.
std::string show(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}
}  // namespace

std::optional<std::string> cell_problem(const Packing& p, std::size_t i, double b_max) {
  const std::string cell = "cell " + std::to_string(i) + ": ";
  const double far = kMaxBoxesAway * p.box.L;
  if (!std::isfinite(p.x(i)) || !std::isfinite(p.y(i)) || !std::isfinite(p.theta(i)))
    return cell + "position or angle not finite";
  if (!(std::abs(p.x(i)) <= far && std::abs(p.y(i)) <= far))
    return cell + "position more than " + show(kMaxBoxesAway) + " box sides from the origin";
  if (!(p.b[i] >= 0 && p.b[i] <= b_max))
    return cell + "bud diameter b = " + show(p.b[i]) + " outside [0, " + show(b_max) + "]";
  if (!(std::isfinite(p.gamma0[i]) && p.gamma0[i] >= 0))
    return cell + "innate rate gamma0 = " + show(p.gamma0[i]) + " must be finite and not negative";
  return std::nullopt;
}

std::optional<std::string> box_problem(const Packing& p, double skin) {
  if (!(std::isfinite(p.box.L) && p.box.L > 0)) return "box side L = " + show(p.box.L) + " must be finite and positive";
  if (!(std::abs(p.box.shear) <= kMaxBoxesAway))
    return "box shear = " + show(p.box.shear) + " must be finite and at most " + show(kMaxBoxesAway) + " in size";
  double sigma_max = kMotherDiameter;
  for (double b : p.b) sigma_max = std::max(sigma_max, b);
  const double L_min = 2.0 * (sigma_max + skin);
  if (!(p.box.L > L_min))
    return "box side L = " + show(p.box.L) + " must exceed 2 (largest lobe diameter + skin) = " + show(L_min) +
           " so that each neighbour pair has one periodic image";
  return std::nullopt;
}

}  // namespace budjam
