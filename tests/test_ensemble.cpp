// The ensemble estimators of budjam_analysis against hand-worked answers: independent samples
// (jamming states, seeds, duplicate runs), the depletion point and interval averages under both
// definitions, the paper's run selection, P*, the ΔZ identity, the ω* collapse and Π(g); and the
// tables reader's reconstruction of a Kaplan–Meier curve from its printed steps.
#include "analysis/depletion_estimators.hpp"
#include "analysis/ensemble_tables.hpp"
#include "analysis/finite_size.hpp"
#include "analysis/jamming_states.hpp"
#include "analysis/run_protocol.hpp"
#include "analysis/structure_estimators.hpp"
#include "budjam/depletion.hpp"
#include "budjam/survival.hpp"
#include "io/text.hpp"

#include <catch2/catch.hpp>
#include "scratch.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

using namespace budjam;
using namespace budjam::tools;

TEST_CASE("runs of one size and seed that jam identically share one jamming state") {
  const std::vector<JammingKey> keys{{15, 1, 100, 176, 0.8387}, {15, 1, 100, 176, 0.8387}, {15, 2, 90, 170, 0.8391},
                                     {8, 1, 100, 176, 0.8387},  {15, 1, 101, 176, 0.8387}, {15, 2, 90, 170, 0.8391}};
  CHECK(jamming_state_ids(keys) == std::vector<std::size_t>{0, 0, 1, 2, 3, 1});
}

TEST_CASE("the mean over jamming states counts each state once: copies do not shrink the SE") {
  // states 0, 1, 2 with means 0.2, 0.3, 0.25 (state 2: one NaN left out) → mean 0.25,
  // s² = (0.05² + 0.05² + 0)/2 = 0.0025, SE = √(0.0025/3)
  const std::vector<double> v{0.2, 0.2, 0.3, 0.25, NAN};
  const std::vector<std::size_t> s{0, 0, 1, 2, 2};
  const MeanSE m = mean_over_states(v, s);
  CHECK(m.n == 3);
  CHECK(m.mean == Approx(0.25));
  CHECK(m.se == Approx(std::sqrt(0.0025 / 3)));
  // six runs per state (six P0 groups sharing their jamming) give the same answer
  std::vector<double> v6;
  std::vector<std::size_t> s6;
  for (int copy = 0; copy < 6; ++copy)
    for (std::size_t k = 0; k < 4; ++k) v6.push_back(v[k]), s6.push_back(s[k]);
  CHECK(mean_over_states(v6, s6).se == Approx(m.se));
  CHECK(mean_over_states(v6, s6).n == 3);
  CHECK_THROWS_AS(mean_over_states(v, std::vector<std::size_t>{0}), std::invalid_argument);
}

TEST_CASE("bootstrap by seed resamples whole seeds") {
  BootstrapOptions bo;
  bo.resamples = 4000;
  SECTION("one state per seed: the plain bootstrap of the state means in seed order, draw for draw") {
    const std::vector<double> v{1, 4, 2, 8};
    const auto b =
        cluster_bootstrap_mean(v, std::vector<std::size_t>{0, 1, 2, 3}, std::vector<std::uint64_t>{7, 3, 5, 1}, bo);
    const auto plain = bootstrap_mean(std::vector<double>{8, 4, 2, 1}, bo);  // seeds 1, 3, 5, 7
    CHECK(b.estimate == Approx(3.75));
    CHECK(b.n == 4);
    CHECK(b.se == Approx(plain.se).epsilon(1e-12));
  }
  SECTION("two seeds, one holding two states: the exact resampling distribution") {
    // seed a: states 1 and 3; seed b: state 5. Draws (a,a) → 2, (a,b), (b,a) → 3, (b,b) → 5,
    // each with probability 1/4: variance 1.1875.
    bo.resamples = 20000;
    const auto b = cluster_bootstrap_mean(std::vector<double>{1, 3, 5}, std::vector<std::size_t>{0, 1, 2},
                                          std::vector<std::uint64_t>{10, 10, 20}, bo);
    CHECK(b.estimate == Approx(3.0));
    CHECK(b.se == Approx(std::sqrt(1.1875)).epsilon(0.02));
  }
}

