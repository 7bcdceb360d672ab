// Crash-safe outputs: atomic whole-file writes, CSV logs that are `.partial` until finished,
// resumable logs, and the JSON helpers.
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/result_files.hpp"
#include "io/text.hpp"

#include "budjam/errors.hpp"

#include <catch2/catch.hpp>
#include "small_disk.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <bit>
#include <csignal>
#include <fstream>
#include <limits>
#include <sstream>

using namespace budjam;
using namespace budjam::io;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag)
      : path(fs::temp_directory_path() / ("budjam-" + tag + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("write_atomically replaces the whole file and leaves no temporary file", "[atomic]") {
  TempDir dir("atomic");
  const fs::path file = dir.path / "summary.json";
  write_atomically(file, "first version, rather long\n");
  write_atomically(file, "second\n");
  CHECK(slurp(file) == "second\n");
  CHECK(names_in(dir.path) == std::vector<std::string>{"summary.json"});
  write_atomically(file, [](std::ostream& out) { out << "from a writer " << 42 << "\n"; });
  CHECK(slurp(file) == "from a writer 42\n");
  // Missing directories are created.
  write_atomically(dir.path / "packings" / "jammed.pack", "x");
  CHECK(slurp(dir.path / "packings" / "jammed.pack") == "x");
  // Permissions follow the umask like any ordinary file (mkstemp alone would give 0600).
  const auto perms = fs::status(file).permissions();
  CHECK((perms & fs::perms::owner_read) != fs::perms::none);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  if (!(mask & 0044)) CHECK((perms & fs::perms::others_read) != fs::perms::none);
}

TEST_CASE("a writer that throws leaves the previous file intact and no temporary file", "[atomic]") {
  TempDir dir("atomic-throw");
  const fs::path file = dir.path / "result.pack";
  write_atomically(file, "complete old content\n");
  CHECK_THROWS_WITH(write_atomically(file,
                                     [](std::ostream& out) {
                                       out << "half of the new con";
                                       throw std::runtime_error("writer failed");
                                     }),
                    "writer failed");
  CHECK(slurp(file) == "complete old content\n");
  CHECK(names_in(dir.path) == std::vector<std::string>{"result.pack"});
  // Without a previous file, nothing appears at all.
  CHECK_THROWS(write_atomically(dir.path / "new.pack", [](std::ostream&) { throw std::runtime_error("no"); }));
  CHECK_FALSE(fs::exists(dir.path / "new.pack"));
}

TEST_CASE("an output that cannot be written raises IoError (a path that names none InputError) and keeps the old file",
          "[atomic]") {
  TempDir dir("atomic-fail");
  const fs::path file = dir.path / "out.json";
  write_atomically(file, "old\n");
  // A directory in the way of the final name: rename fails after the temporary file was written.
  fs::create_directories(dir.path / "blocked" / "inner");
  CHECK_THROWS_AS(write_atomically(Directory::open(dir.path, false), "blocked", "new\n"), IoError);
  CHECK(names_in(dir.path) == std::vector<std::string>{"blocked", "out.json"});
  // By path, both are the user's spelling, refused before anything is made (exit 2): a directory
  // named as the file, a parent that is a regular file.
  CHECK_THROWS_AS(write_atomically(dir.path / "blocked", "new\n"), InputError);
  CHECK_THROWS_AS(write_atomically(file / "child.txt", "x"), InputError);
  CHECK(names_in(dir.path) == std::vector<std::string>{"blocked", "out.json"});
  CHECK(slurp(file) == "old\n");
}

TEST_CASE("read_text_file names the file in its error", "[atomic]") {
  TempDir dir("read");
  CHECK_THROWS_WITH(read_text_file(dir.path / "nope.toml"), Contains("nope.toml: cannot read: No such file"));
  CHECK_THROWS_AS(read_text_file(dir.path), InputError);
}

TEST_CASE("a CSV log is .partial until finished, then complete under its own name", "[atomic][csv]") {
  TempDir dir("csv");
  const fs::path file = dir.path / "steps.csv";
  {
    CsvLog log(Directory::open(dir.path, false), "steps.csv", {"step", "phi", "phase", "N_c"});
    log.row({1, 0.5, "growing", CsvField::missing()});
    log.row({2, 0.1 + 0.2, "jammed", std::optional<double>(12.0)});
    CHECK(fs::exists(log.partial_path()));
    CHECK_FALSE(fs::exists(file));
    CHECK(log.bytes() == fs::file_size(log.partial_path()));
    log.finish();
    CHECK(log.finished());
  }
  CHECK_FALSE(fs::exists(dir.path / "steps.csv.partial"));
  CHECK(slurp(file) == "step,phi,phase,N_c\n1,0.5,growing,\n2,0.30000000000000004,jammed,12\n");
}

TEST_CASE("a log that is never finished stays .partial", "[atomic][csv]") {
  TempDir dir("csv-unfinished");
  {
    CsvLog log(Directory::open(dir.path, false), "divisions.csv", {"step", "id"});
    log.row({5, 7});
  }  // destroyed without finish(): as if the run had stopped here
  CHECK(names_in(dir.path) == std::vector<std::string>{"divisions.csv.partial"});
}

TEST_CASE("starting a log removes a finished log of an earlier run in the same place", "[atomic][csv]") {
  TempDir dir("csv-stale");
  {
    CsvLog log(Directory::open(dir.path, false), "steps.csv", {"a"});
    log.row({1});
    log.finish();
  }
  CsvLog again(Directory::open(dir.path, false), "steps.csv", {"a"});
  CHECK_FALSE(fs::exists(dir.path / "steps.csv"));
}

TEST_CASE("CSV fields read back exactly: round-trip doubles, RFC 4180 quoting", "[csv]") {
  CHECK(CsvField(1e-16).text == "1e-16");
  CHECK(CsvField(-0.0).text == "-0");
  CHECK(CsvField(std::numeric_limits<double>::quiet_NaN()).text == "nan");
  CHECK(CsvField(std::size_t{18446744073709551615u}).text == "18446744073709551615");
  CHECK(CsvField(-3).text == "-3");
  CHECK(CsvField(true).text == "true");
  CHECK(CsvField("plain").text == "plain");
  CHECK(CsvField("a,b").text == "\"a,b\"");
  CHECK(CsvField("say \"hi\"").text == "\"say \"\"hi\"\"\"");
  const double x = 0.8412345678901234;
  CHECK(std::bit_cast<std::uint64_t>(*parse_double(CsvField(x).text)) == std::bit_cast<std::uint64_t>(x));
}

TEST_CASE("a row with the wrong number of fields is refused", "[csv]") {
  TempDir dir("csv-count");
  CsvLog log(Directory::open(dir.path, false), "x.csv", {"a", "b"});
  CHECK_THROWS_AS(log.row({1}), std::logic_error);
  CHECK_THROWS_AS(log.row({1, 2, 3}), std::logic_error);
}

TEST_CASE("resuming a log at a checkpointed size gives the same file as an uninterrupted run", "[csv][checkpoint]") {
  TempDir dir("csv-resume");
  const std::vector<std::string> cols = {"step", "phi"};
  auto value = [](int i) { return 0.5 + 1e-3 * i / 7.0; };

  {  // the uninterrupted run
    CsvLog log(Directory::open(dir.path, false), "ref.csv", cols);
    for (int i = 0; i < 20; ++i) log.row({i, value(i)});
    log.finish();
  }
  std::uint64_t checkpoint = 0;
  {  // the interrupted run: checkpoint after 12 rows, then 5 more rows are lost with the process
    CsvLog log(Directory::open(dir.path, false), "run.csv", cols);
    for (int i = 0; i < 12; ++i) log.row({i, value(i)});
    log.sync();
    checkpoint = log.bytes();
    for (int i = 12; i < 17; ++i) log.row({i, value(i)});
  }
  {
    CsvLog log = CsvLog::resume(Directory::open(dir.path, false), "run.csv", cols, checkpoint);
    CHECK(log.bytes() == checkpoint);
    for (int i = 12; i < 20; ++i) log.row({i, value(i)});
    log.finish();
  }
  CHECK(slurp(dir.path / "run.csv") == slurp(dir.path / "ref.csv"));

  // Refusals: no partial file, another header, fewer bytes than the checkpoint says.
  CHECK_THROWS_AS(CsvLog::resume(Directory::open(dir.path, false), "none.csv", cols, 10), InputError);
  {
    CsvLog log(Directory::open(dir.path, false), "short.csv", cols);
    log.row({1, 2.0});
  }
  CHECK_THROWS_WITH(CsvLog::resume(Directory::open(dir.path, false), "short.csv", {"step", "P"}, 10),
                    Contains("header"));
  CHECK_THROWS_WITH(CsvLog::resume(Directory::open(dir.path, false), "short.csv", cols, 1000),
                    Contains("checkpoint expects 1000"));
  // A cut point inside a row (here: after "step,phi\n1,") would leave half a row to append to.
  CHECK_THROWS_WITH(CsvLog::resume(Directory::open(dir.path, false), "short.csv", cols, 11),
                    Contains("not the end of a line"));
  CHECK(slurp(dir.path / "short.csv.partial") == "step,phi\n1,2\n");  // refused: untouched
  const CsvLog::Cut cut = CsvLog::check_resumable(Directory::open(dir.path, false), "short.csv", cols, 13);
  CHECK(cut.rows == 1);
  CHECK(cut.last_row == "1,2");
  CHECK(CsvLog::check_resumable(Directory::open(dir.path, false), "short.csv", cols, 9).rows == 0);
  CHECK(slurp(dir.path / "short.csv.partial") == "step,phi\n1,2\n");  // checking changes nothing
  CHECK_NOTHROW(CsvLog::resume(Directory::open(dir.path, false), "short.csv", cols, 9));
  CHECK(slurp(dir.path / "short.csv.partial") == "step,phi\n");
}

TEST_CASE("a link in a written file's place is replaced, never written through", "[atomic]") {
  TempDir dir("links");
  const fs::path foreign = dir.path / "foreign.txt";
  std::ofstream(foreign) << "foreign\n";
  fs::create_symlink(foreign, dir.path / "summary.json");
  write_atomically(dir.path / "summary.json", "{}\n");
  CHECK(slurp(foreign) == "foreign\n");
  CHECK_FALSE(fs::is_symlink(dir.path / "summary.json"));
  CHECK(slurp(dir.path / "summary.json") == "{}\n");
  // A log, a read, a subdirectory: refused with one line naming the link.
  const Directory d = Directory::open(dir.path, false);
  fs::create_symlink(foreign, dir.path / "steps.csv.partial");
  CHECK_THROWS_WITH(CsvLog::check_resumable(d, "steps.csv", {"a"}, 2),
                    Contains("steps.csv.partial: is a symbolic link"));
  CHECK_THROWS_WITH(read_text_file(d, "steps.csv.partial"), Contains("is a symbolic link"));
  fs::create_directory_symlink(dir.path, dir.path / "packings");
  CHECK_THROWS_WITH(d.subdirectory("packings", true), Contains("packings: is a symbolic link"));
  CHECK(slurp(foreign) == "foreign\n");
}

TEST_CASE("every file written gets the same mode, the one open(2) gives with 0666 and the umask", "[atomic]") {
  TempDir dir("modes");
  const Directory d = Directory::open(dir.path, false);
  write_atomically(d, "whole.json", "{}\n");
  {
    CsvLog log(d, "log.csv", {"a"});
    log.finish();
  }
  {
    TempFile t(d, "external.gsd");
    // a program that creates its output with its own mode (gsd: 0640) in the temporary's place
    fs::remove(t.path());
    const int fd = ::open(t.path().c_str(), O_WRONLY | O_CREAT | O_EXCL, 0640);
    REQUIRE(fd >= 0);
    ::close(fd);
    t.commit();
  }
  const mode_t mask = ::umask(0);
  ::umask(mask);
  for (const char* f : {"whole.json", "log.csv", "external.gsd"}) {
    INFO(f);
    CHECK((fs::status(dir.path / f).permissions() & fs::perms::all) == fs::perms(0666 & ~mask));
  }
}

TEST_CASE("output names that do not name a file are refused", "[atomic]") {
  TempDir dir("names");
  for (const std::string bad : {"d/", "", ".", "..", "x/..", "=odd.png", "sub/=odd.gsd"}) {
    INFO(bad);
    CHECK_THROWS_AS(check_output_name("--out", bad), InputError);
  }
  CHECK_THROWS_WITH(check_output_name("--out", dir.path), Contains("is a directory"));
  CHECK_NOTHROW(check_output_name("-o", dir.path / "-dash.png"));
  CHECK_NOTHROW(check_output_name("-o", "odd=.png"));
  // Its temporary `.NAME.tmp-XXXXXX` must fit in a name: 243 bytes at most.
  CHECK_NOTHROW(check_output_name("--out", dir.path / std::string(kMaxOutputName, 'x')));
  CHECK_THROWS_WITH(check_output_name("--out", dir.path / std::string(kMaxOutputName + 1, 'x')),
                    Contains("file name too long"));
  CHECK_THROWS_WITH(write_atomically(dir.path / "sub/", "x"), Contains("not a file name"));
  CHECK_FALSE(fs::exists(dir.path / "sub"));
  // A BASE adds extensions: BASE itself may not name a directory, BASE.json may not be one.
  fs::create_directory(dir.path / "r.json");
  CHECK_THROWS_WITH(check_output_base("--out", dir.path / "r", {".json"}), Contains("r.json: is a directory"));
  CHECK_THROWS_WITH(check_output_base("--out", dir.path / ".", {".json"}), Contains("not a file name"));
  CHECK_NOTHROW(check_output_base("--out", dir.path / "r", {".csv"}));
  // A DIR of outputs: what exists of it must be a directory.
  std::ofstream(dir.path / "file") << "the user's\n";
  fs::create_symlink(dir.path / "nowhere", dir.path / "dangling");
  CHECK_THROWS_WITH(check_output_directory("--out", dir.path / "file", {}), Contains("is not a directory"));
  CHECK_THROWS_WITH(check_output_directory("--out", dir.path / "file" / "x", {}), Contains("is not a directory"));
  CHECK_THROWS_WITH(check_output_directory("--out", dir.path / "dangling", {}), Contains("symbolic link to nothing"));
  CHECK_THROWS_WITH(check_output_directory("--out", dir.path, {"r.json"}), Contains("r.json: is a directory"));
  CHECK_NOTHROW(check_output_directory("--out", dir.path / "new" / "dir", {"a.csv"}));
  CHECK_THROWS_AS(Directory::open(dir.path / "file" / "x", true), InputError);
  CHECK_THROWS_AS(Directory::open(dir.path / "dangling", true), InputError);
}

TEST_CASE("an input that is not a regular file is refused, never waited on", "[atomic]") {
  TempDir dir("inputs");
  REQUIRE(::mkfifo((dir.path / "fifo").c_str(), 0600) == 0);
  CHECK_THROWS_WITH(read_text_file(dir.path / "fifo"), Contains("fifo: cannot read: is not a regular file"));
  CHECK_THROWS_WITH(read_text_file("/dev/zero"), Contains("is not a regular file"));
  CHECK_THROWS_WITH(read_text_file(dir.path), Contains("is a directory"));
  { std::ofstream big(dir.path / "big.pack"); }
  fs::resize_file(dir.path / "big.pack", kMaxInputBytes + 1);  // sparse
  CHECK_THROWS_WITH(read_text_file(dir.path / "big.pack"), Contains("larger than 2 GiB"));
}

namespace {
extern "C" void remove_temporaries_and_exit(int) {
  remove_open_temporaries();
  ::_exit(0);
}

// Forks a child running `work` (which never returns) and returns its pid once the child has said,
// by writing to the descriptor it is given, that it is under way.
template <class Work>
pid_t start_child(Work work) {
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(ready[0]);
    work(ready[1]);
  }
  ::close(ready[1]);
  char c;
  REQUIRE(::read(ready[0], &c, 1) == 1);
  ::close(ready[0]);
  return child;
}
}  // namespace

TEST_CASE("a signal at any moment of making temporaries leaves none behind", "[atomic]") {
  // The handler a command installs (remove_open_temporaries, then end) against a writer that makes
  // temporaries without pause: a signal that lands while one is being created must find it listed.
  TempDir dir("signal-temporaries");
  for (int trial = 0; trial < 100; ++trial) {
    const pid_t child = start_child([&](int ready) {
      std::signal(SIGTERM, remove_temporaries_and_exit);
      const Directory d = Directory::open(dir.path, false);
      for (long i = 0;; ++i) {
        TempFile t(d, "result.json");
        t.write("{}\n");
        if (i == 10) (void)!::write(ready, "x", 1);
      }
    });
    ::usleep(static_cast<useconds_t>(100 + 37 * trial));
    ::kill(child, SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);
    INFO("trial " << trial);
    REQUIRE(names_in(dir.path).empty());
  }
}

TEST_CASE("a result's JSON and CSV are replaced as one: a signal never leaves a new CSV beside an old JSON",
          "[atomic]") {
  // A command's --out BASE pair rewritten without pause, each pair carrying its own number in both
  // files, and SIGTERM sent at moments spread over the writes and their fsyncs.
  TempDir dir("signal-pairs");
  for (int trial = 0; trial < 60; ++trial) {
    const pid_t child = start_child([&](int ready) {
      std::signal(SIGTERM, remove_temporaries_and_exit);
      const Directory d = Directory::open(dir.path, false);
      for (long i = 0;; ++i) {
        io::CommandResult r;
        r.json = Json{{"pair", i}};
        r.csv = [i](std::ostream& out) { out << "pair\n" << i << "\n"; };
        io::write_result_files(d, "result", r);
        if (i == 3) (void)!::write(ready, "x", 1);
      }
    });
    ::usleep(static_cast<useconds_t>(50 + 211 * trial));
    ::kill(child, SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);
    INFO("trial " << trial);
    REQUIRE(names_in(dir.path) == std::vector<std::string>{"result.csv", "result.json"});
    const long in_json = io::read_json(dir.path / "result.json").at("pair").get<long>();
    CHECK(slurp(dir.path / "result.csv") == "pair\n" + std::to_string(in_json) + "\n");
  }
}

TEST_CASE("a process killed while logging leaves only whole lines in the .partial file", "[csv]") {
  TempDir dir("csv-kill");
  const fs::path file = dir.path / "steps.csv";
  const pid_t child = start_child([&](int ready) {
    CsvLog log(Directory::open(dir.path, false), "steps.csv", {"step", "phi", "phase"});
    for (long i = 0;; ++i) {
      log.row({i, 0.5 + 1e-9 * static_cast<double>(i), "growing"});
      if (i == 1000) (void)!::write(ready, "x", 1);
    }
  });
  ::usleep(20000);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  REQUIRE(WIFSIGNALED(status));

  CHECK_FALSE(fs::exists(file));
  const std::string text = slurp(dir.path / "steps.csv.partial");
  REQUIRE(text.size() > 1000);
  CHECK(text.back() == '\n');
  std::istringstream lines(text);
  std::string line;
  long n = 0;
  while (std::getline(lines, line)) {
    if (n++ == 0) continue;
    REQUIRE(std::count(line.begin(), line.end(), ',') == 2);
  }
  CHECK(n > 1000);
}

TEST_CASE("json_text is deterministic and writes null for missing values", "[json]") {
  TempDir dir("json");
  Json j;
  j["status"] = "ok";
  j["phi_2"] = number_or_null(std::nullopt);
  j["P"] = number_or_null(std::numeric_limits<double>::infinity());
  j["phi_J"] = 0.1 + 0.2;
  j["N"] = 412;
  CHECK(json_text(j) ==
        "{\n  \"status\": \"ok\",\n  \"phi_2\": null,\n  \"P\": null,\n  \"phi_J\": 0.30000000000000004,\n  \"N\": "
        "412\n}\n");
  write_json(dir.path / "summary.json", j);
  const Json back = read_json(dir.path / "summary.json");
  CHECK(back == j);
  CHECK(std::bit_cast<std::uint64_t>(back["phi_J"].get<double>()) == std::bit_cast<std::uint64_t>(0.1 + 0.2));
  write_atomically(dir.path / "bad.json", "{\"a\": 1,\n");
  CHECK_THROWS_WITH(read_json(dir.path / "bad.json"), Contains("bad.json: invalid JSON: parse error at line"));
}

TEST_CASE("a log that hits a full disk still ends with a whole row", "[csv]") {
  // Sizes chosen so that the disk fills at different places within a row.
  for (std::size_t kib : {8, 12, 16, 20, 28, 36}) {
    TempDir dir("csv-full-" + std::to_string(kib));
    budjam::testing::SmallDisk disk(dir.path / "disk", kib * 1024);
    if (!disk.mounted) {
      WARN(disk.why_not);
      return;
    }
    const fs::path file = disk.path / "steps.csv";
    CsvLog log(Directory::open(disk.path, false), "steps.csv", {"step", "phi", "note"});
    bool full = false;
    for (int i = 0; i < 100000 && !full; ++i) {
      try {
        log.row({i, 0.5 + i * 1e-7, std::string(static_cast<std::size_t>(i % 97), 'x')});
      } catch (const IoError& e) {
        full = true;
        CHECK(std::string(e.what()).find("steps.csv.partial") != std::string::npos);
      }
    }
    REQUIRE(full);
    const std::string text = slurp(disk.path / "steps.csv.partial");
    INFO(kib << " KiB");
    CHECK(text.size() == log.bytes());
    CHECK(text.back() == '\n');
  }
}
