#include "analysis/finite_size.hpp"

#include "budjam/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace budjam::tools {

namespace {

using io::Json;

// A quantity of an analysis.json entry: the key and which of its fields holds the value (a mean, or
// the median for the skewed ones); the standard error is always "se".
struct Quantity {
  const char* name;
  const char* value_field;
};
constexpr Quantity kDepletionQuantities[] = {
    {"dphi_2", "mean"},                 // φ_2 − φ_J, at most one tagged bud left, every run
    {"dphi_2_paper", "mean"},           // the same φ_2, the runs the paper's selection admits
    {"dphi_2_none_left", "mean"},       // φ − φ_J at the first state with no tagged bud left
    {"N_div_2_over_N_J", "median"},     // divisions by φ_2 per cell at jamming
    {"G_2_over_Pmax", "median"},        // shear modulus at φ_2 over P_max, every run
    {"G_2_over_Pmax_paper", "median"},  // the same, the paper's selection and fences
};
// Boxes over one period of the growth-only density's phase (n_J,∞ below).
constexpr int kPhaseBoxes = 6;

constexpr Quantity kJammingQuantities[] = {
    {"u_J", "mean"},               // contact-free buds at jamming over N_nr
    {"u_J_lobes", "mean"},         // the paper's count: contact-free lobes
    {"phi_J", "mean"},             // packing fraction at jamming
    {"Z_J", "mean"},               // contacts per non-rattler cell at jamming
    {"rattler_fraction", "mean"},  // 1 − N_nr/N at jamming
};

double number(const Json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNaN;
}

// The value, its SE and n of a quantity of one size's entry ({} where an older analysis.json lacks it).
Json cell(const Json& entry, const Quantity& q) {
  const Json v = entry.contains(q.name) ? entry[q.name] : Json::object();
  // n: the independent samples, the seeds where states share them (states_json)
  return Json{{"value", v.value(q.value_field, Json())},
              {"se", v.value("se", Json())},
              {"censored", v.value("censored", 0)},
              {"n", std::min(v.value("n", 0), v.value("seeds", v.value("n", 0)))}};
}

// How many seeds were grown at more than one of these sizes.
std::size_t seeds_shared(const std::vector<const std::set<std::uint64_t>*>& seeds) {
  std::map<std::uint64_t, std::size_t> sizes_of;
  for (const auto* s : seeds)
    for (const std::uint64_t seed : *s) ++sizes_of[seed];
  return static_cast<std::size_t>(
      std::count_if(sizes_of.begin(), sizes_of.end(), [](auto& x) { return x.second > 1; }));
}

Json extrapolation_json(const std::vector<double>& N, const std::vector<double>& q, const std::vector<double>& se,
                        const std::vector<const std::set<std::uint64_t>*>& seeds) {
  Json x;
  x["sizes"] = N.size();
  if (N.size() < kMinSizesToExtrapolate) {
    x["limit"] = nullptr;
    x["why"] = std::to_string(N.size()) + " sizes with an error bar; the fit needs " +
               std::to_string(kMinSizesToExtrapolate) + " to test its form";
    return x;
  }
  if (const std::size_t shared = seeds_shared(seeds)) {
    x["limit"] = nullptr;
    x["why"] = "the " + std::to_string(N.size()) + " sizes share seeds (" + std::to_string(shared) +
               (shared == 1 ? " seed" : " seeds") +
               " grown at more than one size): they are correlated, and the fit's chi2 needs independent sizes";
    return x;
  }
  std::vector<double> inv_N;
  for (double n : N) inv_N.push_back(1.0 / n);
  const auto f = weighted_linear_fit(inv_N, q, se);
  x["limit"] = io::number_or_null(f.intercept);  // q_∞
  x["limit_se"] = io::number_or_null(f.intercept_se);
  x["slope"] = io::number_or_null(f.slope);  // c of q_∞ + c/N
  x["slope_se"] = io::number_or_null(f.slope_se);
  x["chi2"] = f.chi2;
  x["dof"] = f.dof;
  Json residuals = Json::array();  // (q − fit)/SE per size, in the order of N
  for (std::size_t k = 0; k < N.size(); ++k) residuals.push_back((q[k] - f.intercept - f.slope * inv_N[k]) / se[k]);
  x["residuals_in_se"] = residuals;
  return x;
}

// How many seeds were grown at more than one of the per-size rows' sizes (the report's account of
// whether its sizes are independent samples).
std::size_t seeds_shared_by_sizes(const Json& rows, const SeedsBySize& seeds) {
  std::vector<const std::set<std::uint64_t>*> of;
  for (const auto& row : rows)
    if (const auto it = seeds.find(number(row, "L")); it != seeds.end()) of.push_back(&it->second);
  return seeds_shared(of);
}

// The extrapolation of one quantity over the per-size rows: the sizes whose value has an error bar.
// `seeds`: the seeds of the runs of each row's L.
Json extrapolate(const Json& rows, const char* name, const SeedsBySize& seeds) {
  std::vector<double> N, value, se;
  std::vector<const std::set<std::uint64_t>*> used_seeds;
  for (const auto& row : rows) {
    const double n = number(row["N_J"], "mean"), v = number(row[name], "value"), s = number(row[name], "se");
    if (std::isfinite(n) && n > 0 && std::isfinite(v) && std::isfinite(s) && s > 0) {
      N.push_back(n);
      value.push_back(v);
      se.push_back(s);
      used_seeds.push_back(&seeds.at(number(row, "L")));
    }
  }
  return extrapolation_json(N, value, se, used_seeds);
}

constexpr const char* kModel =
    "q(N_J) = q_inf + c/N_J, weighted least squares (weights 1/SE^2), errors scaled by max(1, sqrt(chi2/dof)); "
    "fitted with at least 5 sizes, no seed grown at two of them";

}  // namespace

