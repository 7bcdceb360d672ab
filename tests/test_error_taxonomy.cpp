// Bad input is exit 2 naming the file (and line), never "internal"; what a file holds cannot
// reach the terminal raw; file names that look like options stay file names.
#include <catch2/catch.hpp>
#include "input_error.hpp"
#include "io/json.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <algorithm>
#include <fstream>

namespace fs = std::filesystem;
using budjam::testing::check_input_error;
using budjam::testing::slurp;
using budjam::testing::work_dir;

namespace {

// Runs `budjam ARGS` in the scratch directory.
budjam::testing::BudjamRun run_budjam(const std::string& args) {
  return budjam::testing::run_budjam_in(work_dir(), args);
}

const std::string kPacking =
    "budjam-packing 1\nL 8\nshear 0\nN 2\nnext_id 2\nmeta kind jammed\ncells id parent x y theta b gamma0\n"
    "0 -1 2 2 0 0.5 0.002\n1 -1 5 5 1 0.7 0.002\nend\n";

void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("a physically impossible packing is input (exit 2, file and line), not an internal error", "[taxonomy]") {
  const std::vector<std::pair<std::string, std::string>> cases{
      {with(kPacking, "0.5 0.002", "1e300 0.002"), "bad.pack:8: cell 0: bud diameter"},
      {with(kPacking, "L 8", "L 1e-300"), "bad.pack:2: box side L = 1e-300"},
      {with(kPacking, "0 -1 2 2", "0 -1 1e300 2"), "bad.pack:8: cell 0: position"},
  };
  for (const auto& [text, message] : cases) {
    write(work_dir() / "bad.pack", text);
    for (const char* cmd : {"validate bad.pack", "moduli bad.pack", "render bad.pack -o bad.svg"}) {
      const auto r = run_budjam(cmd);
      INFO(cmd << ": " << r.err);
      CHECK(r.code == 2);
      CHECK(r.err.find(message) != std::string::npos);
      CHECK(r.err.find("internal") == std::string::npos);
    }
  }
}

TEST_CASE("control bytes from a file are escaped in the one-line error", "[taxonomy]") {
  write(work_dir() / "esc.pack", with(kPacking, "meta kind jammed", "meta k\x1b[2J\x07y x"));
  const auto r = run_budjam("validate esc.pack");
  CHECK(r.code == 2);
  CHECK(r.err.find('\x1b') == std::string::npos);
  CHECK(r.err.find('\x07') == std::string::npos);
  CHECK(r.err.find("\\x1b[2J\\x07") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("a packing meta value with a carriage return is refused, so every packing read can be written",
          "[taxonomy]") {
  write(work_dir() / "cr.pack", with(kPacking, "meta kind jammed", "meta kind jam\rmed"));
  const auto r = run_budjam("validate cr.pack");
  CHECK(r.code == 2);
  CHECK(r.err.find("cr.pack:6: meta kind: the value holds a carriage return") != std::string::npos);
}

TEST_CASE("render --png passes a file name that starts with '-' as a file", "[taxonomy]") {
  if (std::system("command -v rsvg-convert >/dev/null 2>&1") != 0) {
    WARN("rsvg-convert not installed: skipped");
    return;
  }
  write(work_dir() / "good.pack", kPacking);
  const auto r = run_budjam("render good.pack -o -x.svg --png");
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(fs::file_size(work_dir() / "-x.png") > 0);
}

TEST_CASE("a JSON value of the wrong type in an input is exit 2, not internal", "[taxonomy]") {
  const fs::path run = work_dir() / "json-run";
  fs::create_directories(run / "packings");
  write(run / ".budjam-run", "budjam-run 1\n");
  write(run / "summary.json", R"({"format": "budjam-summary", "version": 1, "status": "finished", "seed": 1,
    "L": 8, "P0": "strong", "phi_J": 0.84, "targets": [], "unjammings": []})");
  write(run / "steps.csv", "step,phi\n");
  write(run / "divisions.csv", "step,phi\n");
  check_input_error(run_budjam("analyse json-run --out json-out"), "json-run/summary.json: P0");
}

TEST_CASE("the spectrum of an unjammed packing (N_nr = 0) is a notice and exit 1, as its moduli, and writes nothing",
          "[taxonomy]") {
  write(work_dir() / "loose.pack", kPacking);  // two cells far apart: every cell is a rattler
  const auto r = run_budjam("dos loose.pack --out loose");
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK(r.err.rfind("budjam: dos: loose.pack: no non-rattler cells", 0) == 0);  // a notice, not an error
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.out.empty());
  CHECK_FALSE(fs::exists(work_dir() / "loose.json"));
  CHECK_FALSE(fs::exists(work_dir() / "loose.csv"));
}

TEST_CASE("a result that cannot be written to standard output is exit 3 with one line, not success", "[taxonomy]") {
  write(work_dir() / "full.pack", kPacking);
  const fs::path err = work_dir() / "full.err";
  using budjam::testing::shell_quoted;
  // --help and --version print results too; a saddle's JSON goes out before its notice, which is left
  // out when it could not: the failure is the one line.
  for (const std::string& args :
       {"validate " + shell_quoted(budjam::testing::source_file("data/scenes/demo.toml")),
        "rigidity " + shell_quoted(work_dir() / "full.pack") + " --network raw --json", std::string("--help"),
        std::string("--version"), std::string("grow --help"),
        "moduli " + shell_quoted(budjam::testing::source_file("tests/data/saddle_jamming_L15_seed3.pack")) +
            " --json"}) {
    INFO(args);
    CHECK(budjam::testing::run_budjam_redirected(args, "/dev/full", err) == 3);
    const std::string e = slurp(err);
    INFO(e);
    CHECK(e.rfind("budjam: error: standard output: cannot write: ", 0) == 0);
    CHECK(std::count(e.begin(), e.end(), '\n') == 1);
  }
}

namespace {

// A jammed-looking run directory whose summary.json is `summary` (steps and divisions empty).
fs::path run_with_summary(const std::string& name, const std::string& summary) {
  const fs::path run = work_dir() / name;
  fs::create_directories(run / "packings");
  write(run / ".budjam-run", "budjam-run 1\n");
  write(run / "summary.json", summary);
  write(run / "steps.csv", "step,phi,P,N,N_f,N_u_buds,chi_c,tagged_active,divisions_since_jamming,Z,dZ\n");
  write(run / "divisions.csv", "step,phi\n");
  return run;
}

const std::string kSummary = R"({"format": "budjam-summary", "version": 1, "status": "finished", "seed": 1,
    "L": 8, "P0": null, "phi_J": 0.84, "N_nr_J": 30, "targets": [], "unjammings": []})";

}  // namespace

