// Growth, growth law, division and initial states follow docs/model.md ("Growth") exactly.
#include "budjam/growth.hpp"

#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"

#include "compressed_packing.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

using namespace budjam;

namespace {

constexpr double kPi = std::numbers::pi;

double cell_area(double b) { return 0.25 * kPi * (1.0 + b * b); }

// Smallest angular distance between two angles.
double angle_gap(double a, double b) { return std::abs(std::remainder(a - b, 2 * kPi)); }

Scene base_scene() {
  Scene s;
  s.L = 10;
  return s;
}

}  // namespace

TEST_CASE("uniform01 takes the top 53 bits of the stream and lies in [0, 1)", "[growth]") {
  Rng a(42), b(42);
  for (int k = 0; k < 1000; ++k) {
    const std::uint64_t raw = b();
    const double u = uniform01(a);
    CHECK(u == static_cast<double>(raw >> 11) / 9007199254740992.0);
    CHECK(u >= 0.0);
    CHECK(u < 1.0);
  }
}

TEST_CASE("innate rates are r0 (1 + delta (U - 1/2)) with mean r0", "[growth]") {
  Scene s = base_scene();
  Rng rng(7), copy(7);
  double sum = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double g = draw_innate_rate(s, rng);
    CHECK(g == s.r0 * (1.0 + s.delta * (uniform01(copy) - 0.5)));
    CHECK(g >= s.r0 * (1 - s.delta / 2));
    CHECK(g < s.r0 * (1 + s.delta / 2));
    sum += g;
  }
  // standard error of the mean: r0 δ / sqrt(12 n) ≈ 1.6e-6
  CHECK(sum / n == Approx(s.r0).margin(1e-5));
}

TEST_CASE("a growth step multiplies the cell area by (1 + gamma dt), all into the bud", "[growth]") {
  for (double b : {0.01, 0.3, 0.7245, 1.0199}) {
    for (double gdt : {1e-9, 0.002, 0.5}) {
      const double nb = grown_bud(b, gdt, 1.0);
      CHECK(cell_area(nb) == Approx((1 + gdt) * cell_area(b)).epsilon(1e-14));
      CHECK(nb * nb == Approx((1 + gdt) * (1 + b * b) - 1).epsilon(1e-13));
      CHECK(grown_bud(b, gdt / 4, 4.0) == Approx(nb).epsilon(1e-15));  // only γΔt matters
    }
    CHECK(grown_bud(b, 0.0, 1.0) == b);  // an underflowed growth factor leaves the bud exactly alone
  }
}

TEST_CASE("growth factor exp(-p/P0) is 1 without feedback, exact 0 on underflow, never NaN", "[growth]") {
  CHECK(growth_factor(123.0, std::nullopt) == 1.0);
  CHECK(growth_factor(0.0, 1e-3) == 1.0);
  CHECK(growth_factor(-1e-9, 1e-3) == 1.0);
  CHECK(growth_factor(1e-3, 1e-3) == Approx(std::exp(-1.0)).epsilon(1e-15));
  CHECK(growth_factor(2e-4, 1e-3) == Approx(std::exp(-0.2)).epsilon(1e-15));
  const double inf = std::numeric_limits<double>::infinity();
  for (double p : {0.1, 1.0, 1e3, 1e300, inf}) {
    const double g = growth_factor(p, 1e-5);
    CHECK_FALSE(std::isnan(g));
    CHECK(g == 0.0);
  }
  // no denormals: anything that would be below DBL_MIN is exactly 0
  const double g = growth_factor(709.0 * 1e-5, 1e-5);
  CHECK((g == 0.0 || g >= std::numeric_limits<double>::min()));
  CHECK_THROWS_AS(growth_factor(1.0, 0.0), InputError);
  CHECK_THROWS_AS(growth_factor(1.0, -1e-3), InputError);
}

