// Non-dominated settings with noise tolerances (budjam/pareto.hpp), on hand-worked examples.
#include "budjam/pareto.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace budjam;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();
}

TEST_CASE("Errors tie within the factor error_ratio or below error_floor; NaN never decides", "[fast]") {
  const ParetoTolerance tol{.cost_ratio = 1.15, .error_ratio = 2.0, .error_floor = 1e-9};
  CHECK(compare_errors(1e-6, 1.9e-6, tol) == 0);
  CHECK(compare_errors(1e-6, 2.1e-6, tol) == -1);
  CHECK(compare_errors(2.1e-6, 1e-6, tol) == 1);
  CHECK(compare_errors(0.0, 1e-10, tol) == 0);  // both at rounding level
  CHECK(compare_errors(0.0, 2e-9, tol) == -1);  // zero against a resolved error
  CHECK(compare_errors(0.0, 0.0, tol) == 0);
  CHECK(compare_errors(kNaN, 1.0, tol) == 0);
  CHECK(compare_errors(1.0, kNaN, tol) == 0);
}

TEST_CASE("A setting dominates another only if nowhere worse beyond noise and somewhere better", "[fast]") {
  const ParetoTolerance tol;  // 15 % in cost, factor 2 in error, floor 1e-9
  const CostErrors base{1.0, {1e-6, 1e-3}, {}};
  CHECK(dominates(CostErrors{0.8, {1e-6, 1e-3}, {}}, base, tol));        // cheaper, same errors
  CHECK_FALSE(dominates(CostErrors{0.9, {1e-6, 1e-3}, {}}, base, tol));  // 10 % cheaper: a tie
  CHECK(dominates(CostErrors{1.1, {1e-7, 1e-3}, {}}, base, tol));        // as cheap within noise, more accurate
  CHECK_FALSE(dominates(CostErrors{1.2, {1e-7, 1e-3}, {}}, base, tol));  // more accurate but dearer
  CHECK_FALSE(dominates(CostErrors{0.5, {1e-6, 1e-2}, {}}, base, tol));  // cheaper but worse in one quantity
  CHECK(dominates(CostErrors{0.5, {kNaN, 1e-3}, {}}, base, tol));        // an unmeasured quantity does not count
  CHECK_FALSE(dominates(base, base, tol));                               // nothing dominates itself
  CHECK_THROWS_AS(dominates(CostErrors{1.0, {0.0}, {}}, base, tol), std::invalid_argument);
}

TEST_CASE("The front of a knob: a tolerance sweep keeps the cheap-loose and dear-tight ends, drops the wasteful",
          "[fast]") {
  const ParetoTolerance tol;
  // Error falls with cost, except "wasteful", which costs more than "tight" for the same error.
  const std::vector<CostErrors> s{
      {0.1, {1e-3}, {}},    // 0 loose
      {0.2, {1e-6}, {}},    // 1 medium
      {0.4, {1e-10}, {}},   // 2 tight (at the floor)
      {1.0, {1e-12}, {}},   // 3 wasteful: no better than tight (both ≤ floor), dearer
      {0.21, {5e-3}, {}}};  // 4 dominated by medium (same cost within noise, worse) and loose
  CHECK(pareto_front(s, tol) == std::vector<std::size_t>{0, 1, 2});
  CHECK(dominated_by(s, 3, tol) == std::vector<std::size_t>{2});
  CHECK(dominated_by(s, 4, tol) == std::vector<std::size_t>{0, 1});  // loose: cheaper and more accurate too
  CHECK(dominated_by(s, 1, tol).empty());
}

TEST_CASE(
    "An error known within a statistical resolution is worse than another only if its lower end exceeds error_ratio "
    "times the other's upper end",
    "[fast]") {
  const ParetoTolerance tol{.cost_ratio = 1.15, .error_ratio = 2.0, .error_floor = 1e-9};
  // One of three seeds switched branch: mean 3.7e-3, 2 SE = 7.4e-3. Not resolved from zero.
  CHECK(compare_errors(3.7e-3, 2e-8, tol, 7.4e-3, 0.0) == 0);
  CHECK(compare_errors(2e-8, 3.7e-3, tol, 0.0, 7.4e-3) == 0);
  // Resolved: the lower end 1e-2 − 1e-3 exceeds 2 × (1e-3 + 1e-4).
  CHECK(compare_errors(1e-2, 1e-3, tol, 1e-3, 1e-4) == 1);
  CHECK(compare_errors(1e-3, 1e-2, tol, 1e-4, 1e-3) == -1);
  // The resolution widens the tie band: 1e-2 ± 4e-3 against 1e-3 ± 1e-3 (6e-3 > 2 × 2e-3: worse), and
  // against 1e-3 ± 2.5e-3 (6e-3 < 2 × 3.5e-3: a tie).
  CHECK(compare_errors(1e-2, 1e-3, tol, 4e-3, 1e-3) == 1);
  CHECK(compare_errors(1e-2, 1e-3, tol, 4e-3, 2.5e-3) == 0);
  // With no resolution the rule is the plain one.
  CHECK(compare_errors(1e-6, 2.1e-6, tol, 0.0, 0.0) == -1);
  // In dominance: a cheaper setting whose φ_2-like error is unresolved is not beaten by an accurate dear one,
  // and dominates it when it is cheaper beyond the cost band.
  const CostErrors branchy{1.0, {3.7e-3}, {7.4e-3}}, steady{1.3, {2e-8}, {1e-8}};
  CHECK_FALSE(dominates(steady, branchy, tol));
  CHECK(dominates(branchy, steady, tol));
  // The resolution is per quantity and may be NaN (not measured): then the error counts as exact.
  const CostErrors nan_res{1.0, {3.7e-3}, {std::numeric_limits<double>::quiet_NaN()}};
  CHECK(dominates(CostErrors{1.0, {2e-8}, {}}, nan_res, tol));
}
