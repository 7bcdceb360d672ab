// The output convention of the per-packing commands (docs/files.md, "Outputs of the commands") and
// the column reference (docs/columns.md): every column budjam writes is documented, and every
// documented column is written.
#include "io/json.hpp"
#include "io/run_data.hpp"

#include "budjam/growth_driver.hpp"

#include <catch2/catch.hpp>
#include "files_doc.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace fs = std::filesystem;

namespace {

using budjam::testing::csv_header;
using budjam::testing::documented_columns;
using budjam::testing::run_budjam;
using budjam::testing::shell_quoted;
using budjam::testing::slurp;
using budjam::testing::source_file;
using budjam::testing::work_dir;

// A demo run without feedback, with every observer that writes a table: the logs, moduli,
// spectra, rigidity events, trials.
const fs::path& demo_run() {
  static const fs::path dir = [] {
    const fs::path d = work_dir() / "run";
    const auto r = run_budjam("grow " + shell_quoted(source_file("data/scenes/demo.toml")) + " --quiet --out " +
                              shell_quoted(d) + " --set growth.P0=none" +
                              " --set 'jamming.targets=[1e-3]' --set jamming.continue_to_phi2=true"
                              " --set observe.rigidity_events=true --set observe.moduli.at_jamming=true"
                              " --set observe.moduli.at_targets=true --set observe.dos.at_targets=true"
                              " --set observe.trials=true");
    REQUIRE(r.code == 0);
    return d;
  }();
  return dir;
}

std::string one_line(const std::string& s) {
  return s.empty() || s.back() != '\n' ? std::string("(not one line)") : s.substr(0, s.find('\n'));
}

}  // namespace

TEST_CASE("every column of every table budjam writes is in docs/columns.md, and every column listed there is written",
          "[cli]") {
  const fs::path run = demo_run(), out = work_dir() / "outputs";
  REQUIRE(
      run_budjam("dos " + shell_quoted(run / "packings/phi2.pack") + " --quiet --out " + shell_quoted(out / "phi2.dos"))
          .code == 0);
  REQUIRE(run_budjam("survival " + shell_quoted(run) + " --quiet --out " + shell_quoted(out / "survival")).code == 0);
  REQUIRE(run_budjam("rigidity " + shell_quoted(run / "packings/phi2.pack") + " --quiet --out " +
                     shell_quoted(out / "rigidity"))
              .code == 0);
  REQUIRE(run_budjam("analyse " + shell_quoted(run) + " --out " + shell_quoted(out / "tables") + " --main-L 8").code ==
          0);
  const std::map<std::string, fs::path> tables{{"`RUN/steps.csv`", run / "steps.csv"},
                                               {"`RUN/divisions.csv`", run / "divisions.csv"},
                                               {"`RUN/bud_events.csv`", run / "bud_events.csv"},
                                               {"`RUN/moduli.csv`", run / "moduli.csv"},
                                               {"`RUN/dos.csv`", run / "dos.csv"},
                                               {"`RUN/rigidity_events.csv`", run / "rigidity_events.csv"},
                                               {"`RUN/trials.csv`", run / "trials.csv"},
                                               {"`RUN/packings/<name>.dos.csv`", run / "packings/target_0.dos.csv"},
                                               {"`BASE.csv` of `budjam dos`", out / "phi2.dos.csv"},
                                               {"`BASE.csv` of `budjam survival`", out / "survival.csv"},
                                               {"`BASE.csv` of `budjam rigidity`", out / "rigidity.csv"},
                                               {"`TABLES/runs.csv`", out / "tables/runs.csv"},
                                               {"`TABLES/targets.csv`", out / "tables/targets.csv"},
                                               {"`TABLES/survival.csv`", out / "tables/survival.csv"},
                                               {"`TABLES/remaining.csv`", out / "tables/remaining.csv"},
                                               {"`TABLES/division_curve.csv`", out / "tables/division_curve.csv"},
                                               {"`TABLES/growth_rates.csv`", out / "tables/growth_rates.csv"},
                                               {"`TABLES/trajectory.csv`", out / "tables/trajectory.csv"},
                                               {"`TABLES/dos.csv`", out / "tables/dos.csv"}};
  for (const auto& [key, file] : tables) {
    INFO(key << " <- " << file);
    REQUIRE(fs::exists(file));
    std::vector<std::string> written = csv_header(file), documented = documented_columns(key);
    REQUIRE(!documented.empty());
    CHECK(written == documented);  // same names, same order
  }
  // No feedback is an empty P0 field, not "none".
  CHECK(slurp(out / "tables/runs.csv").find(",none,") == std::string::npos);
  CHECK(slurp(out / "tables/runs.csv").find(",8,,1,") != std::string::npos);
}