TEST_CASE("growth rates with P0 = 1e-5 and huge bud pressures are finite and non-negative", "[growth]") {
  Scene s = base_scene();
  Rng rng(3);
  Packing p = two_cell_start(s, rng);
  const std::vector<double> pressures{1e12, std::numeric_limits<double>::infinity()};
  const auto rates = growth_rates(p, &pressures, 1e-5);
  for (double r : rates) {
    CHECK(std::isfinite(r));
    CHECK(r == 0.0);
  }
  const std::vector<double> none{0.0, 0.0};
  CHECK(growth_rates(p, &none, 1e-5) == p.gamma0);
  CHECK(growth_rates(p, &pressures, std::nullopt) == p.gamma0);  // P0 = none: no feedback at all
  CHECK(growth_rates(p, nullptr, 1e-5) == p.gamma0);             // below jamming: no pressures passed
  // Grown with these rates, the compressed buds keep their size exactly.
  Packing q = p;
  grow_step(q, rates, 1.0, s, rng);
  CHECK(q.b == p.b);
}

TEST_CASE("the log growth factor is -p/P0 exactly where the factor underflows, and factor_from_log flushes to 0",
          "[growth]") {
  CHECK(log_growth_factor(400.5, 0.5) == -801.0);
  CHECK(log_growth_factor(-1.0, 0.5) == 0.0);
  CHECK(log_growth_factor(1.0, std::nullopt) == 0.0);
  CHECK(log_growth_factor(std::numeric_limits<double>::infinity(), 1e-5) == -std::numeric_limits<double>::infinity());
  CHECK(growth_factor(400.5, 0.5) == 0.0);
  CHECK(factor_from_log(-1.0) == std::exp(-1.0));
  CHECK(factor_from_log(std::log(std::numeric_limits<double>::min()) + 1e-9) >= std::numeric_limits<double>::min());
  CHECK(factor_from_log(-709.0) == 0.0);  // a bare exp(-709) is a denormal
  CHECK(factor_from_log(std::nan("")) == 0.0);
  CHECK_THROWS_AS(log_growth_factor(1.0, 0.0), InputError);
  CHECK_THROWS_AS(log_growth_factor(std::nan(""), 1.0), std::domain_error);
}

// χ_c averages exp(−p/P0) over the compressed buds only; its logarithm is exact where every factor
// underflows: buds at p/P0 = 800 and 802 give ln χ_c = −800 + ln((1 + e^−2)/2).
TEST_CASE("chi_c is the mean growth factor of the compressed buds, and ln chi_c survives underflow", "[growth]") {
  const CompressedFactor none = mean_compressed_factor({0.0, -1.0}, 1e-3);
  CHECK(none.chi == 1.0);
  CHECK(none.log_chi == 0.0);
  const CompressedFactor mild = mean_compressed_factor({1e-3, 0.0, 2e-3}, 1e-3);
  CHECK(mild.chi == Approx((std::exp(-1.0) + std::exp(-2.0)) / 2).epsilon(1e-15));
  CHECK(mild.log_chi == Approx(std::log(mild.chi)).epsilon(1e-14));
  const CompressedFactor deep = mean_compressed_factor({400.0, 401.0}, 0.5);
  CHECK(deep.chi == 0.0);
  CHECK(deep.log_chi == Approx(-800.0 + std::log((1.0 + std::exp(-2.0)) / 2)).epsilon(1e-15));
  const CompressedFactor free_growth = mean_compressed_factor({1.0, 2.0}, std::nullopt);
  CHECK(free_growth.chi == 1.0);
  CHECK(free_growth.log_chi == 0.0);
}

// P0 = 1/2 makes p/P0 exact: 800 and 801. Both factors underflow (e^-800 < DBL_MIN), so the plain
// rates are 0; taken relative to e^-800 the two differ by e^-1 to the last bit.
TEST_CASE("rates scaled by e^800 keep the ratio of buds at p/P0 = 800 and 801 at exactly e^-1", "[growth]") {
  Scene s = base_scene();
  Rng rng(5);
  Packing p = two_cell_start(s, rng);
  const std::vector<double> pressures{400.0, 400.5};
  CHECK(growth_rates(p, &pressures, 0.5) == std::vector<double>{0.0, 0.0});
  const std::vector<double> rates = growth_rates(p, &pressures, 0.5, 800.0);
  CHECK(rates[0] == p.gamma0[0]);
  CHECK(rates[1] == p.gamma0[1] * std::exp(-1.0));
  CHECK((rates[1] / p.gamma0[1]) / (rates[0] / p.gamma0[0]) == Approx(std::exp(-1.0)).epsilon(1e-15));
  // Log scale 0 is the plain rates bit for bit.
  const std::vector<double> mild{2e-4, 0.0};
  CHECK(growth_rates(p, &mild, 1e-3, 0.0) == std::vector<double>{p.gamma0[0] * growth_factor(2e-4, 1e-3), p.gamma0[1]});
}

