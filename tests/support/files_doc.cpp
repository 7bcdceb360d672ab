#include "files_doc.hpp"

#include "run_budjam.hpp"
#include "scratch.hpp"

#include <sstream>

namespace budjam::testing {

std::vector<std::string> csv_header(const std::filesystem::path& file) {
  std::istringstream in(slurp(file));
  std::string line, name;
  std::getline(in, line);
  std::vector<std::string> names;
  std::istringstream fields(line);
  while (std::getline(fields, name, ',')) names.push_back(name);
  return names;
}

std::vector<std::string> documented_columns(const std::string& key) {
  std::istringstream doc(slurp(source_file("docs/columns.md")));
  std::string line;
  bool in_section = false;
  std::vector<std::string> names;
  while (std::getline(doc, line)) {
    if (line.rfind("#", 0) == 0) {
      if (in_section) break;
      in_section = line.rfind("## ", 0) == 0 && line.find(key) != std::string::npos;
    } else if (in_section && line.rfind("| `", 0) == 0) {
      names.push_back(line.substr(3, line.find('`', 3) - 3));
    }
  }
  return names;
}

}  // namespace budjam::testing