TEST_CASE("every key of summary.json and timing.json is in docs/columns.md, and every key listed there is written",
          "[cli]") {
  const budjam::io::Json summary = budjam::io::read_json(demo_run() / "summary.json");
  std::vector<std::string> keys;
  for (const auto& [key, value] : summary.items()) {
    keys.push_back(key);
    const std::string prefix = key + (value.is_array() ? "[]." : ".");
    const budjam::io::Json* entry = key == "targets" ? &value.at(0) : key == "final" ? &value : nullptr;
    if (entry)
      for (const auto& [sub, unused] : entry->items()) keys.push_back(prefix + sub);
  }
  CHECK(keys == documented_columns("`RUN/summary.json`"));
  // named: items() of a temporary would dangle
  const budjam::io::Json timing = budjam::io::read_json(demo_run() / "timing.json");
  std::vector<std::string> timing_keys;
  for (const auto& [key, unused] : timing.items()) timing_keys.push_back(key);
  CHECK(timing_keys == documented_columns("`RUN/timing.json`"));
}

TEST_CASE("summary.json's cost counters agree with trials.csv: trials, marginal relaxations, evaluations by stage",
          "[cli]") {
  const budjam::io::Json summary = budjam::io::read_json(demo_run() / "summary.json");
  const budjam::tools::CsvTable trials = budjam::tools::read_csv(demo_run() / "trials.csv");
  const budjam::tools::CsvTable steps = budjam::tools::read_csv(demo_run() / "steps.csv");
  REQUIRE(summary.at("unjammings").empty());
  // The attempt that produced the jamming point: the search's trials are the rows up to it.
  const long long step_J = summary.at("step_J").get<long long>();
  long long attempt_J = -1;
  for (std::size_t r = 0; r < steps.size(); ++r)
    if (steps.integer(r, steps.column("step"), 0, 1LL << 40) == step_J)
      attempt_J = steps.integer(r, steps.column("attempts"), 0, 1LL << 40);
  REQUIRE(attempt_J > 0);
  long long search_rows = 0, marginal = 0, search_evaluations = 0, above_evaluations = 0;
  for (std::size_t r = 0; r < trials.size(); ++r) {
    const long long evaluations = trials.integer(r, trials.column("evaluations"), 1, 1LL << 40);
    const bool search = trials.integer(r, trials.column("attempt"), 1, 1LL << 40) <= attempt_J;
    search_rows += search;
    marginal += evaluations > budjam::kMarginalEvaluations;
    (search ? search_evaluations : above_evaluations) += evaluations;
  }
  CHECK(search_rows > 0);
  CHECK(search_rows < static_cast<long long>(trials.size()));  // the demo lands a target above jamming
  CHECK(summary.at("search_trials").get<long long>() == search_rows);
  CHECK(summary.at("marginal_relaxations").get<long long>() == marginal);
  CHECK(summary.at("force_evaluations_search").get<long long>() == search_evaluations);
  CHECK(summary.at("force_evaluations_above_jamming").get<long long>() == above_evaluations);
  CHECK(summary.at("force_evaluations_initial").get<long long>() > 0);
  CHECK(summary.at("force_evaluations_initial").get<long long>() + search_evaluations + above_evaluations ==
        summary.at("force_evaluations").get<long long>());
  // The demo scene finishes above jamming with Newton: its factorisations are counted.
  CHECK(summary.at("newton_factorisations").get<long long>() > 0);
  CHECK(summary.at("newton_factor_reuses").get<long long>() >= 0);
  // Without jamming.continuation no branch is followed.
  for (const char* key : {"branches", "branches_reached", "branch_stability_losses", "branch_steps", "branch_events",
                          "branch_rearrangements"})
    CHECK(summary.at(key).get<long long>() == 0);
}

