// `budjam grow` end to end: the run directory, determinism, failure statuses, resume after SIGKILL.
#include "budjam/scene_keys.hpp"
#include "io/checkpoint.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <catch2/catch.hpp>
#include "run_budjam.hpp"
#include "scratch.hpp"
#include "small_disk.hpp"

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

using budjam::testing::slurp;
using budjam::testing::work_dir;

std::string exe() {
  const char* e = std::getenv("BUDJAM_EXE");
  REQUIRE(e != nullptr);
  return e;
}

using Result = budjam::testing::BudjamRun;

Result grow(const std::string& args) { return budjam::testing::run_budjam("grow " + args); }

// A small scene: L = 6, two targets (or `targets`), bud events, quick.
fs::path small_scene(const std::string& name, const std::string& extra = "",
                     const std::string& targets = "[1e-3, 1e-2]") {
  const fs::path p = work_dir() / (name + ".toml");
  std::ofstream(p) << "[run]\nname = \"" << name << "\"\nseed = 3\n[box]\nL = 6.0\n[growth]\nP0 = 1e-3\n"
                   << "[jamming]\ntargets = " << targets << "\n"
                   << extra;
  return p;
}

std::string q(const fs::path& p) { return budjam::testing::shell_quoted(p); }

// Starts `budjam grow SCENE --quiet --set box.L=12 --out DIR` in the background (a run of a few
// seconds, long enough to be interrupted; `box_L` another box), its stderr to
// DIR.stderr; returns its pid.
pid_t start_grow(const fs::path& scene, const fs::path& dir, const std::string& box_L = "12") {
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const std::string e = exe(), sc = scene.string(), out = dir.string(), err = dir.string() + ".stderr";
    const std::string L = "box.L=" + box_L;
    if (!std::freopen(err.c_str(), "w", stderr)) ::_exit(126);
    ::execl(e.c_str(), e.c_str(), "grow", sc.c_str(), "--quiet", "--set", L.c_str(), "--out", out.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

}  // namespace

TEST_CASE("grow writes the documented run directory and lands the targets", "[grow_cli]") {
  const fs::path dir = work_dir() / "run1";
  const Result r = grow(q(small_scene("s1")) + " --quiet --out " + q(dir));
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.empty());  // --quiet
  for (const char* f : {"summary.json", "timing.json", "scene.toml", "steps.csv", "divisions.csv", "bud_events.csv",
                        "packings/jammed.pack", "packings/target_0.pack", "packings/target_1.pack"})
    CHECK(fs::exists(dir / f));
  CHECK_FALSE(fs::exists(dir / "checkpoint.txt"));
  for (const auto& e : fs::recursive_directory_iterator(dir)) CHECK(e.path().extension() != ".partial");

  const auto s = budjam::io::read_json(dir / "summary.json");
  CHECK(s["status"] == "finished");
  CHECK(s["seed"] == 3);
  CHECK(s["L"] == 6.0);
  CHECK(s["P0"] == 1e-3);
  const double phi_J = s["phi_J"].get<double>();
  CHECK(phi_J > 0.75);
  CHECK(phi_J < 0.92);
  REQUIRE(s["targets"].size() == 2);
  for (const auto& t : s["targets"]) CHECK(std::abs(t["phi"].get<double>() - phi_J - t["dphi"].get<double>()) <= 5e-9);
  CHECK(s["n_J"].get<double>() == Approx(s["N_nr_J"].get<double>() / 36.0));

  // The packings are the states the summary describes.
  const auto jam = budjam::io::read_packing(dir / "packings/jammed.pack");
  CHECK(jam.packing.packing_fraction() == phi_J);
  CHECK(jam.meta.number("phi") == phi_J);
  const auto t1 = budjam::io::read_packing(dir / "packings/target_1.pack");
  CHECK(t1.packing.packing_fraction() == s["targets"][1]["phi"].get<double>());
  CHECK(t1.meta.number("dphi") == 1e-2);

  // steps.csv: a header and one row per accepted state (the initial one included)
  std::istringstream steps(slurp(dir / "steps.csv"));
  std::string line;
  std::getline(steps, line);
  CHECK(line.rfind("step,attempts,dt,N,phi,P,E_per_cell,phase,N_c,N_f,", 0) == 0);
  long rows = 0;
  while (std::getline(steps, line)) ++rows;
  CHECK(rows == s["accepted_steps"].get<long>() + 1);
}

TEST_CASE("without --out a run goes to runs/NAME-seedS, NAME the run's name made safe and never hidden", "[grow_cli]") {
  const fs::path here = work_dir() / "default_dirs";
  fs::create_directories(here);
  const fs::path scene = small_scene("named", "", "[]");
  const std::vector<std::pair<std::string, std::string>> names{
      {"demo run", "demo_run"}, {".", "_"}, {"..hidden", "_hidden"}, {"a/../b", "a_.._b"}};
  for (const auto& [name, dir] : names) {
    INFO(name);
    const auto r = budjam::testing::run_budjam_in(
        here, "grow " + q(scene) + " --quiet --set 'run.name=\"" + name + "\"' --set growth.max_steps=2");
    CHECK(r.code == 0);
    CHECK(fs::exists(here / "runs" / (dir + "-seed3") / "scene.toml"));
  }
  std::vector<std::string> made;
  for (const auto& e : fs::directory_iterator(here / "runs")) made.push_back(e.path().filename().string());
  CHECK(made.size() == names.size());
  for (const auto& m : made) CHECK(m.front() != '.');
}

TEST_CASE("the same scene and seed give a byte-identical summary.json; another seed does not", "[grow_cli]") {
  const fs::path scene = small_scene("det");
  const fs::path a = work_dir() / "det_a", b = work_dir() / "det_b", c = work_dir() / "det_c";
  REQUIRE(grow(q(scene) + " --quiet --out " + q(a)).code == 0);
  REQUIRE(grow(q(scene) + " --quiet --out " + q(b)).code == 0);
  REQUIRE(grow(q(scene) + " --quiet --seed 4 --out " + q(c)).code == 0);
  CHECK(slurp(a / "summary.json") == slurp(b / "summary.json"));
  CHECK(slurp(a / "steps.csv") == slurp(b / "steps.csv"));
  CHECK(slurp(a / "bud_events.csv") == slurp(b / "bud_events.csv"));
  CHECK(slurp(a / "packings/target_1.pack") == slurp(b / "packings/target_1.pack"));
  CHECK(slurp(a / "summary.json") != slurp(c / "summary.json"));
  CHECK(budjam::io::read_json(c / "summary.json")["seed"] == 4);
  // Re-running into a finished run directory is refused, and replaces it with --overwrite.
  const Result again = grow(q(scene) + " --quiet --seed 4 --out " + q(a));
  CHECK(again.code == 2);
  CHECK(again.err.find("--overwrite") != std::string::npos);
  CHECK(slurp(a / "summary.json") == slurp(b / "summary.json"));
  REQUIRE(grow(q(scene) + " --quiet --seed 4 --overwrite --out " + q(a)).code == 0);
  CHECK(slurp(a / "summary.json") == slurp(c / "summary.json"));
}

