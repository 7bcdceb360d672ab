// The run directory: what budjam claims, what it refuses, what it deletes, and one writer at a time.
#include "budjam/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/export.hpp"
#include "io/run_directory.hpp"

#include <catch2/catch.hpp>
#include "scratch.hpp"

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <fstream>

namespace fs = std::filesystem;
using namespace budjam;
using namespace budjam::io;
using budjam::testing::slurp;
using budjam::testing::work_dir;
using Catch::Matchers::Contains;

namespace {

fs::path fresh(const std::string& name) {
  const fs::path d = work_dir() / name;
  fs::remove_all(d);
  return d;
}

void put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// What a run of every observer may write (the growth command derives it from the observers'
// declarations: tools::run_owned_entries).
const OwnedEntries kOwned = [] {
  OwnedEntries owned{"scene.toml", "checkpoint.txt", "summary.json",        "timing.json",
                     "steps.csv",  "divisions.csv",  "bud_events.csv",      "moduli.csv",
                     "dos.csv",    "trials.csv",     "rigidity_events.csv", "trajectory.xyz"};
  for (const char* stem : {"jammed", "phi2", "target_#"})
    for (auto& e : run_files::entries_with_suffixes("packings", stem, run_files::packing_suffixes()))
      owned.push_back(e);
  for (auto& e : run_files::entries_with_suffixes("spectra", "step_#", run_files::spectrum_suffixes()))
    owned.push_back(e);
  return owned;
}();

}  // namespace

TEST_CASE("a fresh run claims a new or empty directory and marks it", "[run_directory]") {
  const fs::path d = fresh("new");
  {
    const RunDirectory run = RunDirectory::create(d, false, kOwned);
    CHECK(run.path() == d);
    CHECK(is_run_directory(d));
    CHECK(slurp(d / run_files::lock).find("pid " + std::to_string(::getpid())) == 0);
  }
  const fs::path e = fresh("empty");
  fs::create_directories(e);
  const RunDirectory run = RunDirectory::create(e, false, kOwned);
  CHECK(is_run_directory(e));
}

TEST_CASE("a non-empty directory without the marker is refused and left untouched", "[run_directory]") {
  // scene.toml alone does not make a run: a user's directory that happens to hold one is foreign
  const fs::path d = fresh("foreign");
  put(d / "scene.toml", "x");
  put(d / "thesis.tex", "precious");
  for (bool overwrite : {false, true}) {
    CHECK_THROWS_AS(RunDirectory::create(d, overwrite, kOwned), InputError);
    CHECK_THROWS_WITH(RunDirectory::create(d, overwrite, kOwned), Contains("not a budjam run directory"));
    CHECK(slurp(d / "thesis.tex") == "precious");
    CHECK(slurp(d / "scene.toml") == "x");
    CHECK_FALSE(fs::exists(d / run_files::marker));
    CHECK_FALSE(fs::exists(d / run_files::lock));
  }
  CHECK_THROWS_WITH(RunDirectory::resume(d, kOwned), Contains("not a budjam run directory"));
  const fs::path file = fresh("a-file");
  put(file, "x");
  CHECK_THROWS_WITH(RunDirectory::create(file, true, kOwned), Contains("is not a directory"));
}

TEST_CASE("an existing run is replaced only with overwrite, and only the declared entries go", "[run_directory]") {
  const fs::path d = fresh("rerun");
  { RunDirectory::create(d, false, kOwned); }
  for (const char* f :
       {"scene.toml", "summary.json", "timing.json", "checkpoint.txt", "steps.csv", "divisions.csv.partial",
        "bud_events.csv", "moduli.csv", "dos.csv.partial", "rigidity_events.csv", "trials.csv.partial",
        "trajectory.xyz", "packings/jammed.pack", "packings/target_12.pack", "packings/target_1.moduli.json",
        "packings/phi2.dos.csv", "spectra/step_40.dos.json"})
    put(d / f, "old");
  // A user's files, also those merely named like budjam's temporaries: never removed by pattern.
  const std::vector<std::string> mine{".summary.json.tmp-XyZ123",
                                      "notes.txt",
                                      "packings/.target_1.pack.tmp-abc123",
                                      "packings/jammed.pack.bak",
                                      "packings/mine.pack",
                                      "packings/target_0.pack~",
                                      "packings/target_7.mine",
                                      "packings/target_x.pack",
                                      "spectra/plot.py",
                                      "spectra/step_40.dos.json.orig",
                                      "steps.csv.bak"};
  for (const auto& f : mine) put(d / f, "mine");

  CHECK_THROWS_WITH(RunDirectory::create(d, false, kOwned), Contains("--overwrite"));
  CHECK(slurp(d / "summary.json") == "old");  // refused: nothing touched

  CHECK(remove_run_outputs(Directory::open(d, false), kOwned) == mine);
  for (const auto& f : mine) CHECK(slurp(d / f) == "mine");
  for (const char* f : {"scene.toml", "summary.json", "trajectory.xyz", "packings/jammed.pack",
                        "packings/target_1.moduli.json", "spectra/step_40.dos.json"})
    CHECK_FALSE(fs::exists(d / f));

  put(d / "summary.json", "old");
  const RunDirectory again = RunDirectory::create(d, true, kOwned);
  CHECK_FALSE(fs::exists(d / "summary.json"));
  CHECK(is_run_directory(d));
  CHECK(slurp(d / "notes.txt") == "mine");
}