TEST_CASE("with minimiser.active_set_after, summary.json counts the active-set steps and their factor work", "[cli]") {
  const fs::path run = work_dir() / "active_set";
  REQUIRE(run_budjam("grow " + shell_quoted(source_file("data/scenes/demo.toml")) + " --quiet --out " +
                     shell_quoted(run) + " --set minimiser.active_set_after=300 --set minimiser.active_set_try_after=0")
              .code == 0);
  const budjam::io::Json summary = budjam::io::read_json(run / "summary.json");
  const auto count = [&](const char* key) { return summary.at(key).get<long long>(); };
  CHECK(count("active_set_steps") > 0);
  // Every step factors its model at least once; the set's later changes are mostly updates.
  CHECK(count("active_set_factorisations") >= count("active_set_steps"));
  CHECK(count("active_set_updates") > 0);
  CHECK(summary.at("status").get<std::string>() == "finished");
}

TEST_CASE("with jamming.continuation, summary.json counts one branch per trial started on the lowest overshoot",
          "[cli]") {
  const fs::path run = work_dir() / "continuation";
  REQUIRE(run_budjam("grow " + shell_quoted(source_file("data/scenes/demo.toml")) + " --quiet --out " +
                     shell_quoted(run) + " --set jamming.continuation=true --set observe.trials=true")
              .code == 0);
  const budjam::io::Json summary = budjam::io::read_json(run / "summary.json");
  const budjam::tools::CsvTable trials = budjam::tools::read_csv(run / "trials.csv");
  // A deferred trial relaxed on appears again under its attempt: its branch was followed once.
  std::set<long long> on_branch;
  for (std::size_t r = 0; r < trials.size(); ++r)
    if (trials.text(r, trials.column("start")) == "lowest_overshoot")
      on_branch.insert(trials.integer(r, trials.column("attempt"), 1, 1LL << 40));
  const auto count = [&](const char* key) { return summary.at(key).get<long long>(); };
  REQUIRE(!on_branch.empty());  // the demo's search starts trials on its lowest overshoot
  CHECK(count("branches") == static_cast<long long>(on_branch.size()));
  CHECK(count("branches_reached") + count("branch_stability_losses") <= count("branches"));
  // A branch that reached the trial's sizes took at least one step; the others may have taken none.
  CHECK(count("branch_steps") >= count("branches_reached"));
  CHECK(count("branch_events") >= 0);
  CHECK(count("branch_rearrangements") == 0);  // jamming.crossing_step = 0: a branch ends at a stability loss
  // Each branch step factorises at least once, and those factorisations are Newton's.
  CHECK(count("newton_factorisations") >= count("branch_steps"));
}

namespace {

// A copy of an analysis' tables as versions before the empty P0 field wrote them: "none" in every
// CSV's P0 column (the field after L in each row).
fs::path tables_with_P0_none(const fs::path& tables, const fs::path& copy) {
  fs::remove_all(copy);
  fs::copy(tables, copy, fs::copy_options::recursive);
  for (const auto& e : fs::directory_iterator(copy)) {
    if (e.path().extension() != ".csv") continue;
    std::istringstream in(slurp(e.path()));
    std::string line, text;
    std::getline(in, line);
    const auto header = csv_header(e.path());
    const auto P0 = std::find(header.begin(), header.end(), "P0");
    text = line + "\n";
    while (std::getline(in, line)) {
      if (P0 != header.end()) {
        std::size_t at = 0;
        for (auto k = header.begin(); k != P0; ++k) at = line.find(',', at) + 1;
        if (at < line.size() && line[at] == ',') line.insert(at, "none");
      }
      text += line + "\n";
    }
    std::ofstream(e.path()) << text;
  }
  return copy;
}

}  // namespace