TEST_CASE("a run stopped at the step limit exits 0 with a one-line notice, not an error, and status step_limit",
          "[grow_cli]") {
  const fs::path dir = work_dir() / "limit";
  const Result r = grow(q(small_scene("limit")) + " --quiet --set growth.max_steps=30 --out " + q(dir));
  CHECK(r.code == 0);
  CHECK(r.err.find("budjam: grow: run stopped at the step limit (growth.max_steps = 30 growth steps); recorded: "
                   "not jammed") == 0);
  CHECK(r.err.find("error") == std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  const auto s = budjam::io::read_json(dir / "summary.json");
  CHECK(s["status"] == "step_limit");
  CHECK(s["phi_J"].is_null());
  CHECK(s["targets"].empty());
  CHECK(s["accepted_steps"].get<long>() + s["rejected_steps"].get<long>() == 30);
}

TEST_CASE("a step-size underflow exits 1 with status dt_underflow and no jammed packing", "[grow_cli]") {
  const fs::path dir = work_dir() / "underflow";
  const Result r = grow(q(small_scene("uf")) + " --quiet --set growth.dt_min=0.3 --out " + q(dir));
  CHECK(r.code == 1);
  CHECK(r.err.find("dt_underflow") != std::string::npos);
  const auto s = budjam::io::read_json(dir / "summary.json");
  CHECK(s["status"] == "dt_underflow");
  CHECK(s["phi_J"].is_null());
  CHECK_FALSE(fs::exists(dir / "packings/jammed.pack"));
}

// P0 = 1e-8 with the adaptive step and no floor: soon after jamming every exp(−p/P0) and Δt = dt·e^{p_min/P0}
// leave the double range (p_min/P0 reaches ~1e5); the log lines keep them as decimal text.
TEST_CASE("steps.csv writes dt and chi_c beyond the double range as decimal text, and analyse reads the run",
          "[grow_cli]") {
  const fs::path dir = work_dir() / "beyond";
  const Result r = grow(q(small_scene("beyond")) +
                        " --quiet --set growth.P0=1e-8 --set growth.adaptive_dt=true --set growth.adaptive_floor=0 "
                        "--out " +
                        q(dir));
  REQUIRE(r.code == 0);
  std::istringstream csv(slurp(dir / "steps.csv"));
  std::string line;
  std::getline(csv, line);
  REQUIRE(line.rfind("step,attempts,dt,", 0) == 0);
  const std::size_t chi_column = 16;  // docs/columns.md, steps.csv
  long huge_dt = 0, tiny_chi = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    REQUIRE(f.size() > chi_column);
    // Mantissa in [1, 10) and a decimal exponent beyond ±308: a double reader gets inf or 0.
    auto beyond = [](const std::string& t, int sign) {
      const std::size_t e = t.find('e');
      if (e == std::string::npos) return false;
      const double mantissa = std::stod(t.substr(0, e));
      const long exponent = std::stol(t.substr(e + 1));
      CHECK(mantissa >= 1.0);
      CHECK(mantissa < 10.0);
      return sign * exponent > 308;
    };
    if (beyond(f[2], +1)) {
      ++huge_dt;
      CHECK(std::strtod(f[2].c_str(), nullptr) == HUGE_VAL);
    }
    if (!f[chi_column].empty() && beyond(f[chi_column], -1)) ++tiny_chi;
  }
  CHECK(huge_dt > 10);
  CHECK(tiny_chi > 10);
  const fs::path out = work_dir() / "beyond-analysis";
  CHECK(budjam::testing::run_budjam("analyse " + q(dir) + " --out " + q(out) + " --resamples 20").code == 0);
}

TEST_CASE("grow refuses bad input with exit 2 and one line naming the problem", "[grow_cli]") {
  const fs::path dir = work_dir() / "bad";
  Result r = grow(q(small_scene("bad", "")) + " --quiet --set growth.P0=-1 --out " + q(dir));
  CHECK(r.code == 2);
  CHECK(r.err.find("growth.P0") != std::string::npos);
  // a rule between two keys broken by a --set names that --set, not the file, whichever key it names
  // first (growth.dt is a prefix of growth.dt_min, which is not the key set)
  for (const std::string set : {"growth.dt=1e-300", "growth.dt_min=10"}) {
    r = grow(q(small_scene("bad", "")) + " --quiet --set " + set + " --out " + q(dir));
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("budjam: error: --set " + set + ": growth.dt_min: must be smaller than growth.dt", 0) == 0);
  }
  // ... for each key of every rule between keys: the message names the other key in full
  for (const std::string set :
       {"'jamming.targets=[1e-300]'", "jamming.target_tolerance=0.5", "jamming.max_dphi=1e-300",
        "minimiser.dt_start=100", "minimiser.dt_max=1e-300", "jamming.epsilon_U=1e-30", "minimiser.skin=3"}) {
    r = grow(q(small_scene("bad", "")) + " --quiet --set " + set + " --out " + q(dir));
    INFO(r.err);
    CHECK(r.code == 2);
    std::string unquoted = set;
    std::erase(unquoted, '\'');
    CHECK(r.err.rfind("budjam: error: --set " + unquoted + ": ", 0) == 0);
  }
  std::ofstream(work_dir() / "bad_dt.toml") << "[growth]\ndt_min = 10\n";  // the file's own broken rule
  r = grow(q(work_dir() / "bad_dt.toml") + " --quiet --set growth.P0=1e-3 --out " + q(dir));
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("bad_dt.toml: growth.dt_min: must be smaller than growth.dt") != std::string::npos);
  CHECK_FALSE(fs::exists(dir));
  r = grow("--resume " + q(work_dir() / "no-such-run") + " --quiet");
  CHECK(r.code == 2);
  CHECK(r.err.find("no-such-run") != std::string::npos);
  // a checkpoint of format 1 (written before jamming candidates were checked for saddles) is refused
  const fs::path old = work_dir() / "old-checkpoint";
  fs::create_directories(old);
  fs::copy_file(small_scene("old"), old / "scene.toml");
  std::ofstream(old / ".budjam-run") << "budjam-run 1\n";
  std::ofstream(old / "checkpoint.txt") << "budjam-checkpoint 1\nseed 3\n";
  r = grow("--resume " + q(old) + " --quiet");
  CHECK(r.code == 2);
  CHECK(r.err.find("checkpoint.txt:1: checkpoint version 1") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  // an existing directory that is not a run directory is never overwritten
  const fs::path foreign = work_dir() / "foreign";
  fs::create_directories(foreign);
  std::ofstream(foreign / "precious.txt") << "keep";
  r = grow(q(small_scene("bad2")) + " --quiet --out " + q(foreign));
  CHECK(r.code == 2);
  CHECK(slurp(foreign / "precious.txt") == "keep");
}

