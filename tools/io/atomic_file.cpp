#include "io/atomic_file.hpp"

#include "budjam/errors.hpp"
#include "io/run_directory.hpp"
#include "io/run_program.hpp"
#include "io/text.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace budjam::io {

SignalsHeld::SignalsHeld() {
  sigset_t held;
  sigemptyset(&held);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&held, sig);
  ::pthread_sigmask(SIG_BLOCK, &held, &old_);
}

SignalsHeld::~SignalsHeld() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
namespace fs = std::filesystem;

namespace {

std::string reason(int err) { return std::strerror(err); }

[[noreturn]] void io_fail(const fs::path& path, const std::string& what, int err) {
  throw IoError(path.string() + ": " + what + ": " + reason(err));
}

// Permissions a plain open(…, 0666) would give, honouring the user's umask.
mode_t file_mode() {
  static const mode_t mode = [] {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    return static_cast<mode_t>(0666 & ~mask);
  }();
  return mode;
}

void write_all(int fd, std::string_view data, const fs::path& path) {
  while (!data.empty()) {
    const ssize_t n = ::write(fd, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      io_fail(path, "cannot write", errno);
    }
    data.remove_prefix(static_cast<std::size_t>(n));
  }
}

// The whole of an input file: a regular file (a FIFO would wait for a writer, a device such as
// /dev/zero never end) of at most kMaxInputBytes.
std::string read_all(int fd, const fs::path& path) {
  const std::string at = path.string() + ": cannot read: ";
  struct ::stat st {};
  if (::fstat(fd, &st) != 0) throw InputError(at + reason(errno));
  if (S_ISDIR(st.st_mode)) throw InputError(at + "is a directory");
  if (!S_ISREG(st.st_mode)) throw InputError(at + "is not a regular file (a FIFO, a device or a socket)");
  const auto too_large = [&] {
    return InputError(at + "larger than " + std::to_string(kMaxInputBytes >> 30) + " GiB, the most budjam reads");
  };
  if (static_cast<std::uint64_t>(st.st_size) > kMaxInputBytes) throw too_large();
  std::string text;
  char buf[65536];
  while (true) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(at + reason(errno));
    if (n == 0) return text;
    if (text.size() + static_cast<std::size_t>(n) > kMaxInputBytes) throw too_large();  // grew while read
    text.append(buf, static_cast<std::size_t>(n));
  }
}

// An entry that is not what budjam expects there is the user's input: exit 2.
[[noreturn]] void wrong_kind(const fs::path& path, const struct ::stat& st, const char* expected) {
  if (S_ISLNK(st.st_mode))
    throw InputError(path.string() + ": is a symbolic link; budjam does not follow links in the directories it writes");
  throw InputError(path.string() + ": is not " + expected);
}

// The deepest part of `path` that is an entry (a link to nothing included), or empty if none is.
fs::path deepest_entry(const fs::path& path) {
  std::error_code ec;
  for (fs::path p = path; !p.empty(); p = p.parent_path()) {
    if (fs::exists(fs::symlink_status(p, ec))) return p;
    if (p == p.parent_path()) break;
  }
  return {};
}

// "" when `part` is `path` itself, else "PART " to start a message about `path` with.
std::string which_part(const fs::path& path, const fs::path& part) {
  return part == path ? "" : escape_control(part.string()) + " ";
}

// `.NAME.tmp-XXXXXX`: the only names TemporaryManifest::remove_listed removes.
bool looks_temporary(std::string_view name) {
  const std::size_t at = name.rfind(".tmp-");
  return name.size() > 1 && name.front() == '.' && at != std::string_view::npos && name.size() - at == 11;
}

}  // namespace

// ---- Directory -----------------------------------------------------------------------------

namespace {

// The parts of `path` that do not exist, outermost first ("." and ".." name no new directory).
std::vector<fs::path> missing_directories(const fs::path& path) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (fs::path p = path; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    if (p.has_filename() && p.filename() != "." && p.filename() != "..") out.insert(out.begin(), p);
    if (p == p.parent_path()) break;
  }
  return out;
}

// Removes the directories this process created, deepest first, each only if still empty (rmdir).
void remove_created(const std::vector<fs::path>& created) noexcept {
  for (auto it = created.rbegin(); it != created.rend(); ++it) ::rmdir(it->c_str());
}

}  // namespace

