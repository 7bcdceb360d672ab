#pragma once
// The run directory of `budjam grow` (docs/growth.md "Run directory", docs/files.md "Run
// directories"): every file name a run uses, how a directory is claimed for writing, and what
// budjam may delete in it.
//
// Guarantees:
//  - a directory is a budjam run only if it holds the marker `.budjam-run` that budjam writes
//    when it claims the directory (not because some file such as scene.toml exists);
//  - a fresh run refuses a non-empty directory without the marker, and an existing run unless
//    asked to overwrite it; overwriting removes only the entries the run's writers declare
//    (remove_run_outputs), never anything else a user put there;
//  - every entry budjam uses is opened, replaced and removed relative to the directory's
//    descriptor without following links: a claim is refused (InputError, nothing changed) when one
//    of them is a symbolic link or not of its kind (a file where a file is expected, a real
//    directory for packings/ and spectra/);
//  - one writer at a time: the writer holds an exclusive flock(2) on `.budjam-lock` for its whole
//    lifetime (released by the kernel when the process ends, however it ends); a second writer is
//    refused with a message naming the holder (pid and host);
//  - temporaries of atomic writes are listed in `.budjam-temporaries` (io/atomic_file.hpp,
//    TemporaryManifest); the ones a killed writer left are removed when the directory is claimed
//    again (remove_recorded_temporaries), and no file is ever removed for its name's pattern.
#include "io/atomic_file.hpp"

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

// Every name in a run directory, relative to it.
namespace run_files {
inline constexpr std::string_view marker = ".budjam-run";               // "budjam-run 1": budjam created this run
inline constexpr std::string_view lock = ".budjam-lock";                // flock(2) target; "pid host" of the writer
inline constexpr std::string_view temporaries = ".budjam-temporaries";  // TemporaryManifest
inline constexpr std::string_view scene = "scene.toml";                 // the effective scene, seed included
inline constexpr std::string_view checkpoint = "checkpoint.txt";
inline constexpr std::string_view summary = "summary.json";  // written last: the run is over
inline constexpr int summary_version = 1;                    // its "version"; readers refuse others
inline constexpr std::string_view timing = "timing.json";
inline constexpr std::string_view steps = "steps.csv";
inline constexpr std::string_view divisions = "divisions.csv";
inline constexpr std::string_view bud_events = "bud_events.csv";
inline constexpr std::string_view moduli = "moduli.csv";
inline constexpr std::string_view dos = "dos.csv";
inline constexpr std::string_view rigidity = "rigidity_events.csv";
inline constexpr std::string_view trials = "trials.csv";
inline constexpr std::string_view trajectory = "trajectory.xyz";
// The observers' CSV logs beside steps, divisions and bud_events: the readers of a run
// (load_run's run_tables, `budjam.load_run`) read each one present, and no command's output may
// replace one (run_input_files). A new observer's log belongs here.
inline constexpr std::array<std::string_view, 4> observer_logs{moduli, dos, rigidity, trials};
// `budjam export` of trajectory.xyz to GSD
inline constexpr std::string_view trajectory_gsd = "trajectory.gsd";
inline constexpr std::string_view packings = "packings";  // <name>.pack and their sidecars
inline constexpr std::string_view spectra = "spectra";    // step_<n>.dos.{json,csv}
inline constexpr std::string_view jammed = "jammed";      // packings/jammed.pack
inline constexpr std::string_view phi2 = "phi2";          // packings/phi2.pack

// packings/<stem>.pack
std::filesystem::path packing(std::string_view stem);
// "target_<k>": the stem of the packing at the k-th target
std::string target_stem(std::size_t k);
// True for a packing stem a run writes (jammed, phi2, target_<k>).
bool is_run_packing_stem(std::string_view stem);
}  // namespace run_files

// Whether `name` matches `pattern`: '*' stands for any run of characters, '#' for a number as
// budjam writes one (decimal digits without a leading zero, "0" itself, at most 19 of them),
// everything else for itself.
bool matches_pattern(std::string_view pattern, std::string_view name);

// The entries of a run directory its writers declare, as patterns of relative paths
// ("steps.csv", "packings/target_#.pack", "spectra/step_#.dos.json"). A top-level file pattern also
// owns the file's `.partial` log; a pattern with a directory owns entries of that directory
// (one level), and the directory itself once empty.
using OwnedEntries = std::vector<std::string>;