TEST_CASE("grow into a run directory is refused without --overwrite; --resume is offered only for an unfinished run",
          "[grow_cli]") {
  const fs::path run = work_dir() / "earlier-run";
  fs::create_directories(run);
  std::ofstream(run / ".budjam-run") << "budjam-run 1\n";
  std::ofstream(run / "summary.json") << "{}\n";
  const std::string demo = std::string(std::getenv("BUDJAM_SOURCE_DIR")) + "/data/scenes/demo.toml";
  Result r = grow(q(demo) + " --quiet --out " + q(run));
  CHECK(r.code == 2);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find("--overwrite") != std::string::npos);
  CHECK(r.err.find("--resume") == std::string::npos);  // a finished run has nothing to continue
  fs::remove(run / "summary.json");
  std::ofstream(run / "checkpoint.txt") << "budjam-checkpoint 13\n";
  r = grow(q(demo) + " --quiet --out " + q(run));
  CHECK(r.code == 2);
  CHECK(r.err.find("unfinished") != std::string::npos);
  CHECK(r.err.find("budjam grow --resume " + run.string()) != std::string::npos);
  CHECK(slurp(run / "checkpoint.txt") == "budjam-checkpoint 13\n");
}

TEST_CASE("a directory that merely holds a scene.toml is never emptied", "[grow_cli]") {
  const fs::path d = work_dir() / "thesis";
  fs::create_directories(d);
  std::ofstream(d / "scene.toml") << "x\n";
  std::ofstream(d / "thesis.tex") << "precious\n";
  const std::string demo = std::string(std::getenv("BUDJAM_SOURCE_DIR")) + "/data/scenes/demo.toml";
  for (const char* flag : {"", " --overwrite"}) {
    const Result r = grow(q(demo) + " --quiet --out " + q(d) + flag);
    CHECK(r.code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find("not a budjam run directory") != std::string::npos);
    CHECK(slurp(d / "thesis.tex") == "precious\n");
    CHECK(slurp(d / "scene.toml") == "x\n");
  }
}

