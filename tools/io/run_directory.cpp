#include "io/run_directory.hpp"

#include "budjam/scene.hpp"  // InputError
#include "io/export.hpp"
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
  return stem == jammed || stem == phi2 || matches_pattern("target_#", stem);
}

const std::vector<std::string_view>& packing_suffixes() {
  // export writes STEM.<format> for every format of its registry: a new format is the run's too.
  static const std::vector<std::string> exported = [] {
    std::vector<std::string> s;
    for (const ExportFormat& f : export_formats()) s.push_back("." + std::string(f.name));
    return s;
  }();
  static const std::vector<std::string_view> suffixes = [] {
    std::vector<std::string_view> s{".pack",         ".moduli.json", ".dos.json", ".dos.csv", ".rigidity.json",
                                    ".rigidity.csv", ".svg",         ".png",      ".pdf"};
    s.insert(s.end(), exported.begin(), exported.end());
    return s;
  }();
  return suffixes;
}

const std::vector<std::string_view>& spectrum_suffixes() {
  static const std::vector<std::string_view> suffixes{".dos.json", ".dos.csv"};
  return suffixes;
}

OwnedEntries entries_with_suffixes(std::string_view sub, std::string_view stem,
                                   const std::vector<std::string_view>& suffixes) {
  OwnedEntries out;
  for (const std::string_view suffix : suffixes)
    out.push_back(std::string(sub) + "/" + std::string(stem) + std::string(suffix));
  return out;
}

}  // namespace run_files

bool matches_pattern(std::string_view pattern, std::string_view name) {
  if (pattern.empty()) return name.empty();
  const char p = pattern.front();
  if (p == '*') {
    for (std::size_t k = 0; k <= name.size(); ++k)
      if (matches_pattern(pattern.substr(1), name.substr(k))) return true;
    return false;
  }
  if (p == '#') {
    // A number as budjam writes one (std::to_string of a step or an index): no leading zero, and
    // within 64 bits, so that "target_01" or a 20-digit name is a user's file, never the run's.
    constexpr std::size_t kMaxDigits = 19;
    std::size_t k = 0;
    while (k < name.size() && name[k] >= '0' && name[k] <= '9') ++k;
    k = std::min(k, k > 0 && name.front() == '0' ? std::size_t{1} : kMaxDigits);
    for (; k > 0; --k)
      if (matches_pattern(pattern.substr(1), name.substr(k))) return true;
    return false;
  }
  return !name.empty() && name.front() == p && matches_pattern(pattern.substr(1), name.substr(1));
}

