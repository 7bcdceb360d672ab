#include "io/result_files.hpp"

#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include "budjam/errors.hpp"

#include <sys/stat.h>

#include <ostream>
#include <sstream>
#include <string_view>

namespace budjam::io {

namespace fs = std::filesystem;

fs::path result_base(const std::string& base) {
  // By the name's text: std::filesystem takes ".json" for a stem without an extension.
  for (const std::string_view ext : {".json", ".csv"})
    if (base.ends_with(ext)) return fs::path(base.substr(0, base.size() - ext.size()));
  return fs::path(base);
}

void check_not_an_input(std::string_view option, const fs::path& output, const std::vector<fs::path>& inputs) {
  struct ::stat out {};
  if (::stat(output.c_str(), &out) != 0) return;  // not there: replaces nothing
  for (const fs::path& input : inputs) {
    struct ::stat in {};
    if (::stat(input.c_str(), &in) == 0 && in.st_dev == out.st_dev && in.st_ino == out.st_ino)
      throw InputError(std::string(option) + ": " + escape_control(output.string()) + ": is the input file " +
                       escape_control(input.string()) + " (writing it would replace the input; give another name)");
  }
}

void check_output_request(const OutputRequest& request, bool table, const std::vector<fs::path>& inputs) {
  if (request.base.empty()) return;
  const fs::path base = result_base(request.base);
  const std::string name = fs::path(request.base).filename().string();
  if (base.filename().empty() && !name.empty() && name != "." && name != "..")
    throw InputError("--out: " + escape_control(request.base) + ": no file name before the extension " + name);
  if (table)
    check_output_base("--out", base, {".json", ".csv"});
  else
    check_output_base("--out", base, {".json"});
  for (const char* ext : {".json", ".csv"}) {
    if (!table && std::string_view(ext) == ".csv") continue;
    fs::path file = base;
    file += ext;
    check_not_an_input("--out", file, inputs);
  }
}

std::vector<fs::path> write_result_files(const fs::path& base, const CommandResult& result) {
  return write_result_files(Directory::open(base.parent_path(), true), base.filename().string(), result);
}

std::vector<fs::path> write_result_files(const Directory& dir, const std::string& base_name,
                                         const CommandResult& result) {
  std::vector<fs::path> written{dir / (base_name + ".json")};
  std::vector<std::pair<std::string, std::string>> files;
  if (result.csv) {
    written.push_back(dir / (base_name + ".csv"));
    std::ostringstream table;
    result.csv(table);
    if (!table) throw IoError(written.back().string() + ": formatting the content failed");
    files.emplace_back(base_name + ".csv", table.str());
  }
  files.emplace_back(base_name + ".json", json_text(result.json));
  write_atomically(dir, files);
  return written;
}

void emit(const OutputRequest& request, const CommandResult& result, std::ostream& out) {
  std::vector<fs::path> written;
  if (!request.base.empty()) written = write_result_files(result_base(request.base), result);
  if (request.json) {
    out << json_text(result.json);
    return;
  }
  if (request.quiet) return;
  out << result.summary;
  for (std::size_t k = 0; k < written.size(); ++k)
    out << (k == 0 ? " -> " : ", ") << escape_control(written[k].string());  // one line, whatever the names
  out << '\n';
}

}  // namespace budjam::io
