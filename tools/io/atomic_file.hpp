#pragma once
// Crash-safe output. Every file budjam writes is either complete or absent under its final name:
//  - whole files (packings, summary.json, checkpoints, the effective scene) go through
//    write_atomically: temporary file in the same directory, fsync, rename, fsync the directory;
//  - logs that grow during a run (CSV) are written to NAME.partial, one whole line per write(2),
//    and renamed to NAME only by CsvLog::finish().
// A run directory is finished when summary.json exists; it is written last (docs/files.md).
//
// Files are created, replaced and removed relative to an open Directory: a symbolic link among
// the entries is never followed (O_NOFOLLOW, AT_SYMLINK_NOFOLLOW), only the directory's own path
// is, as the user gave it. Every output file gets the mode open(2) gives with 0666 and the umask.
#include <sys/stat.h>

#include <array>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <iosfwd>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace budjam::io {

// An output could not be written (disk full, no permission, ...). Not the user's input: exit 3.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class TemporaryManifest;

// An open directory. Copies share the descriptor. Names given to its members are single path
// components (no '/').
class Directory {
 public:
  // Opens `path` (created with its parents if `create`; empty: the working directory, and
  // members are then named by their names alone). IoError if it cannot be opened; InputError if
  // it exists and is not a directory, or if creating it would make a new directory at the top level
  // of a run (refuse_directory_in_run). The directories it creates are removed again (deepest
  // first, each only if still empty) when the last copy goes unless a file was committed in it
  // (keep_created): a failed output leaves no directory behind.
  static Directory open(const std::filesystem::path& path, bool create);
  // The directories open() created stay: an output was written in them.
  void keep_created() const;

  // The entry `name` as a directory (created if `create` and absent). InputError naming it if it
  // is a symbolic link or not a directory: a link is never followed.
  Directory subdirectory(std::string_view name, bool create) const;

  const std::filesystem::path& path() const { return path_; }
  int fd() const;
  // For messages and for programs that take a path.
  std::filesystem::path operator/(std::string_view name) const { return path_ / name; }

  // fstatat without following a link; std::nullopt if there is no such entry.
  std::optional<struct ::stat> entry(std::string_view name) const;
  // The names in the directory (not "." and ".."), sorted.
  std::vector<std::string> names() const;
  // Opens the regular file `name` (O_NOFOLLOW; flags as for open(2), O_CREAT with the output
  // mode). InputError if it is a link or not a regular file; IoError for other failures.
  int open_file(std::string_view name, int flags) const;
  // Removes the entry `name` (a file, a link itself, an empty directory); absent is fine.
  void remove(std::string_view name) const;
  void rename(std::string_view from, std::string_view to) const;
  // fsync of the directory: renames and removals reach the disk.
  void sync() const;

  // Temporaries created in this directory or its subdirectories are recorded in `manifest`
  // under their path relative to `root_prefix` ("" for the manifest's own directory).
  void record_temporaries_in(std::shared_ptr<TemporaryManifest> manifest, std::string root_prefix = "");
  const std::shared_ptr<TemporaryManifest>& manifest() const { return manifest_; }
  const std::string& manifest_prefix() const { return prefix_; }

 private:
  struct Handle;
  std::shared_ptr<Handle> handle_;
  std::filesystem::path path_;
  std::shared_ptr<TemporaryManifest> manifest_;
  std::string prefix_;
};

// The temporaries a process has created in a directory tree, listed in a file of that tree, so
// that the next claim of the tree removes exactly those a killed process left, and never a file
// merely named like one. An entry is appended once its temporary exists; the list is emptied
// whenever no temporary is outstanding, and by remove_open_temporaries() when a signal stops the
// process.
class TemporaryManifest {
 public:
  // The list `name` in `root`, opened (created) only when a temporary is first recorded, or
  // by remove_listed() if it exists: claiming a directory that writes nothing creates no list.
  TemporaryManifest(Directory root, std::string_view name);
  ~TemporaryManifest();
  TemporaryManifest(const TemporaryManifest&) = delete;
  TemporaryManifest& operator=(const TemporaryManifest&) = delete;

  void add(const std::string& relative);
  void done();
  // Removes the regular files the list names (links and other kinds are left, as are names that
  // do not look like budjam temporaries), then empties it.
  void remove_listed();

 private:
  Directory root_;
  std::string name_;
  int fd_ = -1;
  int outstanding_ = 0;
  void open(bool create);
};

