// Kaplan–Meier survival with censoring and Greenwood's variance, against a hand-worked example.
#include "budjam/survival.hpp"

#include "budjam/statistics.hpp"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace budjam;

namespace {
// Eight tagged buds: completions (E) at a = 1, 3, 3, 5, 7; censorings (C) at a = 2, 3, 6.
std::vector<SurvivalRecord> example() {
  return {{3, true}, {1, true}, {2, false}, {3, false}, {5, true}, {3, true}, {7, true}, {6, false}};
}
}  // namespace

TEST_CASE("Kaplan-Meier matches the hand-worked censored example") {
  // a = 1: n = 8, d = 1            → S = 7/8
  // a = 2: n = 7, censored 1        → S = 7/8
  // a = 3: n = 6, d = 2, censored 1 → S = 7/8 · 4/6 = 7/12 (censored at a tie are still at risk)
  // a = 5: n = 3, d = 1             → S = 7/12 · 2/3 = 7/18
  // a = 6: n = 2, censored 1
  // a = 7: n = 1, d = 1             → S = 0
  const auto km = kaplan_meier(example());
  REQUIRE(km.steps().size() == 6);
  CHECK(km.records() == 8);
  CHECK(km.events() == 5);
  CHECK(km.steps()[2].at_risk == 6);
  CHECK(km.steps()[2].events == 2);
  CHECK(km.steps()[2].censored == 1);
  CHECK(km.steps()[3].at_risk == 3);
  CHECK(km.S(0.5) == 1.0);
  CHECK(km.S(1.0) == Approx(7.0 / 8));  // right-continuous
  CHECK(km.S(2.5) == Approx(7.0 / 8));
  CHECK(km.S(3.0) == Approx(7.0 / 12));
  CHECK(km.S(5.5) == Approx(7.0 / 18));
  CHECK(km.S(6.9) == Approx(7.0 / 18));
  CHECK(km.S(7.0) == 0.0);
}

TEST_CASE("Greenwood variance matches the hand-worked sums") {
  // Σ d/(n(n−d)): a=1: 1/(8·7) = 1/56; a=3: + 2/(6·4) = 1/12 → 17/168; a=5: + 1/(3·2) → 45/168.
  const auto km = kaplan_meier(example());
  CHECK(km.variance(0.5) == 0.0);
  CHECK(km.variance(1.0) == Approx((49.0 / 64) * (1.0 / 56)));
  CHECK(km.variance(3.0) == Approx((49.0 / 144) * (17.0 / 168)));
  CHECK(km.variance(5.0) == Approx((49.0 / 324) * (45.0 / 168)));
  CHECK(km.variance(7.0) == 0.0);  // Ŝ = 0: no spread left
}

TEST_CASE("integral of S is the exact area under the step function") {
  // ∫_0^8 S = 1·1 + (7/8)·2 + (7/12)·2 + (7/18)·2 + 0 = 169/36
  const auto km = kaplan_meier(example());
  CHECK(km.integral(8.0) == Approx(169.0 / 36));
  CHECK(km.integral(0.5) == Approx(0.5));
  CHECK(km.integral(4.0) == Approx(1.0 + 7.0 / 4 + 7.0 / 12));
  CHECK(km.integral(0.0) == 0.0);
}

TEST_CASE("a_eps is the first completion where u_J S(a) falls to eps") {
  const auto km = kaplan_meier(example());
  // level ε/u_J = 0.6 → first S ≤ 0.6 is 7/12 at a = 3; level 0.5 → 7/18 at a = 5
  CHECK(*a_epsilon(km, 0.25, 0.15) == 3.0);
  CHECK(*a_epsilon(km, 0.25, 0.125) == 5.0);
  CHECK(*a_epsilon(km, 0.25, 0.0) == 7.0);  // exact exhaustion
  CHECK(*a_epsilon(km, 0.25, 0.3) == 0.0);  // ε ≥ u_J: already there
  // all censored: S never falls, a_ε does not exist
  const auto cens = kaplan_meier({{1, false}, {2, false}});
  CHECK_FALSE(a_epsilon(cens, 0.2, 0.01).has_value());
  CHECK(cens.S(10.0) == 1.0);
}