TEST_CASE("analyse --tables reads the P0 \"none\" of earlier tables and writes it as an empty field", "[cli]") {
  const fs::path old = tables_with_P0_none(source_file("data/reference/quick/tables"), work_dir() / "old_tables");
  const fs::path out = work_dir() / "reanalysed";
  REQUIRE(run_budjam("analyse --tables " + shell_quoted(old) + " --out " + shell_quoted(out) + " --main-L 8").code ==
          0);
  CHECK(slurp(old / "runs.csv").find(",8,none,1,") != std::string::npos);
  CHECK(slurp(out / "runs.csv").find(",8,,1,") != std::string::npos);
  CHECK(slurp(out / "runs.csv").find(",none,") == std::string::npos);
  const auto groups = budjam::io::read_json(out / "analysis.json").at("groups");
  CHECK(std::any_of(groups.begin(), groups.end(),
                    [](const auto& g) { return g.at("P0").is_null() && g.at("P0_label") == "none"; }));
}

TEST_CASE(
    "--out BASE writes BASE.json (and BASE.csv), --json prints the same JSON, neither prints one summary line; "
    "a BASE of only \".json\" is refused",
    "[cli]") {
  const fs::path pack = demo_run() / "packings/phi2.pack", out = work_dir() / "convention";
  fs::create_directories(out);
  const std::vector<std::pair<std::string, bool>> commands{{"moduli " + shell_quoted(pack), false},
                                                           {"rigidity " + shell_quoted(pack), true},
                                                           {"dos " + shell_quoted(pack), true},
                                                           {"survival " + shell_quoted(demo_run()), true}};
  for (const auto& [command, has_table] : commands) {
    const std::string name = command.substr(0, command.find(' '));
    INFO(command);
    const fs::path base = out / name;
    const auto plain = run_budjam(command);
    REQUIRE(plain.code == 0);
    CHECK(one_line(plain.out).rfind(name + ": ", 0) == 0);  // "moduli: N = 48, ..."
    CHECK(fs::is_empty(out));                               // no --out: nothing written

    const auto json = run_budjam(command + " --json");
    REQUIRE(json.code == 0);
    CHECK(budjam::io::Json::parse(json.out).is_object());

    // a trailing .json of BASE is dropped; the line names the files
    const auto files = run_budjam(command + " --out " + shell_quoted(base.string() + ".json"));
    REQUIRE(files.code == 0);
    CHECK(one_line(files.out).find(" -> " + base.string() + ".json") != std::string::npos);
    CHECK(fs::exists(base.string() + ".csv") == has_table);
    CHECK(slurp(base.string() + ".json") == json.out);
    CHECK(run_budjam(command + " --quiet --out " + shell_quoted(base)).out.empty());

    // a BASE that is only the extension names no file: refused, nothing written (not ".json.json")
    fs::remove_all(out);
    fs::create_directories(out);
    for (const std::string bare : {".json", ".csv"}) {
      const auto refused = run_budjam(command + " --out " + shell_quoted((out / bare).string()));
      CHECK(refused.code == 2);
      CHECK(one_line(refused.err).find("no file name before the extension " + bare) != std::string::npos);
      CHECK(fs::is_empty(out));
    }
    fs::remove_all(out);
    fs::create_directories(out);
  }
}

