// Ensemble statistics against closed forms and hand-worked values.
#include "budjam/statistics.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

using namespace budjam;

TEST_CASE("mean, variances and standard error match hand-worked values") {
  const std::vector<double> x{2, 4, 4, 4, 5, 5, 7, 9};  // mean 5, Σ(x − x̄)² = 32
  CHECK(mean(x) == Approx(5.0));
  CHECK(population_variance(x) == Approx(4.0));     // 32 / 8
  CHECK(sample_variance(x) == Approx(32.0 / 7.0));  // 32 / 7
  CHECK(standard_error(x) == Approx(std::sqrt(32.0 / 7.0 / 8.0)));
  CHECK(std::isnan(standard_error(std::vector<double>{1.0})));
  CHECK(std::isnan(mean(std::vector<double>{})));
}

TEST_CASE("median and type-7 quantiles interpolate between order statistics") {
  CHECK(median({3, 1, 2}) == 2.0);
  CHECK(median({4, 1, 3, 2}) == 2.5);
  // {1,2,3,4}: h = 3q; q = 0.25 → h = 0.75 → 1 + 0.75·(2 − 1) = 1.75
  CHECK(quantile({4, 3, 2, 1}, 0.25) == Approx(1.75));
  CHECK(quantile({4, 3, 2, 1}, 0.0) == 1.0);
  CHECK(quantile({4, 3, 2, 1}, 1.0) == 4.0);
  CHECK_THROWS(quantile({1.0}, 1.5));
}

TEST_CASE("uniform_index is unbiased over a small range") {
  std::mt19937_64 rng(7);
  std::vector<int> counts(3, 0);
  const int draws = 300000;
  for (int k = 0; k < draws; ++k) counts[uniform_index(rng, 3)]++;
  for (int c : counts) CHECK(std::abs(c - draws / 3) < 5 * std::sqrt(draws * (1.0 / 3) * (2.0 / 3)));
}

TEST_CASE("bootstrap SE of the mean approaches s/sqrt(n) * sqrt((n-1)/n)") {
  // The bootstrap distribution of the mean has variance σ̂²/n with the plug-in σ̂² = s²(n − 1)/n.
  const std::vector<double> x{0.3, 1.7, 2.2, -0.4, 5.1, 3.3, 0.9, 2.8, 1.1, 4.0};
  const double n = static_cast<double>(x.size());
  const double closed = standard_error(x) * std::sqrt((n - 1) / n);
  BootstrapOptions opt;
  opt.resamples = 200000;  // Monte Carlo error of the SE ≈ 1/√(2·resamples) ≈ 0.16 %
  opt.seed = 11;
  const auto b = bootstrap_mean(x, opt);
  CHECK(b.estimate == Approx(mean(x)));
  CHECK(b.se == Approx(closed).epsilon(0.01));
  // the 95 % percentile interval of a nearly normal statistic is about mean ± 1.96 SE
  CHECK(b.lo == Approx(mean(x) - 1.96 * closed).epsilon(0.03));
  CHECK(b.hi == Approx(mean(x) + 1.96 * closed).epsilon(0.03));
}

TEST_CASE("bootstrap of the median of {1,2,3} reproduces its exact resampling distribution") {
  // Median of 3 draws with replacement from {1,2,3}: P(1) = P(3) = 3(1/3)²(2/3) + (1/3)³ = 7/27,
  // P(2) = 13/27. Mean 2, variance 14/27.
  const std::vector<double> x{1, 2, 3};
  BootstrapOptions opt;
  opt.resamples = 100000;
  const auto b = bootstrap_median(x, opt);
  CHECK(b.estimate == 2.0);
  CHECK(b.se == Approx(std::sqrt(14.0 / 27.0)).epsilon(0.01));
  CHECK(b.lo == 1.0);  // 7/27 > 2.5 %: the interval reaches both ends
  CHECK(b.hi == 3.0);
}

TEST_CASE("bootstrap is deterministic for a seed and changes with it") {
  const std::vector<double> x{1, 5, 2, 8, 3, 9, 4};
  BootstrapOptions a;
  a.seed = 3;
  BootstrapOptions c = a;
  c.seed = 4;
  CHECK(bootstrap_median(x, a).se == bootstrap_median(x, a).se);
  CHECK(bootstrap_median(x, a).se != bootstrap_median(x, c).se);
  CHECK(bootstrap_median(x).resamples == 2000);  // the paper's default
  CHECK(bootstrap_median(std::vector<double>{4.0}).se == 0.0);
  CHECK_THROWS(bootstrap_median(std::vector<double>{}));
}