// A temporary file beside `final_name` in `dir`, named `.FINAL.tmp-XXXXXX` (created with O_EXCL,
// so never an existing file or link), removed when destroyed unless committed.
class TempFile {
 public:
  TempFile(Directory dir, std::string_view final_name);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  // For a program that writes the file by its name, or on its standard output (the descriptor).
  std::filesystem::path path() const { return dir_ / name_; }
  std::filesystem::path final_path() const { return dir_ / final_; }
  int fd() const { return fd_; }
  void write(std::string_view data);
  // Makes the content durable with the output mode (also when a program wrote or replaced the
  // file by name), renames it onto the final name and syncs the directory.
  void commit();

 private:
  Directory dir_;
  std::string final_, name_;
  int fd_ = -1;
  bool committed_ = false;
  int slot_ = -1;          // in the list remove_open_temporaries() reads, or -1
  bool unlisted_ = false;  // open and in no slot of that list (it was full)
  // The name no longer names this temporary (removed or committed): out of the handler's reach.
  void forget_name();
};

// Removes every TempFile of this process that is neither committed nor destroyed, then empties the
// lists of temporaries that named only those: for a handler of a signal that ends the process (no
// destructor runs then). Async-signal-safe (unlinkat and ftruncate only).
void remove_open_temporaries() noexcept;

// A handler of a signal that ends the process: stops a helper program still running (whose file
// would otherwise be written anew), removes the open temporaries, then ends the process as the
// signal would have without a handler. Async-signal-safe.
extern "C" void end_process_without_temporaries(int sig);

// While it lives, SIGTERM and SIGHUP whose disposition is the default (to end the process) go through
// end_process_without_temporaries: for writers in a process that does not handle those signals
// itself (the Python module's), so that a stop leaves no temporary behind. Signals the process
// handles or ignores are left as they are.
class TemporariesRemovedOnStop {
 public:
  TemporariesRemovedOnStop();
  ~TemporariesRemovedOnStop();
  TemporariesRemovedOnStop(const TemporariesRemovedOnStop&) = delete;
  TemporariesRemovedOnStop& operator=(const TemporariesRemovedOnStop&) = delete;

 private:
  struct Replaced {
    int sig = 0;
    struct sigaction old {};
    bool installed = false;
  };
  std::array<Replaced, 2> replaced_{};
};

// Holds back SIGINT, SIGTERM and SIGHUP while it lives (they are delivered when it ends), making
// one step of what a stop must not split: a temporary's creation and its listing for
// remove_open_temporaries() (a signal during open(2) would find it not yet listed), the renames of
// files written as one, and a helper program's start and the recording of its pid.
class SignalsHeld {
 public:
  SignalsHeld();
  ~SignalsHeld();
  SignalsHeld(const SignalsHeld&) = delete;
  SignalsHeld& operator=(const SignalsHeld&) = delete;
  // The mask before: what a program started meanwhile should begin with.
  const sigset_t& before() const { return old_; }

 private:
  sigset_t old_{};
};

// Replaces `name` in `dir` by `content` atomically (a TempFile). On any failure the temporary is
// removed, the previous file (if any) is untouched, and IoError is thrown.
void write_atomically(const Directory& dir, std::string_view name, std::string_view content);
void write_atomically(const Directory& dir, std::string_view name, const std::function<void(std::ostream&)>& writer);

// Replaces the files of `dir` named in `files` (name, content) as one: every content is written
// to its temporary before the first rename, and the renames follow in the given order with SIGINT,
// SIGTERM and SIGHUP held back, so that such a stop never leaves some replaced and not the others.
void write_atomically(const Directory& dir, const std::vector<std::pair<std::string, std::string>>& files);

// The most bytes budjam reads of one input file; a larger one is refused (InputError) unread.
inline constexpr std::uint64_t kMaxInputBytes = std::uint64_t{2} << 30;
// The longest name of an output file: its temporary `.NAME.tmp-XXXXXX` must fit in NAME_MAX (255).
inline constexpr std::size_t kMaxOutputName = 255 - 12;

