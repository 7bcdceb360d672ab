// `budjam analyse` end to end on real runs: the ensemble tables carry each run's own numbers
// (summary.json, the moduli files beside its packings), are deterministic, and a missing input is
// refused. The estimators themselves are tested on known answers in test_statistics,
// test_survival and test_depletion.
#include "budjam/statistics.hpp"
#include "io/json.hpp"

#include <catch2/catch.hpp>
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <sys/wait.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <span>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace fs = std::filesystem;

namespace {

using budjam::testing::run_budjam;
using budjam::testing::run_budjam_redirected;
using budjam::testing::slurp;
using budjam::testing::work_dir;

std::string q(const fs::path& p) { return budjam::testing::shell_quoted(p); }

// Rows of a CSV file as column → text.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  auto split = [](const std::string& s) {
    std::vector<std::string> f;
    std::stringstream ss(s);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!s.empty() && s.back() == ',') f.emplace_back();
    return f;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const auto f = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t k = 0; k < header.size() && k < f.size(); ++k) row[header[k]] = f[k];
    rows.push_back(row);
  }
  return rows;
}

// Three small runs (L = 6: no feedback, and P0 = 1e-3 on two seeds), each to two targets and on to
// φ_2, with bud events and the moduli of every saved packing: what Makefile.analysis feeds analyse.
const std::vector<fs::path>& runs() {
  static const std::vector<fs::path> dirs = [] {
    const fs::path scene = work_dir() / "small.toml";
    std::ofstream(scene)
        << "[run]\nname = \"small\"\nseed = 1\n[box]\nL = 6.0\n[growth]\nP0 = 1e-3\n"
        << "[jamming]\ntargets = [1e-3, 1e-2]\ncontinue_to_phi2 = true\n[observe]\nbud_events = true\n";
    std::vector<fs::path> d;
    for (const auto& [P0, seed] : std::vector<std::pair<std::string, int>>{{"none", 3}, {"1e-3", 3}, {"1e-3", 4}}) {
      const fs::path dir = work_dir() / "runs" / ("P0_" + P0) / ("seed" + std::to_string(seed));
      REQUIRE(run_budjam("grow " + q(scene) + " --quiet --out " + q(dir) + " --seed " + std::to_string(seed) +
                         " --set growth.P0=" + P0)
                  .code == 0);
      for (const auto& e : fs::directory_iterator(dir / "packings"))
        if (e.path().extension() == ".pack")
          REQUIRE(run_budjam("moduli " + q(e.path()) + " --quiet --out " +
                             q(fs::path(e.path()).replace_extension(".moduli")))
                      .code == 0);
      d.push_back(dir);
    }
    return d;
  }();
  return dirs;
}

std::string all_runs() {
  std::string s;
  for (const auto& d : runs()) s += q(d) + " ";
  return s;
}

// The tables of an analysis of the runs, in `name`, for a test to edit.
fs::path analysed(const std::string& name) {
  const fs::path a = work_dir() / name;
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  return a;
}

// `analyse --tables a` refused as bad input: exit 2, one line on stderr, no analysis written; the line.
std::string refused_tables(const fs::path& a, const std::string& out_name) {
  const fs::path err = work_dir() / (out_name + ".err");
  CHECK(run_budjam_redirected("analyse --tables " + q(a) + " --out " + q(work_dir() / out_name) + " --main-L 6",
                              "/dev/null", err) == 2);
  const std::string msg = slurp(err);
  INFO(msg);
  CHECK(std::count(msg.begin(), msg.end(), '\n') == 1);
  CHECK(!fs::exists(work_dir() / out_name / "analysis.json"));
  return msg;
}

double number(const std::string& s) { return s.empty() ? NAN : std::stod(s); }

// Rewrites the CSV file `csv` row by row: `edit` gets each data row's fields (numbered from 1) and the header.
void edit_rows(const fs::path& csv, const std::function<void(int row, std::vector<std::string>& fields,
                                                             const std::vector<std::string>& header)>& edit) {
  std::istringstream in(slurp(csv));
  std::string line, t;
  std::vector<std::string> header;
  for (int n = 0; std::getline(in, line); ++n) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!line.empty() && line.back() == ',') f.emplace_back();
    if (n == 0)
      header = f;
    else
      edit(n, f, header);
    for (std::size_t k = 0; k < f.size(); ++k) t += (k ? "," : "") + f[k];
    t += "\n";
  }
  std::ofstream(csv, std::ios::trunc) << t;
}

std::size_t column_of(const std::vector<std::string>& header, const std::string& name) {
  const auto c = std::find(header.begin(), header.end(), name);
  REQUIRE(c != header.end());
  return static_cast<std::size_t>(c - header.begin());
}

}  // namespace

TEST_CASE("analyse tables carry each run's own φ_J, u_J, φ_2 and the G of its moduli files", "[analyse]") {
  const fs::path out = work_dir() / "tables";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(out) + " --main-L 6 --require moduli").code == 0);
  const auto run_rows = read_csv(out / "runs.csv");
  const auto tgt_rows = read_csv(out / "targets.csv");
  REQUIRE(run_rows.size() == runs().size());
  for (const auto& dir : runs()) {
    const auto s = budjam::io::read_json(dir / "summary.json");
    const auto it =
        std::find_if(run_rows.begin(), run_rows.end(), [&](const auto& r) { return r.at("run") == dir.string(); });
    REQUIRE(it != run_rows.end());
    const auto& r = *it;
    CHECK(number(r.at("phi_J")) == Approx(s.at("phi_J").get<double>()).epsilon(1e-12));
    CHECK(number(r.at("u_J")) == Approx(s.at("u_J").get<double>()).epsilon(1e-12));
    if (s.at("phi_2").is_number()) {
      CHECK(number(r.at("dphi_2")) == Approx(s.at("phi_2").get<double>() - s.at("phi_J").get<double>()).epsilon(1e-9));
      const auto side = budjam::io::read_json(dir / "packings" / "phi2.moduli.json");
      CHECK(number(r.at("G_2")) == Approx(side.at("G").get<double>()).epsilon(1e-12));
      CHECK(number(r.at("G_min_2")) == Approx(side.at("shear_stability").at("G_min").get<double>()).epsilon(1e-12));
    }
    // one targets.csv row per landed target, with that packing's moduli
    for (const auto& t : s.at("targets")) {
      const double dphi = t.at("dphi").get<double>();
      const auto row = std::find_if(tgt_rows.begin(), tgt_rows.end(), [&](const auto& x) {
        return x.at("run") == dir.string() && std::abs(number(x.at("dphi")) - dphi) < 1e-12;
      });
      REQUIRE(row != tgt_rows.end());
      CHECK(number(row->at("P")) == Approx(t.at("P").get<double>()).epsilon(1e-12));
      const auto side = budjam::io::read_json(dir / "packings" /
                                              ("target_" + std::to_string(t.at("index").get<long>()) + ".moduli.json"));
      CHECK(number(row->at("G")) == Approx(side.at("G").get<double>()).epsilon(1e-12));
      CHECK(number(row->at("B")) == Approx(side.at("B").get<double>()).epsilon(1e-12));
    }
  }
  // groups: (L = 6, none) with one run and (L = 6, 1e-3) with two
  const auto A = budjam::io::read_json(out / "analysis.json");
  std::map<std::string, long> runs_in;
  for (const auto& g : A.at("groups")) runs_in[g.at("P0_label").get<std::string>()] = g.at("runs").get<long>();
  CHECK(runs_in.at("none") == 1);
  CHECK(runs_in.at("0.001") == 2);
  CHECK(A.at("inputs").at("used").get<long>() == 3);
}

TEST_CASE("analyse is deterministic: the same runs give byte-identical tables", "[analyse]") {
  const fs::path a = work_dir() / "det_a", b = work_dir() / "det_b";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(b) + " --main-L 6").code == 0);
  for (const char* f : {"analysis.json", "runs.csv", "targets.csv", "survival.csv", "trajectory.csv"}) {
    INFO(f);
    CHECK(slurp(a / f) == slurp(b / f));
    CHECK(!slurp(a / f).empty());
  }
}

TEST_CASE("analyse --require moduli refuses a packing without its moduli file: exit 2, one line naming it",
          "[analyse]") {
  const fs::path copy = work_dir() / "incomplete";
  fs::copy(runs().front(), copy, fs::copy_options::recursive);
  fs::remove(copy / "packings" / "target_0.moduli.json");
  const fs::path err = work_dir() / "analyse.err";
  CHECK(run_budjam_redirected(
            "analyse " + q(copy) + " --out " + q(work_dir() / "t_incomplete") + " --main-L 6 --require moduli",
            "/dev/null", err) == 2);
  const std::string e = slurp(err);
  CHECK(e.find("target_0.pack") != std::string::npos);
  CHECK(e.find("no moduli") != std::string::npos);
  CHECK(std::count(e.begin(), e.end(), '\n') == 1);
  // without --require the same run is analysed, its moduli left empty
  CHECK(run_budjam("analyse " + q(copy) + " --out " + q(work_dir() / "t_lenient") + " --main-L 6").code == 0);
}

TEST_CASE("analyse pools runs of one L and P0 only under one protocol, and every run under one set of cells",
          "[analyse]") {
  const fs::path scene = work_dir() / "protocol.toml";
  std::ofstream(scene) << "[run]\nname = \"protocol\"\nseed = 7\n[box]\nL = 6.0\n[growth]\nP0 = 1e-3\n"
                       << "[jamming]\ntargets = [1e-3]\n";
  const auto grow = [&](const std::string& name, const std::string& sets) {
    const fs::path dir = work_dir() / "protocol" / name;
    REQUIRE(run_budjam("grow " + q(scene) + " --quiet --out " + q(dir) + " " + sets).code == 0);
    return dir;
  };
  // What a run records, is called or runs on, its seed and step limit may differ within a group.
  const fs::path same = grow("same",
                             "--seed 8 --set run.name=other --set 'jamming.targets=[1e-3, 1e-2]' "
                             "--set jamming.continue_to_phi2=true --set growth.max_steps=100000 "
                             "--set observe.trials=true --set minimiser.threads=2");
  CHECK(run_budjam("analyse " + all_runs() + q(same) + " --out " + q(work_dir() / "t_same") + " --main-L 6").code == 0);
  // (name, how the run differs, the key named, its value in that run)
  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> refused{
      {"epsilon", "--seed 9 --set jamming.epsilon_U=1e-12", "jamming.epsilon_U", "1e-12"},
      {"search", "--seed 9 --set jamming.search=bisection", "jamming.search", "\"bisection\""},
      {"cells", "--seed 9 --set growth.P0=1e-1 --set cells.alpha0=1.02", "cells.alpha0", "1.02"}};
  for (const auto& [name, sets, key, value] : refused) {
    INFO(name);
    const fs::path dir = grow(name, sets);
    const fs::path err = work_dir() / "protocol.err";
    CHECK(
        run_budjam_redirected("analyse " + all_runs() + q(dir) + " --out " + q(work_dir() / "t_mixed") + " --main-L 6",
                              "/dev/null", err) == 2);
    const std::string e = slurp(err);
    INFO(e);
    CHECK(e.find(": " + key + " = ") != std::string::npos);  // one scene's value, then the other's
    CHECK(e.find(value) != std::string::npos);
    CHECK(e.find((dir / "scene.toml").string()) != std::string::npos);
    CHECK(e.find("analyse them apart") != std::string::npos);
    CHECK(std::count(e.begin(), e.end(), '\n') == 1);
  }
  CHECK_FALSE(fs::exists(work_dir() / "t_mixed"));
}

