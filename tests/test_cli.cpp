// The `budjam` executable's frame: exit codes, one-line errors on stderr, `validate`.
#include "io/packing_file.hpp"
#include "io/scene_file.hpp"

#include <catch2/catch.hpp>
#include "run_budjam.hpp"
#include "scratch.hpp"
#include "small_disk.hpp"

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>
#include <vector>

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

using Result = budjam::testing::BudjamRun;
using budjam::testing::run_budjam;
using budjam::testing::slurp;
using budjam::testing::work_dir;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = work_dir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

// An empty scratch directory `name` with a bin/ for stand-in programs (put first on PATH).
fs::path directory_with_bin(const std::string& name) {
  const fs::path dir = work_dir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "bin");
  return dir;
}

std::size_t lines_in(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

// Exactly one line "budjam: error: ...\n".
void require_one_error_line(const Result& r) {
  INFO(r.err);
  CHECK(lines_in(r.err) == 1);
  CHECK_THAT(r.err, StartsWith("budjam: error: "));
  CHECK(!r.err.empty());
  CHECK(r.err.back() == '\n');
}

}  // namespace

TEST_CASE("budjam validate on a bad scene exits 2 with one stderr line naming the key", "[cli]") {
  struct Case {
    std::string toml, key;
  };
  for (const Case& c :
       std::vector<Case>{{"[growth]\nP0 = -1e-3\n", "growth.P0: must be at least 1e-300"},
                         {"[growth]\nP00 = 1\n", "growth.P00: unknown key"},
                         {"[box]\nL = 1\n", "box.L: must exceed"},
                         {"[jamming]\ntargets = [0.01, 0.001]\n", "jamming.targets: must be strictly increasing"},
                         {"[cells]\nr0 = nan\n", "cells.r0: must be a finite number (got nan)"},
                         {"[growth\n", "bad.toml:1:"}}) {
    INFO(c.toml);
    const fs::path scene = write("bad.toml", c.toml);
    const Result r = run_budjam("validate '" + scene.string() + "'");
    CHECK(r.code == 2);
    require_one_error_line(r);
    CHECK_THAT(r.err, Contains(c.key));
    CHECK(r.out.empty());
  }
}

TEST_CASE("budjam validate prints the effective scene, which reads back to the same scene", "[cli]") {
  const fs::path scene =
      write("good.toml", "[run]\nname = \"cli\"\n[growth]\nP0 = 1e-3\n[jamming]\ntargets = [1e-3, 1e-2]\n");
  const Result r = run_budjam("validate '" + scene.string() + "' --set growth.P0=none --set run.seed=5");
  REQUIRE(r.code == 0);
  CHECK(r.err.empty());
  const budjam::Scene s = budjam::io::parse_scene(r.out, "stdout");
  CHECK_FALSE(s.P0.has_value());
  CHECK(s.seed == 5);
  CHECK(s.name == "cli");
  CHECK(budjam::io::scene_to_toml(s) == r.out);

  const Result j = run_budjam("validate --json '" + scene.string() + "'");
  REQUIRE(j.code == 0);
  const auto json = nlohmann::json::parse(j.out);
  CHECK(json["growth"]["P0"] == 1e-3);
  CHECK(json["jamming"]["targets"].size() == 2);
}

TEST_CASE("budjam validate checks packing files and names the corrupt line", "[cli]") {
  budjam::Packing p;
  p.box.L = 8;
  p.add_cell(4, 3.5, 0.1, 0.5, 0.002, -1);
  p.add_cell(4, 4.5, 0.2, 0.7, 0.002, -1);
  budjam::io::PackingMeta meta;
  meta.set("phase", "jammed");
  const std::string text = budjam::io::format_packing(p, meta);
  const fs::path good = write("good.pack", text);
  const Result ok = run_budjam("validate '" + good.string() + "'");
  REQUIRE(ok.code == 0);
  CHECK_THAT(ok.out, Contains("N = 2"));
  CHECK_THAT(ok.out, Contains("meta.phase = jammed"));

  const fs::path bad = write("bad.pack", text.substr(0, text.size() - 4));  // "end\n" cut off
  const Result r = run_budjam("validate '" + bad.string() + "'");
  CHECK(r.code == 2);
  require_one_error_line(r);
  CHECK_THAT(r.err, Contains("bad.pack:10: truncated"));
}