TEST_CASE("in packings/ only the run's stems with budjam's own suffixes are the run's", "[run_directory]") {
  const fs::path d = fresh("packings_owned");
  { RunDirectory::create(d, false, kOwned); }
  const std::vector<std::string> owned{"packings/jammed.pack",    "packings/target_1.moduli.json",
                                       "packings/phi2.dos.csv",   "packings/target_0.rigidity.json",
                                       "packings/jammed.svg",     "packings/target_3.gsd",
                                       "spectra/step_40.dos.json"};
  const std::vector<std::string> mine{"packings/jammed.pack.bak", "packings/target_0.pack~", "packings/target_7.mine",
                                      "packings/phi2.d/notes", "packings/jammed.moduli.json.old"};
  for (const auto& f : owned) put(d / f, "old");
  for (const auto& f : mine) put(d / f, "mine");
  // A user's directory named like a stem with another suffix does not make the claim refuse.
  const RunDirectory again = RunDirectory::create(d, true, kOwned);
  for (const auto& f : mine) CHECK(slurp(d / f) == "mine");
  for (const auto& f : owned) {
    INFO(f);
    CHECK_FALSE(fs::exists(d / f));
  }
}

TEST_CASE("every export format's file beside a run packing is the run's: --overwrite removes it", "[run_directory]") {
  const fs::path d = fresh("exports_owned");
  { RunDirectory::create(d, false, kOwned); }
  std::vector<std::string> exported;
  for (const budjam::io::ExportFormat& f : budjam::io::export_formats())
    exported.push_back("packings/jammed." + std::string(f.name));
  REQUIRE(exported.size() >= 3);
  for (const auto& f : exported) put(d / f, "old");
  { RunDirectory::create(d, true, kOwned); }
  for (const auto& f : exported) {
    INFO(f);
    CHECK_FALSE(fs::exists(d / f));
  }
}

TEST_CASE("a directory at a name the run owns in packings/ is refused before anything changes", "[run_directory]") {
  const fs::path d = fresh("packings_wrong_kind");
  { RunDirectory::create(d, false, kOwned); }
  put(d / "summary.json", "old");
  fs::create_directories(d / "packings/target_1.moduli.json");
  CHECK_THROWS_WITH(RunDirectory::create(d, true, kOwned), Contains("target_1.moduli.json") && Contains("is not"));
  CHECK(slurp(d / "summary.json") == "old");
}

TEST_CASE("one writer at a time: a second claim names the holder", "[run_directory]") {
  const fs::path d = fresh("locked");
  const RunDirectory first = RunDirectory::create(d, false, kOwned);
  // flock(2) locks belong to the open file description, so a second claim from this process
  // conflicts exactly as one from another process would.
  const std::string holder = "pid " + std::to_string(::getpid());
  CHECK_THROWS_AS(RunDirectory::create(d, true, kOwned), InputError);
  CHECK_THROWS_WITH(RunDirectory::create(d, true, kOwned), Contains("another budjam process") && Contains(holder));
  CHECK_THROWS_WITH(RunDirectory::resume(d, kOwned), Contains(holder));
  CHECK(is_run_directory(d));  // the refused claims removed nothing
}

TEST_CASE("a claim is checked again once the lock is held: a run finished meanwhile needs overwrite",
          "[run_directory]") {
  // create() asks check_claim before it takes the lock and again after: what another process put
  // in place in between is what the second answer sees.
  const fs::path d = fresh("raced");
  fs::create_directories(d);
  const Directory dir = Directory::open(d, false);
  CHECK_FALSE(check_claim(dir, false));  // empty: the first answer
  {
    const RunDirectory other = RunDirectory::create(d, false, kOwned);
    write_atomically(other.root(), run_files::summary, "{}\n");
  }
  CHECK_THROWS_WITH(check_claim(dir, false), Contains("holds a budjam run") && Contains("pass --overwrite"));
  CHECK(check_claim(dir, true));
  put(d / "thesis.tex", "precious");
  fs::remove(d / run_files::marker);
  CHECK_THROWS_WITH(check_claim(dir, true), Contains("not a budjam run directory"));
}

