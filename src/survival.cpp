#include "budjam/survival.hpp"

#include "budjam/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace budjam {

std::optional<SurvivalBand> survival_band(const KaplanMeierStep& step, double variance) {
  if (step.at_risk < kMinSamplesForError || !std::isfinite(variance)) return std::nullopt;
  const double se = std::sqrt(variance);
  return SurvivalBand{se, std::max(0.0, step.S - 1.96 * se), std::min(1.0, step.S + 1.96 * se)};
}

namespace {

// Σ_c U_c(a_k)² at every step k of a curve already made from `r` (sorted as kaplan_meier sorts). With
// weights w_i on the records, n_k = Σ w_i Y_ik and d_k = Σ w_i δ_ik (Y: at risk at a_k, δ: an event
// there), and ∂ log Ŝ(a_k) / ∂w_i = Σ_{k' ≤ k} (Y_ik' d_k' − n_k' δ_ik') / (n_k' (n_k' − d_k')); a
// cluster's influence sums its records', so only its count at risk and its events at each step enter.
void clustered_variances(const std::vector<SurvivalRecord>& r, std::vector<KaplanMeierStep>& steps,
                         std::size_t& clusters) {
  std::map<std::size_t, std::size_t> index;
  for (const auto& x : r) index.try_emplace(x.cluster, index.size());
  clusters = index.size();
  std::vector<double> at_risk(clusters, 0.0), log_influence(clusters, 0.0), events(clusters, 0.0);
  for (const auto& x : r) ++at_risk[index[x.cluster]];
  std::size_t i = 0;
  bool exhausted = false;
  for (auto& st : steps) {
    const std::size_t first = i;
    for (; i < r.size() && r[i].a == st.a; ++i)
      if (r[i].event) ++events[index[r[i].cluster]];
    if (st.events > 0 && st.events < st.at_risk) {
      const double n = static_cast<double>(st.at_risk), d = static_cast<double>(st.events);
      for (std::size_t c = 0; c < clusters; ++c) log_influence[c] += (at_risk[c] * d - n * events[c]) / (n * (n - d));
    }
    exhausted = exhausted || (st.events > 0 && st.events == st.at_risk);
    double sum = 0;
    for (const double u : log_influence) sum += u * u;
    st.clustered_var = exhausted ? 0.0 : st.S * st.S * sum;
    for (std::size_t j = first; j < i; ++j) {
      --at_risk[index[r[j].cluster]];
      if (r[j].event) --events[index[r[j].cluster]];
    }
  }
}

}  // namespace

KaplanMeierCurve kaplan_meier(const std::vector<SurvivalRecord>& records) {
  std::vector<SurvivalRecord> r = records;
  for (const auto& x : r)
    if (!std::isfinite(x.a) || x.a < 0)
      throw std::invalid_argument("kaplan_meier: added size a must be finite and >= 0");
  // Ascending a; at equal a, events before censorings (a censored record is at risk at its own a).
  std::sort(r.begin(), r.end(), [](const SurvivalRecord& x, const SurvivalRecord& y) {
    return x.a < y.a || (x.a == y.a && x.event && !y.event);
  });
  std::vector<KaplanMeierStep> steps;
  std::size_t at_risk = r.size(), events_total = 0;
  double S = 1.0, greenwood_sum = 0.0;
  bool exhausted = false;
  for (std::size_t k = 0; k < r.size();) {
    KaplanMeierStep st;
    st.a = r[k].a;
    st.at_risk = at_risk;
    std::size_t j = k;
    for (; j < r.size() && r[j].a == st.a; ++j) (r[j].event ? st.events : st.censored)++;
    if (st.events > 0) {
      S *= 1.0 - static_cast<double>(st.events) / static_cast<double>(st.at_risk);
      if (st.events == st.at_risk)
        exhausted = true;  // Ŝ = 0: Greenwood's term d/(n(n − d)) is 0·∞; the variance is 0 there
      else
        greenwood_sum += static_cast<double>(st.events) /
                         (static_cast<double>(st.at_risk) * static_cast<double>(st.at_risk - st.events));
    }
    st.S = S;
    st.greenwood_var = exhausted ? 0.0 : S * S * greenwood_sum;
    events_total += st.events;
    at_risk -= st.events + st.censored;
    steps.push_back(st);
    k = j;
  }
  std::size_t clusters = 0;
  clustered_variances(r, steps, clusters);
  return KaplanMeierCurve(std::move(steps), r.size(), events_total, clusters);
}

double KaplanMeierCurve::S(double a) const {
  double s = 1.0;
  for (const auto& st : steps_) {
    if (st.a > a) break;
    s = st.S;
  }
  return s;
}

double KaplanMeierCurve::variance(double a) const {
  double v = 0.0;
  for (const auto& st : steps_) {
    if (st.a > a) break;
    v = st.greenwood_var;
  }
  return v;
}

double KaplanMeierCurve::integral(double a) const {
  if (a <= 0) return 0.0;
  double area = 0.0, prev_a = 0.0, s = 1.0;
  for (const auto& st : steps_) {
    if (st.a >= a) break;
    area += s * (st.a - prev_a);
    prev_a = st.a;
    s = st.S;
  }
  return area + s * (a - prev_a);
}

std::optional<double> KaplanMeierCurve::quantile_point(double level, double relative_slack) const {
  if (level >= 1.0) return 0.0;
  const double slack = relative_slack * std::max(level, 1e-300);
  for (const auto& st : steps_)
    if (st.events > 0 && st.S <= level + slack) return st.a;
  return std::nullopt;
}

std::optional<double> a_epsilon(const KaplanMeierCurve& S, double u_J, double epsilon) {
  if (!(u_J > 0)) throw std::invalid_argument("a_epsilon: u_J must be positive");
  if (!(epsilon >= 0)) throw std::invalid_argument("a_epsilon: epsilon must be >= 0");
  return S.quantile_point(epsilon / u_J);
}

double mean_completion_size(const KaplanMeierCurve& S) {
  double last_event = 0;
  for (const auto& st : S.steps())
    if (st.events > 0) last_event = st.a;
  return S.integral(last_event);
}

std::optional<double> median_completion_size(const KaplanMeierCurve& S) { return S.quantile_point(0.5); }

}  // namespace budjam