TEST_CASE("analyse on a summary.json field of the wrong type is exit 2 naming the file and the key", "[taxonomy]") {
  run_with_summary("str-run", with(kSummary, "\"phi_J\": 0.84", "\"phi_J\": \"0.84\""));
  check_input_error(run_budjam("analyse str-run --out str-out"),
                    "str-run/summary.json: phi_J: expected a number > 0 or null (got \"0.84\")");
  run_with_summary("tgt-run", with(kSummary, "\"targets\": []", "\"targets\": [{\"dphi\": \"x\"}]"));
  check_input_error(run_budjam("analyse tgt-run --out tgt-out"),
                    "tgt-run/summary.json: targets[0].dphi: expected a number > 0 (got \"x\")");
  run_with_summary("arr-run", "[1, 2, 3]");
  check_input_error(run_budjam("analyse arr-run --out arr-out"),
                    "arr-run/summary.json: not a budjam run summary (not a JSON object)");
}

TEST_CASE("a run whose packings is a plain file is an input error (exit 2) naming it, not an output error",
          "[taxonomy]") {
  const fs::path run = run_with_summary("plain-run", kSummary);
  fs::remove(run / "packings");
  write(run / "packings", "not a directory\n");
  check_input_error(run_budjam("analyse plain-run --out plain-out"), "plain-run/packings: not a directory");
  check_input_error(run_budjam("survival plain-run"), "plain-run/packings: not a directory");
}