Json finite_size_json(const Json& groups, const std::map<std::string, SeedsBySize>& seeds) {
  // groups of one P0 in increasing L; "none" (no feedback) is its own P0
  std::map<std::string, std::vector<const Json*>> by_P0;
  for (const auto& g : groups) by_P0[g.value("P0_label", "none")].push_back(&g);
  Json out = Json::array();
  for (auto& [label, gs] : by_P0) {
    if (gs.size() < 2) continue;
    std::sort(gs.begin(), gs.end(), [](const Json* a, const Json* b) { return number(*a, "L") < number(*b, "L"); });
    Json entry;
    entry["P0"] = (*gs.front())["P0"];
    entry["P0_label"] = label;
    Json sizes = Json::array();
    for (const Json* g : gs) {
      Json row;
      row["L"] = (*g)["L"];
      row["runs"] = (*g)["runs"];
      row["N_J"] = Json{{"mean", (*g)["N_J"]["mean"]}, {"se", (*g)["N_J"]["se"]}};
      for (const auto& q : kDepletionQuantities) row[q.name] = cell(*g, q);
      sizes.push_back(row);
    }
    Json extrapolation;
    for (const auto& q : kDepletionQuantities) extrapolation[q.name] = extrapolate(sizes, q.name, seeds.at(label));
    entry["seeds_shared"] = seeds_shared_by_sizes(sizes, seeds.at(label));
    entry["sizes"] = sizes;
    entry["model"] = kModel;
    entry["extrapolation"] = extrapolation;
    out.push_back(entry);
  }
  return out;
}