TEST_CASE("a_eps reaches an exact level despite rounding of the product-limit") {
  // Five tagged buds, four completions, one censored at the end: Ŝ = 4/5·3/4·2/3·1/2 = 1/5, which
  // floating point gives as 0.20000000000000004. With ε = 1/N_nr and u_J = 5/N_nr the level is 1/5:
  // φ_2's "at most one bud left" must be found at the fourth completion.
  const auto km = kaplan_meier({{0.1, true}, {0.2, true}, {0.3, true}, {0.4, true}, {0.5, false}});
  REQUIRE(km.S(0.45) == Approx(0.2));
  const double N_nr = 48.0;
  REQUIRE(a_epsilon(km, 5.0 / N_nr, 1.0 / N_nr).has_value());
  CHECK(*a_epsilon(km, 5.0 / N_nr, 1.0 / N_nr) == 0.4);
}

TEST_CASE("the band is given where at least five records are at risk, clipped to [0, 1]") {
  const auto km = kaplan_meier(example());
  for (const auto& st : km.steps()) {
    INFO("a = " << st.a << ", at risk " << st.at_risk);
    const auto band = survival_band(st, st.greenwood_var);
    REQUIRE(band.has_value() == (st.at_risk >= kMinSamplesForError));
    if (!band) continue;
    CHECK(band->se == Approx(std::sqrt(st.greenwood_var)));
    CHECK(band->lo == Approx(std::max(0.0, st.S - 1.96 * band->se)));
    CHECK(band->hi == Approx(std::min(1.0, st.S + 1.96 * band->se)));
  }
  // the first event of the example: Ŝ = 7/8 with eight at risk, Ŝ + 1.96 se > 1 is clipped
  const auto first = survival_band(km.steps().front(), km.steps().front().greenwood_var);
  REQUIRE(first);
  CHECK(first->hi == 1.0);
  CHECK(first->lo == Approx(7.0 / 8 - 1.96 * std::sqrt(7.0 / 8 * 7.0 / 8 / 56)));
}

TEST_CASE("without censoring Kaplan-Meier is the empirical survival function") {
  std::vector<SurvivalRecord> r;
  for (int k = 1; k <= 10; ++k) r.push_back({0.1 * k, true});
  const auto km = kaplan_meier(r);
  for (int k = 1; k <= 10; ++k) CHECK(km.S(0.1 * k + 1e-12) == Approx(1.0 - 0.1 * k).margin(1e-12));
  // Greenwood without censoring is the binomial variance S(1 − S)/n
  CHECK(km.variance(0.35) == Approx(0.7 * 0.3 / 10));
}

TEST_CASE("the variance clustered by record is Greenwood's at the first event and the binomial one without censoring") {
  std::vector<SurvivalRecord> r;
  for (std::size_t k = 1; k <= 10; ++k) r.push_back({0.1 * static_cast<double>(k), true, k});
  const auto km = kaplan_meier(r);
  CHECK(km.clusters() == 10);
  for (const auto& st : km.steps()) {
    INFO("a = " << st.a);
    if (st.S > 0) CHECK(st.clustered_var == Approx(st.S * (1 - st.S) / 10));
  }
  // with censoring, one record per cluster: Greenwood's sum at the first event (hand-worked example)
  auto ex = example();
  for (std::size_t k = 0; k < ex.size(); ++k) ex[k].cluster = k;
  const auto c = kaplan_meier(ex);
  CHECK(c.steps().front().clustered_var == Approx(c.steps().front().greenwood_var));
}

