#pragma once
// TOML scene files <-> budjam::Scene. One key table (scene_keys()) drives the parser, the
// `--set section.key=value` overrides and the writers, so every key is spelled in one place.
#include "budjam/scene.hpp"
#include "io/json.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace budjam::io {

// A scene value as a file shows it. growth.P0 = none is the string "none".
using SceneValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

// One key of the scene file, e.g. section "growth", name "P0", key() "growth.P0".
struct SceneKeyInfo {
  std::string section;  // "run", "box", ..., "observe.moduli"
  std::string name;
  std::string help;     // one line: meaning and unit
  std::string key() const { return section + "." + name; }
};

// Every key, grouped by section in file order: run, box, cells, init, growth, jamming,
// minimiser, observe, observe.moduli, observe.dos.
const std::vector<SceneKeyInfo>& scene_keys();

// The value of one key ("growth.P0") in a scene; InputError "<key>: unknown key".
SceneValue scene_value(const Scene& scene, std::string_view key);

// Parses TOML text (defaults for absent keys), applies `overrides` ("section.key=value", see
// apply_override), then validate(). Errors are InputError, one line:
//   "<source>:<line>:<col>: <TOML syntax problem>"
//   "<source>:<line>:<col>: growth.P00: unknown key (known in [growth]: P0, dt, dt_min, max_steps)"
//   "<source>:<line>:<col>: growth.dt: expected a number (got \"fast\")"
//   "<source>: growth.P0: must be positive, or \"none\" for no feedback (got -0.001)"   (validate)
Scene parse_scene(std::string_view toml_text, const std::string& source = "<scene>",
                  const std::vector<std::string>& overrides = {});
// Reads the file, then as parse_scene with the path as source.
Scene load_scene(const std::filesystem::path& path, const std::vector<std::string>& overrides = {});

// Sets one key from "section.key=value". The value is TOML (1e-4, true, [1e-3, 1e-2], "text");
// a bare word that is not TOML is taken as a string (growth.P0=none, cells.division=aligned).
// Does not validate (callers apply all overrides, then validate). InputError
// "--set <assignment>: <problem>".
void apply_override(Scene& scene, std::string_view assignment);

// The complete effective scene as TOML (every key, in table order; with `comments`, each key's
// help as a trailing comment). parse_scene(scene_to_toml(s)) reproduces s bit for bit.
std::string scene_to_toml(const Scene& scene, bool comments = false);
// The same content as nested JSON objects ({"run": {"name": ..}, ..., "observe": {"moduli": {..}}}).
Json scene_to_json(const Scene& scene);

// Text of a value as it appears in TOML (doubles round-trip exactly; 1.0 is "1.0").
std::string toml_literal(const SceneValue& value);

}  // namespace budjam::io
