#pragma once
// The bodies of the fuzz harnesses, shared by the libFuzzer entry points (fuzz/fuzz_*.cpp) and by
// test_fuzz_reproducers, which replays the seed corpus and every saved crash or hang reproducer
// (fuzz/corpus/, fuzz/reproducers/) in the ordinary build. Each returns normally for an input
// that is accepted or refused with InputError, and calls std::abort() when a property fails;
// any other exception escapes.
#include "budjam/scene.hpp"
#include "io/checkpoint.hpp"
#include "io/packing_file.hpp"
#include "io/scene_file.hpp"

#include <cstdio>
#include <cstdlib>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::fuzz {

// Any input parses to a valid scene or is refused; an accepted scene survives its own TOML
// round trip exactly.
inline void scene(std::string_view text) {
  try {
    const Scene s = io::parse_scene(text, "fuzz.toml");
    const std::string again = io::scene_to_toml(s);
    if (io::scene_to_toml(io::parse_scene(again, "again.toml")) != again) std::abort();
  } catch (const InputError&) {}
}

// Any input is read or refused; what is read is written back (format_packing must accept it) and
// reads back to the same text.
inline void packing(std::string_view text) {
  try {
    const io::PackingFile f = io::parse_packing(text, "fuzz.pack");
    const std::string written = io::format_packing(f.packing, f.meta);  // throws only on a bug
    const io::PackingFile back = io::parse_packing(written, "again.pack");
    if (io::format_packing(back.packing, back.meta) != written) std::abort();
  } catch (const InputError&) {}
}

// The scene the checkpoint corpus was written with (`budjam grow` of it, stopped by SIGTERM).
inline const Scene& checkpoint_scene() {
  static const Scene s = io::parse_scene(R"(
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
)",
                                         "fuzz.toml");
  return s;
}

// Stand-ins for the run's stateful observers: their sections are log byte counts.
struct LogLengths : Observer {
  std::string label;
  int count;
  LogLengths(std::string l, int n) : label(std::move(l)), count(n) {}
  std::string name() const override { return label; }
  bool stateful() const override { return true; }
  void load_state(std::istream& is) override {
    for (int k = 0; k < count; ++k) {
      unsigned long long bytes = 0;
      if (!(is >> bytes)) throw InputError("bad " + label + " state");
    }
  }
};

// The checkpoint reader past its checksum: the input's last line is replaced by the right
// checksum, so that inputs explore the parser and its range checks instead of being refused
// at once. Any input is read or refused; what is read is restored into a driver and one growth
// attempt is made from it (a short FIRE budget: an edited state may be far from relaxed).
inline void checkpoint(std::string_view input) {
  std::string text(input);
  const std::size_t at = text.rfind("checksum ");
  if (at != std::string::npos) text.resize(at);
  char sum[40];
  std::snprintf(sum, sizeof sum, "checksum %016llx\n", static_cast<unsigned long long>(io::fnv1a64(text)));
  text += sum;
  const Scene& scene = checkpoint_scene();
  LogLengths run_log("run_log", 2), buds("bud_events", 1);
  const std::vector<Observer*> observers{&buds, &run_log};
  try {
    GrowthState s = io::parse_checkpoint(text, "fuzz.txt", scene, scene.seed, observers);
    Scene quick = scene;
    quick.fire.max_iterations = 200;
    GrowthDriver driver(quick);
    driver.restore(std::move(s));
    driver.advance();
  } catch (const InputError&) {}
}

}  // namespace budjam::fuzz
