// libFuzzer entry point; the harness is budjam::fuzz::resume (fuzz/harnesses.hpp), against the run
// directory $BUDJAM_FUZZ_RUN (default fuzz/fixtures/resume, relative to the source tree, where
// scripts/fuzz.sh runs).
#include "harnesses.hpp"

#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path run = [] {
    const char* env = std::getenv("BUDJAM_FUZZ_RUN");
    return std::filesystem::path(env && *env ? env : "fuzz/fixtures/resume");
  }();
  budjam::fuzz::resume(std::string_view(reinterpret_cast<const char*>(data), size), run);
  return 0;
}