TEST_CASE("a new output directory at the top level of a run is refused, for grow as for analyse; packings/ is not",
          "[taxonomy]") {
  const std::string demo = budjam::testing::shell_quoted(budjam::testing::source_file("data/scenes/demo.toml"));
  REQUIRE(run_budjam("grow " + demo + " --quiet --out host-run").code == 0);
  for (const std::string& args :
       {"grow " + demo + " --quiet --out host-run/inner", std::string("analyse host-run --out host-run/inner/"),
        std::string("analyse host-run --out host-run/./inner")}) {
    INFO(args);
    const auto r = run_budjam(args);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("is inside the budjam run directory host-run, whose top level holds only the run's own files") !=
          std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(work_dir() / "host-run" / "inner"));
  }
  const auto beside = run_budjam("rigidity host-run/packings/jammed.pack --out host-run/packings/jammed.rigidity");
  INFO(beside.err);
  CHECK(beside.code == 0);
}

// `budjam ARGS` refused with exit 2 and one line holding `phrase`, `snapshot()` of what it must not
// touch still `before`.
template <class Snapshot, class Value>
void check_refused_as_is(const std::string& args, const std::string& phrase, const Snapshot& snapshot,
                         const Value& before) {
  INFO(args);
  const auto r = run_budjam(args);
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find(phrase) != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(snapshot() == before);
}

TEST_CASE("no output makes a directory at the top level of a run, however deep and through a link", "[taxonomy]") {
  const std::string demo = budjam::testing::shell_quoted(budjam::testing::source_file("data/scenes/demo.toml"));
  REQUIRE(run_budjam("grow " + demo + " --quiet --out deep-run").code == 0);
  fs::remove(work_dir() / "plink");
  fs::create_directory_symlink(work_dir() / "deep-run" / "packings", work_dir() / "plink");
  const auto top = [] {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(work_dir() / "deep-run")) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  };
  const auto before = top();
  const std::string pack = "deep-run/packings/jammed.pack";
  for (const std::string& args :
       {"moduli " + pack + " --out deep-run/sub7/deeper/m", "render " + pack + " -o deep-run/sub2/r.svg",
        "export " + pack + " --format xyz --out deep-run/sub3/e", "grow " + demo + " --quiet --out deep-run/sub9/run",
        std::string("analyse deep-run --out deep-run/sub5/deeper"), std::string("analyse deep-run --out plink/../newA"),
        "dos " + pack + " --out plink/../newB/d"}) {
    check_refused_as_is(args, "is inside the budjam run directory", top, before);
  }
  // Below packings/, beside the packings, an output may make one.
  const auto below = run_budjam("rigidity " + pack + " --out plink/mine/j");
  INFO(below.err);
  CHECK(below.code == 0);
  CHECK(fs::is_regular_file(work_dir() / "deep-run" / "packings" / "mine" / "j.json"));
}