TEST_CASE("command-line mistakes exit 2 with one stderr line", "[cli]") {
  for (const std::string args : {"", "no-such-command", "validate", "validate a.toml b.toml", "validate --bogus x.toml",
                                 "validate missing-file.toml"}) {
    INFO(args);
    const Result r = run_budjam(args);
    CHECK(r.code == 2);
    require_one_error_line(r);
  }
}

TEST_CASE("budjam validate refuses an empty scene file and text that is not UTF-8: exit 2, one line naming the file",
          "[cli]") {
  for (const auto& [name, text, message] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"empty.toml", "", "empty.toml: empty scene file"},
           {"latin1.toml", "[run]\nname = \"caf\xe9\"\n", "latin1.toml:2:12: not valid UTF-8"}}) {
    INFO(name);
    const Result r = run_budjam("validate '" + write(name, text).string() + "'");
    CHECK(r.code == 2);
    require_one_error_line(r);
    CHECK_THAT(r.err, Contains(message));
    CHECK(r.out.empty());
  }
}

TEST_CASE("budjam validate --keys-markdown prints the knob table and needs no file", "[cli]") {
  const Result r = run_budjam("validate --keys-markdown");
  CHECK(r.code == 0);
  CHECK(r.err.empty());
  CHECK(r.out == budjam::io::scene_keys_markdown());
  CHECK_THAT(r.out, Contains("| `box.L` | number | `8.0` | ≤ 10000 so that"));
  const Result both = run_budjam("validate --keys-markdown x.toml");
  CHECK(both.code == 2);
  require_one_error_line(both);
}

TEST_CASE("--version and --help succeed on stdout", "[cli]") {
  const Result v = run_budjam("--version");
  CHECK(v.code == 0);
  CHECK_THAT(v.out, StartsWith("budjam "));
  CHECK(v.err.empty());
  const Result h = run_budjam("--help");
  CHECK(h.code == 0);
  CHECK_THAT(h.out, Contains("validate"));
  const Result hv = run_budjam("validate --help");
  CHECK(hv.code == 0);
  CHECK_THAT(hv.out, Contains("--set"));
}

