// Replays the fuzz harnesses (fuzz/harnesses.hpp) on the seed corpus and on every saved crash or
// hang reproducer (fuzz/reproducers/<harness>/), in the ordinary build: label `hard`, which the
// sanitizer build runs too. A reproducer must now be read or refused with InputError.
#include "../fuzz/harnesses.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> inputs(const std::string& harness) {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  std::vector<fs::path> out;
  for (const char* kind : {"corpus", "reproducers"}) {
    const fs::path d = fs::path(src) / "fuzz" / kind / harness;
    if (fs::is_directory(d))
      for (const auto& e : fs::directory_iterator(d)) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void replay(const std::string& harness, const std::function<void(std::string_view)>& run) {
  const auto files = inputs(harness);
  REQUIRE_FALSE(files.empty());
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    INFO(f.string());
    CHECK_NOTHROW(run(text.str()));
  }
}

}  // namespace

TEST_CASE("the scene harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  replay("scene", budjam::fuzz::scene);
}

TEST_CASE("the packing harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  replay("packing", budjam::fuzz::packing);
}

TEST_CASE("the checkpoint harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  replay("checkpoint", budjam::fuzz::checkpoint);
}

TEST_CASE("the resume harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  const fs::path run = fs::path(std::getenv("BUDJAM_SOURCE_DIR")) / "fuzz" / "fixtures" / "resume";
  replay("resume", [&](std::string_view text) { budjam::fuzz::resume(text, run); });
}

TEST_CASE("the resume harness reaches the checks against the run's files", "[fuzz]") {
  // Its seed is the fixture's own checkpoint: accepted as it is, refused by the cross-checks once
  // a record disagrees with the packings (the harness recomputes the checksum).
  const fs::path run = fs::path(std::getenv("BUDJAM_SOURCE_DIR")) / "fuzz" / "fixtures" / "resume";
  std::ifstream in(run / "checkpoint.txt", std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  const std::string good = text.str();
  const budjam::Scene& scene = budjam::fuzz::checkpoint_scene();
  const budjam::io::Directory dir = budjam::io::Directory::open(run, false);
  budjam::fuzz::RunLogCuts run_log(dir);
  budjam::fuzz::LogLengths buds("bud_events", 1);
  const std::vector<budjam::Observer*> observers{&buds, &run_log};
  auto check = [&](const std::string& t) {
    budjam::io::CheckpointLines lines;
    const budjam::GrowthState s =
        budjam::io::parse_checkpoint(budjam::fuzz::with_checksum(t), "fuzz.txt", scene, scene.seed, observers, &lines);
    budjam::io::check_against_run(s, scene, lines, "fuzz.txt", run_log.steps, run_log.steps_log, run_log.divisions,
                                  dir.subdirectory("packings", false));
  };
  CHECK_NOTHROW(check(good));
  const std::size_t at = good.find("\njamming 1 ");
  REQUIRE(at != std::string::npos);
  // The jamming record's φ_J one digit off: only packings/jammed.pack can tell.
  std::string bad = good;
  const std::size_t phi = bad.find(' ', bad.find(' ', bad.find(' ', bad.find(' ', at + 1) + 1) + 1) + 1) + 1;
  bad[phi + 3] = bad[phi + 3] == '1' ? '2' : '1';
  CHECK_THROWS_WITH(check(bad), Catch::Matchers::Contains("disagrees with packings/jammed.pack"));
  // The unjamming record's step, φ or φ_J moved: only the phase column of steps.csv can tell.
  const std::size_t record = good.find('\n', good.find("\nunjammings 1\n") + 1) + 1;
  const std::string line = good.substr(record, good.find('\n', record) - record);  // "0 <step> <phi> <phi_J> <lost>"
  std::istringstream words(line);
  std::string episode, step, phi_u, phi_J, lost;
  REQUIRE(words >> episode >> step >> phi_u >> phi_J >> lost);
  auto with_record = [&](const std::string& s, const std::string& x, const std::string& x_J) {
    return good.substr(0, record) + episode + ' ' + s + ' ' + x + ' ' + x_J + ' ' + lost +
           good.substr(record + line.size());
  };
  CHECK_NOTHROW(check(with_record(step, phi_u, phi_J)));
  const std::string earlier = std::to_string(std::stol(step) - 1);
  const std::string at_line = "fuzz.txt:" + std::to_string(std::count(good.begin(), good.begin() + record, '\n') + 1);
  for (const std::string& t : {with_record(earlier, phi_u, phi_J), with_record(step, "0.8" + phi_u.substr(4), phi_J),
                               with_record(step, phi_u, "0.8" + phi_J.substr(4))})
    CHECK_THROWS_WITH(check(t), Catch::Matchers::Contains(at_line + ": unjamming 0 at step") &&
                                    Catch::Matchers::Contains("steps.csv.partial jams at step"));
}

TEST_CASE("the degenerate-packing harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  replay("degenerate", budjam::fuzz::degenerate);
}