// The adaptive step's growth of bud i is γ0_i dt exp(−(p_i − p_min)/P0) of its area: at p/P0 = 5000
// and p_min/P0 = 4999.5 no factor nor Δt = dt e^{4999.5} is a double, the product is e^{−1/2}.
TEST_CASE("a bud at p/P0 = 5000 grows by the log-space value gamma0 dt exp(-(p - p_min)/P0)", "[growth]") {
  Scene s = base_scene();
  Rng rng(7);
  Packing p = two_cell_start(s, rng);
  const std::vector<double> pressures{2500.0, 2499.75};  // P0 = 1/2: p/P0 = 5000, 4999.5
  const double log_scale = 4999.5, dt = 0.75;
  const std::vector<double> rates = growth_rates(p, &pressures, 0.5, log_scale);
  Packing q = p;
  grow_step(q, rates, dt, s, rng);
  const double D2 = kMotherDiameter * kMotherDiameter;
  for (std::size_t i = 0; i < 2; ++i) {
    const double gain = p.gamma0[i] * dt * std::exp(log_scale - pressures[i] / 0.5);  // γ0 Δt e^{−p/P0}, in logs
    const double area = D2 + p.b[i] * p.b[i];
    CHECK(q.b[i] * q.b[i] + D2 == Approx((1.0 + gain) * area).epsilon(1e-15));
    CHECK(q.b[i] > p.b[i]);
  }
  CHECK(rates[1] == p.gamma0[1]);  // the least compressed bud grows as in a nominal step
}

TEST_CASE("division places two newborns at (x,y) -/+ (alpha0/2) n and keeps the identity on the mother side",
          "[growth]") {
  Scene s = base_scene();
  Rng rng(11);
  Packing p;
  p.box.L = s.L;
  p.add_cell(1.0, 2.0, 0.0, 0.3, 0.002, -1);
  const double theta = 0.7;
  p.add_cell(5.0, 5.0, theta, 1.0201, 0.0021, -1);
  const auto id_before = p.id[1];
  const auto next_before = p.next_id;
  const Division d = divide(p, 1, s, rng);
  REQUIRE(p.size() == 3);
  CHECK(d.mother_index == 1);
  CHECK(d.daughter_index == 2);
  CHECK(p.id[1] == id_before);  // mother side keeps the identity
  CHECK(p.parent[1] == -1);
  CHECK(p.id[2] == next_before);  // daughter: new id, parent = old cell
  CHECK(p.parent[2] == id_before);
  CHECK(p.next_id == next_before + 1);
  CHECK(d.mother_id == id_before);
  CHECK(d.daughter_id == p.id[2]);
  CHECK(d.b == 1.0201);
  const double h = 0.5 * s.alpha0;
  CHECK(p.x(1) == Approx(5.0 - h * std::cos(theta)).epsilon(1e-15));
  CHECK(p.y(1) == Approx(5.0 - h * std::sin(theta)).epsilon(1e-15));
  CHECK(p.x(2) == Approx(5.0 + h * std::cos(theta)).epsilon(1e-15));
  CHECK(p.y(2) == Approx(5.0 + h * std::sin(theta)).epsilon(1e-15));
  // both newborn: α = α0
  CHECK(1 + p.b[1] == Approx(s.alpha0).epsilon(1e-15));
  CHECK(1 + p.b[2] == Approx(s.alpha0).epsilon(1e-15));
  CHECK(p.b[1] == newborn_bud(s.alpha0));
  // Area is not conserved: about 2.04 -> 2.0002 in units of π D²/4.
  CHECK((cell_area(p.b[1]) + cell_area(p.b[2])) / (kPi / 4) == Approx(2.0002).epsilon(1e-12));
  // the other cell is untouched
  CHECK(p.x(0) == 1.0);
  CHECK(p.b[0] == 0.3);
  // new innate rates in range, orientations in [−π, π)
  for (std::size_t i : {1u, 2u}) {
    CHECK(p.gamma0[i] >= s.r0 * (1 - s.delta / 2));
    CHECK(p.gamma0[i] < s.r0 * (1 + s.delta / 2));
    CHECK(p.theta(i) >= -kPi);
    CHECK(p.theta(i) < kPi);
  }
}