TEST_CASE("spectra/ of a run holds the dos observer's files alone: no command writes or makes anything there",
          "[taxonomy]") {
  const std::string demo = budjam::testing::shell_quoted(budjam::testing::source_file("data/scenes/demo.toml"));
  REQUIRE(run_budjam("grow " + demo + " --quiet --out spec-run --set observe.dos.every=20").code == 0);
  const fs::path spectra = work_dir() / "spec-run" / "spectra";
  REQUIRE(fs::is_directory(spectra));
  const auto listing = [&] {
    std::vector<std::pair<std::string, std::string>> files;
    for (const auto& e : fs::recursive_directory_iterator(work_dir() / "spec-run"))
      files.emplace_back(e.path().string(), e.is_regular_file() ? budjam::testing::slurp(e.path()) : "");
    std::sort(files.begin(), files.end());
    return files;
  };
  std::string spectrum;  // a spectrum the observer wrote, by its base name
  for (const auto& e : fs::directory_iterator(spectra))
    if (e.path().extension() == ".json") spectrum = e.path().stem().string();
  REQUIRE(!spectrum.empty());
  const auto before = listing();
  const std::string pack = "spec-run/packings/jammed.pack";
  for (const std::string& args :
       {"dos " + pack + " --out spec-run/spectra/" + spectrum, "rigidity " + pack + " --out spec-run/spectra/r",
        "render " + pack + " -o spec-run/spectra/new/r.svg", std::string("analyse spec-run --out spec-run/spectra"),
        std::string("analyse spec-run --out spec-run/spectra/a")}) {
    check_refused_as_is(args, "the spectra directory of a budjam run", listing, before);
  }
  // a run whose observer made none: spectra/ is not made either
  REQUIRE(run_budjam("grow " + demo + " --quiet --out nospec-run").code == 0);
  const auto made = run_budjam("moduli nospec-run/packings/jammed.pack --out nospec-run/spectra/m");
  CHECK(made.code == 2);
  CHECK_FALSE(fs::exists(work_dir() / "nospec-run" / "spectra"));
}

TEST_CASE(
    "a finished run without its packings directory is an input error (exit 2) naming it, and nothing is "
    "written",
    "[taxonomy]") {
  const auto grown =
      run_budjam("grow " + budjam::testing::shell_quoted(budjam::testing::source_file("data/scenes/demo.toml")) +
                 " --quiet --out bare-run");
  REQUIRE(grown.code == 0);
  fs::remove_all(work_dir() / "bare-run" / "packings");
  check_input_error(run_budjam("analyse bare-run --out bare-out"), "bare-run/packings: no such directory");
  CHECK_FALSE(fs::exists(work_dir() / "bare-out"));
}

TEST_CASE(
    "moduli and the load-bearing rigidity of an unjammed packing (N_nr = 0) are a notice and exit 1, and write "
    "nothing (not zero moduli or zero floppy modes)",
    "[taxonomy]") {
  write(work_dir() / "gas.pack", kPacking);  // two cells far apart: every cell is a rattler
  for (const std::string command : {"moduli", "rigidity"}) {
    const auto r = run_budjam(command + " gas.pack --out gas-" + command);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.rfind("budjam: " + command + ": gas.pack is not jammed: all 2 cells are rattlers (N_nr = 0)", 0) == 0);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.out.empty());
    CHECK_FALSE(fs::exists(work_dir() / ("gas-" + command + ".json")));
  }
  // The raw network takes every cell: two free dumbbells, 2 × 3 − 3 floppy modes in the plane.
  const auto raw = run_budjam("rigidity gas.pack --network raw --json");
  INFO(raw.err);
  CHECK(raw.code == 0);
  CHECK(budjam::io::Json::parse(raw.out)["floppy_modes"]["plane"] == 3);
}