TEST_CASE("cluster bootstrap: a cluster is one sample, however many values it holds, in any row order") {
  BootstrapOptions bo;
  bo.resamples = 4000;
  const std::vector<double> means{1.0, 2.5, 2.0, 4.0, 3.5, 6.0};
  const auto mean_of = [](std::span<const double> s) { return mean(s); };
  // one value per cluster: the plain bootstrap, draw for draw (clusters taken in id order)
  std::vector<std::uint64_t> ids{0, 1, 2, 3, 4, 5};
  const auto plain = bootstrap_mean(means, bo);
  const auto single = cluster_bootstrap(means, ids, mean_of, bo);
  CHECK(single.n == 6);
  CHECK(single.estimate == Approx(plain.estimate));
  CHECK(single.se == Approx(plain.se).epsilon(1e-12));
  // every value four times in its cluster, rows shuffled: n, estimate and SE unchanged
  std::vector<double> x;
  std::vector<std::uint64_t> c;
  for (int copy = 0; copy < 4; ++copy)
    for (std::size_t k = 0; k < means.size(); ++k) {
      x.push_back(means[(k + 2 * copy) % 6]);
      c.push_back((k + 2 * copy) % 6);
    }
  const auto clustered = cluster_bootstrap(x, c, mean_of, bo);
  CHECK(clustered.n == 6);
  CHECK(clustered.estimate == Approx(plain.estimate));
  CHECK(clustered.se == Approx(plain.se).epsilon(1e-12));
  // the same 24 values as independent samples: an SE about half as large, which the data do not carry
  CHECK(bootstrap_mean(x, bo).se == Approx(plain.se / 2).epsilon(0.15));
  CHECK_THROWS_AS(cluster_bootstrap(x, ids, mean_of, bo), std::invalid_argument);
  CHECK_THROWS_AS(cluster_bootstrap(std::vector<double>{}, std::vector<std::uint64_t>{}, mean_of, bo),
                  std::invalid_argument);
}

TEST_CASE("linear fit is exact on a line") {
  const std::vector<double> x{0.5, 1.0, 2.0, 3.5, 7.0};
  std::vector<double> y;
  for (double v : x) y.push_back(3.0 - 2.0 * v);
  const auto f = linear_fit(x, y);
  CHECK(f.slope == Approx(-2.0).epsilon(1e-14));
  CHECK(f.intercept == Approx(3.0).epsilon(1e-14));
  CHECK(f.slope_se == Approx(0.0).margin(1e-14));
  CHECK(f.r2 == Approx(1.0));
}

TEST_CASE("linear fit slope error matches the hand-worked residual variance") {
  // x = {0,1,2}, y = {0,2,1}: x̄ = ȳ = 1, Sxx = 2, Sxy = 1 → slope 1/2, intercept 1/2;
  // residuals −1/2, 1, −1/2 → RSS = 3/2, σ² = RSS/(n−2) = 3/2, SE(slope) = √(σ²/Sxx) = √(3/4).
  const auto f = linear_fit(std::vector<double>{0, 1, 2}, std::vector<double>{0, 2, 1});
  CHECK(f.slope == Approx(0.5));
  CHECK(f.intercept == Approx(0.5));
  CHECK(f.slope_se == Approx(std::sqrt(0.75)));
  CHECK(f.intercept_se == Approx(std::sqrt(1.5 * (1.0 / 3 + 1.0 / 2))));
  CHECK_THROWS(linear_fit(std::vector<double>{1, 1}, std::vector<double>{0, 1}));
}

TEST_CASE("weighted fit with equal error bars is the ordinary fit, with the propagated slope error") {
  const std::vector<double> x{0, 1, 2, 4}, y{0.1, 2.2, 3.9, 8.3}, sigma(4, 0.5);
  const auto w = weighted_linear_fit(x, y, sigma);
  const auto f = linear_fit(x, y);
  CHECK(w.slope == Approx(f.slope).epsilon(1e-14));
  CHECK(w.intercept == Approx(f.intercept).epsilon(1e-14));
  CHECK(w.dof == 2);
  // χ² = RSS/σ² here is below dof, so the error is σ/√Sxx, not widened (Sxx = Σ(x − x̄)² = 8.75)
  REQUIRE(w.chi2 < 2);
  CHECK(w.slope_se == Approx(0.5 / std::sqrt(8.75)));
}