TEST_CASE("copies of every record within its cluster leave the clustered variance as it is, not Greenwood's") {
  // Twelve clusters of three records each, censored at a third of the sizes.
  std::vector<SurvivalRecord> base;
  for (std::size_t c = 0; c < 12; ++c)
    for (std::size_t j = 0; j < 3; ++j) {
      const double a = 0.3 + 0.17 * static_cast<double>((5 * c + 7 * j) % 13) + 0.05 * static_cast<double>(c % 4);
      base.push_back({a, (c + j) % 3 != 0, c});
    }
  std::vector<SurvivalRecord> copied;
  for (const auto& x : base) copied.insert(copied.end(), 4, x);
  const auto one = kaplan_meier(base), four = kaplan_meier(copied);
  REQUIRE(one.steps().size() == four.steps().size());
  for (std::size_t k = 0; k < one.steps().size(); ++k) {
    const auto &x = one.steps()[k], &y = four.steps()[k];
    INFO("a = " << x.a);
    CHECK(y.S == Approx(x.S));
    CHECK(y.clustered_var == Approx(x.clustered_var).margin(1e-15));
    if (x.greenwood_var > 0) CHECK(y.greenwood_var < 0.3 * x.greenwood_var);  // the buds counted as samples
  }
  // a single cluster: the influences of its records sum to zero
  std::vector<SurvivalRecord> single = base;
  for (auto& x : single) x.cluster = 7;
  for (const auto& st : kaplan_meier(single).steps()) CHECK(st.clustered_var == Approx(0.0).margin(1e-15));
}

TEST_CASE("the clustered variance of S agrees with a bootstrap over clusters") {
  // 40 clusters (runs) of 4–9 records sharing a cluster factor on their sizes, a quarter censored.
  std::mt19937_64 rng(20261207);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<std::vector<SurvivalRecord>> clusters(40);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const double scale = 0.5 + U(rng);
    const auto n = static_cast<std::size_t>(4 + 6 * U(rng));
    for (std::size_t j = 0; j < n; ++j) clusters[c].push_back({scale * -std::log(1 - U(rng)), U(rng) > 0.25, c});
  }
  std::vector<SurvivalRecord> all;
  for (const auto& c : clusters) all.insert(all.end(), c.begin(), c.end());
  const auto km = kaplan_meier(all);
  const std::array<double, 3> at{0.3, 0.7, 1.2};
  std::array<double, 3> sum{}, sum2{};
  const int B = 2000;
  std::uniform_int_distribution<std::size_t> pick(0, clusters.size() - 1);
  for (int b = 0; b < B; ++b) {
    std::vector<SurvivalRecord> r;
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      const auto& from = clusters[pick(rng)];
      for (auto x : from) r.push_back({x.a, x.event, c});
    }
    const auto boot = kaplan_meier(r);
    for (std::size_t i = 0; i < at.size(); ++i) {
      sum[i] += boot.S(at[i]);
      sum2[i] += boot.S(at[i]) * boot.S(at[i]);
    }
  }
  for (std::size_t i = 0; i < at.size(); ++i) {
    const double var_boot = sum2[i] / B - (sum[i] / B) * (sum[i] / B);
    const double clustered = [&] {
      double v = 0;
      for (const auto& st : km.steps())
        if (st.a <= at[i]) v = st.clustered_var;
      return v;
    }();
    INFO("a = " << at[i] << ": S = " << km.S(at[i]) << ", bootstrap var " << var_boot << ", clustered " << clustered);
    // 2000 resamples: the bootstrap's variance is itself uncertain by ≈ 3 %; the jackknife is first order
    CHECK(clustered == Approx(var_boot).epsilon(0.15));
    CHECK(clustered > 1.2 * km.variance(at[i]));  // the shared factor widens the band beyond Greenwood's
  }
}

TEST_CASE("Kaplan-Meier refuses negative or non-finite sizes") {
  CHECK_THROWS(kaplan_meier({{-1.0, true}}));
  CHECK_THROWS(kaplan_meier({{NAN, true}}));
  CHECK(kaplan_meier({}).S(1.0) == 1.0);
}

// ---- `budjam survival` on a hand-made run directory -------------------------------------------------
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "input_error.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

