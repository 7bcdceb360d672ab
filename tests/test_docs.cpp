// The documentation names only what exists: every scene key written as `section.name` in a code
// span or a shell block of README.md and docs/*.md is a row of the knob table, every
// `budjam <subcommand>` there is a subcommand of the executable, the tables of jamming searches
// and observers are their registries', and the checkpoint format named is the one written.
#include "budjam/jamming.hpp"
#include "budjam/scene_keys.hpp"
#include "io/checkpoint.hpp"
#include "io/run_directory.hpp"
#include "scratch.hpp"

#include <catch2/catch.hpp>
#include "run_budjam.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using budjam::testing::run_budjam;
using budjam::testing::slurp;
using budjam::testing::source_file;

namespace {

struct Doc {
  std::string name;
  // Its code spans and the lines of its code blocks, one a line; not the blocks of Python, C++ or
  // diagrams (`text`), nor error messages, which quote bad input.
  std::string code;
};

// README.md and every page of docs/.
std::vector<Doc> documents() {
  std::vector<fs::path> files{source_file("README.md")};
  for (const auto& e : fs::directory_iterator(source_file("docs")))
    if (e.path().extension() == ".md") files.push_back(e.path());
  std::vector<Doc> docs;
  const std::regex span("`([^`\n]+)`");
  for (const fs::path& f : files) {
    Doc d{f.filename().string(), {}};
    std::istringstream in(slurp(f));
    bool block = false, foreign = false;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("```", 0) == 0) {
        const std::string info = line.substr(3);
        foreign = !block && (info == "python" || info == "cpp" || info == "text");
        block = !block;
        continue;
      }
      if (block) {
        if (!foreign && line.rfind("budjam: error:", 0) != 0) d.code += line + '\n';
        continue;
      }
      for (std::sregex_iterator m(line.begin(), line.end(), span), end; m != end; ++m) d.code += (*m)[1].str() + '\n';
    }
    docs.push_back(std::move(d));
  }
  return docs;
}

// The subcommands `budjam --help` lists (as the bash completion reads them).
std::set<std::string> subcommands() {
  const auto help = run_budjam("--help");
  REQUIRE(help.code == 0);
  std::set<std::string> names;
  std::istringstream in(help.out);
  bool listing = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("Subcommands:", 0) == 0) {
      listing = true;
    } else if (listing && line.size() > 2 && line.rfind("  ", 0) == 0 &&
               std::islower(static_cast<unsigned char>(line[2]))) {
      names.insert(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return names;
}

}  // namespace

TEST_CASE("every scene key the documentation names is a row of the knob table", "[docs]") {
  // A section word that begins a name (not a path such as budjam/growth.hpp, nor a file growth.md).
  const std::regex key(
      R"((^|[^A-Za-z0-9_./-])(run|box|cells|init|growth|jamming|minimiser|observe)\.([A-Za-z_][A-Za-z0-9_]*)(\.[A-Za-z_][A-Za-z0-9_]*)?)");
  const std::set<std::string> file_kinds{"md",   "hpp", "cpp", "csv", "tsv", "json", "toml",
                                         "pack", "py",  "sh",  "svg", "png", "txt"};
  std::size_t named = 0;
  for (const Doc& d : documents()) {
    for (std::sregex_iterator m(d.code.begin(), d.code.end(), key), end; m != end; ++m) {
      const std::string section = (*m)[2].str(), name = (*m)[3].str(), more = (*m)[4].str();
      if (file_kinds.count(name)) continue;
      const bool subsection = section == "observe" && (name == "moduli" || name == "dos") && !more.empty();
      const std::string k = subsection ? section + "." + name + more : section + "." + name;
      // A key, or a section that holds keys (`observe.moduli`).
      const bool section_of_keys = std::any_of(budjam::scene_keys().begin(), budjam::scene_keys().end(),
                                               [&](const budjam::SceneKey& r) { return r.section == k; });
      INFO(d.name << ": `" << k << "`");
      CHECK((budjam::find_scene_key(k) != nullptr || section_of_keys));
      ++named;
    }
  }
  CHECK(named > 50);  // the pattern finds the keys the pages name
}

