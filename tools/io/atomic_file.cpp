#include "io/atomic_file.hpp"

#include "budjam/errors.hpp"
#include "io/text.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace budjam::io {
namespace fs = std::filesystem;

namespace {

std::string reason(int err) { return std::strerror(err); }

[[noreturn]] void io_fail(const fs::path& path, const std::string& what, int err) {
  throw IoError(path.string() + ": " + what + ": " + reason(err));
}

fs::path directory_of(const fs::path& path) {
  const fs::path dir = path.parent_path();
  return dir.empty() ? fs::path(".") : dir;
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

// After a rename the directory entry itself must reach the disk too.
void sync_directory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // best effort: the data itself is already synced
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void write_atomically(const fs::path& path, std::string_view content) {
  const fs::path dir = directory_of(path);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(dir.string() + ": cannot create directory: " + ec.message());

  std::string leaf = ".";  // built by appends: GCC 12 -O3 misreads "." + string as overlapping (-Wrestrict)
  leaf += path.filename().string();
  leaf += ".tmp-XXXXXX";
  std::string name = (dir / leaf).string();
  const int fd = ::mkstemp(name.data());
  if (fd < 0) io_fail(dir, "cannot create a temporary file", errno);
  const fs::path tmp = name;
  try {
    if (::fchmod(fd, file_mode()) != 0) io_fail(tmp, "cannot set permissions", errno);
    write_all(fd, content, tmp);
    if (::fsync(fd) != 0) io_fail(tmp, "cannot sync", errno);
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    io_fail(tmp, "cannot close", err);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    io_fail(path, "cannot replace", err);
  }
  sync_directory(dir);
}

void write_atomically(const fs::path& path, const std::function<void(std::ostream&)>& writer) {
  // The whole content is produced before any file is touched: a throwing writer leaves no trace.
  std::ostringstream out;
  writer(out);
  if (!out) throw IoError(path.string() + ": formatting the content failed");
  write_atomically(path, out.view());
}

std::string read_text_file(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path.string() + ": cannot read: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot read: " + reason(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": cannot read: " + reason(errno));
  return std::move(text).str();
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

fs::path CsvLog::partial_path() const {
  fs::path p = path_;
  p += ".partial";
  return p;
}

CsvLog::CsvLog(fs::path path, std::vector<std::string> columns) : path_(std::move(path)), columns_(std::move(columns)) {
  if (columns_.empty()) throw std::logic_error("CsvLog: no columns");
  std::error_code ec;
  fs::create_directories(directory_of(path_), ec);
  // A finished log of an earlier run in the same place must not survive as if it were this one's.
  if (::unlink(path_.c_str()) != 0 && errno != ENOENT) io_fail(path_, "cannot remove old log", errno);
  fd_ = ::open(partial_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) io_fail(partial_path(), "cannot create", errno);
  write_line(header_line(columns_));
}

CsvLog CsvLog::resume(fs::path path, std::vector<std::string> columns, std::uint64_t bytes) {
  CsvLog log;
  log.path_ = std::move(path);
  log.columns_ = std::move(columns);
  const fs::path partial = log.partial_path();
  log.fd_ = ::open(partial.c_str(), O_RDWR | O_CLOEXEC);
  if (log.fd_ < 0) throw InputError(partial.string() + ": cannot resume the log: " + reason(errno));
  struct stat st {};
  if (::fstat(log.fd_, &st) != 0) io_fail(partial, "cannot stat", errno);
  const std::string header = header_line(log.columns_);
  std::string head(header.size(), '\0');
  const ssize_t n = ::pread(log.fd_, head.data(), head.size(), 0);
  if (n != static_cast<ssize_t>(head.size()) || head != header)
    throw InputError(partial.string() + ":1: cannot resume the log: its header is not \"" +
                     header.substr(0, header.size() - 1) + "\"");
  if (bytes < header.size() || static_cast<std::uint64_t>(st.st_size) < bytes)
    throw InputError(partial.string() + ": cannot resume the log: it holds " + std::to_string(st.st_size) +
                     " bytes, the checkpoint expects " + std::to_string(bytes));
  // A cut point is a line end: the byte before it is the newline of a whole row.
  char before = 0;
  if (::pread(log.fd_, &before, 1, static_cast<off_t>(bytes - 1)) != 1 || before != '\n')
    throw InputError(partial.string() + ": cannot resume the log: byte " + std::to_string(bytes) +
                     " recorded in the checkpoint is not the end of a line");
  if (::ftruncate(log.fd_, static_cast<off_t>(bytes)) != 0) io_fail(partial, "cannot truncate", errno);
  if (::lseek(log.fd_, 0, SEEK_END) < 0) io_fail(partial, "cannot seek", errno);
  log.bytes_ = bytes;
  if (::unlink(log.path_.c_str()) != 0 && errno != ENOENT) io_fail(log.path_, "cannot remove old log", errno);
  return log;
}

CsvLog::CsvLog(CsvLog&& o) noexcept
    : path_(std::move(o.path_)), columns_(std::move(o.columns_)), fd_(o.fd_), bytes_(o.bytes_), finished_(o.finished_) {
  o.fd_ = -1;
}

CsvLog& CsvLog::operator=(CsvLog&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(o.path_);
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
  if (fd_ < 0) throw std::logic_error("CsvLog: " + path_.string() + " is closed");
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
    throw std::logic_error("CsvLog: " + path_.filename().string() + " has " + std::to_string(columns_.size()) +
                           " columns, a row gave " + std::to_string(fields.size()));
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
  if (::rename(partial_path().c_str(), path_.c_str()) != 0) io_fail(path_, "cannot rename the finished log", errno);
  sync_directory(directory_of(path_));
  finished_ = true;
}

}  // namespace budjam::io