TEST_CASE(
    "analyse names each run's jamming model: kept under another search, minimiser or P0, changed by the cells, "
    "the growth step or the window",
    "[analyse]") {
  const fs::path scene = work_dir() / "model.toml";
  std::ofstream(scene) << "[run]\nname = \"model\"\nseed = 7\n[box]\nL = 6.0\n[jamming]\ntargets = [1e-3]\n";
  const auto model = [&](const std::string& name, const std::string& sets) {
    const fs::path dir = work_dir() / "model" / name, out = work_dir() / "model" / (name + "_tables");
    REQUIRE(run_budjam("grow " + q(scene) + " --quiet --out " + q(dir) + " " + sets).code == 0);
    REQUIRE(run_budjam("analyse " + q(dir) + " --out " + q(out) + " --main-L 6").code == 0);
    const std::string m = read_csv(out / "runs.csv").at(0).at("jamming_model");
    CHECK(budjam::io::read_json(out / "analysis.json").at("jamming_models") == budjam::io::Json::array({m}));
    return m;
  };
  const std::string base = model("base", "");
  CHECK(base.size() == 16);
  int k = 0;
  for (const char* same :
       {"--set jamming.search=bisection --set minimiser.active_set_after=0 --set growth.P0=1e-3", "--seed 9"}) {
    INFO(same);
    CHECK(model("same" + std::to_string(++k), same) == base);
  }
  for (const char* other : {"--set cells.division=aligned", "--set growth.dt=2", "--set jamming.epsilon_U=1e-14"}) {
    INFO(other);
    CHECK(model("other" + std::to_string(++k), other) != base);
  }
}

TEST_CASE(
    "analyse refuses a sidecar whose N, L or φ are not its packing's (the packing replaced since): exit 2 "
    "naming it",
    "[analyse]") {
  const fs::path copy = work_dir() / "replaced";
  fs::copy(runs().front(), copy, fs::copy_options::recursive);
  REQUIRE(run_budjam("dos " + q(copy / "packings" / "target_0.pack") + " --quiet --out " +
                     q(copy / "packings" / "target_0.dos"))
              .code == 0);
  REQUIRE(run_budjam("analyse " + q(copy) + " --out " + q(work_dir() / "t_matching") + " --main-L 6").code == 0);
  // The packing replaced by another of the run, its sidecars left: each kind is refused in turn.
  fs::copy_file(copy / "packings" / "target_1.pack", copy / "packings" / "target_0.pack",
                fs::copy_options::overwrite_existing);
  for (const char* kind : {"moduli", "dos"}) {
    INFO(kind);
    const fs::path err = work_dir() / "replaced.err";
    CHECK(run_budjam_redirected("analyse " + q(copy) + " --out " + q(work_dir() / "t_replaced") + " --main-L 6",
                                "/dev/null", err) == 2);
    const std::string e = slurp(err);
    CHECK(e.find("target_0." + std::string(kind) + ".json: results of another packing than") != std::string::npos);
    CHECK(std::count(e.begin(), e.end(), '\n') == 1);
    fs::remove(copy / "packings" / ("target_0." + std::string(kind) + ".json"));
  }
  CHECK_FALSE(fs::exists(work_dir() / "t_replaced"));
}

TEST_CASE(
    "analyse leaves the moduli file of a packing without linear response out of the moduli and counts it: a saddle, "
    "or a minimum held by a pair at zero force",
    "[analyse]") {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  for (const auto& [pack, counter] : {std::pair{"saddle_jamming_L15_seed3.pack", "moduli_saddles"},
                                      std::pair{"contact_bounded_jamming_L20_seed3.pack", "moduli_contact_bounded"}}) {
    INFO(pack);
    const fs::path copy = work_dir() / (std::string("with_") + counter);
    fs::copy(runs().front(), copy, fs::copy_options::recursive);
    // the real JSON of such a packing (budjam moduli exits 1 on it) in place of target_0's
    REQUIRE(run_budjam("moduli " + q(fs::path(src) / "tests/data" / pack) + " --quiet --out " +
                       q(copy / "packings" / "target_0.moduli"))
                .code == 1);
    // given the N, L and φ of target_0's packing, which analyse checks a sidecar against
    const auto own = budjam::io::read_json(runs().front() / "packings" / "target_0.moduli.json");
    auto unstable = budjam::io::read_json(copy / "packings" / "target_0.moduli.json");
    for (const char* key : {"N", "L", "phi"}) unstable[key] = own.at(key);
    budjam::io::write_json(copy / "packings" / "target_0.moduli.json", unstable);
    const fs::path out = work_dir() / (std::string("t_") + counter);
    REQUIRE(run_budjam("analyse " + q(copy) + " --out " + q(out) + " --main-L 6 --require moduli").code == 0);
    const auto inputs = budjam::io::read_json(out / "analysis.json").at("inputs");
    CHECK(inputs.at(counter).get<long>() == 1);
    CHECK(inputs.at("moduli_saddles").get<long>() + inputs.at("moduli_contact_bounded").get<long>() == 1);
    const auto s = budjam::io::read_json(copy / "summary.json");
    const double dphi0 = s.at("targets").at(0).at("dphi").get<double>();
    std::size_t seen = 0;
    for (const auto& row : read_csv(out / "targets.csv")) {
      if (std::abs(number(row.at("dphi")) - dphi0) > 1e-12) continue;
      ++seen;
      CHECK(std::isnan(number(row.at("G"))));
      CHECK(std::isnan(number(row.at("B"))));
    }
    CHECK(seen == 1);
  }
}

TEST_CASE("analyse takes χ̄ as the plain mean over the states of [φ_J, φ_2] and the first state with no tagged bud left",
          "[analyse]") {
  const fs::path out = work_dir() / "t_definitions";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(out) + " --main-L 6").code == 0);
  const auto run_rows = read_csv(out / "runs.csv");
  for (const auto& dir : runs()) {
    const auto s = budjam::io::read_json(dir / "summary.json");
    const auto& r =
        *std::find_if(run_rows.begin(), run_rows.end(), [&](const auto& x) { return x.at("run") == dir.string(); });
    const double step_J = s.at("step_J").get<double>();
    const double step_2 = s.at("step_2").is_number() ? s.at("step_2").get<double>() : INFINITY;
    double chi_sum = 0, n = 0, phi_2_none_left = NAN, step_J_first = NAN;
    for (const auto& row : read_csv(dir / "steps.csv")) {
      const double step = number(row.at("step"));
      // the none-left state is the paper's, scanned from the run's first jamming
      if (std::isnan(step_J_first) && row.at("phase") == "jammed") step_J_first = step;
      if (step >= step_J_first && std::isnan(phi_2_none_left) && number(row.at("tagged_active")) == 0)
        phi_2_none_left = number(row.at("phi"));
      if (step < step_J) continue;
      if (step <= step_2) chi_sum += number(row.at("chi_c")), ++n;
    }
    INFO(dir.string());
    if (std::isfinite(step_2)) CHECK(number(r.at("chi_bar")) == Approx(chi_sum / n).epsilon(1e-12));
    if (std::isfinite(phi_2_none_left)) {
      CHECK(number(r.at("phi_2_none_left")) == Approx(phi_2_none_left).epsilon(1e-14));
      // none left comes no earlier than one left
      CHECK(number(r.at("phi_2_none_left")) >= number(r.at("phi_2_first")));
    } else {
      CHECK(r.at("dphi_2_none_left").empty());
    }
  }
}

TEST_CASE(
    "analyse anchors the paper's columns at a run's first jamming and scans for their φ_2 through the unjammed "
    "states after an unjamming",
    "[analyse]") {
  const fs::path out = work_dir() / "t_first_jamming";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(out) + " --main-L 6").code == 0);
  const auto run_rows = read_csv(out / "runs.csv");
  int unjammed = 0;
  for (const auto& dir : runs()) {
    INFO(dir.string());
    const auto& r =
        *std::find_if(run_rows.begin(), run_rows.end(), [&](const auto& x) { return x.at("run") == dir.string(); });
    double step_J_first = NAN, phi_J_first = NAN, N_nr = NAN, tagged = NAN, phi_2_first = NAN, P_2_first = NAN;
    for (const auto& row : read_csv(dir / "steps.csv")) {
      if (std::isnan(step_J_first)) {
        if (row.at("phase") != "jammed") continue;
        step_J_first = number(row.at("step"));
        phi_J_first = number(row.at("phi"));
        N_nr = number(row.at("N")) - number(row.at("N_f"));
        tagged = number(row.at("tagged_active"));
      }
      // the scan includes the jamming state itself
      if (std::isnan(phi_2_first) && number(row.at("tagged_active")) <= 1) {
        phi_2_first = number(row.at("phi"));
        P_2_first = number(row.at("P"));
      }
    }
    REQUIRE(std::isfinite(step_J_first));
    CHECK(number(r.at("step_J_first")) == step_J_first);
    CHECK(number(r.at("phi_J_first")) == Approx(phi_J_first).epsilon(1e-14));
    CHECK(number(r.at("N_nr_J_first")) == N_nr);
    CHECK(number(r.at("tagged_J_first")) == tagged);
    REQUIRE(std::isfinite(phi_2_first));
    CHECK(number(r.at("phi_2_first")) == Approx(phi_2_first).epsilon(1e-14));
    CHECK(number(r.at("dphi_2_first")) == Approx(phi_2_first - phi_J_first).epsilon(1e-12));
    CHECK(number(r.at("P_2_first")) == Approx(P_2_first).epsilon(1e-14));
    if (step_J_first < number(r.at("step_J"))) {
      ++unjammed;
      CHECK(number(r.at("phi_J_first")) < number(r.at("phi_J")));
    } else {  // never unjammed: the paper's anchor is budjam's jamming point and φ_2
      CHECK(r.at("phi_J_first") == r.at("phi_J"));
      CHECK(r.at("phi_2_first") == r.at("phi_2"));
      CHECK(r.at("G_2_first") == r.at("G_2"));
    }
  }
  CHECK(unjammed >= 1);  // one of the three runs unjams after its first jamming
}

