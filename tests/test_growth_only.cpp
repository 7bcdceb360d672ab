// The cell count of the growth process alone (tools/analysis/growth_only.hpp) and the finite-size
// tables built on it (finite_size.hpp).
#include "analysis/finite_size.hpp"
#include "analysis/growth_only.hpp"

#include "budjam/growth_driver.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace budjam;
using namespace budjam::tools;

namespace {

// The growth and division rules of docs/model.md, written out again from the model and nothing else:
// innate rates r0 (1 + δ (U − ½)) drawn at birth, b² ← (1 + γΔt)(D² + b²) − D² for the cells present
// at the start of a step (newborns wait for the next), a split into two newborns of bud diameter
// (α0 − 1)D when 1 + b/D > 2α0, the two founders at α = α0 and α = 1 + √(2.5α0 − (α0 − 1)² − 2). No
// positions and no mechanics: below jamming they do not change the areas.
double cells_by_growth_alone(const Scene& s, double phi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const auto rate = [&] { return s.r0 * (1.0 + s.delta * (U(rng) - 0.5)); };
  std::vector<double> b{s.alpha0 - 1.0, std::sqrt(2.5 * s.alpha0 - (s.alpha0 - 1) * (s.alpha0 - 1) - 2.0)};
  std::vector<double> gamma{rate(), rate()};
  const auto fraction = [&] {
    double area = 0;
    for (double bi : b) area += std::numbers::pi / 4 * (1.0 + bi * bi);
    return area / (s.L * s.L);
  };
  while (fraction() < phi) {
    const std::size_t present = b.size();
    for (std::size_t i = 0; i < present; ++i) {
      b[i] = std::sqrt((1.0 + gamma[i] * s.dt) * (1.0 + b[i] * b[i]) - 1.0);
      if (1.0 + b[i] > 2.0 * s.alpha0) {
        b[i] = s.alpha0 - 1.0;
        gamma[i] = rate();
        b.push_back(s.alpha0 - 1.0);
        gamma.push_back(rate());
      }
    }
  }
  return static_cast<double>(b.size());
}

struct Sample {
  double mean = 0, se = 0;
};
Sample sample(const std::vector<double>& x) {
  double m = 0, v = 0;
  for (double xi : x) m += xi;
  m /= static_cast<double>(x.size());
  for (double xi : x) v += (xi - m) * (xi - m);
  return {m, std::sqrt(v / static_cast<double>(x.size() - 1) / static_cast<double>(x.size()))};
}

Scene no_feedback(double L) {
  Scene s;
  s.L = L;
  s.P0.reset();
  s.targets.clear();
  return s;
}

}  // namespace

TEST_CASE("growth and division alone give the cell count of relaxed packings below jamming (L = 8, φ = 0.75)",
          "[driver]") {
  // 120 runs of the growth driver (FIRE after every step) against 120 histories of the rules alone,
  // with other random streams: the same mean number of cells at the first state with φ ≥ 0.75,
  // within 3 combined SE.
  const double phi = 0.75;
  const std::size_t runs = 120;
  std::vector<double> driven, alone;
  std::size_t stopped = 0, jammed = 0;
  for (std::size_t k = 0; k < runs; ++k) {
    Scene s = no_feedback(8.0);
    s.seed = 5000 + k;
    GrowthDriver d(s);
    while (d.view().phi < phi && d.advance() == RunStatus::running) {}
    stopped += d.view().phi < phi;
    jammed += d.phase() != Phase::unjammed;
    driven.push_back(static_cast<double>(d.packing().size()));
    alone.push_back(cells_by_growth_alone(s, phi, 900000 + k));
  }
  REQUIRE(stopped == 0);
  CHECK(jammed == 0);  // φ = 0.75 lies below every jamming point
  const Sample a = sample(driven), b = sample(alone);
  INFO("driver " << a.mean << " ± " << a.se << ", growth alone " << b.mean << " ± " << b.se);
  CHECK(std::abs(a.mean - b.mean) <= 3 * std::hypot(a.se, b.se));
  CHECK(a.se > 0);  // the runs differ: a test of two ensembles, not of one history
}

TEST_CASE("growth_only_cells agrees with the rules written out in this test, and is reproducible") {
  const Scene s = no_feedback(8.0);
  std::vector<double> alone;
  for (std::uint64_t k = 0; k < 400; ++k) alone.push_back(cells_by_growth_alone(s, 0.8, 7000 + k));
  const Sample b = sample(alone);
  const GrowthOnlyCount g = growth_only_cells(s, 0.8, 400, 1);
  INFO("growth_only_cells " << g.mean << " ± " << g.se << ", in-test " << b.mean << " ± " << b.se);
  CHECK(g.samples == 400);
  CHECK(std::abs(g.mean - b.mean) <= 3 * std::hypot(g.se, b.se));
  const GrowthOnlyCount again = growth_only_cells(s, 0.8, 400, 1);
  CHECK(again.mean == g.mean);
  CHECK(again.se == g.se);
  // the two founders already fill φ ≈ 0.037 of this box: a lower target needs no step
  CHECK(growth_only_cells(s, 0.01, 10, 1).mean == 2);
  CHECK_THROWS(growth_only_cells(s, 1.2, 10, 1));
}