TEST_CASE("division draws gamma0, theta, noise for the mother side, then the daughter, from one stream", "[growth]") {
  Scene s = base_scene();
  Packing p;
  p.box.L = s.L;
  p.add_cell(5.0, 5.0, 0.2, 1.05, 0.002, -1);
  Rng rng(99), ref(99);
  divide(p, 0, s, rng);
  const double g_m = s.r0 * (1 + s.delta * (uniform01(ref) - 0.5));
  const double th_m = -kPi + 2 * kPi * uniform01(ref);
  const double n_m = 5e-5 * (2 * uniform01(ref) - 1);
  const double g_d = s.r0 * (1 + s.delta * (uniform01(ref) - 0.5));
  const double th_d = -kPi + 2 * kPi * uniform01(ref);
  const double n_d = 5e-5 * (2 * uniform01(ref) - 1);
  CHECK(p.gamma0[0] == g_m);
  CHECK(p.gamma0[1] == g_d);
  CHECK(angle_gap(p.theta(0), th_m + n_m) < 1e-14);
  CHECK(angle_gap(p.theta(1), th_d + n_d) < 1e-14);
  CHECK(rng == ref);  // exactly six draws
}

TEST_CASE("aligned and opposite division rules orient the newborns along the old axis within 5e-5 rad", "[growth]") {
  Scene s = base_scene();
  const double theta = -2.9;
  for (auto rule : {DivisionRule::aligned, DivisionRule::opposite}) {
    s.division = rule;
    for (int seed = 0; seed < 50; ++seed) {
      Packing p;
      p.box.L = s.L;
      p.add_cell(5.0, 5.0, theta, 1.05, 0.002, -1);
      Rng rng(seed);
      divide(p, 0, s, rng);
      const double mother_expected = rule == DivisionRule::aligned ? theta : theta + kPi;
      CHECK(angle_gap(p.theta(0), mother_expected) <= 5e-5 + 1e-15);
      CHECK(angle_gap(p.theta(1), theta) <= 5e-5 + 1e-15);
      CHECK(p.theta(0) >= -kPi);
      CHECK(p.theta(0) < kPi);
    }
  }
}

TEST_CASE("grow_step divides a cell as soon as alpha exceeds 2 alpha0; newborns do not grow in the step", "[growth]") {
  Scene s = base_scene();
  Rng rng(5);
  Packing p;
  p.box.L = s.L;
  p.add_cell(2.0, 2.0, 0.0, 1.0199, 0.002, -1);  // crosses b = 1.02 this step
  p.add_cell(7.0, 7.0, 1.0, 0.5, 0.002, -1);     // does not
  const std::vector<double> rates{0.002, 0.002};
  const Packing before = p;
  const auto divisions = grow_step(p, rates, 1.0, s, rng);
  REQUIRE(divisions.size() == 1);
  REQUIRE(p.size() == 3);
  CHECK(grown_bud(before.b[0], 0.002, 1.0) > 1.02);
  CHECK(p.b[0] == newborn_bud(s.alpha0));  // newborn, not grown again in this step
  CHECK(p.b[2] == newborn_bud(s.alpha0));
  CHECK(p.b[1] == grown_bud(0.5, 0.002, 1.0));
  CHECK(divisions[0].b == grown_bud(before.b[0], 0.002, 1.0));

  // a bud just below the threshold does not divide
  Packing q;
  q.box.L = s.L;
  q.add_cell(2.0, 2.0, 0.0, 1.0, 0.002, -1);
  CHECK(grow_step(q, {0.0}, 1.0, s, rng).empty());
  CHECK_FALSE(ready_to_divide(1.02, s.alpha0));
  CHECK(ready_to_divide(std::nextafter(1.02, 2.0) + 1e-15, s.alpha0));
  CHECK_THROWS(grow_step(q, {}, 1.0, s, rng));
}