TEST_CASE(
    "the paper's means over [first φ_J, φ_2] count a jamming after an unjamming twice, as its code writes "
    "that state's row for the followed tags and again for the new ones",
    "[analyse]") {
  // L = 7, P0 = 1e-4, seed 4: jams at step 1591, unjams, jams again at 1593, and reaches φ_2 after it.
  const fs::path scene = work_dir() / "rejam.toml", dir = work_dir() / "rejam_run", out = work_dir() / "rejam_out";
  std::ofstream(scene) << "[run]\nname = \"rejam\"\nseed = 4\n[box]\nL = 7.0\n[growth]\nP0 = 1e-4\n"
                       << "[jamming]\ntargets = [1e-3, 1e-2]\ncontinue_to_phi2 = true\n";
  REQUIRE(run_budjam("grow " + q(scene) + " --quiet --out " + q(dir)).code == 0);
  REQUIRE(run_budjam("analyse " + q(dir) + " --out " + q(out) + " --main-L 7").code == 0);
  const auto r = read_csv(out / "runs.csv").at(0);
  const double phi_2_first = number(r.at("phi_2_first"));
  double chi_sum = 0, n = 0, rejammed_at = NAN;
  std::string phase_before;
  for (const auto& row : read_csv(dir / "steps.csv")) {
    const std::string phase = row.at("phase");
    if (phase == "jammed" && phase_before == "unjammed" && std::isfinite(n) && n > 0) {
      rejammed_at = number(row.at("phi"));
      chi_sum += number(row.at("chi_c")), ++n;  // the followed tags' row of this state
    }
    if (phase == "jammed" || n > 0) {
      if (number(row.at("phi")) > phi_2_first) break;
      chi_sum += number(row.at("chi_c")), ++n;
    }
    phase_before = phase;
  }
  REQUIRE(std::isfinite(rejammed_at));
  REQUIRE(rejammed_at < phi_2_first);  // the doubled state lies inside the mean
  CHECK(number(r.at("chi_bar_first")) == Approx(chi_sum / n).epsilon(1e-12));
}

TEST_CASE("analyse reads the φ_2 definition a run saved: budjam's φ_2 from the log, G of the none-left packing",
          "[analyse]") {
  // Seed 4 of the runs above, grown on to the first state with no tagged bud left, which it saves.
  const fs::path dir = work_dir() / "runs_paper_phi2" / "P0_1e-3" / "seed4";
  REQUIRE(run_budjam("grow " + q(work_dir() / "small.toml") + " --quiet --out " + q(dir) +
                     " --seed 4 --set jamming.phi2_tagged_left=0")
              .code == 0);
  const fs::path phi2 = dir / "packings" / "phi2.pack";
  REQUIRE(run_budjam("moduli " + q(phi2) + " --quiet --out " + q(fs::path(phi2).replace_extension(".moduli"))).code ==
          0);
  const fs::path out = work_dir() / "t_phi2_definition", out_budjam = work_dir() / "t_phi2_definition_budjam";
  REQUIRE(run_budjam("analyse " + q(dir) + " --out " + q(out) + " --main-L 6").code == 0);
  REQUIRE(run_budjam("analyse " + q(runs()[2]) + " --out " + q(out_budjam) + " --main-L 6").code == 0);
  const auto none_left = read_csv(out / "runs.csv").at(0), budjam_def = read_csv(out_budjam / "runs.csv").at(0);
  const auto s = budjam::io::read_json(dir / "summary.json");
  REQUIRE(s.at("phi_2_tagged_left") == 0);
  CHECK(number(none_left.at("phi_2_tagged_left")) == 0);
  CHECK(number(budjam_def.at("phi_2_tagged_left")) == 1);
  // The two runs are one trajectory up to budjam's φ_2: the log gives the state the other run saved.
  CHECK(none_left.at("phi_2") == budjam_def.at("phi_2"));
  CHECK(none_left.at("P_2") == budjam_def.at("P_2"));
  CHECK(none_left.at("N_div_2") == budjam_def.at("N_div_2"));
  CHECK(none_left.at("chi_bar") == budjam_def.at("chi_bar"));
  // This seed's two definitions fall on different states: the saved packing is the none-left one only.
  CHECK(number(none_left.at("phi_2_none_left")) == s.at("phi_2").get<double>());
  CHECK(number(none_left.at("phi_2_none_left")) > number(none_left.at("phi_2")));
  const auto moduli = budjam::io::read_json(dir / "packings" / "phi2.moduli.json");
  CHECK(number(none_left.at("G_2_none_left")) == Approx(moduli.at("G").get<double>()).epsilon(1e-12));
  CHECK(none_left.at("G_2").empty());
  CHECK(budjam_def.at("G_2_none_left").empty());  // it stopped before that state
  CHECK(
      number(budjam_def.at("G_2")) ==
      Approx(budjam::io::read_json(runs()[2] / "packings" / "phi2.moduli.json").at("G").get<double>()).epsilon(1e-12));
}

TEST_CASE(
    "analyse reports copies of one run, and a seed grown again under another name, as duplicates and uses it "
    "once",
    "[analyse]") {
  const fs::path pool = work_dir() / "with_copies";
  fs::create_directories(pool);
  fs::copy(runs()[1], pool / "copy_a", fs::copy_options::recursive);
  fs::copy(runs()[1], pool / "copy_b", fs::copy_options::recursive);
  // the same protocol and seed under another run.name, its summary.json not byte-identical: one sample
  fs::copy(runs()[1], pool / "renamed", fs::copy_options::recursive);
  std::string scene = slurp(pool / "renamed" / "scene.toml");
  const auto name = scene.find("name = \"small\"");
  REQUIRE(name != std::string::npos);
  std::ofstream(pool / "renamed" / "scene.toml") << scene.replace(name, 14, "name = \"again\"");
  const std::string summary = budjam::io::read_json(pool / "renamed" / "summary.json").dump(1);
  std::ofstream(pool / "renamed" / "summary.json") << summary;
  const fs::path out = work_dir() / "t_copies", err = work_dir() / "copies.err";
  REQUIRE(run_budjam_redirected("analyse " + all_runs() + q(pool) + " --out " + q(out) + " --main-L 6", "/dev/null",
                                err) == 0);
  const auto A = budjam::io::read_json(out / "analysis.json");
  CHECK(A.at("inputs").at("runs").get<long>() == 6);
  CHECK(A.at("inputs").at("used").get<long>() == 3);
  REQUIRE(A.at("inputs").at("duplicates").size() == 1);
  CHECK(A.at("inputs").at("duplicates").at(0).size() == 4);
  CHECK(read_csv(out / "runs.csv").size() == 3);
  CHECK(slurp(err).find("duplicate") != std::string::npos);
  // the P0 = 1e-3 group still holds its two seeds, not four copies
  for (const auto& g : A.at("groups"))
    if (g.at("P0_label") == "0.001") CHECK(g.at("runs").get<long>() == 2);
}

TEST_CASE("analyse refuses an episode number no integer holds: exit 2, one line naming file and line", "[analyse]") {
  const fs::path copy = work_dir() / "huge_episode";
  fs::copy(runs().front(), copy, fs::copy_options::recursive);
  const fs::path ev = copy / "bud_events.csv";
  std::string text = slurp(ev);
  const auto header_end = text.find('\n');
  const auto header = text.substr(0, header_end);
  REQUIRE(header.rfind("episode,", 0) == 0);  // the episode is the first field
  const auto field_end = text.find(',', header_end + 1);
  text.replace(header_end + 1, field_end - header_end - 1, "1e300");
  std::ofstream(ev) << text;
  const fs::path err = work_dir() / "huge_episode.err";
  CHECK(run_budjam_redirected("analyse " + q(copy) + " --out " + q(work_dir() / "t_huge") + " --main-L 6", "/dev/null",
                              err) == 2);
  const std::string e = slurp(err);
  CHECK(e.find("bud_events.csv:2: column episode") != std::string::npos);
  CHECK(std::count(e.begin(), e.end(), '\n') == 1);
}

namespace {

// What only the run directories give (per-cell growth factors) and the account of the inputs.
budjam::io::Json without_run_only(budjam::io::Json j) {
  j.erase("inputs");
  j.erase("unavailable");
  j.erase("tables_written");
  for (auto& g : j["groups"])
    for (const char* k : {"g_cells", "g_peak_weight_at_1", "g_compressed_median", "g_compressed_q25",
                          "g_compressed_q75", "g_mean", "h_gamma_pooled"})
      g.erase(k);
  return j;
}

// The fixture runs copied, with the spectrum of every packing: dos.csv in the tables.
fs::path runs_with_spectra() {
  const fs::path dir = work_dir() / "runs_dos";
  if (!fs::exists(dir)) {
    fs::copy(work_dir() / "runs", dir, fs::copy_options::recursive);
    for (const auto& e : fs::recursive_directory_iterator(dir))
      if (e.path().extension() == ".pack")
        REQUIRE(run_budjam("dos " + q(e.path()) + " --quiet --out " + q(fs::path(e.path()).replace_extension(".dos")))
                    .code == 0);
  }
  return dir;
}

}  // namespace

