#pragma once
// When finished runs may be pooled as samples of one protocol (`budjam analyse` per (L, P0),
// `budjam survival` over all its runs): their scenes may differ only in what a run is called,
// records or runs on, its seed and its step limit. Every other key (L, P0, ε_U, Δt, the search, the
// minimiser, ...) sets which states a run reaches, so runs that differ in one are samples of
// different distributions, and a mean or a survival curve over them estimates none of them.
#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace budjam::tools {

// Whether runs pooled as samples of one protocol may differ in this key: run.*, observe.*,
// growth.max_steps, jamming.targets, jamming.continue_to_phi2 and minimiser.threads.
bool may_differ_between_samples(const SceneKey& key);

// The keys `budjam analyse` holds equal within a group (L, P0): every key but those above and the
// cell parameters, which it holds equal across all its runs instead (cells_key).
bool group_protocol_key(const SceneKey& key);
bool cells_key(const SceneKey& key);
// The keys that set which jamming points a run reaches: the cells, the initial state, the growth step
// and the jamming window with its minimum check. Not the search or the minimiser (their ensembles are
// held equal within their errors: docs/speed.md), nor what acts only above jamming (P0, the targets).
// A report takes jamming-point numbers from an ensemble only where these agree with its runs'.
bool jamming_model_key(const SceneKey& key);

// The protocol of a run as a stable name, so that tables (runs.csv) can say which runs may be pooled
// without the scenes: FNV-1a (64 bit) of the canonical text of the keys `selected` admits, one line
// "section.name = value\n" each in scene_keys() order, the value as value_text() writes it (a list
// in full), written as 16 lowercase hex digits. Scenes that agree in every selected key have equal
// hashes on every platform (the text holds shortest round-trip numbers, no locale); a budjam that adds
// a key to the selection changes every hash, so tables of two such versions are not pooled.
std::string protocol_text(const Scene& scene, bool (*selected)(const SceneKey&));
std::string protocol_hash(const Scene& scene, bool (*selected)(const SceneKey&));

// A run's scene and the file it was read from (for messages).
struct RunScene {
  std::filesystem::path file;
  Scene scene;
};

// InputError "<run.file>: <key> = <value>, but <first.file> has <value> (<why>): <remedy>" for the
// first key that `compared` selects in which the two scenes differ.
void require_same_keys(const RunScene& run, const RunScene& first, bool (*compared)(const SceneKey&),
                       std::string_view why, std::string_view remedy);

// The scene.toml of each run directory, every one held to the first's protocol (the keys
// may_differ_between_samples does not allow to differ), with `remedy` ending the message. One run
// is compared with nothing, and its scene is not read.
void require_one_protocol(std::span<const std::filesystem::path> run_dirs, std::string_view remedy);

}  // namespace budjam::tools
