#pragma once
// Kaplan–Meier survival S(a) of the buds that are unconstrained at jamming (paper Eq. 8; docs/model.md
// "Bud events"). The "time" is the added bud size a = b² − b_J² (diameter squared; true area π a/4)
// at which a tagged bud is completed (the event) or leaves observation without completing
// (censored: its cell divided, the run ended, or the packing unjammed).
#include <cstddef>
#include <optional>
#include <vector>

namespace budjam {

struct SurvivalRecord {
  double a = 0;        // ≥ 0: added size at the event or at censoring
  bool event = false;  // true: completed; false: censored
  // The independent sample the record belongs to (its run): the buds of one run share its growth,
  // so the clustered variance resamples clusters, not records.
  std::size_t cluster = 0;
};

// One distinct a at which something happened. `at_risk` counts records with a_i ≥ a (censored
// records at the same a are still at risk: events come first at ties, the usual convention).
struct KaplanMeierStep {
  double a = 0;
  std::size_t at_risk = 0, events = 0, censored = 0;
  double S = 1;              // Ŝ(a) = Π_{a_k ≤ a} (1 − d_k / n_k)
  double greenwood_var = 0;  // Ŝ(a)² Σ_{a_k ≤ a} d_k / (n_k (n_k − d_k)); 0 once Ŝ = 0
  // Σ_c U_c(a)², U_c = Σ_{i ∈ c} ∂Ŝ(a)/∂w_i the infinitesimal-jackknife influence of cluster c
  // (Williams 1995, Biometrics 51, 907; R's survfit with a cluster term): records independent across
  // clusters only. 0 once Ŝ = 0; 0 for a single cluster (the influences sum to zero).
  double clustered_var = 0;
};

class KaplanMeierCurve {
 public:
  KaplanMeierCurve() = default;
  explicit KaplanMeierCurve(std::vector<KaplanMeierStep> steps, std::size_t n, std::size_t events, std::size_t clusters)
      : steps_(std::move(steps)), n_(n), events_(events), clusters_(clusters) {}

  const std::vector<KaplanMeierStep>& steps() const { return steps_; }
  std::size_t records() const { return n_; }
  std::size_t events() const { return events_; }
  // Distinct clusters among the records (0 for no record).
  std::size_t clusters() const { return clusters_; }

  // Right-continuous step function: Ŝ(a) = 1 before the first event.
  double S(double a) const;
  // Greenwood variance of Ŝ(a).
  double variance(double a) const;
  // ∫_0^a Ŝ(a') da' (exact for the step function).
  double integral(double a) const;
  // The smallest a at which Ŝ(a) ≤ level (for u_J S(a_ε) = ε: level = ε/u_J). 0 if level ≥ 1;
  // nullopt if Ŝ never falls that low (too much censoring). Ŝ is a product of rationals computed in
  // floating point: 4/5·3/4·2/3·1/2 comes out a few ulps above 1/5, so "≤ level" allows a relative
  // slack (kQuantileSlack) that meets such exact levels; 0 compares as the floating point has it.
  static constexpr double kQuantileSlack = 1e-12;
  std::optional<double> quantile_point(double level, double relative_slack = kQuantileSlack) const;
  // The largest a observed (event or censoring); Ŝ is undefined beyond it if it did not reach 0.
  double last_observation() const { return steps_.empty() ? 0.0 : steps_.back().a; }

 private:
  std::vector<KaplanMeierStep> steps_;  // ascending a
  std::size_t n_ = 0, events_ = 0, clusters_ = 0;
};

// The pointwise 95 % band of Ŝ at a step from a variance of Ŝ there: se = √variance, Ŝ ± 1.96 se
// clipped to [0, 1]. None where fewer than kMinSamplesForError records are at risk: the tail of the
// curve, where the variance rests on a handful of buds and is itself unreliable (no error bar from
// fewer samples, statistics.hpp).
struct SurvivalBand {
  double se = 0, lo = 0, hi = 0;
};
std::optional<SurvivalBand> survival_band(const KaplanMeierStep& step, double variance);

// Throws std::invalid_argument for a negative or non-finite a.
KaplanMeierCurve kaplan_meier(const std::vector<SurvivalRecord>& records);

// Typical completion size a_c of a curve, in its own units (diameter squared for bud events):
// the mean ∫_0^{a_last} Ŝ da up to the last completion (the mean itself when Ŝ falls to 0 there;
// 0 with no completion), and the median, the smallest a with Ŝ(a) ≤ 1/2 (nullopt if Ŝ stays above).
double mean_completion_size(const KaplanMeierCurve& S);
std::optional<double> median_completion_size(const KaplanMeierCurve& S);

// a_ε with u_J Ŝ(a_ε) = ε (paper Eq. 14).
std::optional<double> a_epsilon(const KaplanMeierCurve& S, double u_J, double epsilon);

}  // namespace budjam