TEST_CASE("analyse --tables recomputes from an analysis' own tables exactly what it computed from the runs",
          "[analyse]") {
  runs();
  const fs::path runs_dir = runs_with_spectra(), a = work_dir() / "rt_runs", b = work_dir() / "rt_tables";
  REQUIRE(run_budjam("analyse " + q(runs_dir) + " --out " + q(a) + " --main-L 6 --require moduli,dos").code == 0);
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(b) + " --main-L 6").code == 0);
  // the per-run records, the pooled survival curves and the spectra come back bit for bit
  for (const char* f : {"runs.csv", "targets.csv", "survival.csv", "trajectory.csv", "dos.csv"}) {
    INFO(f);
    CHECK(slurp(b / f) == slurp(a / f));
  }
  const auto ja = budjam::io::read_json(a / "analysis.json"), jb = budjam::io::read_json(b / "analysis.json");
  REQUIRE(ja["main"]["dos"].is_object());
  CHECK(without_run_only(jb) == without_run_only(ja));
  // what the tables cannot give is not written and is named, with what it needs
  for (const char* f : {"remaining.csv", "division_curve.csv", "growth_rates.csv"}) {
    INFO(f);
    CHECK(!fs::exists(b / f));
    CHECK(jb["unavailable"].contains(f));
  }
  CHECK(jb["unavailable"]["growth_rates.csv"].get<std::string>().find("growth factor of each cell") !=
        std::string::npos);
  CHECK(ja["unavailable"].empty());
  CHECK(jb["inputs"]["tables"] == a.string());
  // counts the tables cannot give are unknown, not 0
  for (const char* count : {"moduli_saddles", "moduli_contact_bounded"}) {
    INFO(count);
    CHECK(ja["inputs"][count] == 0);
    CHECK(jb["inputs"][count].is_null());
    CHECK(jb["unavailable"].contains(count));
  }

  // the paper's N_zero panel from dos.csv: Δφ-target packings with N_zero = N_u exactly, and the slope
  // of N_zero on N_u through the origin, Σ N_zero N_u / Σ N_u²
  std::istringstream dos(slurp(a / "dos.csv"));
  std::string line;
  std::getline(dos, line);
  std::vector<std::string> head;
  for (std::istringstream h(line); std::getline(h, line, ',');) head.push_back(line);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
  };
  std::size_t targets = 0, same = 0;
  double zu = 0, uu = 0;
  while (std::getline(dos, line)) {
    std::vector<std::string> f;
    for (std::istringstream r(line); std::getline(r, line, ',');) f.push_back(line);
    if (f.at(col("packing")).rfind("target_", 0) != 0) continue;
    const double nz = std::stod(f.at(col("N_zero"))), nu = std::stod(f.at(col("N_u")));
    ++targets;
    same += nz == nu;
    zu += nz * nu;
    uu += nu * nu;
  }
  const auto& panel = ja["main"]["dos"]["paper"]["N_zero_vs_N_u"];
  REQUIRE(targets > 0);
  CHECK(panel["packings"] == targets);
  CHECK(panel["N_zero_equals_N_u"] == same);
  CHECK(panel["slope_through_origin"].get<double>() == Approx(zu / uu));
}

TEST_CASE(
    "analyse --tables on tables of an earlier format names what they lack or define otherwise and leaves it empty",
    "[analyse]") {
  runs();
  const fs::path a = work_dir() / "old_runs", old = work_dir() / "old_tables", b = work_dir() / "old_out";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  fs::create_directories(old);
  fs::copy(a / "targets.csv", old / "targets.csv");
  fs::copy(a / "survival.csv", old / "survival.csv");
  // runs.csv of an earlier format: without the first state with none left and the first-jamming selection
  const std::vector<std::string> dropped{"dphi_2_none_left", "selection_divisions_first"};
  {
    std::istringstream in(slurp(a / "runs.csv"));
    std::ofstream out(old / "runs.csv");
    std::vector<std::size_t> drop;
    for (std::string line; std::getline(in, line);) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      if (!line.empty() && line.back() == ',') f.emplace_back();
      if (drop.empty()) {
        for (const auto& d : dropped)
          drop.push_back(static_cast<std::size_t>(std::find(f.begin(), f.end(), d) - f.begin()));
        std::sort(drop.rbegin(), drop.rend());
      }
      for (const std::size_t d : drop) {
        REQUIRE(d < f.size());
        f.erase(f.begin() + static_cast<long>(d));
      }
      for (std::size_t k = 0; k < f.size(); ++k) out << (k ? "," : "") << f[k];
      out << "\n";
    }
  }
  std::ofstream(old / "analysis.json") << "{\"format\": \"budjam-analysis\", \"version\": 1}\n";
  REQUIRE(run_budjam("analyse --tables " + q(old) + " --out " + q(b) + " --main-L 6").code == 0);
  const auto j = budjam::io::read_json(b / "analysis.json");
  // format 1 held χ̄ and λ̄_c as trapezoids in φ: not reported as today's plain means
  for (const char* c : {"chi_bar", "lambda_bar", "dphi_2_pred_area"}) {
    INFO(c);
    CHECK(j["unavailable"].contains(c));
    for (const auto& r : read_csv(b / "runs.csv")) CHECK(r.at(c).empty());
  }
  for (const auto& d : dropped) {  // both are computed from each run's log
    INFO(d);
    REQUIRE(j["unavailable"].contains(d));
    CHECK(j["unavailable"][d].get<std::string>().find("steps.csv") != std::string::npos);
    for (const auto& r : read_csv(b / "runs.csv")) CHECK(r.at(d).empty());
  }
  CHECK(j["unavailable"].contains("dos.csv"));
  for (const auto& g : j["groups"]) CHECK(g["dphi_2_none_left"]["n"] == 0);
}

TEST_CASE("analyse --tables reads a column under the name an earlier version gave it", "[analyse]") {
  runs();
  const fs::path a = work_dir() / "legacy_runs", b = work_dir() / "legacy_out";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  std::string t = slurp(a / "runs.csv");
  const auto at = t.find("dphi_2_none_left");
  REQUIRE(at < t.find('\n'));
  t.replace(at, std::string("dphi_2_none_left").size(), "dphi_2_paper");  // its name before it was renamed
  std::ofstream(a / "runs.csv") << t;
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(b) + " --main-L 6").code == 0);
  const auto j = budjam::io::read_json(b / "analysis.json");
  CHECK(!j["unavailable"].contains("dphi_2_none_left"));
  const auto before = read_csv(a / "runs.csv"), after = read_csv(b / "runs.csv");
  REQUIRE(before.size() == after.size());
  for (std::size_t k = 0; k < before.size(); ++k)
    CHECK(after[k].at("dphi_2_none_left") == before[k].at("dphi_2_paper"));
}

TEST_CASE("analyse takes the paper's u_J as its own analysis does: contact-free buds over N_nr, not lobes",
          "[analyse]") {
  const fs::path a = analysed("uJ_runs"), b = work_dir() / "uJ_out";
  // Lobes and buds told apart: every run's lobe fraction doubled in the tables.
  std::istringstream in(slurp(a / "runs.csv"));
  std::string line, edited;
  std::getline(in, line);
  edited = line + "\n";
  std::vector<std::string> header;
  for (std::stringstream h(line); std::getline(h, line, ',');) header.push_back(line);
  const auto lobes = static_cast<std::size_t>(std::find(header.begin(), header.end(), "u_J_lobes") - header.begin());
  REQUIRE(lobes < header.size());
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    for (std::stringstream r(line); std::getline(r, line, ',');) f.push_back(line);
    if (lobes < f.size() && !f[lobes].empty()) f[lobes] = std::to_string(2 * std::stod(f[lobes]) + 0.01);
    for (std::size_t k = 0; k < f.size(); ++k) edited += (k ? "," : "") + f[k];
    edited += "\n";
  }
  std::ofstream(a / "runs.csv") << edited;
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(b) + " --main-L 6").code == 0);
  const auto main = budjam::io::read_json(b / "analysis.json").at("main");
  REQUIRE(main.at("paper_P0").get<double>() == 1e-3);
  std::vector<double> buds;
  for (const auto& row : read_csv(b / "runs.csv"))
    if (row.at("P0") == "1e-3" || row.at("P0") == "0.001") buds.push_back(number(row.at("u_J")));
  REQUIRE(buds.size() == 2);
  CHECK(main.at("u_J_paper").at("mean").get<double>() == Approx((buds[0] + buds[1]) / 2).epsilon(1e-12));
}

TEST_CASE("analyse --tables refuses a seed listed twice in one group: exit 2, one line naming file and line",
          "[analyse]") {
  const fs::path a = analysed("twice_runs");
  std::string t = slurp(a / "runs.csv");
  const auto last = t.rfind('\n', t.size() - 2) + 1;  // the last run, listed again under another name
  const std::string row = t.substr(last);
  t += "elsewhere/again" + row.substr(row.find(','));
  std::ofstream(a / "runs.csv") << t;
  const std::string msg = refused_tables(a, "twice_out");
  CHECK(msg.find((a / "runs.csv").string() + ":5: run elsewhere/again repeats seed ") != std::string::npos);
  CHECK(msg.find("(one seed is one sample)") != std::string::npos);
}

TEST_CASE("analyse --tables refuses one run listed again under another seed: one jamming state to the last bit",
          "[analyse]") {
  const fs::path a = analysed("relabelled_runs");
  std::string t = slurp(a / "runs.csv");
  const auto last = t.rfind('\n', t.size() - 2) + 1;  // the last run, listed again as seed 99
  std::string row = t.substr(last);
  row = "elsewhere/again" + row.substr(row.find(','));
  std::size_t seed_at = 0;  // the fourth field
  for (int k = 0; k < 3; ++k) seed_at = row.find(',', seed_at) + 1;
  const std::string seed = row.substr(seed_at, row.find(',', seed_at) - seed_at);
  row.replace(seed_at, seed.size(), "99");
  std::ofstream(a / "runs.csv") << t + row;
  const std::string msg = refused_tables(a, "relabelled_out");
  CHECK(msg.find("run elsewhere/again (seed 99) has the jamming state of run ") != std::string::npos);
  CHECK(msg.find("(seed " + seed + ") to the last bit") != std::string::npos);
  CHECK(msg.find("one sample under two seeds") != std::string::npos);
}

TEST_CASE("analyse --tables refuses finished runs of one group with different target rows, without target_rows too",
          "[analyse]") {
  const fs::path a = analysed("target_sets_runs");
  // runs.csv as tables from before target_rows: its column dropped
  std::istringstream runs_in(slurp(a / "runs.csv"));
  std::string line, runs_csv;
  long column = -1;
  for (bool header = true; std::getline(runs_in, line); header = false) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!line.empty() && line.back() == ',') f.emplace_back();
    if (header) column = std::find(f.begin(), f.end(), "target_rows") - f.begin();
    REQUIRE(column < static_cast<long>(f.size()));
    f.erase(f.begin() + column);
    for (std::size_t k = 0; k < f.size(); ++k) runs_csv += (k ? "," : "") + f[k];
    runs_csv += "\n";
  }
  std::ofstream(a / "runs.csv") << runs_csv;
  // the last target row of one P0 = 1e-3 run goes missing
  const auto rows = read_csv(a / "targets.csv");
  std::string run;
  for (const auto& r : rows)
    if (r.at("P0") == "0.001" || r.at("P0") == "1e-3") run = r.at("run");
  REQUIRE(!run.empty());
  std::istringstream in(slurp(a / "targets.csv"));
  std::string kept, dropped;
  std::vector<std::string> lines;
  while (std::getline(in, line)) lines.push_back(line);
  for (std::size_t k = lines.size(); k-- > 0;)
    if (dropped.empty() && lines[k].rfind(run + ",", 0) == 0) dropped = lines[k], lines.erase(lines.begin() + k);
  for (const auto& l : lines) kept += l + "\n";
  std::ofstream(a / "targets.csv") << kept;
  const std::string msg = refused_tables(a, "target_sets_out");
  CHECK(msg.find(" have different target rows (2 and 1)") != std::string::npos);
  CHECK(msg.find("a finished run lands every target of its protocol") != std::string::npos);
}