namespace {

using budjam::testing::slurp;

// The eight buds of the hand-worked example, logged as the growth driver logs them: a tag, then one
// terminal row each (completed = event; divided / censored_end = censored). Episode 0 is an earlier
// jamming episode that unjammed: its rows must be ignored. `scene` is the run's scene.toml; `seed`
// tells its summary from another run's.
void write_run(const std::filesystem::path& d, const std::string& scene = "[run]\nseed = 1\n[growth]\nP0 = 1e-3\n",
               int seed = 1) {
  std::filesystem::create_directories(d / "packings");
  std::ofstream(d / "scene.toml") << scene;
  std::ofstream(d / "summary.json") << R"({"format": "budjam-summary", "version": 1, "status": "finished", "seed": )"
                                    << seed << R"(, "L": 8.0, "P0": 0.001, "phi_J": 0.83, "u_J": 0.25, "N_nr_J": 32,
    "n_J": 0.5, "targets": []})";
  std::ofstream(d / "steps.csv") << "step,phi,P,N,N_f,N_u_buds,chi_c,tagged_active,divisions_since_jamming,Z,dZ\n";
  std::ofstream(d / "divisions.csv") << "step,phi\n";
  std::ofstream ev(d / "bud_events.csv");
  ev << "episode,cell_id,event,step,phi,a\n";
  ev << "0,99,tagged,5,0.8,0\n0,99,censored_unjam,6,0.79,0.5\n";
  const char* kinds[8] = {"completed",    "completed", "divided",   "completed",
                          "censored_end", "completed", "completed", "divided"};
  const double a[8] = {3, 1, 2, 3, 3, 5, 7, 6};
  for (int k = 0; k < 8; ++k) ev << "1," << k << ",tagged,10,0.83,0\n";
  for (int k = 0; k < 8; ++k) {
    if (std::string(kinds[k]) == "completed") ev << "1," << k << ",first_contact,11,0.84," << a[k] << "\n";
    ev << "1," << k << "," << kinds[k] << ",12,0.85," << a[k] << "\n";
  }
}

}  // namespace

TEST_CASE("budjam survival pools the censored bud events of a run into the hand-worked curve") {
  const auto dir = budjam::testing::work_dir();
  write_run(dir / "run");
  // -o BASE (a trailing .csv dropped) writes km.csv and km.json; --json prints the same JSON.
  const auto r = budjam::testing::run_budjam("survival '" + (dir / "run").string() + "' --json -o '" +
                                             (dir / "km.csv").string() + "'");
  REQUIRE(r.code == 0);
  CHECK(slurp(dir / "km.json") == r.out);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["L"] == 8.0);  // the runs' protocol
  CHECK(j["P0"] == 0.001);
  CHECK(j["records"] == 8);
  CHECK(j["events"] == 5);
  // ε = 1/N_nr = 1/32, u_J = 1/4 → level 1/8: Ŝ first ≤ 1/8 at a = 7 (Ŝ = 0); ∫_0^7 S = 169/36
  CHECK(j["a_eps"].get<double>() == 7.0);
  CHECK(j["integral_S"].get<double>() == Approx(169.0 / 36));
  CHECK(j["integral_S_area"].get<double>() == Approx(169.0 / 36 * std::acos(-1.0) / 4));
  const std::string csv = slurp(dir / "km.csv");
  CHECK(csv.find("\n3,") != std::string::npos);
  CHECK(csv.find(",0.5833333333333334,") != std::string::npos);  // Ŝ(3) = 7/12
  // one run: no band anywhere, though six buds are at risk at a = 3 (a run, not a bud, is the sample)
  CHECK(csv.find(",0.5833333333333334,,,,,6,") != std::string::npos);
  CHECK(csv.find("\n5,3.9269908169872414,0.38888888888888895,,,,,3,1,0\n") != std::string::npos);
}