TEST_CASE("a second writer of the same run directory is refused with the holder's pid", "[grow_cli]") {
  const fs::path scene = small_scene("writers");
  const fs::path dir = work_dir() / "writers";
  const pid_t pid = start_grow(scene, dir);
  const auto t0 = std::chrono::steady_clock::now();
  while (slurp(dir / ".budjam-lock").empty() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  // The first writer is held (SIGSTOP) while the others try, so that it still holds the directory
  // however fast it would have finished.
  ::kill(pid, SIGSTOP);
  const Result second = grow(q(scene) + " --quiet --seed 9 --overwrite --out " + q(dir));
  const Result resumer = grow("--resume " + q(dir) + " --quiet");
  ::kill(pid, SIGCONT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  for (const Result& r : {second, resumer}) {
    CHECK(r.code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  INFO(second.err);
  CHECK(second.err.find("pid " + std::to_string(pid)) != std::string::npos);
  // The directory is the first writer's alone.
  CHECK(budjam::io::read_json(dir / "summary.json")["seed"] == 3);
  CHECK(budjam::io::read_packing(dir / "packings/jammed.pack").meta.integer("seed") == 3);
}

TEST_CASE("a run killed with SIGKILL and resumed ends identical to an uninterrupted run", "[grow_cli][.slow]") {
  const std::string extra = "[observe]\ncheckpoint_every = 25\ntrials = true\n";
  const fs::path scene = small_scene("kill", extra);
  const fs::path ref = work_dir() / "kill_ref", dir = work_dir() / "kill_run";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);

  // Kill the same run some time after its first checkpoint (on a fast machine the later kill may
  // come after the run has finished).
  for (double delay : {0.0, 0.3}) {
    fs::remove_all(dir);
    const pid_t pid = start_grow(scene, dir);
    const auto t0 = std::chrono::steady_clock::now();
    while (!fs::exists(dir / "checkpoint.txt") && !fs::exists(dir / "summary.json") &&
           std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::duration<double>(delay));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (delay > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0) continue;
    REQUIRE(WIFSIGNALED(status));  // really killed, not finished
    REQUIRE(fs::exists(dir / "checkpoint.txt"));
    // A killed run never leaves files that look complete.
    CHECK_FALSE(fs::exists(dir / "summary.json"));
    CHECK_FALSE(fs::exists(dir / "steps.csv"));
    CHECK(fs::exists(dir / "steps.csv.partial"));

    const Result r = grow("--resume " + q(dir) + " --quiet");
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(slurp(dir / "summary.json") == slurp(ref / "summary.json"));
    for (const char* f : {"steps.csv", "divisions.csv", "bud_events.csv", "trials.csv", "packings/jammed.pack",
                          "packings/target_0.pack", "packings/target_1.pack", "scene.toml"})
      CHECK(slurp(dir / f) == slurp(ref / f));
    CHECK_FALSE(fs::exists(dir / "checkpoint.txt"));
    // A finished run is not resumed again.
    CHECK(grow("--resume " + q(dir) + " --quiet").code == 2);
  }
}

namespace {

// Starts `budjam grow SCENE --quiet --set box.L=12 --out DIR`, lets it run `delay` seconds after
// the file `after` (in DIR) appears, sends `sig` and returns the exit status.
int grow_and_signal(const fs::path& scene, const fs::path& dir, double delay, int sig,
                    const char* after = "steps.csv.partial", const std::string& box_L = "12") {
  const pid_t pid = start_grow(scene, dir, box_L);
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(dir / after) && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::duration<double>(delay));
  ::kill(pid, sig);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

// Starts `budjam grow SCENE --quiet --set box.L=12 --out DIR` afresh, sends `sig` once `ready()`
// holds (or the run finished, or after a minute) and returns the exit status.
int signal_when(const fs::path& scene, const fs::path& dir, int sig, const std::function<bool()>& ready) {
  fs::remove_all(dir);
  const pid_t pid = start_grow(scene, dir);
  const auto t0 = std::chrono::steady_clock::now();
  while (!ready() && !fs::exists(dir / "summary.json") &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ::kill(pid, sig);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

// `budjam grow --resume DIR` succeeds and ends with the files of the uninterrupted run `ref` of a
// scene with one target and trials.csv.
void resumes_to(const fs::path& dir, const fs::path& ref) {
  const Result r = grow("--resume " + q(dir) + " --quiet");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* f : {"summary.json", "steps.csv", "divisions.csv", "bud_events.csv", "trials.csv",
                        "packings/jammed.pack", "packings/target_0.pack"})
    CHECK(slurp(dir / f) == slurp(ref / f));
}

// grow_and_signal at the first of `delays` whose signal leaves a checkpoint. A signal past jamming,
// while the Newton finish keeps its factor, writes none (that state would not resume exactly), and
// how far a run has got after a given delay depends on the machine: so the delays go down until
// the signal lands in a state that can be saved.
int signal_with_checkpoint(const fs::path& scene, const fs::path& dir, int sig, std::initializer_list<double> delays) {
  for (const double delay : delays) {
    fs::remove_all(dir);
    const int status = grow_and_signal(scene, dir, delay, sig);
    if (fs::exists(dir / "checkpoint.txt")) return status;
  }
  FAIL("no delay left a checkpoint in " << dir);
  return -1;
}

}  // namespace

TEST_CASE("SIGTERM and SIGINT write a checkpoint; the resumed run is byte-identical", "[grow_cli][.slow]") {
  // checkpoint_every = 0: no periodic checkpoints, so the one resumed from is the signal's.
  const fs::path scene = small_scene("term", "[observe]\ncheckpoint_every = 0\n");
  const fs::path ref = work_dir() / "term_ref";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  for (const auto& [sig, code] : {std::pair{SIGTERM, 143}, std::pair{SIGINT, 130}}) {
    const fs::path dir = work_dir() / ("term_" + std::to_string(sig));
    const int status = signal_with_checkpoint(scene, dir, sig, {0.3, 0.1, 0.0});
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == code);
    const std::string err = slurp(dir.string() + ".stderr");
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK(err.find("resume with: budjam grow --resume " + dir.string()) != std::string::npos);
    // A stop that can be resumed is a notice (docs/files.md), not an error.
    CHECK(err.rfind("budjam: grow: stopped by ", 0) == 0);
    CHECK_FALSE(fs::exists(dir / "summary.json"));
    const Result r = grow("--resume " + q(dir) + " --quiet");
    INFO(r.err);
    REQUIRE(r.code == 0);
    for (const char* f : {"summary.json", "steps.csv", "divisions.csv", "bud_events.csv", "packings/jammed.pack",
                          "packings/target_0.pack", "packings/target_1.pack", "scene.toml"})
      CHECK(slurp(dir / f) == slurp(ref / f));
  }
}

TEST_CASE("a signal inside the search onto phi_J checkpoints its open bracket; the resumed run is byte-identical",
          "[grow_cli][.slow]") {
  // No periodic checkpoints: the one resumed from is the signal's, taken between two trials.
  const fs::path scene = small_scene("bracket", "[observe]\ncheckpoint_every = 0\ntrials = true\n", "[1e-3]");
  const fs::path ref = work_dir() / "bracket_ref";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  bool inside = false;
  for (int attempt = 0; attempt < 6 && !inside; ++attempt) {
    const fs::path dir = work_dir() / ("bracket_" + std::to_string(attempt));
    // The first overshoot of the jamming window opens the bracket (trials.csv: verdict rejected).
    const int status = signal_when(
        scene, dir, SIGTERM, [&] { return slurp(dir / "trials.csv.partial").find(",rejected,") != std::string::npos; });
    REQUIRE(WIFEXITED(status));
    if (WEXITSTATUS(status) == 0) continue;  // finished before the signal
    CHECK(WEXITSTATUS(status) == 143);
    const std::string err = slurp(dir.string() + ".stderr");
    INFO(err);
    CHECK(err.find("checkpoint written; resume with") != std::string::npos);
    inside = slurp(dir / "checkpoint.txt").find("\nbracket 1 ") != std::string::npos;
    resumes_to(dir, ref);
  }
  CHECK(inside);  // the case this test is for arose
}

TEST_CASE("a run killed or signalled inside a relaxation resumes it from its checkpoint, byte-identical",
          "[grow_cli][.slow]") {
  // A checkpoint every 300 force evaluations of a relaxation and none between steps: the one
  // resumed from holds a relaxation in progress.
  const fs::path scene =
      small_scene("inside", "[observe]\ncheckpoint_every = 0\ncheckpoint_evaluations = 300\ntrials = true\n", "[1e-3]");
  const fs::path ref = work_dir() / "inside_ref";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  for (const int sig : {SIGKILL, SIGTERM}) {
    bool inside = false;
    for (int attempt = 0; attempt < 6 && !inside; ++attempt) {
      const fs::path dir = work_dir() / ("inside_" + std::to_string(sig) + "_" + std::to_string(attempt));
      const int status = signal_when(
          scene, dir, sig, [&] { return slurp(dir / "checkpoint.txt").find("\nrelaxation 1 ") != std::string::npos; });
      if (WIFEXITED(status) && WEXITSTATUS(status) == 0) continue;  // finished before the signal
      const std::string checkpoint = slurp(dir / "checkpoint.txt");
      inside = checkpoint.find("\nrelaxation 1 ") != std::string::npos;
      const std::string err = slurp(dir.string() + ".stderr");
      INFO(err);
      if (sig == SIGTERM) {
        REQUIRE(WIFEXITED(status));
        CHECK(WEXITSTATUS(status) == 143);
        CHECK(err.find("checkpoint written; resume with") != std::string::npos);
      }
      resumes_to(dir, ref);
    }
    CHECK(inside);  // the case this test is for arose
  }
}

TEST_CASE("a signal as soon as the run directory exists still ends in a checkpoint", "[grow_cli][.slow]") {
  const fs::path scene = small_scene("early", "[observe]\ncheckpoint_every = 0\n");
  for (int k = 0; k < 8; ++k) {
    const fs::path dir = work_dir() / ("early_" + std::to_string(k));
    const int status = grow_and_signal(scene, dir, 0.0, SIGTERM, ".");
    const std::string err = slurp(dir.string() + ".stderr");
    INFO(err);
    REQUIRE(WIFEXITED(status));  // handled, not the default action
    CHECK(WEXITSTATUS(status) == 143);
    CHECK(fs::exists(dir / "checkpoint.txt"));
  }
}

TEST_CASE(
    "a signal while a Newton factor is kept keeps the last periodic checkpoint; the resumed run is byte-identical",
    "[grow_cli][.slow]") {
  // Strong feedback, arrested growth past jamming: the Newton finish keeps its factor from step to
  // step (chord steps) and drops it every 4th step.
  const fs::path scene = work_dir() / "newton.toml";
  std::ofstream(scene) << "[run]\nname = \"newton\"\nseed = 8\n[box]\nL = 12.0\n"
                       << "[growth]\nP0 = 1e-5\nadaptive_dt = true\nadaptive_floor = 0\n"
                       << "[jamming]\ntargets = [1e-3, 1e-2, 3e-2]\n[minimiser]\nnewton_force = 1e-6\n"
                       << "[observe]\ncheckpoint_every = 4\n";
  const fs::path ref = work_dir() / "newton_ref";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  bool kept = false;
  for (int attempt = 0; attempt < 12 && !kept; ++attempt) {
    const fs::path dir = work_dir() / ("newton_" + std::to_string(attempt));
    const int status = grow_and_signal(scene, dir, 0.05 + 0.1 * attempt, SIGTERM, "packings/jammed.pack");
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) continue;  // finished before the signal
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 143);
    const std::string err = slurp(dir.string() + ".stderr");
    INFO(err);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    kept = err.find("is kept (a Newton factor kept in memory is not saved") != std::string::npos;
    CHECK((kept || err.find("checkpoint written") != std::string::npos));
    const Result r = grow("--resume " + q(dir) + " --quiet");
    INFO(r.err);
    REQUIRE(r.code == 0);
    for (const char* f : {"summary.json", "steps.csv", "divisions.csv", "packings/jammed.pack",
                          "packings/target_0.pack", "packings/target_1.pack", "packings/target_2.pack"})
      CHECK(slurp(dir / f) == slurp(ref / f));
  }
  CHECK(kept);  // the case this test is for arose
}

TEST_CASE("resume refuses every damaged checkpoint line and an edited scene, changing nothing", "[grow_cli][.slow]") {
  const fs::path scene = small_scene("damaged", "[observe]\ncheckpoint_every = 0\n");
  const fs::path ref = work_dir() / "damaged_ref", run = work_dir() / "damaged_run";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  REQUIRE(WEXITSTATUS(signal_with_checkpoint(scene, run, SIGTERM, {0.5, 0.2, 0.0})) == 143);
  const std::string checkpoint = slurp(run / "checkpoint.txt");
  std::vector<std::string> lines;
  {
    std::istringstream is(checkpoint);
    for (std::string l; std::getline(is, l);) lines.push_back(l);
  }
  const fs::path copy = work_dir() / "damaged_copy";
  auto fresh_copy = [&] {
    fs::remove_all(copy);
    fs::copy(run, copy, fs::copy_options::recursive);
  };
  auto refused = [&](const std::string& what) {
    const std::string steps = slurp(copy / "steps.csv.partial");
    const Result r = grow("--resume " + q(copy) + " --quiet");
    INFO(what << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(slurp(copy / "steps.csv.partial") == steps);  // refused before anything was cut
    return r.err;
  };
  for (std::size_t k = 0; k < lines.size(); ++k) {
    fresh_copy();
    std::vector<std::string> v = lines;
    v[k] += v[k].empty() ? "1" : (v[k].back() == '7' ? "" : "7");
    if (v[k] == lines[k]) v[k].pop_back();
    std::ofstream out(copy / "checkpoint.txt");
    for (const auto& l : v) out << l << '\n';
    out.close();
    CHECK(refused("line " + std::to_string(k + 1)).find("checkpoint.txt:") != std::string::npos);
  }
  // The scene of the run edited: other physics, or an observer added.
  for (const char* edit : {"growth.P0=2e-3", "observe.rigidity_events=true", "jamming.targets=[1e-3]"}) {
    fresh_copy();
    const fs::path edited = work_dir() / "edited.toml";
    const std::string cmd = "'" + exe() + "' validate " + q(copy / "scene.toml") + " --set " + edit + " > " + q(edited);
    REQUIRE(std::system(cmd.c_str()) == 0);
    fs::copy_file(edited, copy / "scene.toml", fs::copy_options::overwrite_existing);
    CHECK(refused(edit).find("scene.toml has changed") != std::string::npos);
  }
  // The untouched copy resumes to the reference result.
  fresh_copy();
  REQUIRE(grow("--resume " + q(copy) + " --quiet").code == 0);
  CHECK(slurp(copy / "summary.json") == slurp(ref / "summary.json"));
  CHECK(slurp(copy / "steps.csv") == slurp(ref / "steps.csv"));
}

TEST_CASE("a run that fills its disk exits 3 with one line and leaves whole rows", "[grow_cli]") {
  for (std::size_t kib : {24, 40, 56}) {
    budjam::testing::SmallDisk disk(work_dir() / ("disk" + std::to_string(kib)), kib * 1024);
    if (!disk.mounted) {
      WARN(disk.why_not);
      return;
    }
    const Result r = grow(q(small_scene("full")) + " --quiet --out " + q(disk.path / "run"));
    INFO(kib << " KiB: " << r.err);
    CHECK(r.code == 3);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find(disk.path.string()) != std::string::npos);
    for (const auto& e : fs::recursive_directory_iterator(disk.path))
      if (e.path().extension() == ".partial") {
        const std::string text = slurp(e.path());
        CHECK((text.empty() || text.back() == '\n'));
      }
  }
}

namespace {

// Every regular file and link under `dir` with its content (a link: its target), but the lock,
// which records the last claimant.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(e.path(), dir).string();
    if (rel == ".budjam-lock") continue;
    if (e.is_symlink())
      out[rel] = "-> " + fs::read_symlink(e.path()).string();
    else if (e.is_regular_file())
      out[rel] = slurp(e.path());
    else
      out[rel] = "<dir>";
  }
  return out;
}

