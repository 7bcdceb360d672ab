// libFuzzer harness: the scene parser. Any input must parse to a valid scene or be refused with
// InputError; an accepted scene must survive its own TOML round trip exactly.
#include "io/scene_file.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const budjam::Scene s = budjam::io::parse_scene(text, "fuzz.toml");
    const std::string again = budjam::io::scene_to_toml(s);
    if (budjam::io::scene_to_toml(budjam::io::parse_scene(again, "again.toml")) != again) std::abort();
  } catch (const budjam::InputError&) {
  }
  return 0;
}
