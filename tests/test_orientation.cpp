// Cell axes (cos θ, sin θ) from the vector maths library: accurate, the same value for a θ
// however it is computed (alone, in a batch, at any position of a batch), and the force field's
// lobes are place_lobes' lobes bit for bit.
#include "budjam/energy.hpp"
#include "budjam/orientation.hpp"
#include "budjam/packing.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>
#include "random_packing.hpp"

using namespace budjam;

namespace {

std::vector<double> angles(std::size_t n, double range, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-range, range);
  std::vector<double> t(n);
  for (double& v : t) v = u(rng);
  return t;
}

}  // namespace

TEST_CASE("axes lie within 4 ulp of cos θ and sin θ, and on the unit circle", "[orientation]") {
  // Angles of a run stay within a few turns; the large ones reach the library's slow path.
  const double eps = std::numeric_limits<double>::epsilon();
  for (const double range : {1.0, 2 * std::numbers::pi, 100.0, 1e6, 1e15}) {
    const auto t = angles(1001, range, 7);
    std::vector<double> c(t.size()), s(t.size());
    axes(t.data(), t.size(), c.data(), s.data());
    for (std::size_t k = 0; k < t.size(); ++k) {
      INFO("θ = " << t[k]);
      // 4 ulp of a value of magnitude ≤ 1, and never worse than 4 ε: the library's bound.
      CHECK(std::abs(c[k] - std::cos(t[k])) <= 4 * eps);
      CHECK(std::abs(s[k] - std::sin(t[k])) <= 4 * eps);
      CHECK(std::abs(c[k] * c[k] + s[k] * s[k] - 1.0) <= 8 * eps);
    }
  }
  const Axis zero = axis(0.0), quarter = axis(0.5 * std::numbers::pi), half = axis(std::numbers::pi);
  CHECK(zero.c == 1.0);
  CHECK(zero.s == 0.0);
  CHECK(std::abs(quarter.c) <= eps);
  CHECK(quarter.s == 1.0);
  CHECK(half.c == -1.0);
  CHECK(std::abs(half.s) <= eps);
}

TEST_CASE("an angle's axis is the same alone, in a batch of any length and at any place in it", "[orientation]") {
  // Vector lanes are independent, and a short tail is padded: no value may depend on its neighbours.
  const auto t = angles(37, 50.0, 11);
  std::vector<double> c(t.size()), s(t.size());
  axes(t.data(), t.size(), c.data(), s.data());
  for (std::size_t k = 0; k < t.size(); ++k) {
    const Axis a = axis(t[k]);
    CHECK(a.c == c[k]);
    CHECK(a.s == s[k]);
  }
  for (std::size_t n = 1; n <= 9; ++n)
    for (std::size_t first = 0; first + n <= t.size(); first += 5) {
      std::vector<double> cn(n), sn(n);
      axes(t.data() + first, n, cn.data(), sn.data());
      for (std::size_t k = 0; k < n; ++k) {
        CHECK(cn[k] == c[first + k]);
        CHECK(sn[k] == s[first + k]);
      }
    }
  // A batch mixing ordinary and huge angles (the library's slow path for some lanes only).
  std::vector<double> mixed = {0.3, 1e300, -2.0, 7e9, 1.0, -1e20, 3.0};
  std::vector<double> cm(mixed.size()), sm(mixed.size());
  axes(mixed.data(), mixed.size(), cm.data(), sm.data());
  for (std::size_t k = 0; k < mixed.size(); ++k) {
    CHECK(axis(mixed[k]).c == cm[k]);
    CHECK(axis(mixed[k]).s == sm[k]);
  }
}

TEST_CASE("the force field places the lobes where place_lobes does, bit for bit, as cells turn", "[orientation]") {
  // Contacts, stresses and rigidity are found from place_lobes; the forces from the field's own
  // lobes. They must be the same numbers, including for cells that did not turn.
  Packing p = testing::random_packing(300, 0.85, 5, 0.05, 1.0);
  ForceField field(0.15);
  Eigen::VectorXd F;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> kick(0.0, 0.01);
  for (int round = 0; round < 4; ++round) {
    field.evaluate(p, F);
    Lobes reference;
    place_lobes(p, reference);
    const Lobes& mine = field.lobes();
    REQUIRE(mine.size() == reference.size());
    for (std::size_t a = 0; a < mine.size(); ++a) {
      CHECK(mine.x[a] == reference.x[a]);
      CHECK(mine.y[a] == reference.y[a]);
      CHECK(mine.R[a] == reference.R[a]);
    }
    // Turn and move every other cell only, and grow one bud: the others keep their cached axes.
    for (std::size_t i = 0; i < p.size(); i += 2) {
      p.q[3 * i] += kick(rng);
      p.q[3 * i + 2] += 10 * kick(rng);
    }
    p.b[round] = std::min(1.0, p.b[round] + 0.01);
  }
}