struct Directory::Handle {
  int fd = -1;
  std::vector<fs::path> created;  // by open(), outermost first
  bool keep = false;
  explicit Handle(int f) : fd(f) {}
  ~Handle() {
    if (fd >= 0) ::close(fd);
    if (!keep) remove_created(created);  // "nothing written": not even the directories
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
};

int Directory::fd() const { return handle_ ? handle_->fd : -1; }

void Directory::keep_created() const {
  if (handle_) handle_->keep = true;
}

Directory Directory::open(const fs::path& path, bool create) {
  std::vector<fs::path> created;
  if (create && !path.empty()) {
    refuse_directory_in_run("", path, false);
    created = missing_directories(path);
    std::error_code ec;
    fs::create_directories(path, ec);
    std::error_code lec;
    if (ec) remove_created(created);  // the ones made before the failure
    if (ec && !fs::is_directory(path, lec)) {
      // A file, a dangling link or too long a name on the way is the user's spelling: exit 2.
      if (const fs::path e = deepest_entry(path); !e.empty() && !fs::exists(fs::status(e, lec)))
        throw InputError(path.string() + ": " + which_part(path, e) +
                         "is a symbolic link to nothing; cannot create the directory");
      if (ec == std::errc::file_exists || ec == std::errc::not_a_directory || ec == std::errc::filename_too_long ||
          ec == std::errc::too_many_symbolic_link_levels)
        throw InputError(path.string() + ": cannot create directory: " + ec.message());
      throw IoError(path.string() + ": cannot create directory: " + ec.message());
    }
  }
  const int fd = ::open(path.empty() ? "." : path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    remove_created(created);
    errno = err;
    if (errno == ENOTDIR) throw InputError(path.string() + ": is not a directory");
    if (errno == ENAMETOOLONG || errno == ELOOP)
      throw InputError(path.string() + ": cannot open directory: " + reason(errno));
    io_fail(path, "cannot open directory", errno);
  }
  Directory d;
  d.handle_ = std::make_shared<Handle>(fd);
  d.handle_->created = std::move(created);
  d.path_ = path;
  return d;
}

Directory Directory::subdirectory(std::string_view name, bool create) const {
  const std::string n(name);
  if (create && ::mkdirat(fd(), n.c_str(), 0777) != 0 && errno != EEXIST) io_fail(*this / name, "cannot create", errno);
  if (const auto st = entry(name); st && !S_ISDIR(st->st_mode)) wrong_kind(*this / name, *st, "a directory");
  const int sub = ::openat(fd(), n.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (sub < 0) {
    if (errno == ENOENT) throw InputError((*this / name).string() + ": no such directory");
    io_fail(*this / name, "cannot open directory", errno);
  }
  Directory d;
  d.handle_ = std::make_shared<Handle>(sub);
  d.path_ = *this / name;
  d.manifest_ = manifest_;
  d.prefix_ = prefix_ + n + "/";
  return d;
}

std::optional<struct ::stat> Directory::entry(std::string_view name) const {
  struct ::stat st {};
  if (::fstatat(fd(), std::string(name).c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0) return st;
  if (errno == ENOENT) return std::nullopt;
  io_fail(*this / name, "cannot stat", errno);
}

std::vector<std::string> Directory::names() const {
  const int copy = ::openat(fd(), ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  DIR* d = copy < 0 ? nullptr : ::fdopendir(copy);
  if (!d) {
    const int err = errno;
    if (copy >= 0) ::close(copy);
    io_fail(path_, "cannot list", err);
  }
  std::vector<std::string> out;
  while (const dirent* e = ::readdir(d)) {
    const std::string_view n = e->d_name;
    if (n != "." && n != "..") out.emplace_back(n);
  }
  ::closedir(d);
  std::sort(out.begin(), out.end());
  return out;
}

int Directory::open_file(std::string_view name, int flags) const {
  const fs::path where = *this / name;
  // O_NONBLOCK: a FIFO planted under an expected name must not hang the open.
  const int f = ::openat(fd(), std::string(name).c_str(), flags | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0666);
  if (f < 0) {
    const int err = errno;
    if (err == ELOOP || err == ENXIO || err == EISDIR) {
      if (const auto st = entry(name)) wrong_kind(where, *st, "a regular file");
    }
    if (err == ENOENT) throw InputError(where.string() + ": no such file");
    io_fail(where, "cannot open", err);
  }
  struct ::stat st {};
  if (::fstat(f, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(f);
    wrong_kind(where, st, "a regular file");
  }
  // Written in place, a file with another hard link would change under that other name too.
  if ((flags & (O_WRONLY | O_RDWR)) != 0 && st.st_nlink > 1) {
    ::close(f);
    throw InputError(where.string() + ": has another hard link; budjam writes in place only files of its own");
  }
  ::fcntl(f, F_SETFL, ::fcntl(f, F_GETFL) & ~O_NONBLOCK);
  return f;
}

void Directory::remove(std::string_view name) const {
  const std::string n(name);
  if (::unlinkat(fd(), n.c_str(), 0) == 0 || errno == ENOENT) return;
  if ((errno == EISDIR || errno == EPERM) && ::unlinkat(fd(), n.c_str(), AT_REMOVEDIR) == 0) return;
  io_fail(*this / name, "cannot remove", errno);
}

void Directory::rename(std::string_view from, std::string_view to) const {
  if (::renameat(fd(), std::string(from).c_str(), fd(), std::string(to).c_str()) != 0)
    io_fail(*this / to, "cannot rename " + std::string(from) + " to it", errno);
}

void Directory::sync() const {
  ::fsync(fd());  // best effort: the data itself is already synced
}

void Directory::record_temporaries_in(std::shared_ptr<TemporaryManifest> manifest, std::string root_prefix) {
  manifest_ = std::move(manifest);
  prefix_ = std::move(root_prefix);
}

// ---- TemporaryManifest ---------------------------------------------------------------------

namespace {

// Temporaries that found no slot in the list remove_open_temporaries() reads: while one is open, a
// handler cannot remove them all, and so must leave the lists of temporaries that name them.
std::atomic<int> g_unlisted{0};
// The descriptors of the lists of temporaries that name only this process's own (-1: free): a
// handler empties them once it has removed those temporaries. A list that finds no slot keeps its
// names after a signal; the next claim of its tree removes the files.
std::array<std::atomic<int>, 8> g_own_manifests{-1, -1, -1, -1, -1, -1, -1, -1};

void register_own_manifest(int fd) {
  for (std::atomic<int>& m : g_own_manifests) {
    int free = -1;
    if (m.load() == fd || m.compare_exchange_strong(free, fd)) return;
  }
}

void unregister_own_manifest(int fd) {
  for (std::atomic<int>& m : g_own_manifests) {
    int ours = fd;
    m.compare_exchange_strong(ours, -1);
  }
}

}  // namespace

TemporaryManifest::TemporaryManifest(Directory root, std::string_view name) : root_(std::move(root)), name_(name) {}

void TemporaryManifest::open(bool create) {
  if (fd_ >= 0) return;
  fd_ = root_.open_file(name_, O_RDWR | O_APPEND | (create ? O_CREAT : 0));
  // An empty list names nothing of another process; a list with names waits for remove_listed().
  struct stat st {};
  if (::fstat(fd_, &st) == 0 && st.st_size == 0) register_own_manifest(fd_);
}

TemporaryManifest::~TemporaryManifest() {
  if (fd_ < 0) return;
  unregister_own_manifest(fd_);
  ::close(fd_);
}

void TemporaryManifest::add(const std::string& relative) {
  open(true);
  ++outstanding_;
  write_all(fd_, relative + "\n", root_.path() / name_);
}

void TemporaryManifest::done() {
  if (--outstanding_ == 0 && fd_ >= 0 && ::ftruncate(fd_, 0) != 0)
    io_fail(root_.path() / name_, "cannot empty the temporaries list", errno);
}

void TemporaryManifest::remove_listed() {
  if (fd_ < 0 && !root_.entry(name_)) return;  // no list: nothing was left
  open(false);
  ::lseek(fd_, 0, SEEK_SET);
  const std::string text = read_all(fd_, root_.path() / name_);
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line = std::string_view(text).substr(start, end - start);
    start = end + 1;
    // Only `[dir/]...name` paths of budjam temporaries, each directory a real one of the tree.
    std::vector<std::string_view> parts;
    for (std::size_t at = 0; at <= line.size();) {
      const std::size_t slash = std::min(line.find('/', at), line.size());
      parts.push_back(line.substr(at, slash - at));
      at = slash + 1;
    }
    if (!looks_temporary(parts.back())) continue;
    Directory d = root_;
    bool ok = true;
    for (std::size_t k = 0; ok && k + 1 < parts.size(); ++k) {
      const auto st = parts[k] == "." || parts[k] == ".." || parts[k].empty() ? std::nullopt : d.entry(parts[k]);
      ok = st && S_ISDIR(st->st_mode);
      if (ok) d = d.subdirectory(parts[k], false);
    }
    if (!ok) continue;
    if (const auto st = d.entry(parts.back()); st && S_ISREG(st->st_mode)) d.remove(parts.back());
  }
  if (::ftruncate(fd_, 0) != 0) io_fail(root_.path() / name_, "cannot empty the temporaries list", errno);
  outstanding_ = 0;
  register_own_manifest(fd_);
}

// ---- TempFile ------------------------------------------------------------------------------

namespace {

// The open temporaries as a signal handler can read them: a directory descriptor (-1: free, -2:
// being filled) and a name. A temporary that finds no free slot is still removed by its
// destructor; only a signal would leave it.
struct OpenTemporary {
  std::atomic<int> dir_fd{-1};
  char name[NAME_MAX + 1];
};
static_assert(std::atomic<int>::is_always_lock_free);
std::array<OpenTemporary, 32> g_open_temporaries;

int list_temporary(int dir_fd, const std::string& name) {
  if (name.size() > NAME_MAX) return -1;
  for (std::size_t k = 0; k < g_open_temporaries.size(); ++k) {
    int free = -1;
    OpenTemporary& t = g_open_temporaries[k];
    if (!t.dir_fd.compare_exchange_strong(free, -2)) continue;
    std::memcpy(t.name, name.c_str(), name.size() + 1);
    t.dir_fd.store(dir_fd);
    return static_cast<int>(k);
  }
  return -1;
}

void unlist_temporary(int slot) {
  if (slot >= 0) g_open_temporaries[static_cast<std::size_t>(slot)].dir_fd.store(-1);
}

}  // namespace

void remove_open_temporaries() noexcept {
  for (const OpenTemporary& t : g_open_temporaries) {
    const int fd = t.dir_fd.load();
    if (fd >= 0) ::unlinkat(fd, t.name, 0);
  }
  // A list left naming removed files would make the next claim of its tree remove whatever a user
  // has created under those names since.
  if (g_unlisted.load() != 0) return;
  for (const std::atomic<int>& m : g_own_manifests) {
    const int fd = m.load();
    if (fd >= 0) (void)::ftruncate(fd, 0);
  }
}

extern "C" void end_process_without_temporaries(int sig) {
  stop_running_program();  // first: a converter still running would write its file anew
  remove_open_temporaries();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

TemporariesRemovedOnStop::TemporariesRemovedOnStop() {
  replaced_[0].sig = SIGTERM;
  replaced_[1].sig = SIGHUP;
  for (Replaced& r : replaced_) {
    if (::sigaction(r.sig, nullptr, &r.old) != 0 || (r.old.sa_flags & SA_SIGINFO) || r.old.sa_handler != SIG_DFL)
      continue;
    struct sigaction sa {};
    sa.sa_handler = end_process_without_temporaries;
    sigemptyset(&sa.sa_mask);
    r.installed = ::sigaction(r.sig, &sa, nullptr) == 0;
  }
}

TemporariesRemovedOnStop::~TemporariesRemovedOnStop() {
  for (const Replaced& r : replaced_)
    if (r.installed) ::sigaction(r.sig, &r.old, nullptr);
}

TempFile::TempFile(Directory dir, std::string_view final_name) : dir_(std::move(dir)), final_(final_name) {
  static constexpr char kChars[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::optional<SignalsHeld> held(std::in_place);  // until the file is listed
  for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
    name_.assign(1, '.');  // not = "." nor "." + string: GCC 12 -O3 misreads those as overlapping (-Wrestrict)
    name_ += final_;
    name_ += ".tmp-";
    for (int k = 0; k < 6; ++k) name_ += kChars[rng() % (sizeof kChars - 1)];
    fd_ = ::openat(dir_.fd(), name_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ < 0 && errno != EEXIST) io_fail(dir_ / final_, "cannot create a temporary file beside it", errno);
  }
  if (fd_ < 0) io_fail(dir_ / final_, "cannot create a temporary file beside it", EEXIST);
  slot_ = list_temporary(dir_.fd(), name_);
  unlisted_ = slot_ < 0;
  if (unlisted_) ++g_unlisted;
  held.reset();
  // Recorded once it exists: the list never names a file this process did not create.
  if (dir_.manifest()) {
    try {
      dir_.manifest()->add(dir_.manifest_prefix() + name_);
    } catch (...) {
      ::close(fd_);
      ::unlinkat(dir_.fd(), name_.c_str(), 0);
      forget_name();
      throw;
    }
  }
}

TempFile::~TempFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) ::unlinkat(dir_.fd(), name_.c_str(), 0);
  forget_name();  // after the name is gone: a signal in between finds nothing to remove
  if (dir_.manifest()) {
    try {
      dir_.manifest()->done();
    } catch (const IoError&) {
      // A list that could not be emptied only names files that no longer exist.
    }
  }
}

void TempFile::forget_name() {
  unlist_temporary(std::exchange(slot_, -1));
  if (std::exchange(unlisted_, false)) --g_unlisted;
}

// Errors name the file being written, not its temporary: the user never asked for that name.
void TempFile::write(std::string_view data) { write_all(fd_, data, dir_ / final_); }

void TempFile::commit() {
  const int ours = std::exchange(fd_, -1);
  if (::close(ours) != 0) io_fail(dir_ / final_, "cannot close", errno);
  // By name again: a program given path() may have written or replaced it.
  const int fd = dir_.open_file(name_, O_RDONLY);
  const bool ok = ::fchmod(fd, file_mode()) == 0 && ::fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  if (!ok) io_fail(dir_ / final_, "cannot sync", err);
  dir_.rename(name_, final_);
  committed_ = true;
  dir_.keep_created();
  forget_name();
  dir_.sync();
}

namespace {

std::string output_at(std::string_view option, const fs::path& path) {
  const std::string text = path.empty() ? "\"\"" : escape_control(path.string());
  return (option.empty() ? "" : std::string(option) + ": ") + text + ": ";
}

// The name alone: given, and short enough for the temporary `.NAME.tmp-XXXXXX` beside it.
void check_output_spelling(std::string_view option, const fs::path& path) {
  const std::string text = path.string();
  const std::string name = path.filename().string();
  if (text.empty() || text.back() == '/' || name.empty() || name == "." || name == "..")
    throw InputError(output_at(option, path) + "not a file name (it names a directory)");
  if (name.size() > kMaxOutputName)
    throw InputError(output_at(option, path) + "file name too long (" + std::to_string(name.size()) +
                     " bytes; at most " + std::to_string(kMaxOutputName) + ")");
}

// A run directory's top level holds its run's files, which budjam grow writes, and so does its
// spectra/ (the dos observer's): another command's output there could replace one of them
// (summary.json, a log, a spectrum) and break the run for every reader.
bool holds_only_run_files(const fs::path& dir) {
  std::error_code ec;
  return is_run_directory(dir) || (fs::weakly_canonical(dir, ec).filename() == run_files::spectra && !ec &&
                                   is_run_directory(fs::weakly_canonical(dir, ec).parent_path()));
}

void refuse_run_directory(std::string_view option, const fs::path& shown, const fs::path& dir) {
  const fs::path d = dir.empty() ? fs::path(".") : dir;
  if (holds_only_run_files(d))
    throw InputError(output_at(option, shown) + escape_control(d.string()) +
                     (is_run_directory(d) ? " is a budjam run directory, whose top level"
                                          : " is the spectra directory of a budjam run, which") +
                     " holds only the run's own files (write elsewhere, or beside its packings in packings/)");
}

// A run's packings are its data, written only by grow: no other output replaces one.
void refuse_run_packing(std::string_view option, const fs::path& path) {
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (path.extension() != ".pack" || !run_files::is_run_packing_stem(path.stem().string())) return;
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(dir, ec);
  if (ec || canonical.filename() != run_files::packings || !is_run_directory(canonical.parent_path())) return;
  throw InputError(output_at(option, path) + "is a packing of the budjam run " +
                   escape_control(canonical.parent_path().string()) + ", which only budjam grow writes");
}

// The directory a run owns at its top level that other commands' outputs may go in (beside the packings).
bool run_subdirectory(const fs::path& name) { return name == run_files::packings; }

// A path for messages: the user's spelling of `real` where it names that directory, else `real`.
fs::path shown_as(const fs::path& spelled, const fs::path& real) {
  fs::path s = spelled.lexically_normal();
  if (!s.empty() && !s.has_filename()) s = s.parent_path();
  std::error_code ec;
  return !s.empty() && fs::equivalent(s, real, ec) ? s : real;
}

// The nearest part of `dir` that exists must be a directory (links followed, as spelled).
void check_existing_part(std::string_view option, const fs::path& dir) {
  if (const fs::path e = deepest_entry(dir); !e.empty()) {
    std::error_code ec;
    const fs::file_status st = fs::status(e, ec);
    if (!fs::exists(st))
      throw InputError(output_at(option, dir) + which_part(dir, e) + "is a symbolic link to nothing");
    if (!fs::is_directory(st)) throw InputError(output_at(option, dir) + which_part(dir, e) + "is not a directory");
  }
}

// refuse_directory_in_run, naming the output `shown` (a file in `dir`, or `dir`).
void refuse_new_directory(std::string_view option, const fs::path& shown, const fs::path& dir, bool itself) {
  // The deepest part that exists, resolved by the kernel (links, then ".."), and the components
  // below it, which creating `dir` makes one by one.
  std::vector<fs::path> missing;
  fs::path at = dir.empty() ? fs::path(".") : dir;
  std::error_code ec;
  while (!fs::exists(at, ec)) {
    missing.push_back(at.filename());
    const fs::path up = at.parent_path();
    if (up == at) return;
    at = up.empty() ? fs::path(".") : up;
  }
  fs::path real = fs::canonical(at, ec), spelled = at;
  if (ec) return;  // what cannot be resolved cannot be created either: the writer reports it
  const auto refuse = [&](const fs::path& run, const fs::path& made) {
    throw InputError(
        output_at(option, shown) + "is inside " +
        (is_run_directory(run) ? "the budjam run directory " : "the spectra directory of a budjam run, ") +
        escape_control(shown_as(spelled, run).string()) + (is_run_directory(run) ? ", whose top level" : ", which") +
        " holds only the run's own files (write elsewhere" +
        (made.empty() ? std::string() : "; it would make the directory " + escape_control(made.string())) + ")");
  };
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (it->empty() || *it == ".") continue;
    if (*it == "..") {
      real = real.parent_path();
      spelled /= "..";
      continue;
    }
    if (holds_only_run_files(real) && !(run_subdirectory(*it) && is_run_directory(real))) refuse(real, *it);
    real /= *it;
    spelled /= *it;
  }
  if (itself && holds_only_run_files(real.parent_path()) &&
      !(run_subdirectory(real.filename()) && is_run_directory(real.parent_path()))) {
    spelled /= "..";
    refuse(real.parent_path(), {});
  }
}

}  // namespace

void refuse_directory_in_run(std::string_view option, const fs::path& dir, bool itself) {
  refuse_new_directory(option, dir, dir, itself);
}

void check_output_file(std::string_view option, const fs::path& path) {
  check_output_path(option, path);
  refuse_run_directory(option, path, path.parent_path());
  refuse_new_directory(option, path, path.parent_path(), false);
  refuse_run_packing(option, path);
}

void check_output_path(std::string_view option, const fs::path& path) {
  check_output_spelling(option, path);
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(output_at(option, path) + "is a directory");
}

void check_output_name(std::string_view option, const fs::path& path) {
  check_output_file(option, path);
  if (path.filename().string().front() == '=')
    throw InputError(output_at(option, path) + "a file name may not start with '='");
}

void check_output_base(std::string_view option, const fs::path& base,
                       std::initializer_list<std::string_view> extensions) {
  check_output_spelling(option, base);
  check_existing_part(option, base.parent_path());
  refuse_run_directory(option, base, base.parent_path());
  refuse_new_directory(option, base, base.parent_path(), false);
  for (const std::string_view ext : extensions) {
    fs::path file = base;
    file += ext;
    check_output_path(option, file);
  }
}

void check_output_directory(std::string_view option, const fs::path& dir, const std::vector<std::string_view>& names) {
  check_existing_part(option, dir);
  refuse_run_directory(option, dir, dir);
  refuse_directory_in_run(option, dir);
  for (const std::string_view name : names) check_output_path(option, dir / name);
}

void write_atomically(const Directory& dir, std::string_view name, std::string_view content) {
  TempFile tmp(dir, name);
  tmp.write(content);
  tmp.commit();
}

void write_atomically(const fs::path& path, std::string_view content) {
  check_output_path("", path);
  write_atomically(Directory::open(path.parent_path(), true), path.filename().string(), content);
}

void write_atomically(const Directory& dir, std::string_view name, const std::function<void(std::ostream&)>& writer) {
  // The whole content is produced before any file is touched: a throwing writer leaves no trace.
  std::ostringstream out;
  writer(out);
  if (!out) throw IoError((dir / name).string() + ": formatting the content failed");
  write_atomically(dir, name, out.view());
}

void write_atomically(const Directory& dir, const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::unique_ptr<TempFile>> temporaries;
  for (const auto& [name, content] : files) {
    temporaries.push_back(std::make_unique<TempFile>(dir, name));
    temporaries.back()->write(content);
  }
  const SignalsHeld held;
  for (auto& t : temporaries) t->commit();
}

void write_atomically(const fs::path& path, const std::function<void(std::ostream&)>& writer) {
  check_output_path("", path);
  write_atomically(Directory::open(path.parent_path(), true), path.filename().string(), writer);
}

namespace {
std::string read_and_close(int fd, const fs::path& path) {
  try {
    std::string text = read_all(fd, path);
    ::close(fd);
    return text;
  } catch (...) {
    ::close(fd);
    throw;
  }
}
}  // namespace

std::string read_text_file(const Directory& dir, std::string_view name) {
  return read_and_close(dir.open_file(name, O_RDONLY), dir / name);
}

std::string read_text_file(const fs::path& path) {
  // O_NONBLOCK: opening a FIFO does not wait for a writer (read_all refuses it).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw InputError(path.string() + ": cannot read: " + reason(errno));
  return read_and_close(fd, path);
}

// ---- CSV -------------------------------------------------------------------------------------

CsvField::CsvField(double v) : text(format_double(v)) {}

CsvField::CsvField(std::optional<double> v) : text(v ? format_double(*v) : std::string()) {}

CsvField::CsvField(std::string_view s) {
  const bool quote =
      s.find_first_of(",\"\r\n") != std::string_view::npos || (!s.empty() && (s.front() == ' ' || s.back() == ' '));
  if (!quote) {
    text = s;
    return;
  }
  text.reserve(s.size() + 2);
  text.push_back('"');
  for (char c : s) {
    if (c == '"') text.push_back('"');
    text.push_back(c);
  }
  text.push_back('"');
}

namespace {
std::string join(const std::vector<CsvField>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) line += ',';
    line += fields[i].text;
  }
  line += '\n';
  return line;
}
std::string header_line(const std::vector<std::string>& columns) {
  std::vector<CsvField> f;
  for (const auto& c : columns) f.emplace_back(c);
  return join(f);
}
}  // namespace