TEST_CASE("identical summaries are one run copied: grouped, the first copy first") {
  const std::vector<std::string> f{"a", "b", "a", "c", "b", "a"};
  const auto d = duplicate_runs(f);
  REQUIRE(d.size() == 2);
  CHECK(d[0] == std::vector<std::size_t>{0, 2, 5});
  CHECK(d[1] == std::vector<std::size_t>{1, 4});
  CHECK(duplicate_runs(std::vector<std::string>{"a", "b"}).empty());
}

TEST_CASE("depletion point: budjam's at most one tagged bud left, the paper's none left") {
  const std::vector<double> active{5, 3, 1, 1, 0, 0};
  CHECK(*depletion_state(active, 1, 1) == 2);
  CHECK(*depletion_state(active, 1, 0) == 4);
  CHECK_FALSE(depletion_state(std::vector<double>{5, 3, 2}, 1, 1));
  CHECK(*depletion_state(std::vector<double>{0, 0}, 1, 0) == 1);  // the jamming state itself is not above jamming
}

TEST_CASE("χ̄ is the plain mean over the accepted states, not a trapezoid in φ") {
  // χ_c falls 0.9, 0.5, 0.1 over steps at φ − φ_J = 0, 0.001, 0.01: one growth step each, so Eq. 13's
  // average over a is (0.9 + 0.5 + 0.1)/3 = 0.5; the trapezoid in φ weights the long last step:
  // [(0.9+0.5)/2 · 0.001 + (0.5+0.1)/2 · 0.009] / 0.01 = 0.34.
  const std::vector<double> chi{0.9, 0.5, 0.1, 0.7}, phi{0.8, 0.801, 0.81, 0.82};
  CHECK(growth_coordinate_average(chi, 0, 2) == Approx(0.5));
  CHECK(interval_average(phi, chi, 0.8, 0.81) == Approx(0.34));
  CHECK(growth_coordinate_average(chi, 1, 1) == Approx(0.5));
  CHECK(growth_coordinate_average(std::vector<double>{NAN, 0.4, 0.2}, 0, 2) == Approx(0.3));
  CHECK(std::isnan(growth_coordinate_average(chi, 5, 6)));
}

TEST_CASE("the paper's selection admits a seed when a target run that reached φ_2 has at most 10 divisions") {
  // targets in any order: φ 0.85, 0.80, 0.83, 0.81 with 14, 0, 9, 2 divisions after φ_J
  const std::vector<double> phi{0.85, 0.80, 0.83, 0.81}, div{14, 0, 9, 2};
  CHECK(selection_divisions(phi, div, 0.82) == 9);  // the 0.83 run: admitted
  CHECK(paper_admits(selection_divisions(phi, div, 0.82)));
  CHECK(selection_divisions(phi, div, 0.84) == 14);  // the 0.85 run: more than 10
  CHECK(!paper_admits(selection_divisions(phi, div, 0.84)));
  CHECK(selection_divisions(phi, div, 0.81) == 2);        // a run that ends exactly at φ_2 has passed it
  CHECK(std::isnan(selection_divisions(phi, div, 0.9)));  // no target reaches φ_2: no run to select
  CHECK(!paper_admits(selection_divisions(phi, div, 0.9)));
  CHECK(paper_admits(10));
  CHECK(!paper_admits(10.5));
  CHECK_THROWS(selection_divisions(phi, std::vector<double>{1}, 0.8));
  // After an unjamming the count restarts at the new jamming: a later target run can have fewer
  // divisions than an earlier one, and it is one of the runs that reached φ_2.
  const std::vector<double> reset_phi{0.81, 0.84, NAN}, reset_div{12, 3, NAN};
  CHECK(selection_divisions(reset_phi, reset_div, 0.805) == 3);
  CHECK(paper_admits(selection_divisions(reset_phi, reset_div, 0.805)));
}

TEST_CASE("the paper's fences apply to G_2 alone: G_2 > 0 first, four values at least, never an empty set") {
  // admitted 1…8, 30, −1, NaN and (not admitted) 100: the positive admitted ones are 1…8 and 30,
  // quartiles 3 and 7, fences [−3, 13]: 30 falls out; 100 is not admitted and does not move them.
  const std::vector<double> G2{1, 2, 3, 4, 5, 6, 7, 8, 30, -1, NAN, 100};
  std::vector<bool> adm(G2.size(), true);
  adm.back() = false;
  const auto kept = paper_G2_kept(G2, adm);
  CHECK(kept == std::vector<bool>{true, true, true, true, true, true, true, true, false, false, false, false});
  // three positive values: no fences
  CHECK(paper_G2_kept(std::vector<double>{1, 2, 300}, std::vector<bool>(3, true)) == std::vector<bool>(3, true));
  // zero IQR: no fences either
  const std::vector<double> flat{2, 2, 2, 2, 2, 9};
  CHECK(paper_G2_kept(flat, std::vector<bool>(6, true)) == std::vector<bool>(6, true));
}

