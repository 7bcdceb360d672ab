// The run directory: what budjam claims, what it refuses, what it deletes, and one writer at a time.
#include "budjam/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/run_directory.hpp"

#include <catch2/catch.hpp>
#include "scratch.hpp"

#include <unistd.h>
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

}  // namespace

TEST_CASE("a fresh run claims a new or empty directory and marks it", "[run_directory]") {
  const fs::path d = fresh("new");
  {
    const RunDirectory run = RunDirectory::create(d, false);
    CHECK(run.path() == d);
    CHECK(is_run_directory(d));
    CHECK(slurp(d / run_files::lock).find("pid " + std::to_string(::getpid())) == 0);
  }
  const fs::path e = fresh("empty");
  fs::create_directories(e);
  const RunDirectory run = RunDirectory::create(e, false);
  CHECK(is_run_directory(e));
}

TEST_CASE("a non-empty directory without the marker is refused and left untouched", "[run_directory]") {
  // scene.toml alone does not make a run: a user's directory that happens to hold one is foreign
  const fs::path d = fresh("foreign");
  put(d / "scene.toml", "x");
  put(d / "thesis.tex", "precious");
  for (bool overwrite : {false, true}) {
    CHECK_THROWS_AS(RunDirectory::create(d, overwrite), InputError);
    CHECK_THROWS_WITH(RunDirectory::create(d, overwrite), Contains("not a budjam run directory"));
    CHECK(slurp(d / "thesis.tex") == "precious");
    CHECK(slurp(d / "scene.toml") == "x");
    CHECK_FALSE(fs::exists(d / run_files::marker));
    CHECK_FALSE(fs::exists(d / run_files::lock));
  }
  CHECK_THROWS_WITH(RunDirectory::resume(d), Contains("not a budjam run directory"));
  const fs::path file = fresh("a-file");
  put(file, "x");
  CHECK_THROWS_WITH(RunDirectory::create(file, true), Contains("is not a directory"));
}

TEST_CASE("an existing run is replaced only with overwrite, and only budjam's entries go", "[run_directory]") {
  const fs::path d = fresh("rerun");
  { RunDirectory::create(d, false); }
  for (const char* f :
       {"scene.toml", "summary.json", "timing.json", "checkpoint.txt", "steps.csv", "divisions.csv.partial",
        "bud_events.csv", "moduli.csv", "dos.csv.partial", "rigidity_events.csv", "trials.csv.partial",
        "packings/jammed.pack", "packings/target_12.pack", "packings/target_1.moduli.json", "packings/phi2.dos.csv",
        "packings/.target_1.pack.tmp-abc123", "spectra/step_40.dos.json", ".summary.json.tmp-XyZ123"})
    put(d / f, "old");
  for (const char* f :
       {"notes.txt", "packings/mine.pack", "packings/target_x.pack", "spectra/plot.py", "steps.csv.bak"})
    put(d / f, "mine");

  CHECK_THROWS_WITH(RunDirectory::create(d, false), Contains("--overwrite"));
  CHECK(slurp(d / "summary.json") == "old");  // refused: nothing touched

  CHECK(remove_run_outputs(d) == std::vector<std::string>{"notes.txt", "packings/mine.pack", "packings/target_x.pack",
                                                          "spectra/plot.py", "steps.csv.bak"});
  for (const char* f :
       {"notes.txt", "packings/mine.pack", "packings/target_x.pack", "spectra/plot.py", "steps.csv.bak"})
    CHECK(slurp(d / f) == "mine");
  for (const char* f : {"scene.toml", "summary.json", "packings/jammed.pack", "packings/target_1.moduli.json",
                        "packings/.target_1.pack.tmp-abc123", "spectra/step_40.dos.json", ".summary.json.tmp-XyZ123"})
    CHECK_FALSE(fs::exists(d / f));

  put(d / "summary.json", "old");
  const RunDirectory again = RunDirectory::create(d, true);
  CHECK_FALSE(fs::exists(d / "summary.json"));
  CHECK(is_run_directory(d));
  CHECK(slurp(d / "notes.txt") == "mine");
}

TEST_CASE("one writer at a time: a second claim names the holder", "[run_directory]") {
  const fs::path d = fresh("locked");
  const RunDirectory first = RunDirectory::create(d, false);
  // flock(2) locks belong to the open file description, so a second claim from this process
  // conflicts exactly as one from another process would.
  const std::string holder = "pid " + std::to_string(::getpid());
  CHECK_THROWS_AS(RunDirectory::create(d, true), InputError);
  CHECK_THROWS_WITH(RunDirectory::create(d, true), Contains("another budjam process") && Contains(holder));
  CHECK_THROWS_WITH(RunDirectory::resume(d), Contains(holder));
  CHECK(is_run_directory(d));  // the refused claims removed nothing
}

TEST_CASE("the lock is released when the writer goes", "[run_directory]") {
  const fs::path d = fresh("released");
  { const RunDirectory first = RunDirectory::create(d, false); }
  CHECK_NOTHROW(RunDirectory::resume(d));
}

TEST_CASE("resuming removes the temporaries a killed writer left", "[run_directory]") {
  const fs::path d = fresh("stale");
  { RunDirectory::create(d, false); }
  put(d / "packings/.target_1.pack.tmp-Ab12Cd", "half");
  put(d / ".checkpoint.txt.tmp-000000", "half");
  put(d / "packings/target_0.pack", "whole");
  const RunDirectory run = RunDirectory::resume(d);
  CHECK_FALSE(fs::exists(d / "packings/.target_1.pack.tmp-Ab12Cd"));
  CHECK_FALSE(fs::exists(d / ".checkpoint.txt.tmp-000000"));
  CHECK(slurp(d / "packings/target_0.pack") == "whole");
}

TEST_CASE("run packing names", "[run_directory]") {
  CHECK(run_files::packing("jammed") == fs::path("packings/jammed.pack"));
  CHECK(run_files::packing(run_files::target_stem(3)) == fs::path("packings/target_3.pack"));
  CHECK(run_files::is_run_packing_stem("phi2"));
  CHECK(run_files::is_run_packing_stem("target_10"));
  CHECK_FALSE(run_files::is_run_packing_stem("target_"));
  CHECK_FALSE(run_files::is_run_packing_stem("target_1a"));
  CHECK_FALSE(run_files::is_run_packing_stem("jammed2"));
  CHECK(run_files::is_temporary(".jammed.pack.tmp-AbC123"));
  CHECK_FALSE(run_files::is_temporary("jammed.pack"));
}