TEST_CASE("the survival band needs five runs, and five buds at risk") {
  namespace fs = std::filesystem;
  const auto dir = budjam::testing::work_dir() / "five_runs";
  fs::remove_all(dir);
  std::string runs;
  for (int seed = 1; seed <= 5; ++seed) {
    const fs::path run = dir / ("seed" + std::to_string(seed));
    write_run(run, "[run]\nseed = " + std::to_string(seed) + "\n[growth]\nP0 = 1e-3\n", seed);
    runs += " " + budjam::testing::shell_quoted(run);
    const auto r = budjam::testing::run_budjam("survival" + runs + " -o " +
                                               budjam::testing::shell_quoted(dir / ("km" + std::to_string(seed))));
    REQUIRE(r.code == 0);
    const std::string csv = slurp(dir / ("km" + std::to_string(seed) + ".csv"));
    INFO(seed << " runs\n" << csv);
    // Ŝ(3) = 7/12 in every pool of copies; 6 buds of each run at risk there, 3 at a = 5
    const std::string at_3 = ",0.5833333333333334,";
    const auto row = csv.find(at_3);
    REQUIRE(row != std::string::npos);
    CHECK((csv.compare(row + at_3.size(), 1, ",") != 0) == (seed >= 5));
    CHECK((csv.find(at_3 + ",,,," + std::to_string(6 * seed) + ",") != std::string::npos) == (seed < 5));
    // runs alike in every bud: no spread between runs, whatever Greenwood's count of buds says
    if (seed >= 5) CHECK(std::stod(csv.substr(row + at_3.size())) < 1e-12);
  }
}

TEST_CASE("budjam survival counts a run once when it is given twice or copied, as budjam analyse does") {
  namespace fs = std::filesystem;
  const auto dir = budjam::testing::work_dir() / "copies";
  fs::remove_all(dir);
  write_run(dir / "run");
  fs::copy(dir / "run", dir / "copy", fs::copy_options::recursive);
  const std::string run = budjam::testing::shell_quoted(dir / "run"),
                    copy = budjam::testing::shell_quoted(dir / "copy");
  const auto once = budjam::testing::run_budjam("survival " + run + " --json");
  const auto thrice = budjam::testing::run_budjam("survival " + run + " " + copy + " " + run + " --json");
  REQUIRE(once.code == 0);
  REQUIRE(thrice.code == 0);
  auto j1 = nlohmann::json::parse(once.out), j3 = nlohmann::json::parse(thrice.out);
  CHECK(j3["runs"] == 1);
  CHECK(j3["records"] == 8);
  CHECK(j3["duplicates"] == nlohmann::json::array({nlohmann::json::array(
                                {(dir / "run").string(), (dir / "copy").string(), (dir / "run").string()})}));
  CHECK(j1["duplicates"].empty());
  j1.erase("duplicates");
  j3.erase("duplicates");
  CHECK(j1 == j3);  // the same curve and a_eps as from the run alone
  const auto line = budjam::testing::run_budjam("survival " + run + " " + copy);
  CHECK(line.out.find("1 runs (1 duplicate copies left out)") != std::string::npos);
}

TEST_CASE(
    "budjam survival pools runs of one protocol only: another seed or observer is pooled, another P0 or L "
    "is refused naming the key") {
  namespace fs = std::filesystem;
  const auto dir = budjam::testing::work_dir() / "protocol";
  fs::remove_all(dir);
  const auto q = [](const fs::path& p) { return budjam::testing::shell_quoted(p); };
  write_run(dir / "a");
  write_run(dir / "b", "[run]\nseed = 2\nname = \"b\"\n[growth]\nP0 = 1e-3\nmax_steps = 99\n[observe]\ntrials = true\n",
            2);
  const auto pooled = budjam::testing::run_budjam("survival " + q(dir / "a") + " " + q(dir / "b") + " --json");
  REQUIRE(pooled.code == 0);
  CHECK(nlohmann::json::parse(pooled.out)["records"] == 16);
  // (run, its scene, the key named, its value there)
  const std::vector<std::array<std::string, 4>> refused{
      {"p0", "[run]\nseed = 3\n[growth]\nP0 = 1e-1\n", "growth.P0", "0.1"},
      {"feedback_off", "[run]\nseed = 3\n[growth]\nP0 = \"none\"\n", "growth.P0", "none"},
      {"box", "[run]\nseed = 3\n[box]\nL = 20.0\n[growth]\nP0 = 1e-3\n", "box.L", "20"}};
  for (const auto& [name, scene, key, value] : refused) {
    INFO(name);
    write_run(dir / name, scene, 3);
    const fs::path out = dir / ("km_" + name);
    const auto r = budjam::testing::run_budjam("survival " + q(dir / "a") + " " + q(dir / "b") + " " + q(dir / name) +
                                               " --out " + q(out));
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find((dir / name / "scene.toml").string() + ": " + key + " = ") != std::string::npos);
    CHECK(r.err.find(value) != std::string::npos);
    CHECK(r.err.find("give them to survival apart") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(out.string() + ".json"));
  }
}

