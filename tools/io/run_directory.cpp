#include "io/run_directory.hpp"

#include "budjam/scene.hpp"  // InputError
#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

namespace budjam::io {

namespace fs = std::filesystem;

namespace run_files {

fs::path packing(std::string_view stem) { return fs::path(packings) / (std::string(stem) + ".pack"); }

std::string target_stem(std::size_t k) { return "target_" + std::to_string(k); }

bool is_run_packing_stem(std::string_view stem) {
  if (stem == jammed || stem == phi2) return true;
  constexpr std::string_view prefix = "target_";
  if (stem.substr(0, prefix.size()) != prefix || stem.size() == prefix.size()) return false;
  return std::all_of(stem.begin() + prefix.size(), stem.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool is_temporary(std::string_view name) {
  return name.size() > 1 && name.front() == '.' && name.find(".tmp-") != std::string_view::npos;
}

}  // namespace run_files

namespace {

constexpr std::string_view kMarkerText = "budjam-run 1\n";

// The top-level files a run writes (logs also as NAME.partial).
const std::vector<std::string_view>& owned_files() {
  using namespace run_files;
  static const std::vector<std::string_view> names{scene,      checkpoint, summary, timing,   steps, divisions,
                                                   bud_events, moduli,     dos,     rigidity, trials};
  return names;
}

bool owned_top_level(const std::string& name) {
  for (std::string_view f : owned_files())
    if (name == f || name == std::string(f) + ".partial") return true;
  return run_files::is_temporary(name);
}

// packings/<stem>.pack and sidecars <stem>.<anything> of a run packing; spectra/step_<n>.dos.*.
bool owned_in_subdirectory(std::string_view sub, const std::string& name) {
  if (run_files::is_temporary(name)) return true;
  const std::size_t dot = name.find('.');
  if (dot == std::string::npos) return false;
  const std::string_view stem = std::string_view(name).substr(0, dot);
  if (sub == run_files::packings) return run_files::is_run_packing_stem(stem);
  return stem.substr(0, 5) == "step_";
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown host";
  return buf;
}

// Opens and flock()s DIR/.budjam-lock; the lock lives as long as the descriptor (and dies with
// the process). InputError naming the holder if another process has it.
int take_lock(const fs::path& dir) {
  const fs::path path = dir / run_files::lock;
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) throw IoError(path.string() + ": cannot create the lock file: " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[300] = {};
    const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
    ::close(fd);
    if (err != EWOULDBLOCK) throw IoError(path.string() + ": cannot lock: " + std::strerror(err));
    std::string holder = n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
    while (!holder.empty() && holder.back() == '\n') holder.pop_back();
    throw InputError(dir.string() + ": another budjam process is writing this run (" +
                     (holder.empty() ? std::string("holder unknown") : escape_control(holder)) + ")");
  }
  const std::string me = "pid " + std::to_string(::getpid()) + " on " + host_name() + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    const int err = errno;
    ::close(fd);
    throw IoError(path.string() + ": cannot write the lock file: " + std::strerror(err));
  }
  return fd;
}

// Written in place, not through a temporary: a concurrent claim must only ever see the lock and
// the marker, and the marker's existence is all that counts.
void write_marker(const fs::path& dir) {
  const fs::path path = dir / run_files::marker;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  const bool ok =
      fd >= 0 && ::write(fd, kMarkerText.data(), kMarkerText.size()) == static_cast<ssize_t>(kMarkerText.size());
  const int err = errno;
  if (fd >= 0) ::close(fd);
  if (!ok) throw IoError(path.string() + ": cannot write: " + std::strerror(err));
}

bool empty_but_lock(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != run_files::lock) return false;
  return true;
}

}  // namespace

bool is_run_directory(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / run_files::marker, ec);
}

std::vector<std::string> remove_run_outputs(const fs::path& dir) {
  std::vector<std::string> kept;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name == run_files::lock || name == run_files::marker) continue;  // still a run, if an empty one
    if (owned_top_level(name) && !e.is_directory()) {
      fs::remove(e.path());
    } else if ((name == run_files::packings || name == run_files::spectra) && e.is_directory() && !e.is_symlink()) {
      for (const auto& f : fs::directory_iterator(e.path())) {
        const std::string fname = f.path().filename().string();
        if (!f.is_directory() && owned_in_subdirectory(name, fname))
          fs::remove(f.path());
        else
          kept.push_back(name + "/" + fname);
      }
      if (fs::is_empty(e.path())) fs::remove(e.path());
    } else {
      kept.push_back(name);
    }
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

void remove_stale_temporaries(const fs::path& dir) {
  for (const fs::path& d : {dir, dir / run_files::packings, dir / run_files::spectra}) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) continue;
    for (const auto& e : fs::directory_iterator(d))
      if (run_files::is_temporary(e.path().filename().string()) && !e.is_directory()) fs::remove(e.path());
  }
}

RunDirectory RunDirectory::create(const fs::path& dir, bool overwrite) {
  std::error_code ec;
  const bool exists = fs::exists(fs::symlink_status(dir, ec));
  if (exists && !fs::is_directory(dir, ec))
    throw InputError("--out: " + dir.string() + " exists and is not a directory");
  if (exists && !is_run_directory(dir) && !empty_but_lock(dir))
    throw InputError("--out: " + dir.string() + " is not empty and is not a budjam run directory (no " +
                     std::string(run_files::marker) + "); nothing was changed");
  fs::create_directories(dir, ec);
  if (ec) throw IoError(dir.string() + ": cannot create directory: " + ec.message());
  const int fd = take_lock(dir);
  RunDirectory run(dir, fd);
  if (is_run_directory(dir)) {
    if (!overwrite)
      throw InputError("--out: " + dir.string() +
                       " holds a budjam run; pass --overwrite to replace it, or "
                       "continue it with budjam grow --resume " +
                       dir.string());
    remove_run_outputs(dir);
  }
  write_marker(dir);
  return run;
}

RunDirectory RunDirectory::resume(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError("--resume: " + dir.string() + ": no such directory");
  if (!is_run_directory(dir))
    throw InputError("--resume: " + dir.string() + " is not a budjam run directory (no " +
                     std::string(run_files::marker) + ")");
  RunDirectory run(dir, take_lock(dir));
  remove_stale_temporaries(dir);
  return run;
}

RunDirectory::RunDirectory(RunDirectory&& o) noexcept : dir_(std::move(o.dir_)), lock_fd_(o.lock_fd_) {
  o.lock_fd_ = -1;
}

RunDirectory::~RunDirectory() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // closing the descriptor releases the flock
}

}  // namespace budjam::io