TEST_CASE(
    "coordinates before divisions: kept cells copied, a division undone restores the dividing cell's "
    "centroid and axis across the periodic boundary",
    "[growth]") {
  Scene s = base_scene();
  Packing start;
  start.box.L = s.L;
  // Cells 0 and 3 divide only in the larger step, cell 2 in both, cell 1 in neither (rates 0.002:
  // b = 1.0195 reaches 1.01970 at Δt = 0.1 and 1.02150 at Δt = 1; the threshold is 1.02).
  start.add_cell(0.2, 5.0, 3.0, 1.0195, 0.002, -1);  // its daughter lands across x = 0
  start.add_cell(3.0, 3.0, 0.4, 0.5, 0.002, -1);
  start.add_cell(6.0, 2.0, -1.2, 1.0199, 0.002, -1);
  start.add_cell(8.0, 9.9, 1.4, 1.0196, 0.002, -1);  // and this one across y = L
  const std::vector<double> rates(4, 0.002);
  Packing small = start, large = start;
  Rng rng_small(3), rng_large(3);
  const auto d_small = grow_step(small, rates, 0.1, s, rng_small);
  const auto d_large = grow_step(large, rates, 1.0, s, rng_large);
  REQUIRE(d_small.size() == 1);
  REQUIRE(d_small[0].mother_index == 2);
  REQUIRE(d_large.size() == 3);
  // Relaxation may carry a daughter into another periodic image.
  large.q[3 * d_large[0].daughter_index] += s.L;
  large.q[3 * d_large[2].daughter_index + 1] -= s.L;

  const auto q = coordinates_before_divisions(large, d_large, d_small);
  REQUIRE(q);
  REQUIRE(q->size() == small.q.size());
  for (std::size_t i : {0u, 3u}) {
    double dx = (*q)[3 * i] - start.x(i), dy = (*q)[3 * i + 1] - start.y(i);
    start.box.minimum_image(dx, dy);
    CHECK(std::hypot(dx, dy) < 1e-12);
    CHECK(angle_gap((*q)[3 * i + 2], start.theta(i)) < 1e-12);
  }
  CHECK(q->segment<3>(3) == large.q.segment<3>(3));
  CHECK(q->segment<3>(6) == large.q.segment<3>(6));
  CHECK(q->segment<3>(3 * d_small[0].daughter_index) == large.q.segment<3>(3 * d_large[1].daughter_index));

  // The same divisions: exactly the further step's coordinates.
  CHECK(*coordinates_before_divisions(large, d_large, d_large) == large.q);
  // A division the further step did not make has nowhere to come from.
  CHECK_FALSE(coordinates_before_divisions(small, d_small, d_large));
  // Divisions of a different starting packing.
  std::vector<Division> shifted = d_small;
  shifted[0].daughter_index += 1;
  CHECK_THROWS_AS(coordinates_before_divisions(large, d_large, shifted), std::invalid_argument);
}

TEST_CASE("the two-cell start places alpha0 and 1 + sqrt(2.5 alpha0 - (alpha0-1)^2 - 2) cells at the centre",
          "[growth]") {
  Scene s = base_scene();
  s.L = 15;
  Rng rng(1), ref(1);
  const Packing p = two_cell_start(s, rng);
  REQUIRE(p.size() == 2);
  CHECK(p.x(0) == 7.5);
  CHECK(p.y(0) == 7.0);
  CHECK(p.x(1) == 7.5);
  CHECK(p.y(1) == 8.0);
  CHECK(1 + p.b[0] == Approx(1.01).epsilon(1e-15));
  CHECK(1 + p.b[1] == Approx(1.7245).margin(1e-4));
  CHECK(p.b[1] == Approx(std::sqrt(2.5 * 1.01 - 0.01 * 0.01 - 2)).epsilon(1e-15));
  CHECK(p.parent[0] == -1);
  CHECK(p.parent[1] == -1);
  CHECK(p.id[0] != p.id[1]);
  CHECK(p.box.L == 15);
  // draw order per cell: γ0, then θ
  CHECK(p.gamma0[0] == s.r0 * (1 + s.delta * (uniform01(ref) - 0.5)));
  CHECK(p.theta(0) == -kPi + 2 * kPi * uniform01(ref));
  CHECK(p.gamma0[1] == s.r0 * (1 + s.delta * (uniform01(ref) - 0.5)));
  CHECK(p.theta(1) == -kPi + 2 * kPi * uniform01(ref));
}