// A run (box.L = 6, trials and trajectory on) stopped by SIGTERM past jamming: its checkpoint holds a
// jamming record and tagged buds. The signal must land after the first checkpoint past jamming and
// before the run ends. With small_scene's two targets that window was 4 steps, which a loaded
// machine missed in one try of four; a third target Δφ = 5e-2 (reached ~12 000 steps after the
// second) and a signal once target_1.pack exists (past the checkpoint of step 1420) widen it to
// seconds.
fs::path stopped_after_jamming(const std::string& name) {
  const fs::path scene = small_scene(name, "[observe]\ncheckpoint_every = 20\ntrials = true\ntrajectory_every = 40\n",
                                     "[1e-3, 1e-2, 5e-2]");
  const fs::path dir = work_dir() / name;
  for (int attempt = 0; attempt < 5; ++attempt) {
    fs::remove_all(dir);
    const int status = grow_and_signal(scene, dir, 0.0, SIGTERM, "packings/target_1.pack", "6");
    REQUIRE(WIFEXITED(status));
    if (WEXITSTATUS(status) == 143 && slurp(dir / "checkpoint.txt").find("\njamming 1 ") != std::string::npos)
      return dir;
  }
  FAIL("no SIGTERM after jamming left a checkpoint with the jamming record in " << dir);
  return dir;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream is(text);
  for (std::string l; std::getline(is, l);) v.push_back(l);
  return v;
}

std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> w;
  std::istringstream is(line);
  for (std::string x; is >> x;) w.push_back(x);
  return w;
}

std::string joined(const std::vector<std::string>& w) {
  std::string s;
  for (const auto& x : w) s += (s.empty() ? "" : " ") + x;
  return s;
}

// The checkpoint text with its checksum line recomputed, as an editor who knows the format writes it.
void write_with_checksum(const fs::path& file, std::vector<std::string> lines) {
  lines.pop_back();
  std::string body;
  for (const auto& l : lines) body += l + "\n";
  char sum[40];
  std::snprintf(sum, sizeof sum, "checksum %016llx\n", static_cast<unsigned long long>(budjam::io::fnv1a64(body)));
  std::ofstream(file, std::ios::trunc) << body << sum;
}

std::size_t line_starting(const std::vector<std::string>& lines, const std::string& prefix) {
  for (std::size_t k = 0; k < lines.size(); ++k)
    if (lines[k].rfind(prefix, 0) == 0) return k;
  FAIL("no line starts with '" << prefix << "'");
  return 0;
}

// Resumes `dir`, which must be refused with exit 2 and one line holding `expect` (and `also`),
// leaving every file of the directory as it was.
void refused_unchanged(const fs::path& dir, const std::string& expect, const std::string& also = "") {
  const auto before = snapshot(dir);
  const Result r = grow("--resume " + q(dir) + " --quiet");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find(expect) != std::string::npos);
  CHECK(r.err.find(also) != std::string::npos);
  CHECK(snapshot(dir) == before);
}

}  // namespace

