#include "analysis/finite_size.hpp"

#include "budjam/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace budjam::tools {

namespace {

using io::Json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMinSizesToExtrapolate = 3;  // two points fit any line: no test of the 1/N form

// A quantity of a group entry: the key and which of its fields holds the value (a mean, or the
// median for the skewed ones); the standard error is always "se".
struct Quantity {
  const char* name;
  const char* group_key;
  const char* value_field;
};
constexpr Quantity kQuantities[] = {
    {"u_J", "u_J", "mean"},                              // contact-free buds at jamming over N_nr
    {"u_J_lobes", "u_J_lobes", "mean"},                  // the paper's count: contact-free lobes
    {"n_J", "n_J", "mean"},                              // buds per non-rattler cell at jamming
    {"phi_J", "phi_J", "mean"},                          // packing fraction at jamming
    {"dphi_2", "dphi_2", "mean"},                        // φ_2 − φ_J, at most one tagged bud left
    {"dphi_2_paper", "dphi_2_paper", "mean"},            // φ_2 − φ_J, none left, the paper's selection
    {"dphi_2_paper_all", "dphi_2_paper_all", "mean"},    // the same, every run that reached it
    {"N_div_2_over_N_J", "N_div_2_over_N_J", "median"},  // divisions by φ_2 per cell at jamming
    {"G_2_over_Pmax", "G_2_over_Pmax", "median"},        // shear modulus at φ_2 over P_max
    {"G_2_over_Pmax_at_paper_phi2", "G_2_over_Pmax_at_paper_phi2", "median"},  // the same at none left
};

double number(const Json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNaN;
}

Json extrapolation_json(const std::vector<double>& N, const std::vector<double>& q, const std::vector<double>& se) {
  Json x;
  x["sizes"] = N.size();
  if (N.size() < kMinSizesToExtrapolate) {
    x["limit"] = nullptr;
    x["why"] = "fewer than " + std::to_string(kMinSizesToExtrapolate) + " sizes with an error bar";
    return x;
  }
  std::vector<double> inv_N;
  for (double n : N) inv_N.push_back(1.0 / n);
  const auto f = weighted_linear_fit(inv_N, q, se);
  x["limit"] = io::number_or_null(f.intercept);  // q_∞
  x["limit_se"] = io::number_or_null(f.intercept_se);
  x["slope"] = io::number_or_null(f.slope);  // c of q_∞ + c/N_J
  x["slope_se"] = io::number_or_null(f.slope_se);
  x["chi2"] = f.chi2;
  x["dof"] = f.dof;
  return x;
}

}  // namespace

Json finite_size_json(const Json& groups) {
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
      for (const auto& q : kQuantities) {
        // a key an older analysis.json lacks gives an empty cell
        const Json v = g->contains(q.group_key) ? (*g)[q.group_key] : Json::object();
        row[q.name] =
            Json{{"value", v.value(q.value_field, Json())}, {"se", v.value("se", Json())}, {"n", v.value("n", 0)}};
      }
      sizes.push_back(row);
    }
    Json extrapolation;
    for (const auto& q : kQuantities) {
      std::vector<double> N, value, se;
      for (const auto& row : sizes) {
        const double n = number(row["N_J"], "mean"), v = number(row[q.name], "value"), s = number(row[q.name], "se");
        // one run's value has no error bar (a bootstrap of one value gives a rounding-level "SE")
        if (std::isfinite(n) && n > 0 && std::isfinite(v) && std::isfinite(s) && s > 0 &&
            number(row[q.name], "n") >= 2) {
          N.push_back(n);
          value.push_back(v);
          se.push_back(s);
        }
      }
      extrapolation[q.name] = extrapolation_json(N, value, se);
    }
    entry["sizes"] = sizes;
    entry["model"] =
        "q(N_J) = q_inf + c/N_J, weighted least squares (weights 1/SE^2), errors scaled by "
        "max(1, sqrt(chi2/dof))";
    entry["extrapolation"] = extrapolation;
    out.push_back(entry);
  }
  return out;
}

}  // namespace budjam::tools