namespace run_files {
// The files a run owns beside a packing packings/<stem>.pack (stem jammed, phi2 or target_<k>):
// the packing and exactly what budjam's commands and Makefile.analysis write beside it, the one
// list of them (docs/files.md, "Run directories"):
//   .pack                                   grow
//   .moduli.json                            moduli --out STEM.moduli (Makefile.analysis; analyse reads it)
//   .dos.json .dos.csv                      dos --out STEM.dos, the dos observer (Makefile.analysis)
//   .rigidity.json .rigidity.csv            rigidity --out STEM.rigidity
//   .svg .png .pdf                          render -o STEM.svg (--png, or -o STEM.png/.pdf)
//   .xyz .gsd .vtk                          export STEM.pack (its default BASE is STEM): every
//                                           format of export_formats()
// Anything else there (another suffix, a backup such as STEM.pack~ or STEM.pack.bak, a
// directory) is not the run's: --overwrite leaves it, and it does not make a claim refuse.
const std::vector<std::string_view>& packing_suffixes();
// The files a run owns in spectra/ beside a spectrum spectra/step_<n>: .dos.json and .dos.csv.
const std::vector<std::string_view>& spectrum_suffixes();
// "<sub>/<stem><suffix>" for each suffix (stem may be a pattern: "target_#", "step_#").
OwnedEntries entries_with_suffixes(std::string_view sub, std::string_view stem,
                                   const std::vector<std::string_view>& suffixes);
}  // namespace run_files

class RunDirectory {
 public:
  // Claims `dir` for a new run: creates it if needed, takes the lock, writes the marker.
  // InputError (exit 2, nothing touched) if `dir` is not a directory, is not empty and has no
  // marker, holds a run and `overwrite` is false, another writer holds the lock, or an entry of
  // the earlier run is a link or of the wrong kind. With `overwrite`, the recorded temporaries
  // and the `owned` entries of the earlier run are removed.
  static RunDirectory create(const std::filesystem::path& dir, bool overwrite, const OwnedEntries& owned);
  // Claims the run in `dir` to continue it (or to add its trajectory.gsd): marker, lock and entries
  // checked as above. Changes nothing but the lock file (the list of temporaries is created only
  // when one is first recorded); remove_recorded_temporaries() once the resume has been validated.
  static RunDirectory resume(const std::filesystem::path& dir, const OwnedEntries& owned);

  RunDirectory(RunDirectory&& other) noexcept;
  RunDirectory& operator=(RunDirectory&&) = delete;
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;
  ~RunDirectory();  // releases the lock

  const std::filesystem::path& path() const { return root_.path(); }
  std::filesystem::path operator/(std::string_view name) const { return root_ / name; }
  // The run directory; temporaries created in it and its subdirectories are recorded.
  const Directory& root() const { return root_; }
  // packings/, spectra/: created by budjam when absent, never a link.
  Directory subdirectory(std::string_view name) const { return root_.subdirectory(name, true); }
  // Removes the temporaries a killed writer left (and only those: TemporaryManifest).
  void remove_recorded_temporaries() { manifest_->remove_listed(); }

 private:
  RunDirectory(Directory root, int lock_fd) : root_(std::move(root)), lock_fd_(lock_fd) {}
  void open_manifest();
  Directory root_;
  int lock_fd_ = -1;
  std::shared_ptr<TemporaryManifest> manifest_;
};

// True if `dir` holds the marker of a budjam run.
bool is_run_directory(const std::filesystem::path& dir);

// Whether RunDirectory::create may claim `dir` for a new run: InputError unless it is empty but for
// the lock, or holds a run and `overwrite` is given. Returns whether it holds a run. create() asks
// before taking the lock and again once it holds it (a run finished meanwhile is not replaced).
bool check_claim(const Directory& dir, bool overwrite);

// True if `input` is a run's own trajectory.xyz (the entry of a run directory's top level, not a
// link) and `output` that run's trajectory.gsd: the one output of another command at a run's top
// level, an entry the run declares (`budjam export RUN/trajectory.xyz --format gsd`). The caller
// claims the run (RunDirectory::resume) and writes relative to its descriptor.
bool is_run_trajectory_conversion(const std::filesystem::path& input, const std::filesystem::path& output);

// InputError naming the first entry of `dir` that budjam uses (the lock, the marker, the list of
// temporaries, the `owned` entries and their directories) and that is a symbolic link or not of
// its kind.
void check_run_entries(const Directory& dir, const OwnedEntries& owned);

// Removes the `owned` entries of `dir` and nothing else, keeping the marker, the lock and the
// list of temporaries; directories are removed only once empty. Returns the entries that were
// kept (relative paths, sorted), e.g. for a message. Call check_run_entries first.
std::vector<std::string> remove_run_outputs(const Directory& dir, const OwnedEntries& owned);

}  // namespace budjam::io
