#include "budjam/pareto.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace budjam {

namespace {
double resolution_of(const CostErrors& c, std::size_t q) {
  return q < c.resolution.size() && !std::isnan(c.resolution[q]) ? c.resolution[q] : 0.0;
}
}  // namespace

int compare_errors(double e_a, double e_b, const ParetoTolerance& tol, double r_a, double r_b) {
  if (std::isnan(e_a) || std::isnan(e_b)) return 0;
  if (std::max(e_a, e_b) <= tol.error_floor) return 0;
  if (std::max(0.0, e_a - r_a) > tol.error_ratio * (e_b + r_b)) return 1;
  if (std::max(0.0, e_b - r_b) > tol.error_ratio * (e_a + r_a)) return -1;
  return 0;
}

bool dominates(const CostErrors& a, const CostErrors& b, const ParetoTolerance& tol) {
  if (a.errors.size() != b.errors.size()) throw std::invalid_argument("dominates: settings with different quantities");
  if (a.cost > b.cost * tol.cost_ratio) return false;  // dearer beyond noise
  bool better = a.cost * tol.cost_ratio < b.cost;
  for (std::size_t q = 0; q < a.errors.size(); ++q) {
    const int c = compare_errors(a.errors[q], b.errors[q], tol, resolution_of(a, q), resolution_of(b, q));
    if (c > 0) return false;
    better = better || c < 0;
  }
  return better;
}

std::vector<std::size_t> dominated_by(const std::vector<CostErrors>& settings, std::size_t k,
                                      const ParetoTolerance& tol) {
  std::vector<std::size_t> by;
  for (std::size_t j = 0; j < settings.size(); ++j)
    if (j != k && dominates(settings[j], settings[k], tol)) by.push_back(j);
  return by;
}

std::vector<std::size_t> pareto_front(const std::vector<CostErrors>& settings, const ParetoTolerance& tol) {
  std::vector<std::size_t> front;
  for (std::size_t k = 0; k < settings.size(); ++k)
    if (dominated_by(settings, k, tol).empty()) front.push_back(k);
  return front;
}

}  // namespace budjam