TEST_CASE("the 1/N extrapolation needs five sizes and reports its residuals") {
  // u_J = 0.2 + 3/N exactly at five sizes: limit 0.2, zero residuals; three sizes: no fit.
  const std::vector<double> Ls{8, 10, 12, 15, 20}, Ns{48, 75, 108, 170, 300};
  io::Json sizes = io::Json::array();
  for (std::size_t k = 0; k < Ls.size(); ++k) {
    io::Json e;
    e["L"] = Ls[k];
    e["runs"] = 200;
    e["jamming_states"] = 200;
    e["N_J"] = {{"n", 200}, {"mean", Ns[k]}, {"se", 0.5}};
    e["phi_J"] = {{"n", 200}, {"mean", 0.84}, {"se", 0.001}};
    e["u_J"] = {{"n", 200}, {"mean", 0.2 + 3.0 / Ns[k]}, {"se", 0.004}};
    e["rattler_fraction"] = {{"n", 200}, {"mean", 0.02}, {"se", 0.001}};
    e["cells_per_area"] = {{"n", 200}, {"mean", Ns[k] / (Ls[k] * Ls[k])}, {"se", 0.003}};
    sizes.push_back(e);
  }
  // a stand-in for the growth process: 0.77 cells per unit area at any size
  const GrowthOnly growth = [](double L, double) { return GrowthOnlyCount{0.77 * L * L, 0.01 * L * L, 100}; };
  // seeds of their own per size, L·10000 + k as the jamming presets grow them
  SeedsBySize seeds;
  for (double L : Ls)
    for (std::uint64_t k = 0; k < 200; ++k) seeds[L].insert(static_cast<std::uint64_t>(L) * 10000 + k);
  const io::Json J = jamming_finite_size_json(sizes, seeds, growth, 100);
  const auto& u = J["extrapolation"]["u_J"];
  REQUIRE(u["limit"].is_number());
  CHECK(u["limit"].get<double>() == Approx(0.2).epsilon(1e-9));
  CHECK(u["slope"].get<double>() == Approx(3.0).epsilon(1e-6));
  REQUIRE(u["residuals_in_se"].size() == 5);
  for (const auto& r : u["residuals_in_se"]) CHECK(r.get<double>() == Approx(0).margin(1e-6));
  // n_J,∞ = ρ_growth (1 − r_∞), ρ the same in every box: no phase swing
  CHECK(J["n_J_limit"]["value"].get<double>() == Approx(0.77 * 0.98).epsilon(1e-9));
  CHECK(J["n_J_limit"]["phase_swing"].get<double>() == Approx(0).margin(1e-12));
  // a density that swings with the generation a box catches, ρ = 0.77 + 0.006 sin(2π log₂ L²): the boxes
  // spread over one period average the swing out, and its spread enters the error
  const GrowthOnly waves = [](double L, double) {
    const double rho = 0.77 + 0.006 * std::sin(2 * M_PI * std::log2(L * L));
    return GrowthOnlyCount{rho * L * L, 1e-4 * L * L, 100};
  };
  const io::Json JW = jamming_finite_size_json(sizes, seeds, waves, 100);
  const auto& w = JW["n_J_limit"];
  CHECK(w["value"].get<double>() == Approx(0.77 * 0.98).epsilon(1e-9));
  const double swing = 0.006 * 0.98 * std::sqrt(0.5 * 6.0 / 5.0);  // SD of six evenly spaced phases
  CHECK(w["phase_swing"].get<double>() == Approx(swing).epsilon(1e-6));
  CHECK(w["se"].get<double>() > swing / std::sqrt(6.0));
  // each size's density against the growth-only one, in combined SE
  const auto& row = J["sizes"][3];
  const double rho = 170.0 / 225.0, z = (rho - 0.77) / std::hypot(0.003, 0.01);
  CHECK(row["cells_per_area_minus_growth_only_in_se"].get<double>() == Approx(z).epsilon(1e-9));
  // three sizes: rows, no extrapolation, and the reason
  io::Json three = io::Json::array({sizes[0], sizes[2], sizes[4]});
  const io::Json J3 = jamming_finite_size_json(three, seeds, growth, 100);
  CHECK(J3["sizes"].size() == 3);
  CHECK(J3["extrapolation"]["u_J"]["limit"].is_null());
  CHECK(J3["extrapolation"]["u_J"]["why"].get<std::string>().find("needs 5") != std::string::npos);
  CHECK(J3["n_J_limit"].is_null());
  // the same seeds 1…200 at every size (the stream does not depend on L): correlated sizes, no fit, no
  // n_J,∞ (it needs r_∞), and the reason; the per-size rows stay
  SeedsBySize same;
  for (double L : Ls)
    for (std::uint64_t k = 1; k <= 200; ++k) same[L].insert(k);
  const io::Json JS = jamming_finite_size_json(sizes, same, growth, 100);
  CHECK(JS["sizes"].size() == 5);
  CHECK(JS["extrapolation"]["u_J"]["limit"].is_null());
  CHECK(JS["extrapolation"]["u_J"]["why"].get<std::string>().find(
            "share seeds (200 seeds grown at more than one size)") != std::string::npos);
  CHECK(JS["n_J_limit"].is_null());
}