TEST_CASE("a number outside its option's range exits 2 with one line naming the option, and nothing is written",
          "[cli]") {
  const std::string demo = std::string(std::getenv("BUDJAM_SOURCE_DIR")) + "/data/scenes/demo.toml";
  const fs::path pack = write("two.pack",
                              "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\n"
                              "cells id parent x y theta b gamma0\n0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n");
  // Every output goes into `outputs`, which must stay empty: no run directory, BASE.json or picture.
  const fs::path outputs = work_dir() / "range", out = outputs / "out";
  const auto quoted = budjam::testing::shell_quoted;
  const std::string p = quoted(pack), o = quoted(out);
  // CLI11 would read "-1" into an unsigned option as 2^64 − 1; a seed must also fit a TOML integer.
  for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
           {"grow " + demo + " --out " + o + " --seed -1", "--seed"},
           {"grow " + demo + " --out " + o + " --seed 9223372036854775808", "--seed"},
           {"grow " + demo + " --out " + o + " --threads -2", "--threads"},
           {"dos " + p + " --out " + o + " --bins -2", "--bins"},
           {"dos " + p + " --out " + o + " --dense-max-dof -1", "--dense-max-dof"},
           {"analyse " + p + " --out " + o + " --seed -5", "--seed"},
           {"analyse " + p + " --out " + o + " --main-L -3", "--main-L"},
           {"moduli " + p + " --check --out " + o + " --strain nan", "--strain"},
           {"moduli " + p + " --check --out " + o + " --strain 1e300", "--strain"},
           {"moduli " + p + " --check --out " + o + " --strain -1", "--strain"},
           {"moduli " + p + " --check --out " + o + " --strain 0", "--strain"},
           // rsvg-convert draws at most 32767 pixels a side
           {"render " + p + " -o " + quoted(outputs / "big.png") + " --scale 1e6", "--scale"},
           {"render " + p + " -o " + quoted(outputs / "big.svg") + " --png --scale 1e6", "--scale"},
           // a scale whose pixel count no integer holds
           {"render " + p + " -o " + quoted(outputs / "huge.png") + " --scale 1e300", "--scale"},
           // an SVG no viewer opens, one of no pixel, a scale that is no number
           {"render " + p + " -o " + quoted(outputs / "huge.svg") + " --scale 1e308", "--scale"},
           {"render " + p + " -o " + quoted(outputs / "tiny.svg") + " --scale 1e-300", "--scale"},
           {"render " + p + " -o " + quoted(outputs / "tiny.png") + " --scale 1e-300", "--scale"},
           {"render " + p + " -o " + quoted(outputs / "inf.svg") + " --scale inf", "--scale"},
           // more threads than a thread library creates would end the process where it cannot say why
           {"grow " + demo + " --out " + o + " --threads 100000", "--threads"},
           {"grow " + demo + " --out " + o + " --set minimiser.threads=100000", "minimiser.threads"},
           // a histogram no memory holds, and a count no integer holds
           {"dos " + p + " --out " + o + " --bins 99999999999", "--bins"},
           {"dos " + p + " --out " + o + " --bins 18446744073709551616", "--bins"},
           {"analyse " + p + " --out " + o + " --seed 18446744073709551616", "--seed"},
           {"analyse " + p + " --out " + o + " --main-L 0", "--main-L"},
           // refused before any packing is measured
           {"accuracy --packings A=" + p + " --out " + o + " --min-seconds nan", "--min-seconds"},
           {"accuracy --packings A=" + p + " --out " + o + " --min-seconds -1", "--min-seconds"},
           {"accuracy --packings A=" + p + " --out " + o + " --error-floor inf", "--error-floor"},
           {"accuracy --packings A=" + p + " A=" + p + " --out " + o, "--packings"}}) {
    fs::remove_all(outputs);
    fs::create_directory(outputs);
    const Result r = run_budjam(args);
    INFO(args << "\n" << r.err);
    CHECK(r.code == 2);
    require_one_error_line(r);
    CHECK_THAT(r.err, Contains(option + ": "));
    CHECK(r.err.find("internal") == std::string::npos);
    CHECK(r.err.find("-9223372036854775808") == std::string::npos);  // no integer overflow in the message
    CHECK(fs::is_empty(outputs));
  }
}