TEST_CASE("P* = n_J (6 + 2 u_J) a_c / (8 ln 10)") {
  CHECK(crossover_pressure(0.775, 0.2, 0.01) == Approx(0.775 * 6.4 * 0.01 / (8 * std::log(10.0))));
  CHECK(crossover_pressure(0.775, 0.2, 0.01) == Approx(0.0026927).epsilon(1e-4));
}

// Each target a cluster of its own: the targets of distinct seeds.
std::vector<std::uint64_t> own_clusters(std::size_t n) {
  std::vector<std::uint64_t> c(n);
  for (std::size_t k = 0; k < n; ++k) c[k] = k;
  return c;
}

TEST_CASE("B_grow = λ_c B_ext is tested by the median ratio: an arrested target (0 over 0) cannot move it") {
  // Ratios B_grow/(λ_c B): 10, 1, −0.5 (B_grow ≤ 0 ranks lowest), 0.1 and 10^139 (B_grow = 10⁻¹¹
  // fitted on a flat P against λ_c B = 10⁻¹⁵⁰); λ_c B = 0 and a NaN B_grow are left out. Sorted
  // −0.5, 0.1, 1, 10, 10^139: median 1, log₁₀ = 0, where the mean of the four positive logs is 34.75.
  const std::vector<double> B_grow{5, 1, -0.5, 1e-11, 0.05, 3, NAN};
  const std::vector<double> lambda{1, 0.5, 0.5, 1e-150, 0.25, 0, 1};
  const std::vector<double> B_ext{0.5, 2, 2, 1, 2, 0.4, 0.4};
  const auto c = growth_bulk_check(B_grow, lambda, B_ext, own_clusters(7));
  REQUIRE(c);
  CHECK(c->log10_median.n == 5);
  CHECK(c->targets == 5);
  CHECK(c->nonpositive == 1);
  CHECK(c->log10_median.estimate == Approx(0).margin(1e-15));
  // without the arrested target the mean of the positive logs is 0 and the median log₁₀ 0.55 (the
  // mean of 0.1 and 1): that target moves the mean by 34.75 decades, the median by one rank
  CHECK(growth_bulk_check(std::vector<double>{5, 1, -0.5, 0.05}, std::vector<double>{1, 0.5, 0.5, 0.25},
                          std::vector<double>{0.5, 2, 2, 2}, own_clusters(4))
            ->log10_median.estimate == Approx(std::log10(0.55)));

  // ratios −1, −2, 2: the median −1 is ≤ 0, its log −∞; no target qualifying gives nullopt
  const auto down = growth_bulk_check(std::vector<double>{-1, -2, 2}, std::vector<double>{1, 1, 1},
                                      std::vector<double>{1, 1, 1}, own_clusters(3));
  REQUIRE(down);
  CHECK(down->nonpositive == 2);
  CHECK(std::isinf(down->log10_median.estimate));
  CHECK(down->log10_median.estimate < 0);
  CHECK_FALSE(
      growth_bulk_check(std::vector<double>{1}, std::vector<double>{0}, std::vector<double>{1}, own_clusters(1)));
  CHECK_THROWS_AS(
      growth_bulk_check(std::vector<double>{1, 2}, std::vector<double>{1}, std::vector<double>{1, 2}, own_clusters(2)),
      std::invalid_argument);
}