CsvLog::CsvLog(Directory dir, std::string name, std::vector<std::string> columns)
    : dir_(std::move(dir)), name_(std::move(name)), columns_(std::move(columns)) {
  if (columns_.empty()) throw std::logic_error("CsvLog: no columns");
  // A finished log of an earlier run in the same place must not survive as if it were this one's.
  dir_.remove(name_);
  dir_.remove(partial_name());
  fd_ = dir_.open_file(partial_name(), O_WRONLY | O_CREAT | O_EXCL);
  write_line(header_line(columns_));
}

std::string interrupted_log_file(const Directory& dir, const std::string& name) {
  const std::string partial = name + ".partial";
  if (dir.entry(partial)) return partial;
  const auto finished = dir.entry(name);
  return finished && S_ISREG(finished->st_mode) ? name : partial;
}

void reopen_interrupted_log(const Directory& dir, const std::string& name) {
  if (interrupted_log_file(dir, name) == name) dir.rename(name, name + ".partial");
}

CsvLog::Cut CsvLog::check_resumable(const Directory& dir, const std::string& name,
                                    const std::vector<std::string>& columns, std::uint64_t bytes) {
  const std::string partial = interrupted_log_file(dir, name);
  const fs::path where = dir / partial;
  std::string text;
  try {
    text = read_text_file(dir, partial);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + " (cannot resume the log)");
  }
  const std::string header = header_line(columns);
  if (text.compare(0, header.size(), header) != 0)
    throw InputError(where.string() + ":1: cannot resume the log: its header is not \"" +
                     header.substr(0, header.size() - 1) + "\"");
  if (bytes < header.size() || text.size() < bytes)
    throw InputError(where.string() + ": cannot resume the log: it holds " + std::to_string(text.size()) +
                     " bytes, the checkpoint expects " + std::to_string(bytes));
  // A cut point is a line end: the byte before it is the newline of a whole row.
  if (text[bytes - 1] != '\n')
    throw InputError(where.string() + ": cannot resume the log: byte " + std::to_string(bytes) +
                     " recorded in the checkpoint is not the end of a line");
  Cut cut;
  cut.bytes = bytes;
  const std::string_view kept = std::string_view(text).substr(0, bytes);
  cut.rows = static_cast<std::size_t>(std::count(kept.begin(), kept.end(), '\n')) - 1;
  if (cut.rows > 0) {
    const std::size_t from = kept.rfind('\n', bytes - 2) + 1;
    cut.last_row = kept.substr(from, bytes - 1 - from);
  }
  return cut;
}