TEST_CASE("every budjam subcommand the documentation names exists", "[docs]") {
  const std::set<std::string> known = subcommands();
  REQUIRE(known.count("grow") == 1);
  // Not a path that follows one executable with another (`OLD/budjam build/budjam`).
  const std::regex command(R"((^|[\s/`(])budjam ([a-z][a-z-]*)(?![A-Za-z0-9_-]*/))");
  std::size_t named = 0;
  for (const Doc& d : documents()) {
    for (std::sregex_iterator m(d.code.begin(), d.code.end(), command), end; m != end; ++m) {
      INFO(d.name << ": `budjam " << (*m)[2].str() << "`");
      CHECK(known.count((*m)[2].str()) == 1);
      ++named;
    }
  }
  CHECK(named > 30);
}

TEST_CASE("docs/jamming.md's table of jamming searches names exactly the registry's searches, in its order", "[docs]") {
  const std::string doc = slurp(source_file("docs/jamming.md"));
  const std::string header = "| `jamming.search` | what it does |\n|---|---|\n";
  const auto at = doc.find(header);
  REQUIRE(at != std::string::npos);
  std::istringstream rows(doc.substr(at + header.size()));
  std::vector<std::string> documented, registered;
  for (std::string line; std::getline(rows, line) && line.rfind("| `", 0) == 0;) documented.push_back(line);
  for (const budjam::JammingSearchKind& k : budjam::jamming_searches())
    registered.push_back("| `" + std::string(k.name) + "` | " + std::string(k.description) + " |");
  CHECK(documented == registered);
}

TEST_CASE("docs/growth.md's table of observers is the registry's, and each is switched on by scene keys", "[docs]") {
  const std::string doc = slurp(source_file("docs/growth.md"));
  const std::string begin = "<!-- observers: generated by `budjam validate --observers-markdown` -->\n";
  const auto a = doc.find(begin), b = doc.find("<!-- end of observers -->");
  REQUIRE(a != std::string::npos);
  REQUIRE(b != std::string::npos);
  const auto printed = run_budjam("validate --observers-markdown");
  REQUIRE(printed.code == 0);
  // Regenerate it after registering an observer: budjam validate --observers-markdown.
  CHECK(doc.substr(a + begin.size(), b - a - begin.size()) == printed.out);
  // The second column: a key of the knob table, or `section.*` for every key of a section.
  const std::regex row(R"(^\| `[a-z_]+` \| `([a-z_.]+?)(\.\*)?` \|)");
  std::size_t rows = 0;
  std::istringstream in(printed.out);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    ++rows;
    const std::string keys = m[1].str();
    INFO(line);
    if (m[2].matched)
      CHECK(std::any_of(budjam::scene_keys().begin(), budjam::scene_keys().end(),
                        [&](const budjam::SceneKey& k) { return k.section == keys; }));
    else
      CHECK(budjam::find_scene_key(keys) != nullptr);
  }
  CHECK(rows >= 7);
}

TEST_CASE("every CSV log an observer writes at the top of a run directory is one the run's readers read", "[docs]") {
  const auto printed = run_budjam("validate --observers-markdown");
  REQUIRE(printed.code == 0);
  namespace run_files = budjam::io::run_files;
  const std::regex log(R"(`([a-z_]+\.csv)`)");
  std::size_t logs = 0;
  for (std::sregex_iterator it(printed.out.begin(), printed.out.end(), log), end; it != end; ++it) {
    const std::string name = (*it)[1].str();
    INFO(name << ": add it to io::run_files::observer_logs (docs/howto.md)");
    ++logs;
    const bool read = name == run_files::steps || name == run_files::divisions || name == run_files::bud_events ||
                      std::find(run_files::observer_logs.begin(), run_files::observer_logs.end(), name) !=
                          run_files::observer_logs.end();
    CHECK(read);
  }
  CHECK(logs >= 5);
}

TEST_CASE("every checkpoint format the documentation names is the one the writer writes", "[docs]") {
  const std::regex named("budjam-checkpoint ([0-9]+)");
  std::size_t names = 0;
  for (const Doc& d : documents())
    for (std::sregex_iterator m(d.code.begin(), d.code.end(), named), end; m != end; ++m, ++names) {
      INFO(d.name << ": " << m->str());
      CHECK(std::stoi((*m)[1].str()) == budjam::io::kCheckpointVersion);
    }
  CHECK(names >= 1);  // docs/growth.md, "Checkpoints and resume"
}