TEST_CASE("B_grow test: the targets of one seed are one sample, whatever their number or row order") {
  // Eight seeds with ratios 0.5 … 4; each seed's targets repeated three times (one run's targets are
  // alike) must give the same n, median and SE as one target per seed, and so must any row order.
  const std::vector<double> per_seed{0.5, 0.8, 1.0, 1.3, 1.7, 2.2, 3.0, 4.0};
  std::vector<double> B_grow, ones;
  std::vector<std::uint64_t> seed;
  for (int copy = 0; copy < 3; ++copy)
    for (std::size_t k = 0; k < per_seed.size(); ++k) {
      B_grow.push_back(per_seed[k]);
      ones.push_back(1.0);
      seed.push_back(10 + k);
    }
  const std::vector<double> ones8(8, 1.0);
  const auto once = growth_bulk_check(per_seed, ones8, ones8, own_clusters(8));
  const auto thrice = growth_bulk_check(B_grow, ones, ones, seed);
  REQUIRE(once);
  REQUIRE(thrice);
  CHECK(thrice->log10_median.n == 8);
  CHECK(thrice->targets == 24);
  CHECK(thrice->log10_median.estimate == Approx(once->log10_median.estimate));
  CHECK(thrice->log10_median.se == Approx(once->log10_median.se).epsilon(1e-12));
  // rows reversed: the same draws of the same clusters
  std::vector<double> rb(B_grow.rbegin(), B_grow.rend());
  std::vector<std::uint64_t> rs(seed.rbegin(), seed.rend());
  CHECK(growth_bulk_check(rb, ones, ones, rs)->log10_median.se == thrice->log10_median.se);
  // counted as 24 independent targets, the error would shrink by about √3
  const auto as_targets = growth_bulk_check(B_grow, ones, ones, own_clusters(24));
  CHECK(as_targets->log10_median.se < 0.8 * thrice->log10_median.se);
}

TEST_CASE("excess contacts are integers whose sign is that of ΔZ") {
  // N_nr = 10, N_u = 2: N_c,iso = 60 − 4 − 2 = 54
  CHECK(excess_contacts(54, 10, 2) == 0);
  CHECK(excess_contacts(53, 10, 2) == -1);
  CHECK(excess_contacts(58, 10, 2) == 4);
}

TEST_CASE("ω* collapse: proportionality fits through the origin and integer sign counts") {
  // (N_c, N_nr, N_u) → ΔZ, Z − 6: (56, 10, 2) → 0.2, −0.4; (62, 10, 0) → 0.4, 0.2; (108, 20, 4) → −0.1, −0.6
  const std::vector<CollapsePoint> p{{0.1, 56, 10, 2}, {0.2, 62, 10, 0}, {0.01, 108, 20, 4}};
  const auto c = omega_collapse(p);
  CHECK(c.packings == 3);
  CHECK(c.dZ_negative == 1);
  CHECK(c.Z_minus_6_negative == 2);
  CHECK(c.dZ.slope == Approx(0.099 / 0.21));  // Σ ΔZ ω* / Σ ΔZ²
  CHECK(c.Z_minus_6.slope == Approx((-0.04 + 0.04 - 0.006) / 0.56));
  CHECK(c.dZ.r2 > c.Z_minus_6.r2);
  CHECK_THROWS_AS(omega_collapse({}), std::invalid_argument);
}

TEST_CASE("ΔZ identity residuals per P0, in order of appearance") {
  const std::vector<IdentityPoint> pts{{1e-3, 0.1}, {1e-3, -0.1}, {1e-5, 0.2}, {1e-3, 0.3}, {1e-5, NAN}};
  const auto r = dz_identity_residuals(pts);
  REQUIRE(r.size() == 2);
  CHECK(r[0].P0 == 1e-3);
  CHECK(r[0].residual.n == 3);
  CHECK(r[0].residual.mean == Approx(0.1));
  CHECK(r[0].residual.se == Approx(0.2 / std::sqrt(3.0)));
  CHECK(r[0].rms == Approx(std::sqrt(0.11 / 3)));
  CHECK(r[1].P0 == 1e-5);
  CHECK(r[1].residual.n == 1);
  CHECK(r[1].rms == Approx(0.2));
}

TEST_CASE("Π(g): the δ peak at g = 1, densities on the paper's bins and quartiles of the rest") {
  const auto edges = paper_growth_rate_edges();
  REQUIRE(edges.size() == 13);
  CHECK(edges.back() == 0.995);
  const std::vector<double> g{1, 1, 0.98, 0.5, 0.5, 0.02, 0.999};
  const auto d = growth_rate_distribution(g, edges);
  CHECK(d.cells == 7);
  CHECK(d.weight_at_one == Approx(2.0 / 7));
  REQUIRE(d.density.size() == 12);
  CHECK(d.density[0] == Approx(1.0 / 7 / 0.03));    // 0.02 in [0, 0.03)
  CHECK(d.density[7] == Approx(2.0 / 7 / 0.15));    // two at 0.5 in [0.45, 0.60)
  CHECK(d.density[11] == Approx(1.0 / 7 / 0.025));  // 0.98 in [0.97, 0.995); 0.999 is beyond the last edge
  CHECK(d.density[5] == 0.0);
  CHECK(d.median == Approx(0.5));  // of {0.02, 0.5, 0.5, 0.98, 0.999}
  CHECK(d.q25 == Approx(0.5));
  CHECK(d.q75 == Approx(0.98));
  CHECK_THROWS_AS(growth_rate_distribution(std::vector<double>{}, edges), std::invalid_argument);
}

