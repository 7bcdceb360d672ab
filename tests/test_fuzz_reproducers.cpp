// Replays the fuzz harnesses (fuzz/harnesses.hpp) on the seed corpus and on every saved crash or
// hang reproducer (fuzz/reproducers/<harness>/), in the ordinary build: label `hard`, which the
// sanitizer build runs too. A reproducer must now be read or refused with InputError.
#include "../fuzz/harnesses.hpp"

#include <catch2/catch.hpp>

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

TEST_CASE("the degenerate-packing harness passes on its corpus and reproducers", "[fuzz][.hard]") {
  replay("degenerate", budjam::fuzz::degenerate);
}