TEST_CASE("analyse --tables names a table edited after its analysis in inputs.unchecked, and only such a table",
          "[analyse]") {
  const fs::path a = analysed("digest_runs");
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(work_dir() / "digest_same") + " --main-L 6").code == 0);
  const auto unchecked = [&](const fs::path& out) {
    return budjam::io::read_json(out / "analysis.json").at("inputs").at("unchecked").dump();
  };
  CHECK(unchecked(work_dir() / "digest_same").find("is not the table its analysis wrote") == std::string::npos);
  // one value changed (the first run's u_J, a digit appended): analysed as given, and named
  edit_rows(a / "runs.csv", [](int row, auto& f, const auto& header) {
    if (row == 1) f[column_of(header, "u_J")] += "7";
  });
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(work_dir() / "digest_edited") + " --main-L 6").code ==
          0);
  const std::string names = unchecked(work_dir() / "digest_edited");
  CHECK(names.find((a / "runs.csv").string() + " is not the table its analysis wrote") != std::string::npos);
  CHECK(names.find("targets.csv is not the table") == std::string::npos);
}

TEST_CASE("analyse keeps a statistic of phi_2 or of the none-left state only where every run of the group reached it",
          "[analyse]") {
  // A run that stopped before a state (its last target, a step limit) would have reached it late: a
  // mean over the runs that did reach it is biased, so the group's value is withheld, the runs that
  // stopped first counted.
  const fs::path a = analysed("censored_runs");
  auto group = [](const fs::path& out) {
    const auto j = budjam::io::read_json(out / "analysis.json");
    for (const auto& g : j.at("groups"))
      if (!g.at("P0").is_null()) return g;
    FAIL("no feedback group");
    return budjam::io::Json();
  };
  const auto all = group(a);
  REQUIRE(all.at("runs") == 2);
  REQUIRE(all.at("dphi_2").at("n") == 2);  // both runs reached φ_2
  CHECK(all.at("dphi_2").at("mean").is_number());
  CHECK(!all.at("dphi_2").contains("censored"));
  // the none-left state: a mean where both reached it, else none and the run that stopped first counted
  const auto& none_left = all.at("dphi_2_none_left");
  CHECK(none_left.at("n").get<int>() + none_left.value("censored", 0) == 2);
  CHECK(none_left.at("mean").is_number() == (none_left.at("n") == 2));
  // The second run stopped before either state: its φ_2 and none-left columns blank.
  edit_rows(a / "runs.csv", [](int, auto& f, const auto& header) {
    if (f[column_of(header, "P0")].empty() || f[column_of(header, "seed")] != "4") return;
    // what a run that ends before φ_2 leaves empty (its jamming and target columns kept)
    for (const char* c : {"phi_2",
                          "dphi_2",
                          "P_2",
                          "Z_2",
                          "dZ_2",
                          "u_2",
                          "N_div_2",
                          "chi_bar",
                          "lambda_bar",
                          "phi_2_none_left",
                          "dphi_2_none_left",
                          "P_2_none_left",
                          "N_div_2_none_left",
                          "a_eps",
                          "integral_S",
                          "dphi_2_pred_area",
                          "dphi_2_pred_diameter_sq",
                          "B_2",
                          "G_2",
                          "G_2_energy",
                          "G_min_2",
                          "G_2_none_left",
                          "phi_2_first",
                          "dphi_2_first",
                          "P_2_first",
                          "chi_bar_first",
                          "G_2_first"})
      f[column_of(header, c)].clear();
  });
  const fs::path out = work_dir() / "censored_out";
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(out) + " --main-L 6").code == 0);
  const auto cut = group(out);
  for (const char* key : {"dphi_2", "phi_2", "P_2", "G_2", "N_div_2_over_N_J", "dphi_2_none_left",
                          "N_div_2_over_N_J_paper", "dphi_2_paper", "lambda_bar_paper"}) {
    INFO(key);
    CHECK(!cut.at(key).contains("by_seed"));  // nor may a trend pair the runs that reached it
    CHECK(cut.at(key).at("censored").get<int>() >= 1);
    CHECK(cut.at(key).at("n").get<int>() + cut.at(key).at("censored").get<int>() == 2);
    CHECK(cut.at(key).value("mean", budjam::io::Json()).is_null());
    CHECK(cut.at(key).value("median", budjam::io::Json()).is_null());
  }
  CHECK(cut.at("u_J").at("n") == 2);  // the jamming point: every run reached it
  CHECK(cut.at("u_J").at("mean").is_number());
}

TEST_CASE("analyse --tables refuses a target of a run runs.csv does not list: exit 2, one line naming file and line",
          "[analyse]") {
  const fs::path a = analysed("orphan_runs");
  std::string t = slurp(a / "targets.csv");
  const auto row = t.find('\n') + 1;  // the first target's run
  t.replace(row, t.find(',', row) - row, "elsewhere/seed9");
  std::ofstream(a / "targets.csv") << t;
  const std::string msg = refused_tables(a, "orphan_out");
  CHECK(msg.find((a / "targets.csv").string() + ":2: run elsewhere/seed9 is not in runs.csv") != std::string::npos);
}

TEST_CASE("analyse --tables refuses a run whose target rows are missing: exit 2, one line naming the run",
          "[analyse]") {
  const fs::path a = analysed("missing_targets_runs");
  const auto rows = read_csv(a / "targets.csv");
  REQUIRE(!rows.empty());
  // every row of the first run: runs.csv counts them (target_rows)
  const std::string run = rows.front().at("run");
  const auto landed = std::count_if(rows.begin(), rows.end(), [&](const auto& r) { return r.at("run") == run; });
  std::istringstream in(slurp(a / "targets.csv"));
  std::string kept, line;
  for (bool header = true; std::getline(in, line); header = false)
    if (header || line.rfind(run + ",", 0) != 0) kept += line + "\n";
  std::ofstream(a / "targets.csv") << kept;
  const std::string msg = refused_tables(a, "missing_targets_out");
  CHECK(msg.find((a / "targets.csv").string() + ": run " + run + " has 0 target rows where runs.csv says it landed " +
                 std::to_string(landed)) != std::string::npos);
  CHECK(msg.find("rows are missing or added") != std::string::npos);
  // an empty count does not switch the check off
  std::string runs_csv = slurp(a / "runs.csv");
  const auto header_end = runs_csv.find('\n');
  const std::string header = runs_csv.substr(0, header_end);
  const auto column = std::count(header.begin(), header.begin() + header.find("target_rows"), ',');
  std::istringstream in_runs(runs_csv);
  std::string edited;
  for (bool first = true; std::getline(in_runs, line); first = false) {
    if (!first) {  // empty the field of every run
      std::size_t at = 0;
      for (long k = 0; k < column; ++k) at = line.find(',', at) + 1;
      line.erase(at, line.find(',', at) == std::string::npos ? std::string::npos : line.find(',', at) - at);
    }
    edited += line + "\n";
  }
  std::ofstream(a / "runs.csv") << edited;
  CHECK(refused_tables(a, "missing_targets_empty").find("target_rows") != std::string::npos);
}

TEST_CASE("analyse --tables counts the runs its analysis left out, as analysis.json names them", "[analyse]") {
  const fs::path a = analysed("left_out_runs");
  auto j = budjam::io::read_json(a / "analysis.json");
  const std::size_t used = j["inputs"]["used"].get<std::size_t>();
  j["inputs"]["never_jammed"] = budjam::io::Json::array({"runs/x/seed9 (step_limit)"});
  j["inputs"]["duplicates"] = budjam::io::Json::array({budjam::io::Json::array({"runs/x/seed1", "copy/seed1"})});
  std::ofstream(a / "analysis.json") << j.dump();
  const fs::path b = work_dir() / "left_out_out";
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(b) + " --main-L 6").code == 0);
  const auto jb = budjam::io::read_json(b / "analysis.json");
  CHECK(jb["inputs"]["never_jammed"] == j["inputs"]["never_jammed"]);
  CHECK(jb["inputs"]["duplicates"] == j["inputs"]["duplicates"]);
  CHECK(jb["inputs"]["used"] == used);
  CHECK(jb["inputs"]["runs"] == used + 2);  // the run that never jammed and the second copy
  CHECK_FALSE(jb["unavailable"].contains("never_jammed"));
  // a list of the wrong kind is refused, naming the file and the key
  j["inputs"]["never_jammed"] = "runs/x/seed9";
  std::ofstream(a / "analysis.json") << j.dump();
  CHECK(
      refused_tables(a, "left_out_bad").find((a / "analysis.json").string() + ": inputs.never_jammed is not a list") !=
      std::string::npos);
  // inputs of the wrong kind are refused; a list left out is named
  j["inputs"] = budjam::io::Json::array();
  std::ofstream(a / "analysis.json") << j.dump();
  CHECK(refused_tables(a, "left_out_array").find("inputs is not an object") != std::string::npos);
  j["inputs"] = budjam::io::Json::object({{"never_jammed", budjam::io::Json::array()}});
  std::ofstream(a / "analysis.json") << j.dump();
  const fs::path d = work_dir() / "left_out_no_copies";
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(d) + " --main-L 6").code == 0);
  CHECK(budjam::io::read_json(d / "analysis.json")["unavailable"].contains("duplicates"));
  // tables without analysis.json say that they cannot tell
  fs::remove(a / "analysis.json");
  const fs::path c = work_dir() / "left_out_none";
  REQUIRE(run_budjam("analyse --tables " + q(a) + " --out " + q(c) + " --main-L 6").code == 0);
  CHECK(budjam::io::read_json(c / "analysis.json")["unavailable"].contains("never_jammed"));
}

TEST_CASE(
    "analyse --tables refuses a survival curve whose steps do not add up to its buds: exit 2, one line naming "
    "file and line",
    "[analyse]") {
  runs();
  const fs::path a = work_dir() / "km_runs";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  const std::string good = slurp(a / "survival.csv");
  // (what is changed, the line named): the first row's count of buds one more; the second step's risk
  // set larger than the first's
  const auto field = [](const std::string& t, std::size_t line, std::size_t column) {
    std::size_t at = 0;
    for (std::size_t k = 1; k < line; ++k) at = t.find('\n', at) + 1;
    for (std::size_t k = 0; k < column; ++k) at = t.find(',', at) + 1;
    return std::pair{at, t.find_first_of(",\n", at) - at};
  };
  const std::size_t risk = [&] {  // the column of at_risk, by its name in the header
    const std::string header = good.substr(0, good.find('\n'));
    return static_cast<std::size_t>(std::count(header.begin(), header.begin() + header.find("at_risk"), ','));
  }();
  for (const std::size_t line : {2, 4}) {
    INFO("line " << line);
    std::string t = good;
    const auto [at, n] = field(t, line, risk);
    t.replace(at, n, std::to_string(std::stoul(t.substr(at, n)) + 1));
    std::ofstream(a / "survival.csv") << t;
    const fs::path err = work_dir() / "km.err";
    CHECK(run_budjam_redirected("analyse --tables " + q(a) + " --out " + q(work_dir() / "km_out") + " --main-L 6",
                                "/dev/null", err) == 2);
    const std::string msg = slurp(err);
    INFO(msg);
    CHECK(msg.find((a / "survival.csv").string() + ":" + std::to_string(line) + ": ") != std::string::npos);
    CHECK(std::count(msg.begin(), msg.end(), '\n') == 1);
    CHECK(!fs::exists(work_dir() / "km_out" / "analysis.json"));
  }
}

