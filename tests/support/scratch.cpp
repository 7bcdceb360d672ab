#include "scratch.hpp"

#include <unistd.h>
#include <fstream>
#include <sstream>
#include <system_error>

namespace budjam::testing {

const std::filesystem::path& work_dir() {
  struct WorkDir {
    std::filesystem::path path = std::filesystem::temp_directory_path() / ("budjam-test-" + std::to_string(::getpid()));
    WorkDir() {
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~WorkDir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const WorkDir dir;
  return dir.path;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace budjam::testing
