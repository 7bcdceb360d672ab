// libFuzzer entry point; the harness is budjam::fuzz::degenerate (fuzz/harnesses.hpp).
#include "harnesses.hpp"

#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  budjam::fuzz::degenerate(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
