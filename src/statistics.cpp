#include "budjam/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

namespace budjam {

namespace {

double sum_sq_dev(std::span<const double> x, double m) {
  double s = 0;
  for (double v : x) s += (v - m) * (v - m);
  return s;
}
}  // namespace

double mean(std::span<const double> x) {
  if (x.empty()) return kNaN;
  double s = 0;
  for (double v : x) s += v;
  return s / static_cast<double>(x.size());
}

double sample_variance(std::span<const double> x) {
  if (x.size() < 2) return kNaN;
  return sum_sq_dev(x, mean(x)) / static_cast<double>(x.size() - 1);
}

double population_variance(std::span<const double> x) {
  if (x.empty()) return kNaN;
  return sum_sq_dev(x, mean(x)) / static_cast<double>(x.size());
}

double standard_error(std::span<const double> x) {
  if (x.size() < 2) return kNaN;
  return std::sqrt(sample_variance(x) / static_cast<double>(x.size()));
}

double median(std::vector<double> x) { return quantile(std::move(x), 0.5); }

double quantile(std::vector<double> x, double q) {
  if (x.empty()) return kNaN;
  if (!(q >= 0.0 && q <= 1.0)) throw std::invalid_argument("quantile: q must lie in [0, 1]");
  std::sort(x.begin(), x.end());
  const double h = static_cast<double>(x.size() - 1) * q;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, x.size() - 1);
  return x[lo] + (h - static_cast<double>(lo)) * (x[hi] - x[lo]);
}

std::uint64_t uniform_index(std::mt19937_64& rng, std::uint64_t n) {
  if (n == 0) throw std::invalid_argument("uniform_index: n must be positive");
  // Accept draws below the largest multiple of n that fits in 2^64, so every residue is equally likely.
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
  std::uint64_t r;
  do r = rng();
  while (r >= limit);
  return r % n;
}

BootstrapResult bootstrap(std::span<const double> x, const Statistic& statistic, const BootstrapOptions& options) {
  if (x.empty()) throw std::invalid_argument("bootstrap: no data");
  if (options.resamples < 2) throw std::invalid_argument("bootstrap: need at least 2 resamples");
  if (!(options.confidence > 0.0 && options.confidence < 1.0))
    throw std::invalid_argument("bootstrap: confidence must lie in (0, 1)");
  BootstrapResult r;
  r.n = x.size();
  r.resamples = options.resamples;
  r.estimate = statistic(x);
  std::mt19937_64 rng(options.seed);
  std::vector<double> sample(x.size()), stats(static_cast<std::size_t>(options.resamples));
  for (auto& s : stats) {
    for (auto& v : sample) v = x[uniform_index(rng, x.size())];
    s = statistic(sample);
  }
  r.se = std::sqrt(sample_variance(stats));
  r.lo = quantile(stats, 0.5 * (1.0 - options.confidence));
  r.hi = quantile(stats, 0.5 * (1.0 + options.confidence));
  return r;
}

BootstrapResult bootstrap_median(std::span<const double> x, const BootstrapOptions& options) {
  return bootstrap(
      x, [](std::span<const double> s) { return median(std::vector<double>(s.begin(), s.end())); }, options);
}

BootstrapResult bootstrap_mean(std::span<const double> x, const BootstrapOptions& options) {
  return bootstrap(
      x, [](std::span<const double> s) { return mean(s); }, options);
}

BootstrapResult cluster_bootstrap(std::span<const double> x, std::span<const std::uint64_t> cluster,
                                  const Statistic& statistic, const BootstrapOptions& options) {
  if (x.size() != cluster.size()) throw std::invalid_argument("cluster_bootstrap: values and clusters differ in size");
  if (x.empty()) throw std::invalid_argument("cluster_bootstrap: no data");
  std::map<std::uint64_t, std::vector<double>> by_id;
  for (std::size_t k = 0; k < x.size(); ++k) by_id[cluster[k]].push_back(x[k]);
  std::vector<std::vector<double>> clusters;
  for (auto& [id, v] : by_id) clusters.push_back(std::move(v));
  std::vector<double> index(clusters.size()), pooled;
  for (std::size_t k = 0; k < index.size(); ++k) index[k] = static_cast<double>(k);
  const Statistic of_drawn = [&](std::span<const double> drawn) {
    pooled.clear();
    for (double i : drawn) {
      const auto& c = clusters[static_cast<std::size_t>(i)];
      pooled.insert(pooled.end(), c.begin(), c.end());
    }
    return statistic(pooled);
  };
  BootstrapResult r = bootstrap(index, of_drawn, options);  // its estimate pools every cluster once
  r.n = clusters.size();
  return r;
}