TEST_CASE("weighted fit ignores a point whose error bar is huge and widens errors the scatter contradicts") {
  const auto w = weighted_linear_fit(std::vector<double>{1, 2, 3}, std::vector<double>{1, 3, 100},
                                     std::vector<double>{0.1, 0.1, 1e8});
  CHECK(w.slope == Approx(2.0).epsilon(1e-9));
  CHECK(w.intercept == Approx(-1.0).epsilon(1e-9));
  // three points off a line by far more than their error bars: χ²/dof ≫ 1 scales the errors by √(χ²/dof)
  const std::vector<double> x{0, 1, 2}, sigma(3, 0.01);
  const auto off = weighted_linear_fit(x, std::vector<double>{0, 2, 1}, sigma);
  CHECK(off.chi2 == Approx(1.5 / 1e-4));
  CHECK(off.slope_se == Approx(linear_fit(x, std::vector<double>{0, 2, 1}).slope_se));
  CHECK_THROWS_AS(weighted_linear_fit(x, std::vector<double>{0, 2, 1}, std::vector<double>{1, 0, 1}),
                  std::invalid_argument);
}

TEST_CASE("weighted fit intercept errors cover the truth: pulls have unit spread over synthetic data") {
  // y = 0.8 − 3/N with error bars that differ by a factor 4 between points, as a finite-size table's do
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::vector<double> x{1.0 / 48, 1.0 / 176, 1.0 / 300, 1.0 / 700, 1.0 / 1200};
  const std::vector<double> sigma{0.02, 0.012, 0.01, 0.007, 0.005};
  std::vector<double> pulls;
  for (int trial = 0; trial < 4000; ++trial) {
    std::vector<double> y;
    for (std::size_t k = 0; k < x.size(); ++k) y.push_back(0.8 - 3.0 * x[k] + sigma[k] * gauss(rng));
    const auto f = weighted_linear_fit(x, y, sigma);
    pulls.push_back((f.intercept - 0.8) / f.intercept_se);
  }
  // the Birge ratio only widens, so the spread is at most 1 and not far below it
  const double spread = std::sqrt(sample_variance(pulls));
  CHECK(spread < 1.02);
  CHECK(spread > 0.85);
  CHECK(std::abs(mean(pulls)) < 0.05);
}

TEST_CASE("fit through the origin matches the hand-worked slope, residuals and uncentred R²") {
  // y = 2x + (0.1, −0.1, 0.1): Σxy = 1·2.1 + 2·3.9 + 3·6.1 = 28.2, Σx² = 14 → slope = 28.2/14.
  const std::vector<double> x{1, 2, 3}, y{2.1, 3.9, 6.1};
  const auto f = fit_through_origin(x, y);
  const double b = 28.2 / 14;
  double rss = 0, syy = 0;
  for (std::size_t k = 0; k < 3; ++k) rss += (y[k] - b * x[k]) * (y[k] - b * x[k]), syy += y[k] * y[k];
  CHECK(f.slope == Approx(b));
  CHECK(f.slope_se == Approx(std::sqrt(rss / 2 / 14)));
  CHECK(f.r2 == Approx(1 - rss / syy));
  CHECK(f.rms == Approx(std::sqrt(rss / 3)));
  CHECK(f.n == 3);
  // A line with an offset is no proportionality: the free fit is exact, the origin fit leaves
  // RSS = Σy² − (Σxy)²/Σx² = 50 − 26²/14 = 12/7, though its uncentred R² is still 0.966.
  const std::vector<double> shifted{3, 4, 5};  // y = x + 2
  CHECK(linear_fit(x, shifted).r2 == Approx(1.0));
  CHECK(fit_through_origin(x, shifted).rms == Approx(std::sqrt(4.0 / 7)));
  CHECK(fit_through_origin(x, shifted).r2 == Approx(1 - (12.0 / 7) / 50));
  CHECK_THROWS_AS(fit_through_origin(std::vector<double>{0, 0}, std::vector<double>{1, 2}), std::invalid_argument);
}

TEST_CASE("Tukey fences lie 1.5 IQR beyond the type-7 quartiles") {
  // 1…8 and 30: Q1 = 3, Q3 = 7, IQR = 4 → fences [−3, 13]; 30 is an outlier.
  const std::vector<double> x{1, 2, 3, 4, 5, 6, 7, 8, 30};
  const auto f = tukey_fences(x);
  CHECK(f.lo == Approx(-3.0));
  CHECK(f.hi == Approx(13.0));
  CHECK(f.contains(8.0));
  CHECK_FALSE(f.contains(30.0));
  CHECK(tukey_fences(x, 3.0).hi == Approx(19.0));
}
