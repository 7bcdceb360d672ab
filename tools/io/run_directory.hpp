#pragma once
// The run directory of `budjam grow` (docs/growth.md "Run directory", docs/files.md "Run
// directories"): every file name a run uses, how a directory is claimed for writing, and what
// budjam may delete in it.
//
// Guarantees:
//  - a directory is a budjam run only if it holds the marker `.budjam-run` that budjam writes
//    when it claims the directory (not because some file such as scene.toml exists);
//  - a fresh run refuses a non-empty directory without the marker, and an existing run unless
//    asked to overwrite it; overwriting removes only the entries budjam creates (remove_run_outputs),
//    never anything else a user put there;
//  - one writer at a time: the writer holds an exclusive flock(2) on `.budjam-lock` for its whole
//    lifetime (released by the kernel when the process ends, however it ends); a second writer is
//    refused with a message naming the holder (pid and host);
//  - temporaries of atomic writes left by a killed writer (`.NAME.tmp-XXXXXX`) are removed when
//    the directory is claimed again.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

// Every name in a run directory, relative to it.
namespace run_files {
inline constexpr std::string_view marker = ".budjam-run";  // "budjam-run 1": budjam created this run
inline constexpr std::string_view lock = ".budjam-lock";   // flock(2) target; "pid host" of the writer
inline constexpr std::string_view scene = "scene.toml";    // the effective scene, seed included
inline constexpr std::string_view checkpoint = "checkpoint.txt";
inline constexpr std::string_view summary = "summary.json";  // written last: the run is over
inline constexpr std::string_view timing = "timing.json";
inline constexpr std::string_view steps = "steps.csv";
inline constexpr std::string_view divisions = "divisions.csv";
inline constexpr std::string_view bud_events = "bud_events.csv";
inline constexpr std::string_view moduli = "moduli.csv";
inline constexpr std::string_view dos = "dos.csv";
inline constexpr std::string_view rigidity = "rigidity_events.csv";
inline constexpr std::string_view trials = "trials.csv";
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
// True for `.NAME.tmp-XXXXXX`, the temporary of an atomic write (io/atomic_file.hpp).
bool is_temporary(std::string_view filename);
}  // namespace run_files

class RunDirectory {
 public:
  // Claims `dir` for a new run: creates it if needed, takes the lock, writes the marker.
  // InputError (exit 2, nothing touched) if `dir` is not a directory, is not empty and has no
  // marker, holds a run and `overwrite` is false, or another writer holds the lock. With
  // `overwrite`, the entries of the earlier run are removed (only those budjam creates).
  static RunDirectory create(const std::filesystem::path& dir, bool overwrite);
  // Claims the run in `dir` to continue it: marker and lock as above, and stale temporaries are
  // removed. Does not look at the checkpoint.
  static RunDirectory resume(const std::filesystem::path& dir);

  RunDirectory(RunDirectory&& other) noexcept;
  RunDirectory& operator=(RunDirectory&&) = delete;
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;
  ~RunDirectory();  // releases the lock

  const std::filesystem::path& path() const { return dir_; }
  std::filesystem::path operator/(std::string_view name) const { return dir_ / name; }

 private:
  RunDirectory(std::filesystem::path dir, int lock_fd) : dir_(std::move(dir)), lock_fd_(lock_fd) {}
  std::filesystem::path dir_;
  int lock_fd_ = -1;
};

// True if `dir` holds the marker of a budjam run.
bool is_run_directory(const std::filesystem::path& dir);

// Removes what a run creates in `dir` (run_files names, run packings and their sidecars, spectra,
// temporaries) and nothing else, keeping the marker and the lock; directories are removed only once empty. Returns the
// entries that were kept (relative paths, sorted), e.g. for a message.
std::vector<std::string> remove_run_outputs(const std::filesystem::path& dir);

// Removes the temporaries of interrupted atomic writes in `dir`, packings/ and spectra/.
void remove_stale_temporaries(const std::filesystem::path& dir);

}  // namespace budjam::io
