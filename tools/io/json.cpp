#include "io/json.hpp"

#include "budjam/errors.hpp"
#include "io/atomic_file.hpp"

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

}  // namespace budjam::io