Json jamming_finite_size_json(const Json& sizes_in, const SeedsBySize& seeds, const GrowthOnly& growth_only,
                              double large_L) {
  std::vector<const Json*> sizes;
  for (const auto& s : sizes_in) sizes.push_back(&s);
  if (sizes.size() < 2) return nullptr;
  std::sort(sizes.begin(), sizes.end(), [](const Json* a, const Json* b) { return number(*a, "L") < number(*b, "L"); });
  Json rows = Json::array();
  for (const Json* s : sizes) {
    const double L = number(*s, "L"), phi_J = number((*s)["phi_J"], "mean");
    Json row;
    row["L"] = L;
    row["runs"] = (*s)["runs"];
    row["jamming_states"] = (*s)["jamming_states"];
    row["N_J"] = Json{{"mean", (*s)["N_J"]["mean"]}, {"se", (*s)["N_J"]["se"]}};
    for (const auto& q : kJammingQuantities) row[q.name] = cell(*s, q);
    row["n_J"] = cell(*s, {"n_J", "mean"});
    row["cells_per_area"] = cell(*s, {"cells_per_area", "mean"});
    if (std::isfinite(phi_J)) {
      const GrowthOnlyCount g = growth_only(L, phi_J);
      const double rho = number(row["cells_per_area"], "value"), rho_se = number(row["cells_per_area"], "se");
      row["growth_only_cells_per_area"] =
          Json{{"value", g.mean / (L * L)}, {"se", g.se / (L * L)}, {"n", g.samples}, {"at_phi", phi_J}};
      const double combined = std::hypot(rho_se, g.se / (L * L));
      row["cells_per_area_minus_growth_only_in_se"] = io::number_or_null((rho - g.mean / (L * L)) / combined);
    }
    rows.push_back(row);
  }
  Json extrapolation;
  for (const auto& q : kJammingQuantities) extrapolation[q.name] = extrapolate(rows, q.name, seeds);
  Json J;
  J["sizes"] = rows;
  J["seeds_shared"] = seeds_shared_by_sizes(rows, seeds);
  J["model"] = kModel;
  J["extrapolation"] = extrapolation;
  // n_J,∞ = ρ_∞ (1 − r_∞): the growth-only density of a large box times the extrapolated non-rattler
  // fraction. ρ at fixed φ is not monotone in L: divisions come in generations, N doubles each time L
  // grows by √2, and a box catches a generation at a phase its size sets. An infinite box averages over
  // that phase, so ρ_∞ is the mean over kPhaseBoxes sides spread evenly over one period in log L
  // (large_L · 2^(k/2K)); its error holds the spread over the phase (SD/√K) with the histories' own.
  // The boxes are filled to the ⟨φ_J⟩ of the largest size measured (no model needed).
  const Json& r = extrapolation["rattler_fraction"];
  const double phi_ref = number(rows.back()["phi_J"], "value");
  if (r["limit"].is_number() && std::isfinite(phi_ref)) {
    std::vector<double> rho, rho_se;
    std::size_t samples = 0;
    for (int k = 0; k < kPhaseBoxes; ++k) {
      const double side = large_L * std::exp2(k / (2.0 * kPhaseBoxes));
      const GrowthOnlyCount g = growth_only(side, phi_ref);
      rho.push_back(g.mean / (side * side));
      rho_se.push_back(g.se / (side * side));
      samples += g.samples;
    }
    const double K = kPhaseBoxes, rho_inf = mean(rho);
    const double swing = std::sqrt(sample_variance(rho));
    const double rho_inf_se = std::hypot(mean(rho_se), swing) / std::sqrt(K);
    const double keep = 1.0 - r["limit"].get<double>(), keep_se = r["limit_se"].get<double>();
    J["n_J_limit"] = Json{{"value", rho_inf * keep},
                          {"se", std::hypot(rho_inf_se * keep, rho_inf * keep_se)},
                          {"phase_swing", swing * keep},
                          {"growth_only_cells_per_area", rho_inf},
                          {"growth_only_L", Json::array({large_L, large_L * std::exp2((K - 1) / (2 * K))})},
                          {"growth_only_boxes", kPhaseBoxes},
                          {"growth_only_at_phi", phi_ref},
                          {"growth_only_samples", samples}};
  } else {
    J["n_J_limit"] = nullptr;
  }
  return J;
}

}  // namespace budjam::tools