TEST_CASE(
    "survival.csv read back gives the Kaplan-Meier steps: events from the drop of S, censored from the risk set") {
  // Ties of events with a censoring (a = 2, 4), censoring-only steps (a = 3, 5, 6; the last one
  // censored), and Ŝ falling by a third at a = 4 (2 events among 6 at risk): Ŝ = 10/11, 8/11, 16/33.
  const std::vector<SurvivalRecord> records{{1, true}, {2, true},  {2, false}, {2, true},  {3, false}, {4, true},
                                            {4, true}, {4, false}, {5, false}, {6, false}, {6, false}};
  const auto km = kaplan_meier(records);
  const auto dir = budjam::testing::work_dir() / "km_tables";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "runs.csv") << "run,L,P0,seed,status\nr1,8,0.001,1,finished\n";
  std::ofstream(dir / "targets.csv") << "run,L,P0,seed,dphi,below_phi2\n";
  {  // as `budjam analyse` writes it: a first row with the records, then one row per step
    std::ofstream f(dir / "survival.csv");
    f << "L,P0,a,S,se,lo,hi,at_risk\n8,0.001,0,1,0,1,1," << km.records() << "\n";
    for (const auto& st : km.steps())
      f << "8,0.001," << io::format_double(st.a) << "," << io::format_double(st.S) << ","
        << io::format_double(std::sqrt(st.greenwood_var)) << ",0,1," << st.at_risk << "\n";
  }
  const Ensemble e = read_ensemble_tables(dir);
  const auto& back = e.survival.at(GroupKey{8, 1e-3});
  CHECK(back.records() == km.records());
  CHECK(back.events() == km.events());
  REQUIRE(back.steps().size() == km.steps().size());
  for (std::size_t k = 0; k < km.steps().size(); ++k) {
    const auto &x = back.steps()[k], &y = km.steps()[k];
    INFO("a = " << y.a);
    CHECK(x.a == y.a);
    CHECK(x.S == y.S);
    CHECK(x.at_risk == y.at_risk);
    CHECK(x.events == y.events);
    CHECK(x.censored == y.censored);
    CHECK(x.greenwood_var == Approx(y.greenwood_var).epsilon(1e-14));
  }
  CHECK(median_completion_size(back) == median_completion_size(km));
  CHECK(back.integral(30) == km.integral(30));
  CHECK(e.unavailable.count("remaining.csv") == 1);
  // A table without se_greenwood holds Greenwood's se, not the run-clustered one: no band from it.
  CHECK(e.unavailable.count("survival.csv:se") == 1);
  for (const auto& st : back.steps()) CHECK(std::isnan(st.clustered_var));
}

TEST_CASE("survival.csv read back keeps the run-clustered se it holds, step by step", "[ensemble]") {
  std::vector<SurvivalRecord> records;
  for (std::size_t run = 0; run < 6; ++run)
    for (std::size_t k = 0; k < 4; ++k)
      records.push_back({0.5 + 0.3 * static_cast<double>((run * 5 + k * 3) % 7) + 0.01 * static_cast<double>(run),
                         (run + k) % 4 != 0, run});
  const auto km = kaplan_meier(records);
  const auto dir = budjam::testing::work_dir() / "km_tables_clustered";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "runs.csv") << "run,L,P0,seed,status\nr1,8,0.001,1,finished\n";
  std::ofstream(dir / "targets.csv") << "run,L,P0,seed,dphi,below_phi2\n";
  {
    std::ofstream f(dir / "survival.csv");
    f << "L,P0,a,S,se,lo,hi,se_greenwood,at_risk\n8,0.001,0,1,,,,," << km.records() << "\n";
    for (const auto& st : km.steps())
      f << "8,0.001," << io::format_double(st.a) << "," << io::format_double(st.S) << ","
        << io::format_double(std::sqrt(st.clustered_var)) << ",0,1," << io::format_double(std::sqrt(st.greenwood_var))
        << "," << st.at_risk << "\n";
  }
  const Ensemble e = read_ensemble_tables(dir);
  CHECK(e.unavailable.count("survival.csv:se") == 0);
  const auto& back = e.survival.at(GroupKey{8, 1e-3});
  REQUIRE(back.steps().size() == km.steps().size());
  for (std::size_t k = 0; k < km.steps().size(); ++k)
    CHECK(back.steps()[k].clustered_var == Approx(km.steps()[k].clustered_var).epsilon(1e-12).margin(1e-300));
}

