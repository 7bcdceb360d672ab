#pragma once
// The bodies of the fuzz harnesses, shared by the libFuzzer entry points (fuzz/fuzz_*.cpp) and by
// test_fuzz_reproducers, which replays the seed corpus and every saved crash or hang reproducer
// (fuzz/corpus/, fuzz/reproducers/) in the ordinary build. Each returns normally for an input
// that is accepted or refused with InputError, and calls std::abort() when a property fails;
// any other exception escapes.
#include "budjam/moduli.hpp"
#include "budjam/scene.hpp"
#include "budjam/spectrum.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "io/packing_file.hpp"
#include "io/run_data.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <istream>
#include <numbers>
#include <sstream>
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
checkpoint_evaluations = 300
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

// The input with its last line replaced by the right checksum, so that inputs explore the parser
// and its range checks instead of being refused at once.
inline std::string with_checksum(std::string_view input) {
  std::string text(input);
  const std::size_t at = text.rfind("checksum ");
  if (at != std::string::npos) text.resize(at);
  char sum[40];
  std::snprintf(sum, sizeof sum, "checksum %016llx\n", static_cast<unsigned long long>(io::fnv1a64(text)));
  return text + sum;
}

// One growth attempt from an accepted state (a short FIRE budget: an edited state may be far
// from relaxed).
inline void advance_from(GrowthState s) {
  Scene quick = checkpoint_scene();
  quick.fire.max_iterations = 200;
  GrowthDriver driver(quick);
  driver.restore(std::move(s));
  driver.advance();
}

// The checkpoint reader past its checksum. Any input is read or refused; what is read is restored
// into a driver and one growth attempt is made from it.
inline void checkpoint(std::string_view input) {
  const std::string text = with_checksum(input);
  const Scene& scene = checkpoint_scene();
  LogLengths run_log("run_log", 2), buds("bud_events", 1);
  const std::vector<Observer*> observers{&buds, &run_log};
  try {
    advance_from(io::parse_checkpoint(text, "fuzz.txt", scene, scene.seed, observers));
  } catch (const InputError&) {}
}

// The run log's section read as `budjam grow --resume` reads it: the two log lengths, each
// checked against the log in `dir` (its header as the file has it).
struct RunLogCuts : Observer {
  io::Directory dir;
  io::CsvLog::Cut steps, divisions;
  io::StepsLog steps_log;  // steps.csv up to its cut
  explicit RunLogCuts(io::Directory d) : dir(std::move(d)) {}
  std::string name() const override { return "run_log"; }
  bool stateful() const override { return true; }
  io::CsvLog::Cut cut(const std::string& log, std::uint64_t bytes) const {
    const std::string text = io::read_text_file(dir, log + ".partial");
    std::vector<std::string> columns;
    std::istringstream header(text.substr(0, text.find('\n')));
    for (std::string c; std::getline(header, c, ',');) columns.push_back(c);
    return io::CsvLog::check_resumable(dir, log, columns, bytes);
  }
  void load_state(std::istream& is) override {
    std::uint64_t s = 0, d = 0;
    if (!(is >> s >> d)) throw InputError("bad run_log state");
    steps = cut("steps.csv", s);
    steps_log = io::read_steps(io::read_text_file(dir, "steps.csv.partial").substr(0, s), "steps.csv.partial");
    divisions = cut("divisions.csv", d);
  }
};

// The resume checks past the checksum: the checkpoint parsed, then cross-checked against the
// logs and packings of a run of checkpoint_scene() killed after jamming (`run_dir`, e.g.
// fuzz/fixtures/resume/, as `budjam grow` left it), which are only read. Any input is refused
// with InputError or accepted; what is accepted is grown one attempt.
inline void resume(std::string_view input, const std::filesystem::path& run_dir) {
  const std::string text = with_checksum(input);
  const Scene& scene = checkpoint_scene();
  const io::Directory dir = io::Directory::open(run_dir, false);
  RunLogCuts run_log(dir);
  LogLengths buds("bud_events", 1);
  const std::vector<Observer*> observers{&buds, &run_log};
  try {
    io::CheckpointLines lines;
    GrowthState s = io::parse_checkpoint(text, "fuzz.txt", scene, scene.seed, observers, &lines);
    io::check_against_run(s, scene, lines, "fuzz.txt", run_log.steps, run_log.steps_log, run_log.divisions,
                          dir.subdirectory("packings", false));
    advance_from(std::move(s));
  } catch (const InputError&) {}
}

// Degenerate geometry, structured: the bytes place up to 48 cells in a small box (byte 0: L, byte 1:
// the Lees–Edwards shear; then 4 bytes per cell: x, y, θ, b, with x = 255 stacking the cell on the
// previous one), so that stacked, coincident and interpenetrating cells come at once, which text
// mutations of a packing file rarely reach. Every packing the reader accepts gets moduli and a
// dense spectrum with finite numbers, or a NoResultError (no answer, said so); never NaN as a result.
inline void degenerate(std::string_view bytes) {
  const auto byte = [&](std::size_t k) { return static_cast<double>(static_cast<unsigned char>(bytes[k])); };
  if (bytes.size() < 6) return;
  Packing p;
  p.box.L = 2.6 + byte(0) / 16;
  p.box.shear = (byte(1) - 128) / 256;
  for (std::size_t k = 2; k + 4 <= bytes.size() && p.size() < 48; k += 4) {
    if (byte(k) == 255 && p.size() > 0) {
      const std::size_t i = p.size() - 1;
      p.add_cell(p.x(i), p.y(i), p.theta(i), p.b[i], 0.002, -1);
    } else {
      p.add_cell(p.box.L * byte(k) / 256, p.box.L * byte(k + 1) / 256, 2 * std::numbers::pi * byte(k + 2) / 256,
                 1.2 * byte(k + 3) / 256, 0.002, -1);
    }
  }
  io::PackingFile f;
  try {
    f = io::parse_packing(io::format_packing(p), "fuzz.pack");
  } catch (const InputError&) {
    return;
  }
  const tools::PackingContacts pc = tools::analyse_contacts(f.packing);
  try {
    const ElasticResponse e = elastic_response(f.packing, pc.contacts, pc.network);
    require_relaxed_moduli(e, "fuzz.pack");
    if (e.energy_minimum() && !(std::isfinite(e.B()) && std::isfinite(e.G()) && std::isfinite(e.G_energy())))
      std::abort();
  } catch (const NoResultError&) {}
  if (pc.network.N_nr == 0) return;  // refused as input by the spectrum (tested elsewhere)
  try {
    SpectrumOptions o;
    o.method = SpectrumMethod::dense;
    if (!packing_spectrum(f.packing, pc.contacts, pc.network, o).spectrum.lambda.allFinite()) std::abort();
  } catch (const NoResultError&) {}
}

}  // namespace budjam::fuzz