TEST_CASE("random seeds are newborn cells that overlap nowhere, also across the periodic boundary", "[growth]") {
  Scene s = base_scene();
  s.L = 20;
  s.init = InitialState::random_seeds;
  s.n_seeds = 150;  // covered fraction ≈ 0.30
  Rng rng(17);
  const Packing p = random_seeds(s, rng);
  REQUIRE(p.size() == 150);
  Lobes lobes;
  place_lobes(p, lobes);
  for (std::size_t a = 0; a < lobes.size(); ++a)
    for (std::size_t b = a + 1; b < lobes.size(); ++b) {
      if (cell_of(a) == cell_of(b)) continue;
      double dx = lobes.x[a] - lobes.x[b], dy = lobes.y[a] - lobes.y[b];
      p.box.minimum_image(dx, dy);
      INFO("lobes " << a << " " << b);
      CHECK(std::hypot(dx, dy) >= lobes.R[a] + lobes.R[b]);
    }
  for (std::size_t i = 0; i < p.size(); ++i) {
    CHECK(p.b[i] == newborn_bud(s.alpha0));
    CHECK(p.x(i) >= 0.0);
    CHECK(p.x(i) < s.L);
  }
  Rng again(17);
  const Packing q = random_seeds(s, again);
  CHECK(q.q == p.q);
  CHECK(q.gamma0 == p.gamma0);

  s.n_seeds = 1000;  // cannot fit in 400 D²
  Rng r2(1);
  CHECK_THROWS_AS(random_seeds(s, r2), InputError);
}

