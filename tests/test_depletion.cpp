// Mean-field relations of the paper: Lambert W, the φ_2 prediction, λ_c, B_grow, ΔZ_0(P), h_γ.
#include "budjam/depletion.hpp"
#include "budjam/survival.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

using namespace budjam;

TEST_CASE("Lambert W0 at known points") {
  const double e = std::numbers::e;
  CHECK(lambert_w0(0.0) == 0.0);
  CHECK(lambert_w0(e) == Approx(1.0).epsilon(1e-15));
  CHECK(lambert_w0(2 * e * e) == Approx(2.0).epsilon(1e-15));
  CHECK(lambert_w0(1.0) == Approx(0.5671432904097838).epsilon(1e-15));  // the omega constant
  CHECK(lambert_w0(-std::log(2.0) / 2) == Approx(-std::log(2.0)).epsilon(1e-14));
  CHECK(lambert_w0(-1.0 / e) == Approx(-1.0).margin(1e-7));  // branch point (√ singularity)
  CHECK(lambert_w0(10.0) == Approx(1.7455280027406994).epsilon(1e-15));
  CHECK_THROWS_AS(lambert_w0(-0.5), std::domain_error);
}

TEST_CASE("Lambert W0 inverts w e^w over its whole domain") {
  for (double x : {-0.3678, -0.36, -0.3, -0.1, -1e-6, 1e-8, 0.5, 3.0, 50.0, 1e4, 1e12}) {
    const double w = lambert_w0(x);
    CHECK(w * std::exp(w) == Approx(x).epsilon(1e-13));
    CHECK(w >= -1.0);
  }
}

TEST_CASE("mean-field u_J solves u = exp(-(2 - 2u)) and is about 0.20") {
  const double u = u_J_mean_field();
  CHECK(u == Approx(std::exp(-(2.0 - 2.0 * u))).epsilon(1e-14));
  CHECK(u == Approx(0.2032).margin(5e-4));
  CHECK(u < 1.0);  // not the trivial root
}

TEST_CASE("phi_2 formula for a step survival reduces to Eq. 16") {
  // S(a) = Θ(a_c − a): every tagged bud completes at a_c → a_ε = a_c, ∫_0^{a_ε} S = a_c and
  // n_J[χ̄ a_c + (1 − χ̄) u_J a_c] = n_J a_c [u_J + (1 − u_J) χ̄].
  const double a_c = 0.012, n_J = 0.775, u_J = 0.23, chi = 0.37;
  std::vector<SurvivalRecord> r(40, SurvivalRecord{a_c, true});
  const auto km = kaplan_meier(r);
  const double a_eps = *a_epsilon(km, u_J, 1.0 / 150);
  CHECK(a_eps == a_c);
  CHECK(km.integral(a_eps) == Approx(a_c));
  const double general = phi2_excess(n_J, u_J, chi, a_eps, km.integral(a_eps));
  CHECK(general == Approx(phi2_excess_step(n_J, u_J, chi, a_c)).epsilon(1e-14));
  CHECK(general == Approx(n_J * a_c * (u_J + (1 - u_J) * chi)).epsilon(1e-14));
  // limits: no feedback (χ̄ = 1) → n_J a_ε; total arrest of the compressed sector (χ̄ = 0) → n_J u_J ∫S
  CHECK(phi2_excess(n_J, u_J, 1.0, 0.01, 0.004) == Approx(n_J * 0.01));
  CHECK(phi2_excess(n_J, u_J, 0.0, 0.01, 0.004) == Approx(n_J * u_J * 0.004));
}

TEST_CASE("phi_2 with a as true area is pi/4 of the diameter-squared reading") {
  const auto p = predict_phi2(0.775, 0.23, 0.2, 0.02, 0.008);
  CHECK(p.dphi2_diameter_sq == Approx(phi2_excess(0.775, 0.23, 0.2, 0.02, 0.008)));
  CHECK(p.dphi2_area / p.dphi2_diameter_sq == Approx(std::numbers::pi / 4));
}