TEST_CASE("a claim to resume creates no list of temporaries; the first temporary does", "[run_directory]") {
  const fs::path d = fresh("no-list");
  { const RunDirectory first = RunDirectory::create(d, false, kOwned); }
  CHECK_FALSE(fs::exists(d / run_files::temporaries));
  RunDirectory run = RunDirectory::resume(d, kOwned);
  run.remove_recorded_temporaries();
  CHECK_FALSE(fs::exists(d / run_files::temporaries));
  write_atomically(run.root(), run_files::summary, "{}\n");
  CHECK(fs::is_regular_file(d / run_files::temporaries));
  CHECK(slurp(d / run_files::temporaries).empty());
}

TEST_CASE("the lock is released when the writer goes", "[run_directory]") {
  const fs::path d = fresh("released");
  { const RunDirectory first = RunDirectory::create(d, false, kOwned); }
  CHECK_NOTHROW(RunDirectory::resume(d, kOwned));
}

TEST_CASE("only the temporaries a writer recorded are removed when the run is claimed again", "[run_directory]") {
  const fs::path d = fresh("stale");
  // A writer that dies while two temporaries exist: they stay on disk, and in the list.
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    RunDirectory run = RunDirectory::create(d, false, kOwned);
    TempFile left(run.subdirectory(run_files::packings), "target_1.pack");
    TempFile also(run.root(), "checkpoint.txt");
    left.write("half");
    also.write("half");
    ::_exit(0);  // no destructor runs, as under SIGKILL
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  std::vector<std::string> recorded;
  for (const auto& e : fs::recursive_directory_iterator(d))
    if (e.path().filename().string().find(".tmp-") != std::string::npos)
      recorded.push_back(fs::relative(e.path(), d).string());
  REQUIRE(recorded.size() == 2);
  put(d / "packings/.target_2.pack.tmp-Ab12Cd", "a user's file named like a temporary");
  put(d / "packings/target_0.pack", "whole");
  RunDirectory run = RunDirectory::resume(d, kOwned);
  for (const auto& r : recorded) CHECK(fs::exists(d / r));  // resume validates before it removes anything
  run.remove_recorded_temporaries();
  for (const auto& r : recorded) CHECK_FALSE(fs::exists(d / r));
  CHECK(slurp(d / "packings/.target_2.pack.tmp-Ab12Cd") == "a user's file named like a temporary");
  CHECK(slurp(d / "packings/target_0.pack") == "whole");
  CHECK(slurp(d / run_files::temporaries).empty());
}

TEST_CASE("a temporary is removed on every way out, and the list empties when none is left", "[run_directory]") {
  const fs::path d = fresh("temporaries");
  RunDirectory run = RunDirectory::create(d, false, kOwned);
  {
    TempFile t(run.root(), "summary.json");
    t.write("{}");
    CHECK(fs::exists(t.path()));
    CHECK_FALSE(slurp(d / run_files::temporaries).empty());
    // destroyed without commit, as by an exception
  }
  CHECK(slurp(d / run_files::temporaries).empty());
  write_atomically(run.root(), "summary.json", "{}\n");
  CHECK(slurp(d / "summary.json") == "{}\n");
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(d)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{".budjam-lock", ".budjam-run", ".budjam-temporaries", "summary.json"});
}