TEST_CASE("analyse takes run directories or --tables, not both and not neither: exit 2", "[analyse]") {
  runs();
  CHECK(run_budjam("analyse --out " + q(work_dir() / "none_out")).code == 2);
  CHECK(
      run_budjam("analyse " + all_runs() + "--tables " + q(work_dir()) + " --out " + q(work_dir() / "both_out")).code ==
      2);
}

// The columns of a hand-built runs.csv (the stored tables' layout).
namespace {
// A tables directory written by hand: `write` fills its runs.csv and targets.csv.
fs::path hand_tables(const std::string& name, const std::function<void(std::ostream&, std::ostream&)>& write) {
  const fs::path dir = work_dir() / name;
  fs::create_directories(dir);
  std::ofstream runs(dir / "runs.csv"), targets(dir / "targets.csv");
  write(runs, targets);
  return dir;
}
}  // namespace

constexpr const char* kRunsHeader =
    "run,L,P0,seed,status,jamming_state,phi_J,u_J,n_J,N_J,N_nr_J,phi_2,dphi_2,P_2,lambda_bar,lambda_bar_lobes,"
    "dphi_2_pred_area,dphi_2_pred_diameter_sq,dphi_2_pred_paper,G_2,phi_J_first,phi_2_first,dphi_2_first,P_2_first,"
    "G_2_first,selection_divisions_first\n";

TEST_CASE(
    "the paper's rules on hand-built tables: selection by the divisions of the target runs past φ_2, Eq. 14 as "
    "diameter², "
    "its φ_2 summary over the runs with a prediction, fences on G_2 alone, φ_J and φ_2 from the first jamming",
    "[analyse]") {
  // Six runs of one group. Targets at Δφ = 10⁻³ (before every φ_2) and 3·10⁻² (beyond it), with the
  // divisions after φ_J counted there; runs.csv's selection_divisions_first holds those of the target
  // runs past φ_2 (here the 3·10⁻² one). Run 6 has 2 divisions at the first target but 12 at the one
  // past φ_2: not admitted. Run 5's G_2 is an outlier of the
  // admitted G_2 (fences [0.8, 1.6] from 1.0, 1.1, 1.2, 1.3, 50): out of the G_2 statistics only. Run 5
  // has no prediction under the paper's rule (its Ŝ never fell to 1/tagged): out of the φ_2 summary.
  // Run 3 unjammed after a first jamming 0.004 below budjam's φ_J (its last): the paper's columns
  // (*_first) measure from there, budjam's from its own φ_J, with another G_2 (as if another state).
  const fs::path dir = work_dir() / "hand_tables", out = work_dir() / "hand_tables_out";
  fs::create_directories(dir);
  const std::vector<double> dphi_2{0.010, 0.012, 0.014, 0.016, 0.018, 0.020};
  const std::vector<double> dphi_2_budjam{0.010, 0.012, 0.010, 0.016, 0.018, 0.020};
  const std::vector<double> G_2{1.0, 1.1, 1.2, 1.3, 50, 1.15}, P_2{0.01, 0.011, 0.012, 0.013, 0.014, 0.015};
  const std::vector<double> div_far{3, 4, 5, 6, 10, 12};
  {
    std::ofstream r(dir / "runs.csv");
    r << kRunsHeader;
    std::ofstream t(dir / "targets.csv");
    t << "run,L,P0,seed,dphi,phi,N_div,below_phi2\n";
    for (int k = 0; k < 6; ++k) {
      const std::string run = "hand/seed" + std::to_string(k + 1);
      const double phi_J = 0.84, phi_J_first = k == 2 ? 0.836 : phi_J, phi_2 = phi_J_first + dphi_2[k];
      r << run << ",15,0.001," << k + 1 << ",finished," << k << "," << phi_J << ",0.2,0.76,172,170," << phi_2 << ","
        << dphi_2_budjam[k] << "," << P_2[k] << "," << 0.5 + 0.01 * k << "," << 0.6 + 0.01 * k << ","
        << 0.75 * dphi_2_budjam[k] << "," << dphi_2[k] + 0.002 * k << ","
        << (k == 4 ? std::string() : std::to_string(dphi_2[k] + 0.001 * k)) << "," << (k == 2 ? 2.0 : G_2[k]) << ","
        << phi_J_first << "," << phi_2 << "," << dphi_2[k] << "," << P_2[k] << "," << G_2[k] << "," << div_far[k]
        << "\n";
      t << run << ",15,0.001," << k + 1 << ",0.001," << phi_J + 0.001 << ",2,true\n";
      t << run << ",15,0.001," << k + 1 << ",0.03," << phi_J + 0.03 << "," << div_far[k] << ",false\n";
    }
  }
  REQUIRE(run_budjam("analyse --tables " + q(dir) + " --out " + q(out) + " --main-L 15").code == 0);
  const auto j = budjam::io::read_json(out / "analysis.json");
  REQUIRE(j["groups"].size() == 1);
  const auto& g = j["groups"][0];
  // admitted: runs 1–5; with a prediction: runs 1–4
  CHECK(g["dphi_2_paper"]["admitted"] == 5);
  CHECK(g["dphi_2_paper"]["predicted"] == 4);
  CHECK(g["dphi_2_paper"]["runs"] == 6);
  CHECK(g["dphi_2_paper"]["n"] == 4);
  CHECK(g["dphi_2_paper"]["mean"].get<double>() == Approx(0.013));
  CHECK(g["P_2_over_Pmax_paper"]["mean"].get<double>() == Approx(0.115));
  // λ̄_c: the paper's with u the contact-free lobes, over the admitted runs; budjam's with the buds, every run
  CHECK(g["lambda_bar_paper"]["mean"].get<double>() == Approx(0.62));
  CHECK(g["lambda_bar"]["mean"].get<double>() == Approx(0.525));
  // Eq. 14 under the paper's a_ε, paired with the same runs: prediction − simulation = 0.001 k, k = 0…3
  CHECK(g["dphi_2_pred_paper"]["mean"].get<double>() == Approx(0.0145));
  CHECK(g["dphi_2_pred_minus_sim_paper"]["mean"].get<double>() == Approx(0.0015));
  // budjam's column: every run, a as true area
  CHECK(g["dphi_2"]["n"] == 6);
  CHECK(g["dphi_2"]["mean"].get<double>() == Approx(0.086 / 6));
  CHECK(g["dphi_2_pred_minus_sim_area"]["mean"].get<double>() == Approx(-0.25 * 0.086 / 6));
  CHECK(g["G_2"]["median"].get<double>() == Approx(1.225));  // budjam's G_2: 1.0, 1.1, 1.15, 1.3, 2.0, 50
  // G_2: the outlier is fenced out; four values left, median of 1.0, 1.1, 1.2, 1.3 over P_max = 0.1
  CHECK(g["G_2_over_Pmax_paper"]["n"] == 4);
  CHECK(g["G_2_over_Pmax_paper"]["median"].get<double>() == Approx(11.5));
  // fewer than five values: no error bar
  CHECK(g["G_2_over_Pmax_paper"]["se"].is_null());
  CHECK(g["G_2_over_P_2_paper"]["n"] == 4);
  // the values the trends pair by seed: the predicted runs' (seeds 1–4), the kept runs' for G_2/P_2
  const auto& by_seed = g["dphi_2_paper"]["by_seed"];
  REQUIRE(by_seed.size() == 4);
  for (int k = 0; k < 4; ++k) CHECK(by_seed[std::to_string(k + 1)].get<double>() == Approx(dphi_2[k]));
  CHECK_FALSE(by_seed.contains("5"));
  CHECK_FALSE(by_seed.contains("6"));
  const auto& ratio = g["G_2_over_P_2_paper"]["by_seed"];
  CHECK(ratio.size() == 4);
  CHECK_FALSE(ratio.contains("5"));
  CHECK(ratio["2"].get<double>() == Approx(G_2[1] / P_2[1]));
}

