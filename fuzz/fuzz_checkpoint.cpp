// libFuzzer harness: the checkpoint reader, past its checksum. The input's last line is replaced
// by the right checksum, so that the fuzzer explores the parser and its range checks instead of
// the (trivially refused) damaged files. Any input is read or refused with InputError; what is
// read is restored into a driver, which must accept it.
#include "io/checkpoint.hpp"
#include "io/scene_file.hpp"

#include <cstdint>
#include <cstdio>
#include <istream>
#include <string>

namespace {

// The scene of the seed corpus (fuzz/corpus/checkpoint, written by `budjam grow` with it).
constexpr const char* kScene = R"(
[run]
name = "fuzz"
seed = 3
[box]
L = 6.0
[growth]
P0 = 1e-3
[jamming]
targets = [1e-3, 1e-2]
[observe]
checkpoint_every = 20
)";

// Stand-ins for the run's stateful observers: their sections are log byte counts.
struct LogLengths : budjam::Observer {
  std::string label;
  int count;
  LogLengths(std::string l, int n) : label(std::move(l)), count(n) {}
  std::string name() const override { return label; }
  bool stateful() const override { return true; }
  void load_state(std::istream& is) override {
    for (int k = 0; k < count; ++k) {
      unsigned long long bytes = 0;
      if (!(is >> bytes)) throw budjam::InputError("bad " + label + " state");
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const budjam::Scene scene = budjam::io::parse_scene(kScene, "fuzz.toml");
  std::string text(reinterpret_cast<const char*>(data), size);
  const std::size_t at = text.rfind("checksum ");
  if (at != std::string::npos) text.resize(at);
  char sum[40];
  std::snprintf(sum, sizeof sum, "checksum %016llx\n",
                static_cast<unsigned long long>(budjam::io::fnv1a64(text)));
  text += sum;
  LogLengths run_log("run_log", 2), buds("bud_events", 1);
  const std::vector<budjam::Observer*> observers{&buds, &run_log};
  try {
    budjam::GrowthState s = budjam::io::parse_checkpoint(text, "fuzz.txt", scene, scene.seed, observers);
    budjam::GrowthDriver driver(scene);
    driver.restore(std::move(s));
  } catch (const budjam::InputError&) {
  }
  return 0;
}