TEST_CASE(
    "render stopped by SIGINT while its converter runs leaves neither a temporary nor the output, and "
    "no converter behind; the converter starts with no signal blocked",
    "[cli]") {
  const fs::path dir = directory_with_bin("render_sigint");
  // A converter that says it has started (with its pid), takes its time, then writes: as an orphan it
  // would write after budjam removed its temporaries.
  const fs::path converter = dir / "bin" / "rsvg-convert", mark = dir / "started";
  std::ofstream(converter) << "#!/bin/sh\ngrep SigBlk /proc/self/status > blocked\necho $$ > "
                           << budjam::testing::shell_quoted(mark) << ".new\nmv " << budjam::testing::shell_quoted(mark)
                           << ".new " << budjam::testing::shell_quoted(mark)
                           << "\nsleep 2\necho drawn\necho late > late\n";
  fs::permissions(converter, fs::perms::owner_all);
  std::ofstream(dir / "p.pack")
      << "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\n"
         "cells id parent x y theta b gamma0\n0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n";
  const char* exe = std::getenv("BUDJAM_EXE");
  REQUIRE(exe);
  const std::string path = (dir / "bin").string() + ":" + std::getenv("PATH");
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::setenv("PATH", path.c_str(), 1);
    if (::chdir(dir.c_str()) == 0) ::execl(exe, "budjam", "render", "p.pack", "-o", "out.png", nullptr);
    ::_exit(127);
  }
  for (int k = 0; k < 600 && !fs::exists(mark); ++k) ::usleep(50000);
  REQUIRE(fs::exists(mark));
  ::kill(pid, SIGINT);  // budjam alone, as a batch scheduler signals it
  int status = 0;
  ::waitpid(pid, &status, 0);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGINT);
  // budjam killed and reaped its converter before it ended: it is gone and writes nothing later
  CHECK(::kill(std::stoi(slurp(mark)), 0) != 0);
  ::usleep(2500000);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  CHECK(left == std::vector<std::string>{"bin", "blocked", "p.pack", "started"});
  // budjam holds the fatal signals back only while it records the converter's pid: the converter
  // itself starts with none blocked
  CHECK(slurp(dir / "blocked") == "SigBlk:\t0000000000000000\n");
}

TEST_CASE(
    "render and export leave a user's files named like their temporaries alone; two exports to one base both land",
    "[cli]") {
  if (std::system("command -v rsvg-convert >/dev/null 2>&1") != 0 ||
      std::system("/usr/bin/python3 -c 'import gsd.hoomd' >/dev/null 2>&1") != 0) {
    WARN("rsvg-convert or python3-gsd not installed: skipped");
    return;
  }
  const fs::path dir = work_dir() / "user_temporaries";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "p.pack")
      << "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\n"
         "cells id parent x y theta b gamma0\n0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n";
  const std::vector<std::string> users{"out.png.tmp",         "out.svg.tmp", ".out.png.tmp-abcdef",
                                       ".out.svg.tmp-abcdef", "out.gsd.tmp", "out.gsd.frames.json",
                                       ".out.gsd.tmp-abcdef"};
  for (const auto& name : users) std::ofstream(dir / name) << "the user's " << name << "\n";
  for (const std::string args : {"render p.pack -o out.svg --png", "export p.pack --format gsd --out out"}) {
    const Result r = budjam::testing::run_budjam_in(dir, args);
    INFO(args << "\n" << r.err);
    CHECK(r.code == 0);
  }
  for (const auto& name : users) CHECK(slurp(dir / name) == "the user's " + name + "\n");
  for (const char* made : {"out.svg", "out.png", "out.gsd"}) CHECK(fs::file_size(dir / made) > 0);

  // Two writers of one base at once: each writes through its own temporary and renames it.
  const std::string exe = budjam::testing::shell_quoted(std::getenv("BUDJAM_EXE"));
  const std::string both = "cd " + budjam::testing::shell_quoted(dir) + " && (" + exe +
                           " export p.pack --format gsd --out both 2>one.err & one=$!; " + exe +
                           " export p.pack --format gsd --out both 2>two.err & two=$!; wait $one && wait $two)";
  CHECK(std::system(both.c_str()) == 0);
  CHECK(slurp(dir / "one.err").empty());
  CHECK(slurp(dir / "two.err").empty());
  const std::string read_back =
      "/usr/bin/python3 -c 'import gsd.hoomd, sys; f = gsd.hoomd.open(sys.argv[1]); "
      "sys.exit(0 if len(f) == 1 and f[0].particles.N == 4 else 1)' " +
      budjam::testing::shell_quoted(dir / "both.gsd");
  CHECK(std::system(read_back.c_str()) == 0);
  std::vector<std::string> left, expected = users;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  for (const char* name : {"p.pack", "out.svg", "out.png", "out.gsd", "both.gsd", "one.err", "two.err"})
    expected.emplace_back(name);
  std::sort(left.begin(), left.end());
  std::sort(expected.begin(), expected.end());
  CHECK(left == expected);
}

