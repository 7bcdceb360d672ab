#pragma once
// JSON outputs (summary.json, checkpoints): key order as inserted, numbers as nlohmann prints
// them (shortest text that reads back bit-identically; locale-free), null for a missing value.
#include "io/atomic_file.hpp"

#include <cmath>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace budjam::io {

using Json = nlohmann::ordered_json;

// null for NaN/±inf or nullopt ("not reached", "not measured"), the number otherwise.
inline Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
inline Json number_or_null(std::optional<double> v) { return v ? number_or_null(*v) : Json(nullptr); }

// Deterministic text: 2-space indent, a final newline. Same value => same bytes.
std::string json_text(const Json& value);

// Atomic write of json_text(value) (io/atomic_file.hpp).
void write_json(const std::filesystem::path& path, const Json& value);
void write_json(const Directory& dir, std::string_view name, const Json& value);

// InputError "<path>: cannot read: ..." or "<path>: invalid JSON: <parser message>".
Json read_json(const std::filesystem::path& path);

}  // namespace budjam::io

namespace budjam::io {

// `--out DIR` of a command that replaces its own files in DIR (analyse, accuracy): DIR may be new,
// empty, or an earlier output of the command, recognised by `marker` (a regular file, not a link,
// in DIR) holding a JSON object for which `is_own` is true. Any other non-empty DIR is refused,
// InputError "<option>: <DIR> is not empty and not an output of <command> (...)", so that a
// user's own runs.csv or accuracy.md is never replaced. Changes nothing.
void check_own_output_directory(std::string_view option, const std::filesystem::path& dir, std::string_view command,
                                std::string_view marker, const std::function<bool(const Json&)>& is_own);

}  // namespace budjam::io