TEST_CASE("survival keeps -o as --out: -o BASE.csv writes BASE.csv and BASE.json", "[cli]") {
  const fs::path base = work_dir() / "km";
  REQUIRE(
      run_budjam("survival " + shell_quoted(demo_run()) + " --quiet -o " + shell_quoted(base.string() + ".csv")).code ==
      0);
  CHECK(csv_header(base.string() + ".csv").front() == "a");
  CHECK(budjam::io::read_json(base.string() + ".json").contains("a_eps"));
}

TEST_CASE("scripts/progress.py counts the stamps that exist and extrapolates the pace since the first made", "[cli]") {
  const fs::path dir = work_dir() / "stamps";
  fs::create_directories(dir);
  std::string stamps;
  for (const char* name : {"s0", "s1", "s2", "s3"}) stamps.append(" ").append(shell_quoted(dir / name));
  const fs::path err = work_dir() / "progress.txt";
  const auto shell = [](const std::string& cmd) { REQUIRE(std::system(cmd.c_str()) == 0); };
  const std::string now = "$(date +%s)";
  // made 120 s ago, 60 s ago and now, by a make that started 130 s ago
  shell("cd " + shell_quoted(dir) + " && touch -d @$((" + now + " - 120)) s0 && touch -d @$((" + now +
        " - 60)) s1 && touch s2");
  const auto progress = [&](int at_start) {
    shell("python3 " + shell_quoted(source_file("scripts/progress.py")) + " moduli $((" + now + " - 130)) " +
          std::to_string(at_start) + stamps + " 2> " + shell_quoted(err));
    return slurp(err);
  };
  // two made after the first in 120 s: the last one in ~60 s
  CHECK_THAT(progress(0), Catch::Matchers::StartsWith("[moduli 3/4 runs, ETA 1m0"));
  CHECK(progress(2) == "[moduli 3/4 runs]\n");  // one made by this make: no pace yet
  std::ofstream(dir / "s3");
  CHECK(progress(0) == "[moduli 4/4 runs]\n");  // done
}

TEST_CASE("scripts/progress.py weights the runs left by the cost of the done runs of their group", "[cli]") {
  // Two groups of runs: the cheap one done (1 s each, the last two made in 60 s), the costly one
  // (one run of it done, 30 s) with two runs left: ETA = 60 s × (30 + 30) / (1 + 30) ≈ 116 s, where
  // weighing every run alike would say 60 s × 2 / 2 = 60 s.
  const fs::path grid = work_dir() / "grid";
  const auto shell = [](const std::string& cmd) { REQUIRE(std::system(cmd.c_str()) == 0); };
  std::string stamps;
  const std::string now = "$(date +%s)";
  int k = 0;
  for (const auto& [group, seed, wall, ago] :
       std::vector<std::tuple<std::string, int, double, int>>{{"P0_none", 1, 1.0, 60},
                                                              {"P0_none", 2, 1.0, 30},
                                                              {"P0_1e-5", 1, 30.0, 0},
                                                              {"P0_1e-5", 2, 0, -1},
                                                              {"P0_1e-5", 3, 0, -1}}) {
    const fs::path run = grid / "L8" / group / ("seed" + std::to_string(seed));
    fs::create_directories(run);
    stamps.append(" ").append(shell_quoted(run / "summary.json"));
    ++k;
    if (ago < 0) continue;
    std::ofstream(run / "timing.json") << "{\"wall_seconds\": " << wall << ", \"final_N\": 48}";
    shell("touch -d @$((" + now + " - " + std::to_string(ago) + ")) " + shell_quoted(run / "summary.json"));
  }
  const fs::path err = work_dir() / "progress-weighted.txt";
  shell("python3 " + shell_quoted(source_file("scripts/progress.py")) + " grow $((" + now + " - 70)) 0" + stamps +
        " 2> " + shell_quoted(err));
  CHECK_THAT(slurp(err), Catch::Matchers::Matches(R"(\[grow 3/5 runs, ETA 1m5[5-9]s\]\n)"));
}