namespace {

constexpr std::string_view kMarkerText = "budjam-run 1\n";
constexpr std::string_view kPartial = ".partial";

// The patterns of `owned` for directory `sub` ("" = top level), without the directory part.
std::vector<std::string_view> patterns_in(const OwnedEntries& owned, std::string_view sub) {
  std::vector<std::string_view> out;
  for (const std::string& o : owned) {
    const std::size_t slash = o.find('/');
    const std::string_view dir = slash == std::string::npos ? std::string_view() : std::string_view(o).substr(0, slash);
    if (dir == sub)
      out.push_back(slash == std::string::npos ? std::string_view(o) : std::string_view(o).substr(slash + 1));
  }
  return out;
}

std::vector<std::string> owned_subdirectories(const OwnedEntries& owned) {
  std::vector<std::string> out;
  for (const std::string& o : owned)
    if (const std::size_t slash = o.find('/'); slash != std::string::npos) out.push_back(o.substr(0, slash));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool owned_name(const std::vector<std::string_view>& patterns, std::string_view name, bool logs) {
  for (std::string_view p : patterns) {
    if (matches_pattern(p, name)) return true;
    if (logs && name.size() > kPartial.size() && name.substr(name.size() - kPartial.size()) == kPartial &&
        matches_pattern(p, name.substr(0, name.size() - kPartial.size())))
      return true;
  }
  return false;
}

bool is_bookkeeping(std::string_view name) {
  return name == run_files::lock || name == run_files::marker || name == run_files::temporaries;
}

void expect_regular(const Directory& dir, std::string_view name) {
  if (const auto st = dir.entry(name); st && !S_ISREG(st->st_mode)) {
    if (S_ISLNK(st->st_mode))
      throw InputError((dir / name).string() +
                       ": is a symbolic link; budjam does not follow links in a run directory (nothing was changed)");
    throw InputError((dir / name).string() + ": is not a regular file (nothing was changed)");
  }
  // A file with another hard link is also a file outside the run: writing it in place (the lock,
  // the logs) would change the other name's contents.
  if (const auto st = dir.entry(name); st && S_ISREG(st->st_mode) && st->st_nlink > 1)
    throw InputError((dir / name).string() + ": has " + std::to_string(st->st_nlink - 1) +
                     " other hard link(s); budjam writes only files of its own (nothing was changed)");
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown host";
  return buf;
}

// Opens and flock()s DIR/.budjam-lock; the lock lives as long as the descriptor (and dies with
// the process). InputError naming the holder if another process has it.
int take_lock(const Directory& dir) {
  expect_regular(dir, run_files::lock);
  const int fd = dir.open_file(run_files::lock, O_RDWR | O_CREAT);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[300] = {};
    const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
    ::close(fd);
    if (err != EWOULDBLOCK) throw IoError((dir / run_files::lock).string() + ": cannot lock: " + std::strerror(err));
    std::string holder = n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
    while (!holder.empty() && holder.back() == '\n') holder.pop_back();
    throw InputError(dir.path().string() + ": another budjam process is writing this run (" +
                     (holder.empty() ? std::string("holder unknown") : escape_control(holder)) + ")");
  }
  const std::string me = "pid " + std::to_string(::getpid()) + " on " + host_name() + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    const int err = errno;
    ::close(fd);
    throw IoError((dir / run_files::lock).string() + ": cannot write the lock file: " + std::strerror(err));
  }
  return fd;
}

// Written in place, not through a temporary: a concurrent claim must only ever see the lock and
// the marker, and the marker's existence is all that counts.
void write_marker(const Directory& dir) {
  const int fd = dir.open_file(run_files::marker, O_WRONLY | O_CREAT | O_TRUNC);
  const bool ok = ::write(fd, kMarkerText.data(), kMarkerText.size()) == static_cast<ssize_t>(kMarkerText.size());
  const int err = errno;
  ::close(fd);
  if (!ok) throw IoError((dir / run_files::marker).string() + ": cannot write: " + std::strerror(err));
}

bool has_marker(const Directory& dir) {
  expect_regular(dir, run_files::marker);
  return dir.entry(run_files::marker).has_value();
}

bool empty_but_lock(const Directory& dir) {
  for (const std::string& name : dir.names())
    if (name != run_files::lock) return false;
  return true;
}

}  // namespace

bool is_run_directory(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(fs::symlink_status(dir / run_files::marker, ec));
}

bool is_run_trajectory_conversion(const fs::path& input, const fs::path& output) {
  if (input.filename() != run_files::trajectory || output.filename() != run_files::trajectory_gsd) return false;
  const fs::path dir = input.parent_path().empty() ? fs::path(".") : input.parent_path();
  const fs::path out_dir = output.parent_path().empty() ? fs::path(".") : output.parent_path();
  std::error_code ec;
  if (!is_run_directory(dir) || !fs::is_regular_file(fs::symlink_status(input, ec))) return false;
  return fs::equivalent(dir, out_dir, ec);
}

void check_run_entries(const Directory& dir, const OwnedEntries& owned) {
  const auto top = patterns_in(owned, "");
  for (const std::string& name : dir.names())
    if (is_bookkeeping(name) || owned_name(top, name, true)) expect_regular(dir, name);
  for (const std::string& sub : owned_subdirectories(owned)) {
    const auto st = dir.entry(sub);
    if (!st) continue;
    const Directory d = dir.subdirectory(sub, false);  // refuses a link or another kind
    const auto inside = patterns_in(owned, sub);
    for (const std::string& name : d.names())
      if (owned_name(inside, name, false)) expect_regular(d, name);
  }
}