TEST_CASE("a refused resume leaves the run directory byte-identical, whichever file is damaged", "[grow_cli]") {
  const fs::path run = stopped_after_jamming("damage");
  const fs::path copy = work_dir() / "damage_copy";
  auto fresh_copy = [&] {
    fs::remove_all(copy);
    fs::copy(run, copy, fs::copy_options::recursive);
  };
  auto truncate_to = [&](const char* file, std::size_t bytes) {
    fs::resize_file(copy / file, std::min<std::uintmax_t>(bytes, fs::file_size(copy / file)));
  };
  // Each log cut short of what the checkpoint records (the other logs would be cut back first
  // if the checks were not all made before the first cut).
  for (const char* log : {"steps.csv.partial", "divisions.csv.partial", "bud_events.csv.partial", "trials.csv.partial",
                          "trajectory.xyz.partial"}) {
    fresh_copy();
    truncate_to(log, 3);
    INFO(log);
    refused_unchanged(copy, log);
  }
  fresh_copy();
  std::string text = slurp(copy / "checkpoint.txt");
  text[text.size() / 2] = text[text.size() / 2] == '1' ? '2' : '1';
  std::ofstream(copy / "checkpoint.txt", std::ios::trunc) << text;
  refused_unchanged(copy, "checkpoint.txt:");

  fresh_copy();
  std::ofstream(copy / "scene.toml", std::ios::app) << "[box]\nL = 13.0\n";
  refused_unchanged(copy, "scene.toml");

  fresh_copy();
  std::ofstream(copy / "packings/jammed.pack", std::ios::app) << "not a cell\n";
  refused_unchanged(copy, "jammed.pack");

  fresh_copy();
  fs::remove(copy / ".budjam-run");
  refused_unchanged(copy, "not a budjam run directory");

  // Nor does a refused resume create the list of temporaries where there was none.
  fresh_copy();
  fs::remove(copy / ".budjam-temporaries");
  std::ofstream(copy / "scene.toml", std::ios::app) << "[box]\nL = 13.0\n";
  refused_unchanged(copy, "scene.toml");
  fs::remove(copy / "checkpoint.txt");
  refused_unchanged(copy, "no checkpoint.txt");

  // A temporary a killed writer recorded is removed only by a resume that goes ahead.
  fresh_copy();
  const Result r = grow("--resume " + q(copy) + " --quiet");
  INFO(r.err);
  CHECK(r.code == 0);
  for (const auto& e : fs::recursive_directory_iterator(copy))
    CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("resume cross-checks a checkpoint edited with its checksum recomputed against the logs and packings",
          "[grow_cli]") {
  const fs::path run = stopped_after_jamming("edited");
  const std::vector<std::string> lines = lines_of(slurp(run / "checkpoint.txt"));
  const fs::path copy = work_dir() / "edited_copy";
  auto edited = [&](const std::function<void(std::vector<std::string>&)>& edit, const std::string& expect) {
    fs::remove_all(copy);
    fs::copy(run, copy, fs::copy_options::recursive);
    std::vector<std::string> v = lines;
    edit(v);
    REQUIRE(v != lines);
    write_with_checksum(copy / "checkpoint.txt", v);
    refused_unchanged(copy, expect);
  };
  const std::size_t state = line_starting(lines, "state "), counters = line_starting(lines, "counters ");
  const std::size_t jamming = line_starting(lines, "jamming "), buds = line_starting(lines, "buds ");
  const std::size_t run_log = line_starting(lines, "observer run_log ");
  auto at = [](std::size_t k) { return "checkpoint.txt:" + std::to_string(k + 1) + ": "; };

  // A step counter one ahead (attempts and accepted kept consistent): steps.csv has one row fewer.
  edited(
      [&](auto& v) {
        auto s = words_of(v[state]), c = words_of(v[counters]);
        s[5] = std::to_string(std::stol(s[5]) + 1), s[6] = std::to_string(std::stol(s[6]) + 1);
        c[1] = std::to_string(std::stol(c[1]) + 1);
        v[state] = joined(s), v[counters] = joined(c);
      },
      at(state) + "step ");
  // One division more than divisions.csv holds.
  edited(
      [&](auto& v) {
        auto c = words_of(v[counters]);
        c[5] = std::to_string(std::stol(c[5]) + 1);
        v[counters] = joined(c);
      },
      at(counters) + "divisions ");
  // Z_J = 9.5, which packings/jammed.pack does not have.
  edited(
      [&](auto& v) {
        auto j = words_of(v[jamming]);
        j[14] = "9.5";
        v[jamming] = joined(j);
      },
      at(jamming) + "Z = 9.5 disagrees with packings/jammed.pack");
  // What only the cells of packings/jammed.pack can tell: N_u, and n_J from their N_nr; and the count of
  // buds tagged there, which the checkpoint's own tags tell.
  for (const auto& [field, value, expect] :
       std::vector<std::tuple<std::size_t, std::string, std::string>>{{12, "20", "N_u = 20, but the cells of "},
                                                                      {19, "0.5", "n_J = 0.5, but its N_nr"},
                                                                      {20, "1", "1 buds tagged at jamming"}}) {
    INFO(expect);
    REQUIRE(words_of(lines[jamming])[static_cast<std::size_t>(field)] != value);
    edited(
        [&](auto& v) {
          auto j = words_of(v[jamming]);
          j[field] = value;
          v[jamming] = joined(j);
        },
        at(jamming) + expect);
  }
  // The divisions since jamming, one more than the last row of steps.csv says.
  edited(
      [&](auto& v) {
        auto s = words_of(v[state]);
        s[8] = std::to_string(std::stol(s[8]) + 1);
        v[state] = joined(s);
      },
      at(state) + std::to_string(std::stol(words_of(lines[state])[8]) + 1) +
          " divisions since jamming, but the last row");
  // A target's φ_target (φ_J + Δφ) and its χ_c (its row of steps.csv).
  const std::size_t target = line_starting(lines, "targets ") + 1;
  REQUIRE(std::stoi(words_of(lines[target - 1])[1]) > 0);
  for (const auto& [field, value, expect] : std::vector<std::tuple<long, std::string, std::string>>{
           {2, "0.835", "phi_target = 0.835, but phi_J + dphi"}, {-2, "0.9", "chi_c = 0.9 at step"}}) {
    INFO(expect);
    edited(
        [&](auto& v) {
          auto t = words_of(v[target]);
          t[field >= 0 ? static_cast<std::size_t>(field) : t.size() - static_cast<std::size_t>(-field)] = value;
          v[target] = joined(t);
        },
        at(target) + expect);
  }
  // A cell of the accepted state's packing grown a little: the last row of steps.csv logged another state.
  const std::size_t packing = line_starting(lines, "packing ");
  edited(
      [&](auto& v) {
        auto c = words_of(v[packing + 1]);
        c[3] = budjam::io::format_double(std::stod(c[3]) + 0.01);  // b
        v[packing + 1] = joined(c);
      },
      at(state) + "the packing has N = ");
  // A tag that ended as completed said divided, or the other way round: as many events, but not
  // that bud's own (bud_events.csv).
  const std::size_t tags = static_cast<std::size_t>(std::stoi(words_of(lines[buds])[2]));
  std::size_t ended = 0;
  for (std::size_t k = buds + 1; k <= buds + tags && !ended; ++k)
    if (words_of(lines[k])[3] == "1" || words_of(lines[k])[3] == "2") ended = k;
  REQUIRE(ended);  // the run goes on past jamming: some tagged bud completed or divided
  edited(
      [&](auto& v) {
        auto t = words_of(v[ended]);
        t[3] = t[3] == "1" ? "2" : "1";
        v[ended] = joined(t);
      },
      "bud_events.csv.partial: the rows of bud ");
  // A tagged bud's size at jamming.
  REQUIRE(std::stoi(words_of(lines[buds])[2]) > 0);
  edited(
      [&](auto& v) {
        auto t = words_of(v[buds + 1]);
        t[1] = "0.5";
        v[buds + 1] = joined(t);
      },
      at(buds + 1) + "tagged bud");
  // steps.csv's recorded length 50 rows short (still a line end).
  edited(
      [&](auto& v) {
        auto b = words_of(v[run_log + 1]);
        const std::string steps = slurp(run / "steps.csv.partial").substr(0, std::stoul(b[0]));
        std::size_t cut = steps.size() - 1;
        for (int k = 0; k < 50; ++k) cut = steps.rfind('\n', cut - 1);
        b[0] = std::to_string(cut + 1);
        v[run_log + 1] = joined(b);
      },
      at(state) + "step ");
  // The recorded length of trials.csv and of bud_events.csv one row short (still a line end): the
  // checkpoint's attempts and its tagged buds count their rows.
  for (const std::string log : {"trials", "bud_events"}) {
    const std::size_t section = line_starting(lines, "observer " + log + " ");
    edited(
        [&](auto& v) {
          auto b = words_of(v[section + 1]);
          const std::string text = slurp(run / (log + ".csv.partial")).substr(0, std::stoul(b[0]));
          b[0] = std::to_string(text.rfind('\n', text.size() - 2) + 1);
          v[section + 1] = joined(b);
        },
        log + ".csv.partial: ");
  }
  // A cell of packings/jammed.pack moved by a tenth of a diameter, its meta lines kept: its contacts
  // are no longer the record's.
  fs::remove_all(copy);
  fs::copy(run, copy, fs::copy_options::recursive);
  std::vector<std::string> pack = lines_of(slurp(copy / "packings" / "jammed.pack"));
  const std::size_t cell = static_cast<std::size_t>(
      std::find_if(pack.begin(), pack.end(), [](const std::string& l) { return !l.empty() && std::isdigit(l[0]); }) -
      pack.begin());
  REQUIRE(cell < pack.size());
  auto w = words_of(pack[cell]);
  w[2] = budjam::io::format_double(std::stod(w[2]) + 0.1);  // x
  pack[cell] = joined(w);
  std::ofstream out(copy / "packings" / "jammed.pack", std::ios::trunc);
  for (const auto& l : pack) out << l << "\n";
  out.close();
  refused_unchanged(copy, at(jamming), "but the cells of packings/jammed.pack give");
}

TEST_CASE("a relaxation in progress that the resumed attempt does not make is refused, the run directory unchanged",
          "[grow_cli]") {
  // Only the resumed attempt can tell that a checkpoint's relaxation in progress is not its own;
  // the logs are cut back, and checkpoints written, only after it has.
  const fs::path scene =
      small_scene("pending", "[observe]\ncheckpoint_every = 0\ncheckpoint_evaluations = 300\n", "[1e-3]");
  const fs::path run = work_dir() / "pending";
  std::vector<std::string> lines;
  for (int attempt = 0; attempt < 6 && lines.empty(); ++attempt) {
    const int status = signal_when(scene, run, SIGTERM, [&] {
      return slurp(run / "checkpoint.txt").find("\nrelaxation 1 ") != std::string::npos;
    });
    if (WIFEXITED(status) && WEXITSTATUS(status) == 143 &&
        slurp(run / "checkpoint.txt").find("\nrelaxation 1 ") != std::string::npos)
      lines = lines_of(slurp(run / "checkpoint.txt"));
  }
  REQUIRE(!lines.empty());
  const std::size_t k = line_starting(lines, "relaxation 1 ");
  const fs::path copy = work_dir() / "pending_copy";
  auto edited = [&](std::size_t line, std::size_t word, const std::function<std::string(const std::string&)>& to,
                    const std::string& expect) {
    fs::remove_all(copy);
    fs::copy(run, copy, fs::copy_options::recursive);
    std::vector<std::string> v = lines;
    std::istringstream is(v[line]);
    std::vector<std::string> w{std::istream_iterator<std::string>(is), {}};
    w.at(word) = to(w.at(word));
    std::string joined;
    for (const auto& x : w) joined += (joined.empty() ? "" : " ") + x;
    REQUIRE(joined != v[line]);
    v[line] = joined;
    write_with_checksum(copy / "checkpoint.txt", v);
    refused_unchanged(copy, "checkpoint.txt: ", expect);  // the refusal names the checkpoint
  };
  SECTION("another growth attempt's") {
    // The reader takes the attempts made (a deferred trial resumed) or the next (a trial grown).
    std::istringstream state(lines[line_starting(lines, "state ")]);
    std::vector<std::string> w{std::istream_iterator<std::string>(state), {}};
    const long made = std::stol(w.at(6));
    edited(
        k, 2, [&](const std::string& a) { return std::to_string(std::stol(a) == made ? made + 1 : made); },
        "its relaxation in progress");
  }
  SECTION("a relaxation the attempt does not make") {
    edited(
        k, 3, [](const std::string& i) { return i == "2" ? "1" : "2"; }, "made no relaxation");
  }
  SECTION("cells moved past the reach of its neighbour list") {
    edited(
        k + 2, 0, [](const std::string& x) { return std::to_string(std::stod(x) + 1.0); },
        "does not fit its neighbour list");
  }
}

TEST_CASE("resume refuses a scene with any key edited, and a P0 edit even with the scene hash recomputed",
          "[grow_cli]") {
  using namespace budjam;
  const fs::path run = stopped_after_jamming("keys");
  const std::string text = slurp(run / "scene.toml");
  const Scene original = io::parse_scene(text, "scene.toml");
  const fs::path copy = work_dir() / "keys_copy";
  auto fresh_copy = [&] {
    fs::remove_all(copy);
    fs::copy(run, copy, fs::copy_options::recursive);
  };
  std::size_t edited_keys = 0;
  for (const SceneKey& k : scene_keys()) {
    if (k.key() == "minimiser.threads") continue;  // not physics: a resume may use other threads
    // The first of a few plausible edits of the key that still makes a valid scene.
    std::optional<Scene> changed;
    const SceneValue v = k.get(original);
    std::vector<SceneValue> candidates;
    if (const auto* b = std::get_if<bool>(&v)) candidates.push_back(!*b);
    if (const auto* i = std::get_if<std::int64_t>(&v)) candidates = {*i + 1, *i - 1};
    if (const auto* d = std::get_if<double>(&v)) candidates = {*d * 1.25, *d * 0.8, *d + 1, *d - 1};
    if (const auto* s = std::get_if<std::string>(&v)) {
      for (const auto& c : k.choices)
        if (c != *s) candidates.push_back(c);
      if (k.type == KeyType::text) candidates.push_back(*s + "x");
      if (k.type == KeyType::real_or_none) candidates.push_back(1e-3);
    }
    if (const auto* l = std::get_if<std::vector<double>>(&v)) {
      auto longer = *l;
      longer.push_back(l->empty() ? 0.5 : l->back() * 2);
      candidates.push_back(longer);
      if (!l->empty()) candidates.push_back(std::vector<double>(l->begin(), l->end() - 1));
    }
    if (k.type == KeyType::real_or_none && std::holds_alternative<double>(v)) candidates.push_back(std::string("none"));
    // Keys valid only with another: random seeds need at least one cell, a crossing step the continuation.
    const std::vector<std::function<void(Scene&)>> companions{
        [](Scene&) {},
        [](Scene& s) {
          find_scene_key("init.kind")->set(s, std::string("random_seeds"));
          if (s.n_seeds == 0) s.n_seeds = 1;
        },
        [](Scene& s) { s.continuation = true; }};
    for (const SceneValue& c : candidates) {
      if (c == v) continue;  // 0 × 1.25 is no edit
      for (const auto& companion : companions) {
        Scene s = original;
        try {
          k.set(s, c);
          companion(s);
          validate(s);
          changed = s;
          break;
        } catch (const std::exception&) {}
      }
      if (changed) break;
    }
    INFO(k.key());
    REQUIRE(changed);
    fresh_copy();
    std::ofstream(copy / "scene.toml", std::ios::trunc) << io::scene_to_toml(*changed);
    refused_unchanged(copy, "scene.toml has changed");
    ++edited_keys;
  }
  CHECK(edited_keys + 1 == scene_keys().size());

  // growth.P0 edited and the checkpoint's scene hash (and checksum) recomputed: the saved packings,
  // grown under the old P0, disagree.
  fresh_copy();
  Scene other = original;
  other.P0 = 2e-3;
  std::ofstream(copy / "scene.toml", std::ios::trunc) << io::scene_to_toml(other);
  std::vector<std::string> v = lines_of(slurp(run / "checkpoint.txt"));
  char hash[20];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(io::scene_hash(other)));
  v[line_starting(v, "scene ")] = std::string("scene ") + hash;
  write_with_checksum(copy / "checkpoint.txt", v);
  refused_unchanged(copy, "P0 = 0.002 disagrees with packings/jammed.pack");
}