// InputError "<option>: <path>: ..." ("<path>: ..." if option is empty) unless `path` names a file
// budjam may write: a name is given (not empty, no trailing '/', not "." or ".."), at most
// kMaxOutputName bytes, and it is not an existing directory.
void check_output_path(std::string_view option, const std::filesystem::path& path);
// check_output_path, and `path` is none of a budjam run's own files: not at the top level of a run
// directory (the run's files live there), its directory makes none at a run's top level
// (refuse_directory_in_run), and not a run's packing packings/<stem>.pack, which only
// grow writes. The output-name rules of every writer of a named file (the commands' outputs and
// the Python module's Packing.write and export): InputError.
void check_output_file(std::string_view option, const std::filesystem::path& path);
// check_output_file, and the name does not start with '=' (which converters' option parsers take
// as part of an option). This and the two below refuse the top level of a budjam run directory (its
// run's own files live there): InputError.
void check_output_name(std::string_view option, const std::filesystem::path& path);
// `--out BASE` of a command writing BASE<ext> for each extension: BASE names a file (as above), its
// directory makes none at a run's top level, and each BASE<ext> passes check_output_path. Before any work, so nothing
// is computed to be lost.
void check_output_base(std::string_view option, const std::filesystem::path& base,
                       std::initializer_list<std::string_view> extensions);
// The one rule for where outputs may make directories: resolved through links from the deepest part
// of `dir` that exists ("link/.." is the directory above the link's target), no directory that
// would be created for `dir` lies directly in a budjam run directory (one holding its marker) other
// than its packings/ and spectra/, which the run owns; with `itself`, nor does `dir` itself, existing
// or not (an output directory: `grow --out`, `analyse --out`, `accuracy --out`). InputError.
void refuse_directory_in_run(std::string_view option, const std::filesystem::path& dir, bool itself = true);
// `--out DIR` of a command writing the files `names` in DIR: the part of DIR that exists is a
// directory (a file or a dangling link on the way is refused), DIR passes refuse_directory_in_run
// and each DIR/name passes check_output_path. Changes nothing.
void check_output_directory(std::string_view option, const std::filesystem::path& dir,
                            const std::vector<std::string_view>& names);

// Replaces `path` by `content` atomically. On any failure the temporary file is removed, the
// previous file at `path` (if any) is untouched, and IoError is thrown (InputError if `path` does
// not pass check_output_path).
void write_atomically(const std::filesystem::path& path, std::string_view content);

// Same, with the content produced by `writer`; if `writer` throws, nothing is written and the
// exception propagates unchanged.
void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& writer);

// The regular file `name` of `dir` as a string (a link is not followed); InputError
// "<path>: cannot read: <reason>" when it cannot be read.
std::string read_text_file(const Directory& dir, std::string_view name);

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

// The file holding the growing log `name` of an interrupted run: `<name>.partial`, or `<name>` itself
// where the run was killed while it finished, after renaming that log and before its summary.json
// made the run finished (the finish renames the logs first). Changes nothing.
std::string interrupted_log_file(const Directory& dir, const std::string& name);
// Gives the log `name` its growing name `<name>.partial` again (for a resume that has passed every
// check), where the interrupted finish had already renamed it.
void reopen_interrupted_log(const Directory& dir, const std::string& name);

// An append-only CSV log that is never mistaken for a complete one: rows go to `<name>.partial`
// (each row one write(2) of a whole line, so a killed run leaves only whole lines), and finish()
// renames it to `<name>`. For checkpoints, bytes() is the size of what has been written; resume()
// cuts the .partial file back to that size and appends from there.
class CsvLog {
 public:
  // What a resumable log holds up to a checkpoint's length.
  struct Cut {
    std::uint64_t bytes = 0;
    std::size_t rows = 0;  // whole rows after the header
    std::string last_row;  // the last of them without its newline (empty if none)
  };

  // Starts a new log (an existing .partial file is replaced) and writes the header line.
  CsvLog(Directory dir, std::string name, std::vector<std::string> columns);
  // Checks, without changing anything, that interrupted_log_file() of an interrupted run can be cut
  // at `bytes` (a value of bytes() recorded in a checkpoint): a regular file with this header,
  // at least `bytes` long, `bytes` a line end. InputError naming the file otherwise.
  static Cut check_resumable(const Directory& dir, const std::string& name, const std::vector<std::string>& columns,
                             std::uint64_t bytes);
  // check_resumable, then truncates the file to `bytes` and appends from there.
  static CsvLog resume(Directory dir, std::string name, std::vector<std::string> columns, std::uint64_t bytes);

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
  std::filesystem::path path() const { return dir_ / name_; }
  std::filesystem::path partial_path() const { return dir_ / partial_name(); }
  bool finished() const { return finished_; }

 private:
  CsvLog() = default;
  std::string partial_name() const { return name_ + ".partial"; }
  void write_line(const std::string& line);
  Directory dir_;
  std::string name_;
  std::vector<std::string> columns_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  bool finished_ = false;
};

}  // namespace budjam::io