TEST_CASE(
    "the ΔZ identity's error adds the no-feedback branch's SE to that over runs; a missing value in the "
    "branch is left out of it",
    "[analyse]") {
  // No feedback: 7 runs jammed at P_J = 0, ΔZ_J = 0; at Δφ = 0.01 six give P = 0.01 and ΔZ = 0.10 …
  // 0.15, the seventh no P. The branch there is ΔZ_0 = 0.125 ± SE(0.10 … 0.15). Feedback (P0 = 0.01):
  // 5 runs at the same P and u = u_J with ΔZ = 0.125 + 0.002 k, residuals 0.002 k (k = 0 … 4). Their
  // 34 buds tagged at jamming are 0.2 of the target's 170 non-rattlers, and one free mother makes the
  // contact-free lobes u = 0.2 + 1/170.
  const fs::path out = work_dir() / "branch_tables_out";
  const fs::path dir = hand_tables("branch_tables", [](std::ostream& r, std::ostream& t) {
    r << "run,L,P0,seed,status,jamming_state,phi_J,u_J,n_J,N_J,N_nr_J,P_J,dZ_J,tagged_J\n";
    t << "run,L,P0,seed,dphi,phi,N_div,below_phi2,P,dZ,u,u_lobes,N_nr\n";
    for (int k = 0; k < 7; ++k) {
      const std::string run = "branch/none/seed" + std::to_string(100 + k);
      r << run << ",15,," << 100 + k << ",finished," << k << ",0.84,0.2,0.76,172,170,0,0,34\n";
      t << run << ",15,," << 100 + k << ",0.01,0.85,0,true," << (k < 6 ? "0.01" : "") << "," << 0.10 + 0.01 * k
        << ",0.2,0.2,170\n";
    }
    for (int k = 0; k < 5; ++k) {
      const std::string run = "branch/fed/seed" + std::to_string(200 + k);
      r << run << ",15,0.01," << 200 + k << ",finished," << 7 + k << ",0.84,0.2,0.76,172,170,0,0,34\n";
      t << run << ",15,0.01," << 200 + k << ",0.01,0.85,0,true,0.01," << 0.125 + 0.002 * k << ",0.2," << 0.2 + 1.0 / 170
        << ",170\n";
    }
  });
  const auto res = run_budjam("analyse --tables " + q(dir) + " --out " + q(out) + " --main-L 15");
  REQUIRE(res.code == 0);
  const auto j = budjam::io::read_json(out / "analysis.json");
  const auto& per = j["main"]["dZ_identity"]["per_P0_unrepopulated_by_run"];
  REQUIRE(per.size() == 1);
  const auto& x = per[0];
  const std::vector<double> branch{0.10, 0.11, 0.12, 0.13, 0.14, 0.15}, runs{0, 0.002, 0.004, 0.006, 0.008};
  CHECK(x["n"] == 5);
  CHECK(x["mean"].get<double>() == Approx(0.004).margin(1e-12));
  CHECK(x["se_runs"].get<double>() == Approx(budjam::standard_error(runs)));
  CHECK(x["se_branch"].get<double>() == Approx(budjam::standard_error(branch)));
  CHECK(x["se"].get<double>() == Approx(std::hypot(budjam::standard_error(runs), budjam::standard_error(branch))));
  // the paper's figure, with the paper's ingredients (u the contact-free lobes, u_J the tagged buds over
  // the target's N_nr): one (P0, Δφ) cell, ⟨ΔZ⟩ = 0.129 ± 0.0014 against ⟨prediction⟩ = 0.125 − 2/170 ± 0:
  // more than 2 combined SE apart
  const auto& cells = j["main"]["dZ_identity"]["paper_cells"];
  REQUIRE(cells["cells"].size() == 1);
  CHECK(cells["cells"][0]["measured"]["mean"].get<double>() == Approx(0.129));
  CHECK(cells["cells"][0]["predicted"]["mean"].get<double>() == Approx(0.125 - 2.0 / 170));
  CHECK(cells["cells_tested"] == 1);
  CHECK(cells["cells_apart_2se"] == 1);
}

TEST_CASE(
    "analyse writes no SE, bootstrap SE or interval from fewer than five samples: B_grow test per group, "
    "ΔZ identity per P0, the P† fit",
    "[analyse]") {
  // Three feedback groups of two runs (seeds of their own) with two targets each: 2 seeds and 4 targets
  // per group (no error bar), 6 seeds pooled (an error bar), and a P† fit over 3 values of P0 (no
  // error bar).
  const fs::path out = work_dir() / "few_tables_out";
  const fs::path dir = hand_tables("few_tables", [](std::ostream& r, std::ostream& t) {
    r << kRunsHeader;
    // the paper's λ_c from u_lobes and χ_c: (0.8 · 0.25) / (0.2 + 0.8 · 0.25) = 0.5, as budjam's lambda_c
    t << "run,L,P0,seed,dphi,phi,N_div,below_phi2,P,dZ,dZ_pred,lambda_c,B_grow,B,u_lobes,chi_c\n";
    const char* P0s[] = {"0.01", "0.001", "0.0001"};
    int k = 0;
    for (int p = 0; p < 3; ++p)
      for (int s = 1; s <= 2; ++s, ++k) {
        const std::string run = "few/P0_" + std::string(P0s[p]) + "/seed" + std::to_string(s);
        const double P_2 = 0.01 / (p + 1) + 0.001 * s;
        r << run << ",15," << P0s[p] << "," << k + 1 << ",finished," << k << ",0.84,0.2,0.76,172,170,0.85,0.01," << P_2
          << ",0.5,0.5,0.01,0.011,0.011,1.0,0.84,0.85,0.01," << P_2 << ",1.0,2\n";
        for (int d = 0; d < 2; ++d)
          t << run << ",15," << P0s[p] << "," << k + 1 << "," << (d ? 0.03 : 0.001) << "," << (d ? 0.87 : 0.841)
            << ",2," << (d ? "false" : "true") << ",0.01," << 0.01 * (k + d) << "," << 0.001 * d << ",0.5,"
            << 1.0 + 0.1 * (k + d) << ",2.0,0.2,0.25\n";
      }
  });
  REQUIRE(run_budjam("analyse --tables " + q(dir) + " --out " + q(out) + " --main-L 15").code == 0);
  const auto j = budjam::io::read_json(out / "analysis.json");
  REQUIRE(j["groups"].size() == 3);
  for (const auto& g : j["groups"]) {
    const auto& b = g["B_grow_over_lambda_B_log10"];
    CHECK(b["n"] == 2);
    CHECK(b["targets"] == 4);
    CHECK(b["median"].is_number());
    CHECK(b["se"].is_null());
    CHECK(b["ci95"][0].is_null());
    CHECK(b["ci95"][1].is_null());
  }
  const auto& pooled = j["main"]["B_grow_over_lambda_B_log10"];
  CHECK(pooled["n"] == 6);
  CHECK(pooled["targets"] == 12);
  CHECK(pooled["se"].is_number());
  // the paper's figure: a cell per (P0, Δφ), weak to strong feedback, Δφ increasing; two runs a cell
  // give no SE, so no cell is tested
  const auto& cells = pooled["paper_cells"];
  REQUIRE(cells["cells"].size() == 6);
  CHECK(cells["cells"][0]["P0"].get<double>() == Approx(0.01));
  CHECK(cells["cells"][0]["dphi"].get<double>() == Approx(0.001));
  CHECK(cells["cells"][1]["dphi"].get<double>() == Approx(0.03));
  CHECK(cells["cells"][5]["P0"].get<double>() == Approx(0.0001));
  CHECK(cells["cells"][0]["measured"]["n"] == 2);
  CHECK(cells["cells_tested"] == 0);
  for (const auto& x : j["main"]["dZ_identity"]["per_P0_unrepopulated_by_run"]) {
    CHECK(x["n"] == 2);
    CHECK(x["se"].is_null());
  }
  CHECK(j["main"]["P_dagger_points"] == 3);
  CHECK(j["main"]["P_dagger"].is_number());
  CHECK(j["main"]["P_dagger_se"].is_null());
}

namespace {
// Lines on stderr that say what tables of an earlier format left unchecked, but for the digests
// hand-built tables have no analysis.json to hold.
constexpr const char* kNoDigests = "whether a table was edited after its analysis cannot be checked";
std::size_t unchecked_notices(const std::string& err) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = err.find("cannot be checked", at)) != std::string::npos; ++at) ++n;
  for (std::size_t at = 0; (at = err.find(kNoDigests, at)) != std::string::npos; ++at) --n;
  return n;
}

// runs.csv of hand-built tables: six runs of L = 15 in two groups (P0 = 0.01 and 0.001, three seeds
// each), each row's protocol and cells from `protocol(k)` and `cells(k)` (no columns where null), and
// one jamming model where the protocol is given.
fs::path protocol_tables(const std::string& name, std::string (*protocol)(int), std::string (*cells)(int)) {
  return hand_tables(name, [&](std::ostream& r, std::ostream& t) {
    r << "run,L,P0,seed,status,jamming_state" << (protocol ? ",protocol,jamming_model" : "") << (cells ? ",cells" : "")
      << ",phi_J,u_J,n_J,N_J,N_nr_J,target_rows\n";
    t << "run,L,P0,seed,dphi,below_phi2\n";
    for (int k = 0; k < 6; ++k) {
      r << name << "/seed" << k + 1 << ",15," << (k < 3 ? "0.01" : "0.001") << "," << k + 1 << ",finished," << k;
      if (protocol) r << "," << protocol(k) << ",45b0cfaa13de4058";
      if (cells) r << "," << cells(k);
      r << ",0.84,0.2,0.76,172,170,0\n";
    }
  });
}
std::string one_protocol(int k) { return k < 3 ? "0123456789abcdef" : "00000000000000ff"; }  // one per group
std::string one_cells(int) { return "b1779c6cab5be437"; }
}  // namespace

TEST_CASE(
    "analyse --tables pools runs of one L and P0 only under one protocol and all under one set of cells: "
    "runs.csv's protocol and cells columns",
    "[analyse]") {
  const auto analyse = [](const fs::path& dir) {
    return run_budjam("analyse --tables " + q(dir) + " --out " + q(fs::path(dir) += "_out") + " --main-L 15");
  };
  // one protocol per group (the groups differ: P0 is part of it), one set of cells: analysed, nothing unchecked
  {
    const auto res = analyse(protocol_tables("protocols_same", one_protocol, one_cells));
    INFO(res.err);
    CHECK(res.code == 0);
    CHECK(unchecked_notices(res.err) == 0);
  }
  // (name, protocol, cells, what the one line says)
  using Column = std::string (*)(int);
  const std::vector<std::tuple<std::string, Column, Column, std::string>> refused{
      {"protocols_two", [](int k) { return k == 2 ? std::string("fedcba9876543210") : one_protocol(k); }, one_cells,
       "runs.csv:4: runs protocols_two/seed1 and protocols_two/seed3 differ in protocol (0123456789abcdef, "
       "fedcba9876543210): the runs of one L = 15, P0 = 0.01 are samples of one protocol"},
      {"cells_two", one_protocol, [](int k) { return k == 4 ? std::string("0000000000000001") : one_cells(k); },
       "runs.csv:6: runs cells_two/seed1 and cells_two/seed5 differ in cells"},
      {"protocols_some_empty", [](int k) { return k == 3 ? std::string() : one_protocol(k); }, one_cells,
       "runs.csv:5: run protocols_some_empty/seed4 has no protocol, but run protocols_some_empty/seed1 (line 2) has "
       "one"}};
  for (const auto& [name, protocol, cells, message] : refused) {
    INFO(name);
    const auto res = analyse(protocol_tables(name, protocol, cells));
    INFO(res.err);
    CHECK(res.code == 2);
    CHECK(res.err.find(message) != std::string::npos);
    CHECK(std::count(res.err.begin(), res.err.end(), '\n') == 1);
    CHECK(!fs::exists(work_dir() / (name + "_out") / "analysis.json"));
  }
  // tables from before the columns: analysed, with one line saying which file leaves the protocol
  // unchecked, and one the jamming model
  const fs::path legacy = protocol_tables("protocols_legacy", nullptr, nullptr);
  const auto res = analyse(legacy);
  INFO(res.err);
  CHECK(res.code == 0);
  CHECK(unchecked_notices(res.err) == 2);
  CHECK(res.err.find((legacy / "runs.csv").string() + " has no protocol or cells column") != std::string::npos);
  CHECK(res.err.find((legacy / "runs.csv").string() + " has no jamming_model column") != std::string::npos);
  const auto j = budjam::io::read_json(fs::path(legacy) += "_out/analysis.json");
  CHECK(std::count_if(j["inputs"]["unchecked"].begin(), j["inputs"]["unchecked"].end(), [](const auto& x) {
          return x.template get<std::string>().find(kNoDigests) == std::string::npos;
        }) == 2);
}

