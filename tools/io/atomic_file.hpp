#pragma once
// Crash-safe output. Every file budjam writes is either complete or absent under its final name:
//  - whole files (packings, summary.json, checkpoints, the effective scene) go through
//    write_atomically: temporary file in the same directory, fsync, rename, fsync the directory;
//  - logs that grow during a run (CSV) are written to NAME.partial, one whole line per write(2),
//    and renamed to NAME only by CsvLog::finish().
// A run directory is finished when summary.json exists; it is written last (docs/files.md).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace budjam::io {

// An output could not be written (disk full, no permission, ...). Not the user's input: exit 3.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Replaces `path` by `content` atomically. On any failure the temporary file is removed, the
// previous file at `path` (if any) is untouched, and IoError is thrown.
void write_atomically(const std::filesystem::path& path, std::string_view content);

// Same, with the content produced by `writer`; if `writer` throws, nothing is written and the
// exception propagates unchanged.
void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& writer);

// Whole file as a string; InputError "<path>: cannot read: <reason>" when it cannot be read
// (reading is always of the user's input).
std::string read_text_file(const std::filesystem::path& path);

// One CSV field, formatted when constructed: doubles as round-trip text (format_double),
// integers exactly, booleans as true/false, strings quoted only when they need it (RFC 4180),
// a missing value (std::nullopt or CsvField::missing()) as an empty field.
struct CsvField {
  std::string text;

  CsvField(double v);
  CsvField(std::optional<double> v);
  CsvField(bool v) : text(v ? "true" : "false") {}
  template <class I>
  requires(std::is_integral_v<I> && !std::is_same_v<I, bool>) CsvField(I v) : text(std::to_string(v)) {}
  CsvField(std::string_view s);
  CsvField(const char* s) : CsvField(std::string_view(s)) {}
  CsvField(const std::string& s) : CsvField(std::string_view(s)) {}
  static CsvField missing() { return CsvField(std::optional<double>{}); }
};

// An append-only CSV log that is never mistaken for a complete one: rows go to `<path>.partial`
// (each row one write(2) of a whole line, so a killed run leaves only whole lines), and finish()
// renames it to `<path>`. For checkpoints, bytes() is the size of what has been written; resume()
// cuts the .partial file back to that size and appends from there.
class CsvLog {
 public:
  // Starts a new log (an existing .partial file is replaced) and writes the header line.
  CsvLog(std::filesystem::path path, std::vector<std::string> columns);
  // Reopens `<path>.partial` of an interrupted run, checks its header, truncates it to `bytes`
  // (a value of bytes() recorded in a checkpoint) and appends from there. InputError if the file
  // is missing, has another header, is shorter than `bytes` or `bytes` is not a line end.
  static CsvLog resume(std::filesystem::path path, std::vector<std::string> columns, std::uint64_t bytes);

  CsvLog(CsvLog&& other) noexcept;
  CsvLog& operator=(CsvLog&& other) noexcept;
  CsvLog(const CsvLog&) = delete;
  CsvLog& operator=(const CsvLog&) = delete;
  ~CsvLog();  // closes; an unfinished log stays `.partial`

  // Appends one row; std::logic_error if the number of fields differs from the header's.
  void row(std::initializer_list<CsvField> fields);
  void row(const std::vector<CsvField>& fields);

  // fsync: call before writing a checkpoint that records bytes().
  void sync();
  // sync, then rename `<path>.partial` to `<path>`. No rows may follow.
  void finish();

  std::uint64_t bytes() const { return bytes_; }
  const std::vector<std::string>& columns() const { return columns_; }
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path partial_path() const;
  bool finished() const { return finished_; }

 private:
  CsvLog() = default;
  void write_line(const std::string& line);
  std::filesystem::path path_;
  std::vector<std::string> columns_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  bool finished_ = false;
};

}  // namespace budjam::io