TEST_CASE("an error line is cut to a bounded length, keeping its start and its end", "[taxonomy]") {
  std::string deep = "missing";
  while (deep.size() < 3000) deep += "/long-directory-name";
  const auto r = run_budjam("validate '" + deep + "/s.toml'");
  INFO(r.err.size());
  CHECK(r.code == 2);
  CHECK(r.err.rfind("budjam: error: missing/long-directory-name/", 0) == 0);
  CHECK(r.err.find("bytes left out ...]") != std::string::npos);
  CHECK(r.err.find("s.toml") != std::string::npos);
  CHECK(r.err.size() < 1200);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE(
    "scene resource bounds: init.cells, the number of targets and their output are refused with the key and "
    "the limit",
    "[taxonomy]") {
  const auto validate = [](const std::string& toml) {
    write(work_dir() / "res.toml", toml);
    return run_budjam("validate res.toml");
  };
  check_input_error(validate("[box]\nL = 8000\n[init]\nkind = \"random_seeds\"\ncells = 10000000\n"),
                    "res.toml: init.cells: must be at most 1e+06 so that the initial state fits in memory");
  // 10⁵ increasing targets: refused by their number, in one short line although the list is long.
  std::string targets = "[jamming]\nmax_dphi = 0.2\ntargets = [";
  for (int k = 1; k <= 100000; ++k) targets += (k > 1 ? ", " : "") + std::to_string(k * 1e-6);
  const auto many = validate(targets + "]\n");
  check_input_error(many, "res.toml: jamming.targets: at most 1000 targets (each writes a packing file)");
  CHECK(many.err.find("(100000 values)") != std::string::npos);
  CHECK(many.err.size() < 400);
  // 200 targets at L = 1000: about 18 GB of target packings.
  std::string big = "[box]\nL = 1000\n[jamming]\nmax_dphi = 0.2\ntargets = [";
  for (int k = 1; k <= 200; ++k) big += (k > 1 ? ", " : "") + std::to_string(k * 1e-4);
  check_input_error(validate(big + "]\n"),
                    "res.toml: jamming.targets: their packings would take about 18 GB at box.L = 1000, more "
                    "than the limit of 10 GB");
  CHECK(validate("[box]\nL = 1000\n[jamming]\ntargets = [1e-3, 1e-2]\n").code == 0);
}

// tests/data/negative_G_target_L8.pack: the Δφ = 10⁻³ target of the demo scene without feedback
// (seed 1, L = 8), whose contact-virial shear stress falls under Lees–Edwards shear.
TEST_CASE("moduli names the simple-shear modulus it prints, and a negative one comes with a notice (exit 0)",
          "[taxonomy]") {
  // Built by appending: GCC 12 reads "'" + std::string&& as an overlapping memcpy (-Wrestrict).
  std::string pack = "'";
  pack += budjam::testing::source_file("tests/data/negative_G_target_L8.pack").string();
  pack += "'";
  const auto r = run_budjam("moduli " + pack);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.out.find(", G_simple = -0.00527") != std::string::npos);
  CHECK(r.out.find("(G: Lees-Edwards simple shear)") != std::string::npos);
  CHECK(r.err.find("budjam: moduli: ") == 0);
  CHECK(r.err.find(": G_simple = -0.00527") != std::string::npos);
  CHECK(r.err.find("is negative") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  // A positive G: no notice.
  const auto positive = run_budjam(
      "moduli '" + budjam::testing::source_file("tests/data/shear_conventions_differ_L8.pack").string() + "'");
  CHECK(positive.code == 0);
  CHECK(positive.err.empty());
}

TEST_CASE(
    "validate (also --json), export and render refuse a packing whose meta value is not UTF-8 or that starts with a "
    "byte-order mark, naming file and line (exit 2)",
    "[taxonomy]") {
  write(work_dir() / "latin1.pack", with(kPacking, "meta kind jammed", "meta kind t\xe9rget"));
  write(work_dir() / "bom.pack", "\xEF\xBB\xBF" + kPacking);
  for (const std::string command : {"validate", "validate --json", "export --format xyz --out o", "render -o o.svg"}) {
    INFO(command);
    const auto latin1 = run_budjam(command.substr(0, command.find(' ')) + " latin1.pack" +
                                   (command.find(' ') == std::string::npos ? "" : command.substr(command.find(' '))));
    check_input_error(latin1, "latin1.pack:6: meta kind: the value is not valid UTF-8");
    const auto bom = run_budjam(command.substr(0, command.find(' ')) + " bom.pack" +
                                (command.find(' ') == std::string::npos ? "" : command.substr(command.find(' '))));
    check_input_error(bom, "bom.pack:1: the file starts with a UTF-8 byte-order mark");
  }
}