namespace {

// `text` with its first `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

// survival and analyse on `run`: both exit 2 with one line starting `start`, never "internal".
void check_both_refuse(const std::filesystem::path& run, const std::string& start) {
  const std::string q = budjam::testing::shell_quoted(run);
  for (const std::string& command : {"survival " + q, "analyse " + q + " --out " + q + "_an"}) {
    INFO(command);
    budjam::testing::check_input_error(budjam::testing::run_budjam(command), start);
  }
}

}  // namespace

TEST_CASE(
    "survival and analyse refuse a bud size a that is empty, NaN, infinite or negative, naming file, line and "
    "column a (exit 2, never internal)") {
  namespace fs = std::filesystem;
  const auto dir = budjam::testing::work_dir() / "bad_a";
  fs::remove_all(dir);
  write_run(dir / "good");
  const std::string events = slurp(dir / "good" / "bud_events.csv");
  // line 21 is the completed row of bud 0 (a = 3); its a is the last field
  const std::string row = "1,0,completed,12,0.85,3\n";
  REQUIRE(events.find(row) != std::string::npos);
  int line = 1;
  for (std::size_t k = 0; k < events.find(row); ++k) line += events[k] == '\n';
  const std::vector<std::pair<std::string, std::string>> cases{{"inf", "not a finite number"},
                                                               {"-inf", "not a finite number"},
                                                               {"nan", "not a finite number"},
                                                               {"-0.5", "expected a number >= 0"},
                                                               {"", "empty, expected a number >= 0"}};
  int n = 0;
  for (const auto& [value, problem] : cases) {
    const fs::path run = dir / ("run" + std::to_string(n++));
    fs::copy(dir / "good", run, fs::copy_options::recursive);
    std::ofstream(run / "bud_events.csv") << replaced(events, row, "1,0,completed,12,0.85," + value + "\n");
    check_both_refuse(run, (run / "bud_events.csv").string() + ":" + std::to_string(line) + ": column a: " + problem);
  }
}

TEST_CASE(
    "survival and analyse refuse a summary.json value out of its type or range, another format version, a "
    "number overflow and a missing steps.csv column, naming the file and key (exit 2, never internal)") {
  namespace fs = std::filesystem;
  const auto dir = budjam::testing::work_dir() / "bad_summary";
  fs::remove_all(dir);
  write_run(dir / "good");
  const std::string summary = slurp(dir / "good" / "summary.json");
  // (what summary.json says instead, the message after "RUN/summary.json: ")
  const std::vector<std::array<std::string, 3>> cases{
      {"\"N_nr_J\": 32", "\"N_nr_J\": -5", "N_nr_J: expected a non-negative integer or null (got -5)"},
      {"\"N_nr_J\": 32", "\"N_nr_J\": 0", "N_nr_J: 0, but a jammed run"},
      {"\"N_nr_J\": 32", "\"N_nr_J\": 1e999", "invalid JSON: number overflow"},
      {"\"N_nr_J\": 32", "\"N_nr_J\": 32, \"tagged_J\": \"6\"", "tagged_J: expected a non-negative integer"},
      {"\"phi_J\": 0.83", "\"phi_J\": \"0.83\"", "phi_J: expected a number > 0 or null (got \"0.83\")"},
      {"\"u_J\": 0.25", "\"u_J\": 1.5", "u_J: expected a number in [0, 1] or null (got 1.5)"},
      {"\"status\": \"finished\"", "\"status\": 3", "status: expected a string (got 3)"},
      {"\"status\": \"finished\"", "\"status\": \"running\"",
       "status: \"running\" is not the status of a finished run"},
      {"\"version\": 1", "\"version\": 2", "version: 2 is not a summary format this budjam reads (expected 1)"},
      {"\"targets\": []", "\"targets\": {}", "targets: not a list"},
      {"\"targets\": []", "\"targets\": [{\"dphi\": \"x\"}]", "targets[0].dphi: expected a number > 0 (got \"x\")"},
      {"\"targets\": []", "\"targets\": [{\"dphi\": 0.01}]", "targets[0].index: missing"}};
  int n = 0;
  for (const auto& [from, to, message] : cases) {
    const fs::path run = dir / ("run" + std::to_string(n++));
    fs::copy(dir / "good", run, fs::copy_options::recursive);
    std::ofstream(run / "summary.json") << replaced(summary, from, to);
    check_both_refuse(run, (run / "summary.json").string() + ": " + message);
  }
  const fs::path run = dir / "no_column";
  fs::copy(dir / "good", run, fs::copy_options::recursive);
  std::ofstream(run / "steps.csv") << "step,phi,P,N,N_f,N_u_buds,chi_c,tagged_active,Z,dZ\n";
  check_both_refuse(run, (run / "steps.csv").string() + ": no column 'divisions_since_jamming'");
}