namespace {
// One analysis.json group entry with the fields the depletion finite-size table reads: Δφ_2 =
// 0.02 + 3/N_J exactly, G_2/P_max a median that does not depend on size.
io::Json size_group(double L, const char* P0_label, double N_J, double se) {
  io::Json g;
  g["L"] = L;
  g["P0"] = std::string(P0_label) == "none" ? io::Json(nullptr) : io::Json(std::stod(P0_label));
  g["P0_label"] = P0_label;
  g["runs"] = 20;
  g["N_J"] = {{"n", 20}, {"mean", N_J}, {"se", 1.0}};
  g["dphi_2"] = {{"n", 20}, {"mean", 0.02 + 3.0 / N_J}, {"se", se}};
  g["dphi_2_paper"] = {{"n", 3}, {"mean", 0.02}, {"se", nullptr}};
  g["N_div_2_over_N_J"] = {{"n", 20}, {"median", 0.05}, {"se", se}};
  g["G_2_over_Pmax"] = {{"n", 20}, {"median", 0.4}, {"se", se}};
  return g;
}

// Seeds of their own per size and P0 label: 20 from L·1000 on.
std::map<std::string, SeedsBySize> own_seeds(const io::Json& groups) {
  std::map<std::string, SeedsBySize> seeds;
  for (const auto& g : groups) {
    auto& s = seeds[g["P0_label"].get<std::string>()][g["L"].get<double>()];
    for (std::uint64_t k = 0; k < 20; ++k) s.insert(static_cast<std::uint64_t>(g["L"].get<double>()) * 1000 + k);
  }
  return seeds;
}
}  // namespace

TEST_CASE("the depletion finite-size table extrapolates with five sizes per P0, not with three") {
  io::Json groups = io::Json::array();
  const std::vector<double> Ls{20, 8, 10, 15, 12}, Ns{300, 48, 75, 176, 108};  // any order
  for (std::size_t k = 0; k < Ls.size(); ++k) groups.push_back(size_group(Ls[k], "0.001", Ns[k], 0.001));
  for (double L : {8.0, 15.0, 20.0}) groups.push_back(size_group(L, "none", L * L * 0.77, 0.001));
  groups.push_back(size_group(15, "1e-05", 176, 0.001));  // one size only: no entry
  const auto fs = finite_size_json(groups, own_seeds(groups));
  REQUIRE(fs.size() == 2);
  const auto& fed = fs[0]["P0_label"] == "0.001" ? fs[0] : fs[1];
  const auto& none = fs[0]["P0_label"] == "none" ? fs[0] : fs[1];
  CHECK(fed["sizes"][0]["L"] == 8);
  CHECK(fed["sizes"][4]["L"] == 20);
  const auto& d = fed["extrapolation"]["dphi_2"];
  CHECK(d["limit"].get<double>() == Approx(0.02).epsilon(1e-9));
  CHECK(d["slope"].get<double>() == Approx(3.0).epsilon(1e-6));
  CHECK(d["residuals_in_se"].size() == 5);
  CHECK(fed["extrapolation"]["G_2_over_Pmax"]["limit"].get<double>() == Approx(0.4));
  // values without an error bar (n < 5) are not fitted; a quantity the groups lack gives empty cells
  CHECK(fed["extrapolation"]["dphi_2_paper"]["limit"].is_null());
  CHECK(fed["extrapolation"]["dphi_2_paper"]["sizes"] == 0);
  CHECK(fed["sizes"][0]["G_2_over_Pmax_paper"]["value"].is_null());
  // three sizes: rows, no extrapolation, and the reason
  CHECK(none["sizes"].size() == 3);
  CHECK(none["extrapolation"]["dphi_2"]["limit"].is_null());
  CHECK(none["extrapolation"]["dphi_2"]["why"].get<std::string>().find("needs 5") != std::string::npos);
}