// ---- hard case: a division into a crowded neighbourhood ------------------------------
// A jammed packing of random dumbbells (tests/support/compressed_packing.hpp) compressed well past
// jamming, in which the most crowded cell is one growth step from dividing. The step goes through
// the library's own path (growth_rates → grow_step → divide, one random stream) and FIRE relaxes
// the result as the growth driver does.
TEST_CASE(
    "a division into a crowded neighbourhood places newborns exactly and FIRE relaxes them to a finite force balance",
    "[.hard][growth]") {
  testing::CompressionProtocol proto;
  proto.b_max = 1.0;  // every other cell stays below the division threshold during the step
  testing::CompressedPacking cp = testing::compress_random_dumbbells(40, 7, proto);
  Packing p = cp.packing;
  const std::size_t n = p.size();

  // The most crowded cell (most contacts) gets a bud just below the threshold b = 2α0 − 1 = 1.02.
  std::vector<int> contacts_of(n, 0);
  for (const Contact& c : cp.contacts) ++contacts_of[cell_of(c.i)], ++contacts_of[cell_of(c.j)];
  const std::size_t k =
      static_cast<std::size_t>(std::max_element(contacts_of.begin(), contacts_of.end()) - contacts_of.begin());
  p.b[k] = 1.0199;
  // Squeeze φ up by 0.08 and relax, so that every lobe is pressed into its neighbours.
  testing::rescale_to(p, p.packing_fraction() + 0.08);
  Scene scene = base_scene();
  scene.L = p.box.L;
  ForceField field(scene.skin);
  REQUIRE(minimise(p, field, scene.fire).converged);
  Eigen::VectorXd f;
  field.invalidate();
  const double E_before = field.evaluate(p, f) / static_cast<double>(n);
  INFO("E/N before = " << E_before << ", contacts of the dividing cell = " << contacts_of[k]);
  REQUIRE(E_before > 1e-6);  // well past jamming: a crowded neighbourhood

  const Packing before = p;
  Rng rng(3);  // this stream points a newborn bud into a neighbour (checked below)
  const std::vector<double> rates = growth_rates(p, nullptr, std::nullopt);
  const std::vector<Division> divisions = grow_step(p, rates, 1.0, scene, rng);

  // Exactly the one division, bookkept as the model says.
  REQUIRE(divisions.size() == 1);
  const Division& d = divisions[0];
  REQUIRE(p.size() == n + 1);
  CHECK(d.mother_index == k);
  CHECK(d.daughter_index == n);
  CHECK(p.id[k] == before.id[k]);
  CHECK(p.parent[k] == before.parent[k]);
  CHECK(p.id[n] == before.next_id);
  CHECK(p.parent[n] == before.id[k]);
  CHECK(p.next_id == before.next_id + 1);
  CHECK(p.b[k] == newborn_bud(scene.alpha0));
  CHECK(p.b[n] == newborn_bud(scene.alpha0));
  const double h = 0.5 * scene.alpha0, c = std::cos(before.theta(k)), s = std::sin(before.theta(k));
  CHECK(p.x(k) == Approx(before.x(k) - h * c).margin(1e-14));
  CHECK(p.y(k) == Approx(before.y(k) - h * s).margin(1e-14));
  CHECK(p.x(n) == Approx(before.x(k) + h * c).margin(1e-14));
  CHECK(p.y(n) == Approx(before.y(k) + h * s).margin(1e-14));
  for (std::size_t i = 0; i < n; ++i) {
    if (i == k) continue;
    CHECK(p.x(i) == before.x(i));
    CHECK(p.b[i] == grown_bud(before.b[i], rates[i], 1.0));
  }

  // The newborns land inside their neighbours: a 0.01 bud swallowed whole by a neighbour's lobe,
  // and the newborn mothers pressed into theirs.
  Lobes lobes;
  place_lobes(p, lobes);
  double bud_depth = 0;     // largest overlap of a newborn bud with another cell's lobe / bud diameter
  double mother_depth = 0;  // largest overlap of a newborn mother with another cell's lobe
  for (std::size_t cell : {k, n})
    for (std::size_t a : {mother_lobe(cell), bud_lobe(cell)})
      for (std::size_t o = 0; o < lobes.size(); ++o) {
        if (cell_of(o) == cell) continue;
        double dx = lobes.x[a] - lobes.x[o], dy = lobes.y[a] - lobes.y[o];
        p.box.minimum_image(dx, dy);
        const double overlap = lobes.R[a] + lobes.R[o] - std::hypot(dx, dy);
        if (is_bud(a))
          bud_depth = std::max(bud_depth, overlap / (2 * lobes.R[a]));
        else
          mother_depth = std::max(mother_depth, overlap);
      }
  INFO("newborn bud overlap / its diameter = " << bud_depth << ", newborn mother overlap = " << mother_depth);
  REQUIRE(bud_depth >= 1.0);
  REQUIRE(mother_depth > 0.05);

  field.invalidate();
  const double U_divided = field.evaluate(p, f);
  REQUIRE(std::isfinite(U_divided));
  REQUIRE(f.allFinite());

  field.invalidate();
  const FireResult fr = minimise(p, field, scene.fire);
  const double tol = std::max(scene.fire.force_tol, force_resolution(p));
  CHECK(fr.converged);
  CHECK(fr.max_force <= tol);
  CHECK(std::isfinite(fr.energy));
  CHECK(p.q.allFinite());
  CHECK(fr.energy <= U_divided);

  // An independent evaluation of the relaxed state: a true force and torque balance.
  ForceField fresh(scene.skin);
  const double U_after = fresh.evaluate(p, f);
  REQUIRE(f.allFinite());
  CHECK(U_after == Approx(fr.energy).epsilon(1e-12));
  double fmax = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    fmax =
        std::max({fmax, std::abs(f[3 * i]), std::abs(f[3 * i + 1]), std::abs(f[3 * i + 2]) / p.dumbbell(i).gyration});
  }
  CHECK(fmax <= tol);
  CHECK(U_after / static_cast<double>(p.size()) > scene.epsilon_U);  // still jammed: the division did not open space
  // The sisters are neighbours, not on top of each other.
  double dx = p.x(n) - p.x(k), dy = p.y(n) - p.y(k);
  p.box.minimum_image(dx, dy);
  CHECK(std::hypot(dx, dy) > 0.9);
}
