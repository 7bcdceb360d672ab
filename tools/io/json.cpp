#include "io/json.hpp"

#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <system_error>

namespace budjam::io {

std::string json_text(const Json& value) { return value.dump(2) + "\n"; }

void write_json(const std::filesystem::path& path, const Json& value) { write_atomically(path, json_text(value)); }

void write_json(const Directory& dir, std::string_view name, const Json& value) {
  write_atomically(dir, name, json_text(value));
}

Json read_json(const std::filesystem::path& path) {
  const std::string text = read_text_file(path);
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    // e.what() is "[json.exception.parse_error.101] parse error at line 3, column 5: ..." (or
    // out_of_range.406 for a number no double holds, such as 1e999)
    std::string what = e.what();
    if (const auto at = what.find("] "); at != std::string::npos) what = what.substr(at + 2);
    throw InputError(path.string() + ": invalid JSON: " + what);
  }
}

void check_own_output_directory(std::string_view option, const std::filesystem::path& dir, std::string_view command,
                                std::string_view marker, const std::function<bool(const Json&)>& is_own) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(fs::status(dir, ec))) return;                       // new (or refused elsewhere)
  if (fs::directory_iterator(dir, ec) == fs::directory_iterator()) return;  // empty (or unreadable: later)
  bool own = false;
  const fs::path file = dir / marker;
  if (fs::is_regular_file(fs::symlink_status(file, ec))) {
    try {
      const Json j = read_json(file);
      own = j.is_object() && is_own(j);
    } catch (const std::exception&) {
      own = false;
    }
  }
  if (!own)
    throw InputError(std::string(option) + ": " + one_line(dir.string()) + " is not empty and holds no " +
                     std::string(marker) + " written by budjam " + std::string(command) +
                     ": its files would be replaced (choose a new or empty directory, or remove them)");
}

}  // namespace budjam::io
