#pragma once
// JSON outputs (summary.json, checkpoints): key order as inserted, numbers as nlohmann prints
// them (shortest text that reads back bit-identically; locale-free), null for a missing value.
#include "io/atomic_file.hpp"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

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