TEST_CASE("--overwrite after a run with every observer on leaves no file of the earlier run", "[grow_cli]") {
  const std::string all =
      "[observe]\ncheckpoint_every = 10\ntrials = true\nrigidity_events = true\n"
      "trajectory_every = 20\n[observe.moduli]\nat_jamming = true\nat_targets = true\n"
      "[observe.dos]\nat_jamming = true\nevery = 50\n";
  const std::string none = "[observe]\nbud_events = false\n";
  const fs::path everything = small_scene("observers_all", all), nothing = small_scene("observers_none", none);
  const fs::path dir = work_dir() / "observers", ref = work_dir() / "observers_ref";
  REQUIRE(grow(q(everything) + " --quiet --out " + q(dir)).code == 0);
  const auto first = snapshot(dir);
  for (const char* f : {"trajectory.xyz", "trials.csv", "rigidity_events.csv", "moduli.csv", "dos.csv"}) {
    INFO(f);
    CHECK(first.count(f) == 1);
  }
  std::ofstream(dir / "notes.txt") << "mine\n";
  // What `budjam export trajectory.xyz --format gsd` writes beside the trajectory belongs to the run.
  std::ofstream(dir / "trajectory.gsd") << "frames\n";
  REQUIRE(grow(q(nothing) + " --quiet --overwrite --out " + q(dir)).code == 0);
  REQUIRE(grow(q(nothing) + " --quiet --out " + q(ref)).code == 0);
  auto after = snapshot(dir), expected = snapshot(ref);
  CHECK(after["notes.txt"] == "mine\n");
  after.erase("notes.txt");
  std::vector<std::string> names_after, names_expected;
  for (const auto& [name, content] : after) names_after.push_back(name);
  for (const auto& [name, content] : expected) names_expected.push_back(name);
  CHECK(names_after == names_expected);
}

