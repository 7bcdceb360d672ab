#pragma once
// Ensemble statistics as the paper reports them: means with standard errors across runs, medians
// with bootstrap errors (2000 resamples), percentile confidence intervals, and least-squares lines
// with the error of the slope. Deterministic: the bootstrap draws from its own seeded stream with an
// unbiased integer draw, so the same data and seed give the same error bars on every platform.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <span>
#include <vector>

namespace budjam {

// What a statistic is without the data it needs (and a missing value in a table of them).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// No error bar, bootstrap or otherwise, and no verdict from fewer samples than this: an SE from 2–4
// values is itself uncertain by 35–70 %, and a bootstrap of so few values has only a handful of
// distinct resamples.
inline constexpr std::size_t kMinSamplesForError = 5;

// Arithmetic mean; NaN for no data.
double mean(std::span<const double> x);
// Unbiased sample variance s² = Σ(x − x̄)²/(n − 1); NaN for n < 2.
double sample_variance(std::span<const double> x);
// Population variance Σ(x − x̄)²/n (e.g. Var(g) in h_γ); NaN for no data.
double population_variance(std::span<const double> x);
// Standard error of the mean s/√n; NaN for n < 2.
double standard_error(std::span<const double> x);
// Median (mean of the two middle values for even n); NaN for no data.
double median(std::vector<double> x);
// Quantile q ∈ [0, 1] by linear interpolation between order statistics (Hyndman–Fan type 7,
// numpy's default): h = (n − 1) q, x_(⌊h⌋) + (h − ⌊h⌋)(x_(⌊h⌋+1) − x_(⌊h⌋)). NaN for no data.
double quantile(std::vector<double> x, double q);

struct BootstrapOptions {
  int resamples = 2000;      // the paper's 2000
  std::uint64_t seed = 1;    // the resampling stream (mt19937_64)
  double confidence = 0.95;  // percentile interval [(1−c)/2, (1+c)/2]
};

struct BootstrapResult {
  double estimate = 0;    // the statistic of the data itself
  double se = 0;          // standard deviation (n − 1 normalised) of the resampled statistics
  double lo = 0, hi = 0;  // percentile confidence interval of the resampled statistics
  int resamples = 0;
  std::size_t n = 0;
};

using Statistic = std::function<double(std::span<const double>)>;

// Nonparametric bootstrap: `resamples` samples of size n drawn with replacement. Throws
// std::invalid_argument for no data or fewer than 2 resamples. For n = 1 every resample equals
// the data: se = 0.
BootstrapResult bootstrap(std::span<const double> x, const Statistic& statistic, const BootstrapOptions& options = {});
BootstrapResult bootstrap_median(std::span<const double> x, const BootstrapOptions& options = {});
BootstrapResult bootstrap_mean(std::span<const double> x, const BootstrapOptions& options = {});

// Cluster bootstrap: whole clusters drawn with replacement, the statistic taken over the pooled values
// of the drawn clusters. For values that are not independent one by one (the Δφ targets of one run,
// the runs of one seed, which share their growth up to jamming) the cluster is the independent sample:
// n = clusters. The clusters are ordered by id, so the result does not depend on the order of the
// rows. Throws std::invalid_argument for mismatched sizes or no data.
BootstrapResult cluster_bootstrap(std::span<const double> x, std::span<const std::uint64_t> cluster,
                                  const Statistic& statistic, const BootstrapOptions& options = {});

// Uniform integer in [0, n), unbiased (rejection of the top partial block of 2^64), the same on
// every platform (std::uniform_int_distribution is not specified bit for bit). n > 0.
std::uint64_t uniform_index(std::mt19937_64& rng, std::uint64_t n);

// Ordinary least squares y = intercept + slope x.
struct LinearFit {
  double slope = 0, intercept = 0;
  double slope_se = 0, intercept_se = 0;  // from the residual variance σ² = RSS/(n − 2); 0 for n = 2
  double r2 = 0;                          // coefficient of determination (1 when y is constant and fitted)
  std::size_t n = 0;
};
// Throws std::invalid_argument for mismatched sizes, n < 2 or all x equal.
LinearFit linear_fit(std::span<const double> x, std::span<const double> y);

// Weighted least squares y = intercept + slope x with known standard errors σ_k of the y_k (weights
// 1/σ_k²): the fit of measured means, each with its own error bar. The parameter errors come from
// (XᵀWX)⁻¹ scaled by the Birge ratio max(1, χ²/dof) — error bars that the scatter contradicts are
// widened, never narrowed; with dof = 0 (two points) they are the propagated σ alone.
struct WeightedFit {
  double slope = 0, intercept = 0;
  double slope_se = 0, intercept_se = 0;
  double chi2 = 0;  // Σ (residual/σ)²
  std::size_t dof = 0;
};
// Throws std::invalid_argument for mismatched sizes, n < 2, a σ that is not finite and > 0, or all x equal.
WeightedFit weighted_linear_fit(std::span<const double> x, std::span<const double> y, std::span<const double> sigma);

// Mean ± SE summary of a sample, the paper's error bars for means.
struct MeanSE {
  double mean = 0, se = 0;
  std::size_t n = 0;
};
MeanSE mean_se(std::span<const double> x);

// Least squares through the origin, y = slope x: the test of a proportionality (ω* ∝ ΔZ) rather
// than of a linear relation. r2 is uncentred, 1 − RSS/Σy², as is usual without an intercept.
struct OriginFit {
  double slope = 0, slope_se = 0;  // slope_se from σ² = RSS/(n − 1); 0 for n = 1
  double r2 = 0;
  double rms = 0;  // √(RSS/n)
  std::size_t n = 0;
};
// Throws std::invalid_argument for mismatched sizes, no data or all x zero.
OriginFit fit_through_origin(std::span<const double> x, std::span<const double> y);

// Tukey's fences [Q1 − k·IQR, Q3 + k·IQR] with type-7 quartiles (see quantile); values outside are
// outliers. NaN fences for no data.
struct Fences {
  double lo = 0, hi = 0;
  bool contains(double v) const { return v >= lo && v <= hi; }
};
Fences tukey_fences(std::vector<double> x, double k = 1.5);

}  // namespace budjam