CsvLog CsvLog::resume(Directory dir, std::string name, std::vector<std::string> columns, std::uint64_t bytes) {
  check_resumable(dir, name, columns, bytes);
  reopen_interrupted_log(dir, name);
  CsvLog log;
  log.dir_ = std::move(dir);
  log.name_ = std::move(name);
  log.columns_ = std::move(columns);
  log.fd_ = log.dir_.open_file(log.partial_name(), O_RDWR);
  if (::ftruncate(log.fd_, static_cast<off_t>(bytes)) != 0) io_fail(log.partial_path(), "cannot truncate", errno);
  if (::lseek(log.fd_, 0, SEEK_END) < 0) io_fail(log.partial_path(), "cannot seek", errno);
  log.bytes_ = bytes;
  log.dir_.remove(log.name_);
  return log;
}

CsvLog::CsvLog(CsvLog&& o) noexcept
    : dir_(std::move(o.dir_)),
      name_(std::move(o.name_)),
      columns_(std::move(o.columns_)),
      fd_(o.fd_),
      bytes_(o.bytes_),
      finished_(o.finished_) {
  o.fd_ = -1;
}

CsvLog& CsvLog::operator=(CsvLog&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    dir_ = std::move(o.dir_);
    name_ = std::move(o.name_);
    columns_ = std::move(o.columns_);
    fd_ = o.fd_;
    bytes_ = o.bytes_;
    finished_ = o.finished_;
    o.fd_ = -1;
  }
  return *this;
}

