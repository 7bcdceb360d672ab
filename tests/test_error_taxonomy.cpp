// Bad input is exit 2 naming the file (and line), never "internal"; what a file holds cannot
// reach the terminal raw; file names that look like options stay file names.
#include <catch2/catch.hpp>
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <algorithm>
#include <fstream>

namespace fs = std::filesystem;
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
  const auto r = run_budjam("analyse json-run --out json-out");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.rfind("budjam: error: json-run/summary.json: P0", 0) == 0);
  CHECK(r.err.find("internal") == std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("the spectrum of an unjammed packing is refused naming the packing", "[taxonomy]") {
  write(work_dir() / "loose.pack", kPacking);  // two cells far apart: every cell is a rattler
  const auto r = run_budjam("dos loose.pack");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("loose.pack: no non-rattler cells") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}