TEST_CASE("a finite-size fit is made only over sizes with no seed in common; the per-size rows stay") {
  // Δφ_2 = 0.02 + 3/N_J exactly at five sizes (one P0): fitted with disjoint seeds; with one seed grown
  // at two sizes (its random stream does not depend on L: correlated sizes) no limit, and the reason.
  io::Json groups = io::Json::array();
  const std::vector<double> Ls{8, 10, 12, 15, 20}, Ns{48, 75, 108, 176, 300};
  for (std::size_t k = 0; k < Ls.size(); ++k) groups.push_back(size_group(Ls[k], "0.001", Ns[k], 0.001));
  auto seeds = own_seeds(groups);
  const auto disjoint = finite_size_json(groups, seeds);
  REQUIRE(disjoint.size() == 1);
  CHECK(disjoint[0]["extrapolation"]["dphi_2"]["limit"].get<double>() == Approx(0.02).epsilon(1e-9));
  seeds["0.001"][20.0].insert(12005);  // seed 12005 of L = 12 grown at L = 20 as well
  const auto shared = finite_size_json(groups, seeds);
  REQUIRE(shared.size() == 1);
  const auto& d = shared[0]["extrapolation"]["dphi_2"];
  CHECK(d["limit"].is_null());
  CHECK(!d.contains("chi2"));
  CHECK(d["why"].get<std::string>().find("share seeds (1 seed grown at more than one size)") != std::string::npos);
  CHECK(shared[0]["sizes"].size() == 5);
  CHECK(shared[0]["sizes"][4]["dphi_2"]["value"].get<double>() == Approx(0.02 + 3.0 / 300));
  // a size whose quantity has no error bar is not used, and its seeds do not count: Δφ_2 of L = 20 without
  // an SE leaves four sizes, too few, whatever their seeds
  groups[4]["dphi_2"]["se"] = nullptr;
  CHECK(finite_size_json(groups, seeds)[0]["extrapolation"]["dphi_2"]["why"].get<std::string>().find("needs 5") !=
        std::string::npos);
}

TEST_CASE("a run's protocol hash is FNV-1a 64 of its canonical key text: equal where runs may be pooled, not else") {
  // the published FNV-1a 64 test vectors: the hash is a format, the same on every platform
  CHECK(io::fnv1a64("") == 0xcbf29ce484222325ULL);
  CHECK(io::fnv1a64("a") == 0xaf63dc4c8601ec8cULL);
  CHECK(io::fnv1a64("foobar") == 0x85944171f73967e8ULL);
  const Scene a;
  const std::string text = protocol_text(a, group_protocol_key);
  CHECK(text.find("box.L = 8\n") != std::string::npos);
  CHECK(text.find("jamming.epsilon_U = 1e-16\n") != std::string::npos);
  CHECK(text.find("run.") == std::string::npos);
  CHECK(text.find("cells.") == std::string::npos);
  CHECK(protocol_text(a, cells_key).find("cells.alpha0 = 1.01\n") != std::string::npos);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(io::fnv1a64(text)));
  CHECK(protocol_hash(a, group_protocol_key) == hex);
  // what a run is called, records, runs on, its seed and step limit leave the hash as it is
  Scene same = a;
  same.name = "other";
  same.seed = 9;
  same.bud_events = false;
  same.max_steps = 100;
  same.targets = {1e-3, 1e-2};
  same.threads = 2;
  CHECK(protocol_hash(same, group_protocol_key) == protocol_hash(a, group_protocol_key));
  CHECK(protocol_hash(same, cells_key) == protocol_hash(a, cells_key));
  // a protocol key changes it; a cell parameter changes the cells hash only
  Scene eps = a;
  eps.epsilon_U = 1e-12;
  CHECK(protocol_hash(eps, group_protocol_key) != protocol_hash(a, group_protocol_key));
  Scene cells = a;
  cells.alpha0 = 1.02;
  CHECK(protocol_hash(cells, group_protocol_key) == protocol_hash(a, group_protocol_key));
  CHECK(protocol_hash(cells, cells_key) != protocol_hash(a, cells_key));
}