LinearFit linear_fit(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size()) throw std::invalid_argument("linear_fit: x and y differ in length");
  if (x.size() < 2) throw std::invalid_argument("linear_fit: need at least 2 points");
  const double n = static_cast<double>(x.size());
  const double mx = mean(x), my = mean(y);
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
    syy += (y[k] - my) * (y[k] - my);
  }
  if (!(sxx > 0)) throw std::invalid_argument("linear_fit: all x are equal");
  LinearFit f;
  f.n = x.size();
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  double rss = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double e = y[k] - (f.intercept + f.slope * x[k]);
    rss += e * e;
  }
  f.r2 = syy > 0 ? 1.0 - rss / syy : 1.0;
  if (x.size() > 2) {
    const double s2 = rss / (n - 2.0);
    f.slope_se = std::sqrt(s2 / sxx);
    f.intercept_se = std::sqrt(s2 * (1.0 / n + mx * mx / sxx));
  }
  return f;
}

WeightedFit weighted_linear_fit(std::span<const double> x, std::span<const double> y, std::span<const double> sigma) {
  if (x.size() != y.size() || x.size() != sigma.size())
    throw std::invalid_argument("weighted_linear_fit: x, y and sigma differ in length");
  if (x.size() < 2) throw std::invalid_argument("weighted_linear_fit: need at least 2 points");
  double sw = 0, swx = 0, swy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!(std::isfinite(sigma[k]) && sigma[k] > 0))
      throw std::invalid_argument("weighted_linear_fit: every sigma must be finite and positive");
    const double w = 1.0 / (sigma[k] * sigma[k]);
    sw += w;
    swx += w * x[k];
    swy += w * y[k];
  }
  // centred on the weighted mean of x, so that nearly equal x do not cancel catastrophically
  const double mx = swx / sw, my = swy / sw;
  double sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double w = 1.0 / (sigma[k] * sigma[k]);
    sxx += w * (x[k] - mx) * (x[k] - mx);
    sxy += w * (x[k] - mx) * (y[k] - my);
  }
  if (!(sxx > 0)) throw std::invalid_argument("weighted_linear_fit: all x are equal");
  WeightedFit f;
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double e = (y[k] - (f.intercept + f.slope * x[k])) / sigma[k];
    f.chi2 += e * e;
  }
  f.dof = x.size() - 2;
  const double birge = f.dof > 0 ? std::max(1.0, f.chi2 / static_cast<double>(f.dof)) : 1.0;
  f.slope_se = std::sqrt(birge / sxx);
  f.intercept_se = std::sqrt(birge * (1.0 / sw + mx * mx / sxx));
  return f;
}

MeanSE mean_se(std::span<const double> x) {
  MeanSE m;
  m.n = x.size();
  m.mean = mean(x);
  m.se = x.size() >= 2 ? standard_error(x) : kNaN;
  return m;
}

OriginFit fit_through_origin(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size()) throw std::invalid_argument("fit_through_origin: x and y differ in length");
  if (x.empty()) throw std::invalid_argument("fit_through_origin: no data");
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxx += x[k] * x[k];
    sxy += x[k] * y[k];
    syy += y[k] * y[k];
  }
  if (!(sxx > 0)) throw std::invalid_argument("fit_through_origin: all x are zero");
  OriginFit f;
  f.n = x.size();
  f.slope = sxy / sxx;
  double rss = 0;
  for (std::size_t k = 0; k < x.size(); ++k) rss += (y[k] - f.slope * x[k]) * (y[k] - f.slope * x[k]);
  f.r2 = syy > 0 ? 1.0 - rss / syy : 1.0;
  f.rms = std::sqrt(rss / static_cast<double>(f.n));
  if (f.n > 1) f.slope_se = std::sqrt(rss / static_cast<double>(f.n - 1) / sxx);
  return f;
}

Fences tukey_fences(std::vector<double> x, double k) {
  const double q1 = quantile(x, 0.25), q3 = quantile(std::move(x), 0.75);
  return {q1 - k * (q3 - q1), q3 + k * (q3 - q1)};
}

}  // namespace budjam