std::vector<std::string> remove_run_outputs(const Directory& dir, const OwnedEntries& owned) {
  const auto top = patterns_in(owned, "");
  const auto subs = owned_subdirectories(owned);
  std::vector<std::string> kept;
  // The summary says the run finished: it goes first, so that a removal stopped half-way (a file it
  // may not delete) leaves a run that no reader takes for a finished one.
  if (const auto st = dir.entry(run_files::summary);
      st && S_ISREG(st->st_mode) && owned_name(top, run_files::summary, false))
    dir.remove(run_files::summary);
  for (const std::string& name : dir.names()) {
    if (is_bookkeeping(name)) continue;  // still a run, if an empty one
    const auto st = dir.entry(name);
    if (!st) continue;
    if (S_ISREG(st->st_mode) && owned_name(top, name, true)) {
      dir.remove(name);
    } else if (S_ISDIR(st->st_mode) && std::find(subs.begin(), subs.end(), name) != subs.end()) {
      const Directory d = dir.subdirectory(name, false);
      const auto inside = patterns_in(owned, name);
      for (const std::string& f : d.names()) {
        const auto fst = d.entry(f);
        if (fst && S_ISREG(fst->st_mode) && owned_name(inside, f, false))
          d.remove(f);
        else
          kept.push_back(name + "/" + f);
      }
      if (d.names().empty()) dir.remove(name);
    } else {
      kept.push_back(name);
    }
  }
  dir.sync();
  std::sort(kept.begin(), kept.end());
  return kept;
}

bool check_claim(const Directory& dir, bool overwrite) {
  const bool run = has_marker(dir);
  if (!run && !empty_but_lock(dir))
    throw InputError("--out: " + dir.path().string() + " is not empty and is not a budjam run directory (no " +
                     std::string(run_files::marker) + "); nothing was changed");
  if (run && !overwrite) {
    // --resume continues only a run that has not finished and left a checkpoint
    const bool resumable = !dir.entry(run_files::summary) && dir.entry(run_files::checkpoint);
    throw InputError("--out: " + dir.path().string() +
                     (resumable ? " holds an unfinished budjam run" : " holds a budjam run") +
                     "; pass --overwrite to replace it" +
                     (resumable ? ", or continue it with budjam grow --resume " + dir.path().string() : ""));
  }
  return run;
}

void RunDirectory::open_manifest() {
  manifest_ = std::make_shared<TemporaryManifest>(root_, run_files::temporaries);
  root_.record_temporaries_in(manifest_);
}

RunDirectory RunDirectory::create(const fs::path& dir, bool overwrite, const OwnedEntries& owned) {
  std::error_code ec;
  const bool exists = fs::exists(fs::symlink_status(dir, ec));
  if (exists && !fs::is_directory(dir, ec))
    throw InputError("--out: " + dir.string() +
                     (fs::exists(dir, ec) ? " exists and is not a directory" : " is a symbolic link to nothing"));
  refuse_directory_in_run("--out", dir);
  Directory root = Directory::open(dir, true);
  // Before the lock, so that a user's directory never gets a lock file; and again once it is held,
  // so that a run another process finished in between is not replaced without --overwrite.
  check_claim(root, overwrite);
  RunDirectory claimed(root, take_lock(root));
  const bool run = check_claim(root, overwrite);
  if (run) {
    check_run_entries(root, owned);
    claimed.open_manifest();
    claimed.remove_recorded_temporaries();
    remove_run_outputs(root, owned);
  }
  write_marker(root);
  if (!claimed.manifest_) claimed.open_manifest();
  return claimed;
}

RunDirectory RunDirectory::resume(const fs::path& dir, const OwnedEntries& owned) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError("--resume: " + dir.string() + ": no such directory");
  Directory root = Directory::open(dir, false);
  if (!has_marker(root))
    throw InputError("--resume: " + dir.string() + " is not a budjam run directory (no " +
                     std::string(run_files::marker) + ")");
  RunDirectory claimed(root, take_lock(root));
  check_run_entries(root, owned);
  claimed.open_manifest();
  return claimed;
}

RunDirectory::RunDirectory(RunDirectory&& o) noexcept
    : root_(std::move(o.root_)), lock_fd_(o.lock_fd_), manifest_(std::move(o.manifest_)) {
  o.lock_fd_ = -1;
}

RunDirectory::~RunDirectory() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // closing the descriptor releases the flock
}

}  // namespace budjam::io