TEST_CASE("lambda_c partitions the density increment between the sectors") {
  CHECK(lambda_c(0.0, 0.5) == 1.0);          // no free buds: everything loads the network
  CHECK(lambda_c(0.2, 1.0) == Approx(0.8));  // no feedback: λ_c = 1 − u
  CHECK(lambda_c(0.2, 0.0) == 0.0);          // full arrest: all growth goes into free buds
  for (double u : {0.05, 0.2, 0.5})
    for (double chi : {1e-3, 0.3, 0.9}) {
      const double g = u + (1 - u) * chi;  // ⟨g⟩, Eq. E5
      CHECK(lambda_c(u, chi) == Approx(1.0 - u / g));
    }
}

TEST_CASE("interval average is the trapezoid mean over the interval") {
  const std::vector<double> x{0.0, 1.0, 2.0, 3.0, 4.0, 10.0};
  const std::vector<double> y{5.0, 1.0, 2.0, 3.0, 4.0, 100.0};
  CHECK(interval_average(x, y, 1.0, 4.0) == Approx(2.5));  // linear y = x on [1, 4]
  CHECK(interval_average(x, y, 2.0, 2.0) == 2.0);
  CHECK(std::isnan(interval_average(x, y, 5.0, 6.0)));
}

TEST_CASE("B_grow is phi dP/dphi over the last five states before the target") {
  // P rises with slope 3 up to φ = 0.84 and with slope 7 over the last five states before 0.85;
  // a state beyond the target must be ignored.
  std::vector<double> phi, P;
  for (int k = 0; k < 10; ++k) {
    phi.push_back(0.80 + 0.004 * k);
    P.push_back(3.0 * 0.004 * k);
  }
  const double p0 = P.back(), f0 = phi.back();
  for (int k = 1; k <= 5; ++k) {
    phi.push_back(f0 + 0.002 * k);
    P.push_back(p0 + 7.0 * 0.002 * k);
  }
  phi.push_back(0.9);
  P.push_back(100.0);
  const double target = phi[14];
  const auto b = b_grow(phi, P, target);
  REQUIRE(b);
  CHECK(b->points == 5);
  CHECK(b->B == Approx(target * 7.0).epsilon(1e-10));
  CHECK(b->B_se == Approx(0.0).margin(1e-9));
  CHECK_FALSE(b_grow(std::vector<double>{0.8}, std::vector<double>{0.0}, 0.8));
}

TEST_CASE("piecewise-linear branch interpolates, clamps and averages repeated points") {
  const PiecewiseLinear f({{1e-3, 0.5}, {1e-4, 0.1}, {1e-2, 1.5}, {1e-2, 2.5}});
  CHECK(f(1e-4) == Approx(0.1));
  CHECK(f(5.5e-4) == Approx(0.3));
  CHECK(f(1e-2) == Approx(2.0));
  CHECK(f(0.0) == Approx(0.1));
  CHECK(f(1.0) == Approx(2.0));
}

TEST_CASE("h_gamma of a two-sector sample equals the sector-moment formula") {
  // u of the cells at g = 1 (unconstrained), the rest at g = χ: χ_c2 = χ².
  std::vector<double> g;
  for (int k = 0; k < 20; ++k) g.push_back(1.0);
  for (int k = 0; k < 80; ++k) g.push_back(0.25);
  CHECK(growth_heterogeneity(g) == Approx(growth_heterogeneity_sectors(0.2, 0.25, 0.0625)));
  CHECK(growth_heterogeneity(std::vector<double>(5, 1.0)) == 0.0);  // no feedback: δ(g − 1)
}

TEST_CASE("histogram counts values in half-open bins, last bin closed") {
  const std::vector<double> edges{0.0, 0.5, 1.0};
  const auto c = histogram(std::vector<double>{0.0, 0.2, 0.5, 0.99, 1.0, 1.5}, edges);
  CHECK(c[0] == 2);
  CHECK(c[1] == 3);
}
