#pragma once
// TOML scene files <-> budjam::Scene. The knob table (budjam/scene_keys.hpp) drives the parser, the
// `--set section.key=value` overrides, the writers and the docs table, so every key is spelled in
// one place.
#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"
#include "io/json.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

// Parses TOML text (defaults for absent keys), applies `overrides` ("section.key=value", see
// apply_override), then validate(). Errors are InputError, one line:
//   "<source>: empty scene file (...)"                     (nothing but white space)
//   "<source>:<line>:<col>: not valid UTF-8 (...)"         (checked before the TOML parser)
//   "<source>:<line>:<col>: <TOML syntax problem>"
//   "<source>:<line>:<col>: growth.P00: unknown key (known in [growth]: P0, dt, dt_min, max_steps, ...)"
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

// The knob table as a Markdown table (key, type, default, accepted values, meaning): the one in
// docs/files.md (`budjam validate --keys-markdown`).
std::string scene_keys_markdown();

}  // namespace budjam::io