TEST_CASE("a run killed while it finished, its logs renamed and no summary.json yet, resumes to the uninterrupted run",
          "[grow_cli][.slow]") {
  const fs::path scene = small_scene("finish", "[observe]\ncheckpoint_every = 0\ntrials = true\n");
  const fs::path ref = work_dir() / "finish_ref", dir = work_dir() / "finish_run";
  REQUIRE(grow(q(scene) + " --quiet --set box.L=12 --out " + q(ref)).code == 0);
  signal_with_checkpoint(scene, dir, SIGTERM, {0.3, 0.1, 0.0});
  REQUIRE_FALSE(fs::exists(dir / "summary.json"));
  // The finish renames each log, then writes summary.json: a kill between leaves some logs renamed.
  fs::rename(dir / "steps.csv.partial", dir / "steps.csv");
  fs::rename(dir / "divisions.csv.partial", dir / "divisions.csv");
  resumes_to(dir, ref);
  CHECK_FALSE(fs::exists(dir / "steps.csv.partial"));
  CHECK_FALSE(fs::exists(dir / "checkpoint.txt"));
}

TEST_CASE("--overwrite keeps a user's files and directories in packings/ and removes the run's derived files",
          "[grow_cli]") {
  const fs::path scene = small_scene("overwrite_packings");
  const fs::path dir = work_dir() / "overwrite_packings";
  fs::remove_all(dir);
  REQUIRE(grow(q(scene) + " --quiet --out " + q(dir)).code == 0);
  REQUIRE(fs::exists(dir / "packings/target_1.pack"));
  // The run's own: a derived file budjam writes beside a packing.
  REQUIRE(budjam::testing::run_budjam("moduli " + q(dir / "packings/target_1.pack") + " --quiet --out " +
                                      q(dir / "packings/target_1.moduli"))
              .code == 0);
  REQUIRE(fs::exists(dir / "packings/target_1.moduli.json"));
  // The user's: a backup, another suffix, an editor's backup, a directory named like a packing.
  fs::copy_file(dir / "packings/jammed.pack", dir / "packings/jammed.pack.bak");
  std::ofstream(dir / "packings/target_7.mine") << "n\n";
  std::ofstream(dir / "packings/target_0.pack~") << "n\n";
  // Named like the run's, but with a number the run never writes (a leading zero, beyond 64 bits).
  std::ofstream(dir / "packings/target_01.pack") << "n\n";
  std::ofstream(dir / "packings/target_99999999999999999999.pack") << "n\n";
  fs::create_directories(dir / "packings/phi2.d");
  std::ofstream(dir / "packings/phi2.d/notes") << "mine\n";
  const std::string backup = slurp(dir / "packings/jammed.pack.bak");
  const Result r = grow(q(scene) + " --quiet --overwrite --out " + q(dir));
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(slurp(dir / "packings/jammed.pack.bak") == backup);
  CHECK(slurp(dir / "packings/target_7.mine") == "n\n");
  CHECK(slurp(dir / "packings/target_0.pack~") == "n\n");
  CHECK(slurp(dir / "packings/target_01.pack") == "n\n");
  CHECK(slurp(dir / "packings/target_99999999999999999999.pack") == "n\n");
  CHECK(slurp(dir / "packings/phi2.d/notes") == "mine\n");
  CHECK_FALSE(fs::exists(dir / "packings/target_1.moduli.json"));
}