TEST_CASE(
    "a converter or GSD writer that fails, or ends well having written nothing, replaces none of the earlier "
    "outputs",
    "[cli]") {
  const fs::path dir = directory_with_bin("failed_writers");
  std::ofstream(dir / "bin" / "rsvg-convert") << "#!/bin/sh\necho 'cannot draw' >&2\nexit 1\n";
  fs::permissions(dir / "bin" / "rsvg-convert", fs::perms::owner_all);
  std::ofstream(dir / "p.pack")
      << "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\n"
         "cells id parent x y theta b gamma0\n0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n";
  const std::vector<std::string> earlier{"z.svg", "z.png", "g.gsd"};
  for (const auto& name : earlier) std::ofstream(dir / name) << "the earlier " << name << "\n";
  // The environment the child inherits: the failing converter first on PATH, a "Python" that writes nothing.
  const std::string path = std::getenv("PATH");
  ::setenv("PATH", ((dir / "bin").string() + ":" + path).c_str(), 1);
  const Result render = budjam::testing::run_budjam_in(dir, "render p.pack -o z.svg --png");
  ::setenv("PATH", path.c_str(), 1);
  ::setenv("BUDJAM_PYTHON", "/bin/true", 1);
  const Result gsd = budjam::testing::run_budjam_in(dir, "export p.pack --format gsd --out g");
  ::unsetenv("BUDJAM_PYTHON");
  for (const auto& [r, says] : {std::pair{render, "rsvg-convert"}, std::pair{gsd, "without writing a GSD file"}}) {
    INFO(r.err);
    CHECK(r.code == 3);
    require_one_error_line(r);
    CHECK_THAT(r.err, Contains(says));
  }
  for (const auto& name : earlier) CHECK(slurp(dir / name) == "the earlier " + name + "\n");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  CHECK(left == std::vector<std::string>{"bin", "g.gsd", "p.pack", "z.png", "z.svg"});
}

TEST_CASE("an output that fills its disk is exit 3 with one line naming that output, never its temporary", "[cli]") {
  budjam::testing::SmallDisk disk(work_dir() / "full_disk", 16 * 1024);
  if (!disk.mounted) {
    WARN(disk.why_not);
    return;
  }
  {
    std::ofstream fill(disk.path / "fill", std::ios::binary);
    const std::string block(1024, 'x');
    for (int k = 0; k < 64 && fill; ++k) fill << block << std::flush;
  }
  const fs::path pack = work_dir() / "full_disk.pack";
  std::ofstream(pack) << "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\n"
                         "cells id parent x y theta b gamma0\n0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n";
  const std::string out = budjam::testing::shell_quoted(disk.path / "out");
  std::vector<std::pair<std::string, std::string>> commands{
      {"export " + budjam::testing::shell_quoted(pack) + " --format xyz --out " + out, "out.xyz"},
      {"rigidity " + budjam::testing::shell_quoted(pack) + " --network raw --out " + out, "out.csv"}};
  if (std::system("/usr/bin/python3 -c 'import gsd.hoomd' >/dev/null 2>&1") == 0)
    commands.emplace_back("export " + budjam::testing::shell_quoted(pack) + " --format gsd --out " + out, "out.gsd");
  for (const auto& [args, named] : commands) {
    const Result r = budjam::testing::run_budjam(args);
    INFO(args << "\n" << r.err);
    CHECK(r.code == 3);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find((disk.path / named).string() + ": ") != std::string::npos);
    CHECK(r.err.find(".tmp-") == std::string::npos);
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(disk.path)) left.push_back(e.path().filename().string());
    CHECK(left == std::vector<std::string>{"fill"});
  }
}
