// libFuzzer harness: the packing reader. Any input is read or refused with InputError; what is
// read is written back (format_packing must accept it) and reads back to the same text.
#include "io/packing_file.hpp"

#include "budjam/scene.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const budjam::io::PackingFile f = budjam::io::parse_packing(text, "fuzz.pack");
    const std::string written = budjam::io::format_packing(f.packing, f.meta);  // throws only on a bug
    const budjam::io::PackingFile back = budjam::io::parse_packing(written, "again.pack");
    if (budjam::io::format_packing(back.packing, back.meta) != written) std::abort();
  } catch (const budjam::InputError&) {
  }
  return 0;
}