CsvLog::~CsvLog() {
  if (fd_ >= 0) ::close(fd_);
}

void CsvLog::write_line(const std::string& line) {
  if (fd_ < 0) throw std::logic_error("CsvLog: " + path().string() + " is closed");
  try {
    write_all(fd_, line, partial_path());
  } catch (const IoError&) {
    // Disk full mid-line: take back the part that was written, so the log still ends with a
    // whole row (best effort: if even that fails, resume() cuts it at the checkpoint).
    if (::ftruncate(fd_, static_cast<off_t>(bytes_)) == 0) ::lseek(fd_, 0, SEEK_END);
    throw;
  }
  bytes_ += line.size();
}

void CsvLog::row(std::initializer_list<CsvField> fields) { row(std::vector<CsvField>(fields)); }

void CsvLog::row(const std::vector<CsvField>& fields) {
  if (fields.size() != columns_.size())
    throw std::logic_error("CsvLog: " + name_ + " has " + std::to_string(columns_.size()) + " columns, a row gave " +
                           std::to_string(fields.size()));
  write_line(join(fields));
}

void CsvLog::sync() {
  if (fd_ >= 0 && ::fsync(fd_) != 0) io_fail(partial_path(), "cannot sync", errno);
}

void CsvLog::finish() {
  if (finished_) return;
  sync();
  if (fd_ >= 0 && ::close(fd_) != 0) {
    fd_ = -1;
    io_fail(partial_path(), "cannot close", errno);
  }
  fd_ = -1;
  dir_.rename(partial_name(), name_);
  dir_.sync();
  finished_ = true;
}

}  // namespace budjam::io