TEST_CASE(
    "analyse writes each run's protocol and cells hashes to runs.csv and the runs of each pooled survival curve, "
    "and its own tables pass their checks",
    "[analyse]") {
  runs();
  const fs::path a = work_dir() / "hashes", b = work_dir() / "hashes_again";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  const auto rows = read_csv(a / "runs.csv");
  REQUIRE(rows.size() == 3);
  std::map<std::string, std::set<std::string>> protocols;  // P0 → protocols
  std::set<std::string> cells;
  for (const auto& r : rows) {
    for (const char* c : {"protocol", "cells"}) {
      INFO(c);
      CHECK(r.at(c).size() == 16);
      CHECK(r.at(c).find_first_not_of("0123456789abcdef") == std::string::npos);
    }
    protocols[r.at("P0")].insert(r.at("protocol"));
    cells.insert(r.at("cells"));
    CHECK(number(r.at("bud_records")) > 0);  // every fixture run records bud events
  }
  CHECK(protocols.at("0.001").size() == 1);                            // seeds 3 and 4: one protocol
  CHECK(*protocols.at("0.001").begin() != *protocols.at("").begin());  // P0 is part of it
  CHECK(cells.size() == 1);
  for (const auto& s : read_csv(a / "survival.csv")) CHECK(s.at("runs") == (s.at("P0").empty() ? "1" : "2"));
  const auto res = run_budjam("analyse --tables " + q(a) + " --out " + q(b) + " --main-L 6");
  INFO(res.err);
  CHECK(res.code == 0);
  CHECK(unchecked_notices(res.err) == 0);
  CHECK(slurp(b / "survival.csv") == slurp(a / "survival.csv"));
}

TEST_CASE(
    "analyse --tables refuses a survival.csv whose curves do not pool the runs of runs.csv: exit 2, one line naming "
    "survival.csv and the group",
    "[analyse]") {
  runs();
  const fs::path a = work_dir() / "pooled";
  REQUIRE(run_budjam("analyse " + all_runs() + "--out " + q(a) + " --main-L 6").code == 0);
  // a copy of the tables with `edit` applied to its runs.csv, targets.csv or survival.csv (by line)
  const auto edited = [&](const std::string& name, const std::string& file,
                          const std::function<bool(std::string&)>& keep) {
    const fs::path dir = work_dir() / name;
    fs::remove_all(dir);
    fs::copy(a, dir, fs::copy_options::recursive);
    std::istringstream in(slurp(dir / file));
    std::string text;
    for (std::string line; std::getline(in, line);)
      if (keep(line)) text += line + "\n";
    std::ofstream(dir / file) << text;
    return dir;
  };
  const std::string seed4 = runs()[2].string();
  const auto analyse = [](const fs::path& dir) {
    return run_budjam("analyse --tables " + q(dir) + " --out " + q(fs::path(dir) += "_out") + " --main-L 6");
  };
  {  // runs.csv cut to one of the two runs of P0 = 1e-3 (and targets.csv with it), survival.csv kept whole
    const fs::path dir = edited("pooled_cut", "runs.csv", [&](std::string& l) { return l.rfind(seed4, 0) != 0; });
    std::string t;
    std::istringstream in(slurp(dir / "targets.csv"));
    for (std::string line; std::getline(in, line);)
      if (line.rfind(seed4, 0) != 0) t += line + "\n";
    std::ofstream(dir / "targets.csv") << t;
    const auto res = analyse(dir);
    INFO(res.err);
    CHECK(res.code == 2);
    CHECK(res.err.find((dir / "survival.csv").string() + ":") != std::string::npos);
    CHECK(res.err.find("group L = 6, P0 = 0.001 pools 2 runs, but runs.csv has 1") != std::string::npos);
    CHECK(std::count(res.err.begin(), res.err.end(), '\n') == 1);
  }
  {  // the curve of the no-feedback group left out
    const fs::path dir =
        edited("pooled_missing", "survival.csv", [](std::string& l) { return l.rfind("6,,", 0) != 0; });
    const auto res = analyse(dir);
    INFO(res.err);
    CHECK(res.code == 2);
    CHECK(res.err.find((dir / "survival.csv").string() + ": no curve of group L = 6, P0 = none, whose 1 runs") !=
          std::string::npos);
    CHECK(std::count(res.err.begin(), res.err.end(), '\n') == 1);
  }
  {  // one group's runs emptied: rows of two formats
    const fs::path dir = edited("pooled_mixed", "survival.csv", [](std::string& l) {
      if (l.rfind("6,,", 0) == 0) l.erase(l.rfind(',') + 1);
      return true;
    });
    const auto res = analyse(dir);
    INFO(res.err);
    CHECK(res.code == 2);
    CHECK(res.err.find((dir / "survival.csv").string() + ":") != std::string::npos);
    CHECK(res.err.find("rows of tables of different formats") != std::string::npos);
  }
  {  // survival.csv from before its runs column: analysed, one line says it cannot be checked
    const fs::path dir = edited("pooled_legacy", "survival.csv", [](std::string& l) {
      l.erase(l.rfind(','));
      return true;
    });
    const auto res = analyse(dir);
    INFO(res.err);
    CHECK(res.code == 0);
    CHECK(unchecked_notices(res.err) == 1);
    CHECK(res.err.find((dir / "survival.csv").string() + " has no runs column") != std::string::npos);
  }
}

namespace {
// Hand-built tables of L = 15 with one spectrum per Δφ-target packing: `seeds` runs (one a seed) of two
// packings each, every packing written `copies` times. N_zero on N_u is not exactly proportional.
fs::path spectrum_tables(const std::string& name, int seeds, int copies) {
  const fs::path dir = hand_tables(name, [&](std::ostream& r, std::ostream& t) {
    r << "run,L,P0,seed,status,jamming_state,phi_J,u_J,n_J,N_J,N_nr_J\n";
    t << "run,L,P0,seed,dphi,below_phi2\n";
    for (int s = 1; s <= seeds; ++s)
      r << name << "/seed" << s << ",15,0.01," << s << ",finished," << s << ",0.84,0.2,0.76,172,170\n";
  });
  std::ofstream d(dir / "dos.csv");
  d << "run,packing,dphi,omega_star,dZ,Z_minus_6,N_c,N_nr,N_zero,N_u\n";
  for (int s = 1; s <= seeds; ++s)
    for (int p = 0; p < 2; ++p)
      for (int c = 0; c < copies; ++c) {
        const int N_u = 10 + 3 * s + p, N_zero = N_u + (s % 3 == 0 ? 2 : 0) - p, N_c = 560 + 5 * s + 7 * p;
        d << name << "/seed" << s << ",target_" << p * copies + c << ",0.01," << 0.01 * (s + p) << ","
          << (N_c - (600 - 2 * N_u - 2)) / 100.0 << "," << (N_c - 600) / 100.0 << "," << N_c << ",100," << N_zero << ","
          << N_u << "\n";
      }
  return dir;
}

budjam::io::Json spectrum_of(const fs::path& dir) {
  const fs::path out = fs::path(dir) += "_out";
  REQUIRE(run_budjam("analyse --tables " + q(dir) + " --out " + q(out) + " --main-L 15").code == 0);
  return budjam::io::read_json(out / "analysis.json")["main"]["dos"];
}
}  // namespace

TEST_CASE(
    "the SEs of the spectrum's slopes are bootstraps over seeds: none from fewer than five seeds, and copies of a "
    "seed's packings do not shrink them",
    "[analyse]") {
  const auto few = spectrum_of(spectrum_tables("spectrum_4_seeds", 4, 1));
  REQUIRE(few.is_object());
  CHECK(few["paper"]["N_zero_vs_N_u"]["seeds"] == 4);
  CHECK(few["paper"]["N_zero_vs_N_u"]["slope_through_origin"].is_number());
  CHECK(few["paper"]["N_zero_vs_N_u"]["slope_se"].is_null());
  CHECK(few["paper"]["through_origin_dZ"]["slope_se"].is_null());
  CHECK(few["paper"]["through_origin_Z_minus_6"]["slope_se"].is_null());
  CHECK(few["omega_star_vs_dZ"]["slope_se"].is_null());

  const auto once = spectrum_of(spectrum_tables("spectrum_6_seeds", 6, 1));
  const auto twice = spectrum_of(spectrum_tables("spectrum_6_seeds_twice", 6, 2));
  const auto& nz = once["paper"]["N_zero_vs_N_u"];
  REQUIRE(nz["slope_se"].is_number());
  // the seed-clustered bootstrap with analyse's default options (2000 resamples, seed 1)
  std::vector<double> N_u, N_zero, index;
  std::vector<std::uint64_t> seed;
  for (int s = 1; s <= 6; ++s)
    for (int p = 0; p < 2; ++p) {
      index.push_back(static_cast<double>(N_u.size()));
      N_u.push_back(10 + 3 * s + p);
      N_zero.push_back(10 + 3 * s + p + (s % 3 == 0 ? 2 : 0) - p);
      seed.push_back(static_cast<std::uint64_t>(s));
    }
  const auto by_seed = budjam::cluster_bootstrap(index, seed, [&](std::span<const double> drawn) {
    double xy = 0, xx = 0;
    for (double i : drawn) {
      xy += N_u[static_cast<std::size_t>(i)] * N_zero[static_cast<std::size_t>(i)];
      xx += N_u[static_cast<std::size_t>(i)] * N_u[static_cast<std::size_t>(i)];
    }
    return xy / xx;
  });
  CHECK(nz["slope_se"].get<double>() == Approx(by_seed.se).epsilon(1e-9));
  // every packing twice: twice the packings, the same seeds, the same slopes and SEs (an SE over packings
  // would shrink by √2)
  CHECK(twice["paper"]["N_zero_vs_N_u"]["packings"] == 2 * nz["packings"].get<int>());
  for (const char* fit : {"N_zero_vs_N_u", "through_origin_dZ", "through_origin_Z_minus_6"}) {
    INFO(fit);
    const auto &a = once["paper"][fit], &b = twice["paper"][fit];
    REQUIRE(a["slope_se"].is_number());
    CHECK(b["slope_se"].get<double>() == Approx(a["slope_se"].get<double>()).epsilon(1e-9));
  }
  REQUIRE(once["omega_star_vs_dZ"]["slope_se"].is_number());
  CHECK(twice["omega_star_vs_dZ"]["slope_se"].get<double>() ==
        Approx(once["omega_star_vs_dZ"]["slope_se"].get<double>()).epsilon(1e-9));
}