TEST_CASE("survival refuses an epsilon outside [0, 1] or not finite, naming the option") {
  const auto dir = budjam::testing::work_dir() / "bad_epsilon";
  std::filesystem::remove_all(dir);
  write_run(dir / "run");
  for (const char* e : {"-1", "inf", "nan", "1.5"}) {
    const auto r =
        budjam::testing::run_budjam("survival " + budjam::testing::shell_quoted(dir / "run") + " --epsilon " + e);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("budjam: error: epsilon: must be a finite number in [0, 1]", 0) == 0);
  }
}

TEST_CASE("Kaplan-Meier and Greenwood reproduce the textbook 6-MP leukaemia table") {
  // Remission times of the 6-MP arm of Freireich et al. (1963), + = censored; the estimates and
  // Greenwood standard errors of Klein & Moeschberger, Survival Analysis, Table 4.1A.
  const std::vector<SurvivalRecord> sixmp{{6, true},   {6, true},   {6, true},   {6, false}, {7, true},   {9, false},
                                          {10, true},  {10, false}, {11, false}, {13, true}, {16, true},  {17, false},
                                          {19, false}, {20, false}, {22, true},  {23, true}, {25, false}, {32, false},
                                          {32, false}, {34, false}, {35, false}};
  const auto km = kaplan_meier(sixmp);
  const std::vector<std::array<double, 3>> table{{6, 0.857, 0.0764},  {7, 0.807, 0.0869},  {10, 0.753, 0.0963},
                                                 {13, 0.690, 0.1068}, {16, 0.627, 0.1141}, {22, 0.538, 0.1282},
                                                 {23, 0.448, 0.1346}};
  for (const auto& [t, S, se] : table) {
    INFO("t = " << t);
    CHECK(km.S(t) == Approx(S).margin(5e-4));
    CHECK(std::sqrt(km.variance(t)) == Approx(se).margin(5e-5));
  }
  CHECK(km.S(35) == Approx(0.448).margin(5e-4));  // no completion after 23: Ŝ stays, undefined beyond 35
  CHECK(*median_completion_size(km) == 23.0);     // the textbook median remission time
  // mean up to the last event: 6·1 + 1·6/7·... = ∫_0^23 Ŝ
  const double mean23 = 6 + (7 - 6) * (18.0 / 21) + (10 - 7) * km.S(7) + (13 - 10) * km.S(10) + (16 - 13) * km.S(13) +
                        (22 - 16) * km.S(16) + (23 - 22) * km.S(22);
  CHECK(mean_completion_size(km) == Approx(mean23));
}

TEST_CASE("the median completion size is absent while Ŝ stays above one half") {
  const auto km = kaplan_meier({{1, true}, {2, false}, {3, false}, {4, false}});  // Ŝ = 3/4 after a = 1
  CHECK_FALSE(median_completion_size(km));
  CHECK(mean_completion_size(km) == Approx(1.0));
  CHECK(mean_completion_size(kaplan_meier({{1, false}})) == 0.0);
}
