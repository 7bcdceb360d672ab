#pragma once
// Accuracy against cost: which settings of one numerical knob are worth using. A setting
// has a cost (seconds) and errors of several quantities; a setting is on the (Pareto) front when no
// other setting of the same knob is at least as cheap and at least as accurate in every quantity
// and better in one. Measured costs and errors carry noise, so comparisons allow ties:
//   cost:  a is cheaper than b when a.cost · cost_ratio < b.cost; not dearer when a.cost ≤ b.cost · cost_ratio
//   error: e_a and e_b tie when both are ≤ error_floor, or when the larger is ≤ error_ratio × the smaller;
//          otherwise the smaller one is better
// An error may carry a statistical resolution r (an ensemble quantity measured on a few seeds: the
// error is a difference of means, r its uncertainty): it is then known only to lie in
// [max(0, e − r), e + r], and a is worse than b only when a's lower end exceeds error_ratio × b's
// upper end. With r = 0 this is the rule above. A resolution is never taken from fewer than 5 seeds
// (`budjam accuracy`): such an ensemble error is passed as NaN, not as an exact one.
// Errors that are NaN (not measured, or a quantity the knob cannot change) take no part.
// With tolerances, dominance is not transitive; the front is the set of settings that no other
// setting dominates. A default is "on the front" of its knob when no other setting of that knob
// dominates it.
#include <cstddef>
#include <vector>

namespace budjam {

struct CostErrors {
  double cost = 0;                 // seconds (or any cost), finite
  std::vector<double> errors;      // one per quantity, ≥ 0 or NaN
  std::vector<double> resolution;  // one per quantity (≥ 0; NaN = 0), or empty: every error exact
};

struct ParetoTolerance {
  double cost_ratio = 1.15;   // timing noise: costs within 15 % are a tie
  double error_ratio = 2.0;   // errors within a factor 2 are a tie (seed-to-seed spread)
  double error_floor = 1e-9;  // errors both at or below this are a tie (rounding level)
};

// −1: e_a better than e_b, 0: tie, +1: worse (NaN on either side: tie). r_a, r_b: the errors'
// statistical resolutions.
int compare_errors(double e_a, double e_b, const ParetoTolerance& tol, double r_a = 0, double r_b = 0);
// a dominates b: not dearer and no error worse (beyond the tolerances), and cheaper or some error better.
bool dominates(const CostErrors& a, const CostErrors& b, const ParetoTolerance& tol);
// Indices of the settings that no other setting dominates, ascending.
std::vector<std::size_t> pareto_front(const std::vector<CostErrors>& settings, const ParetoTolerance& tol);
// Indices of the settings that dominate settings[k].
std::vector<std::size_t> dominated_by(const std::vector<CostErrors>& settings, std::size_t k,
                                      const ParetoTolerance& tol);

}  // namespace budjam