TEST_CASE("a link or an entry of the wrong kind among a run's entries is refused and never followed",
          "[run_directory]") {
  const fs::path outside = fresh("outside");
  put(outside / "precious.txt", "foreign");
  fs::create_directories(outside / "foreign_dir");
  put(outside / "foreign_dir/jammed.pack", "foreign");
  auto snapshot = [&] { return slurp(outside / "precious.txt") + "|" + slurp(outside / "foreign_dir/jammed.pack"); };
  const std::string before = snapshot();
  // Each entry kind budjam uses, as a link to a foreign file (or directory).
  const std::vector<std::pair<std::string, fs::path>> attacks{
      {".budjam-lock", outside / "precious.txt"},         {".budjam-run", outside / "precious.txt"},
      {".budjam-temporaries", outside / "precious.txt"},  {"steps.csv.partial", outside / "precious.txt"},
      {"checkpoint.txt", outside / "precious.txt"},       {"scene.toml", outside / "precious.txt"},
      {"trajectory.xyz", outside / "precious.txt"},       {"packings", outside / "foreign_dir"},
      {"packings/jammed.pack", outside / "precious.txt"}, {"spectra", outside / "foreign_dir"}};
  for (const auto& [entry, target] : attacks) {
    for (bool resume : {false, true}) {
      const fs::path d = fresh("attacked");
      { RunDirectory::create(d, false, kOwned); }
      fs::create_directories(d / "packings");
      fs::remove(d / entry);
      fs::create_symlink(target, d / entry);
      INFO(entry << (resume ? " (resume)" : " (overwrite)"));
      try {
        if (resume)
          RunDirectory::resume(d, kOwned);
        else
          RunDirectory::create(d, true, kOwned);
        FAIL("the claim was accepted");
      } catch (const InputError& e) {
        const std::string what = e.what();
        CHECK(what.find("symbolic link") != std::string::npos);
        CHECK(what.find('\n') == std::string::npos);
      }
      CHECK(fs::is_symlink(d / entry));  // the link itself is left as it was
      CHECK(snapshot() == before);
    }
  }
  // The same entries as a second hard link of a foreign file: written in place, it would change that file.
  for (const char* entry : {".budjam-lock", ".budjam-temporaries", "steps.csv.partial", "checkpoint.txt"}) {
    for (bool resume : {false, true}) {
      const fs::path d = fresh("hard_linked");
      { RunDirectory::create(d, false, kOwned); }
      fs::remove(d / entry);
      fs::create_hard_link(outside / "precious.txt", d / entry);
      INFO(entry << (resume ? " (resume)" : " (overwrite)"));
      if (resume)
        CHECK_THROWS_WITH(RunDirectory::resume(d, kOwned), Contains(entry) && Contains("hard link"));
      else
        CHECK_THROWS_WITH(RunDirectory::create(d, true, kOwned), Contains(entry) && Contains("hard link"));
      CHECK(fs::hard_link_count(d / entry) == 2);
      CHECK(snapshot() == before);
    }
  }
  // Entries of the wrong kind: a directory where a log is expected, a file for packings/.
  for (const char* entry : {"steps.csv.partial", "packings"}) {
    const fs::path d = fresh("wrong_kind");
    { RunDirectory::create(d, false, kOwned); }
    if (std::string(entry) == "packings")
      put(d / entry, "a file");
    else
      fs::create_directories(d / entry);
    INFO(entry);
    CHECK_THROWS_WITH(RunDirectory::resume(d, kOwned), Contains(entry) && Contains("is not"));
    CHECK_THROWS_WITH(RunDirectory::create(d, true, kOwned), Contains(entry) && Contains("is not"));
    CHECK(fs::exists(d / entry));
  }
}

TEST_CASE("run packing names and owned-entry patterns", "[run_directory]") {
  CHECK(run_files::packing("jammed") == fs::path("packings/jammed.pack"));
  CHECK(run_files::packing(run_files::target_stem(3)) == fs::path("packings/target_3.pack"));
  CHECK(run_files::is_run_packing_stem("phi2"));
  CHECK(run_files::is_run_packing_stem("target_10"));
  CHECK_FALSE(run_files::is_run_packing_stem("target_"));
  CHECK_FALSE(run_files::is_run_packing_stem("target_1a"));
  CHECK_FALSE(run_files::is_run_packing_stem("jammed2"));
  CHECK(matches_pattern("target_#.*", "target_12.dos.json"));
  CHECK_FALSE(matches_pattern("target_#.*", "target_x.pack"));
  CHECK_FALSE(matches_pattern("target_#.*", "target_.pack"));
  // only numbers as budjam writes them: no leading zero, within 64 bits
  CHECK(matches_pattern("target_#.pack", "target_0.pack"));
  CHECK(matches_pattern("step_#.dos.json", "step_1000000000000000000.dos.json"));
  CHECK_FALSE(matches_pattern("target_#.pack", "target_01.pack"));
  CHECK_FALSE(matches_pattern("target_#.pack", "target_00.pack"));
  CHECK_FALSE(matches_pattern("step_#.dos.json", "step_007.dos.json"));
  CHECK_FALSE(matches_pattern("target_#.pack", "target_99999999999999999999.pack"));
  CHECK(matches_pattern("step_#.dos.*", "step_40.dos.csv"));
  CHECK_FALSE(matches_pattern("steps.csv", "steps.csv.bak"));
}
