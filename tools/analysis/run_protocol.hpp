#pragma once
// When finished runs may be pooled as samples of one protocol (`budjam analyse` per (L, P0),
// `budjam survival` over all its runs): their scenes may differ only in what a run is called,
// records or runs on, its seed and its step limit. Every other key (L, P0, ε_U, Δt, the search, the
// minimiser, ...) sets which states a run reaches, so runs that differ in one are samples of
// different distributions, and a mean or a survival curve over them estimates none of them.
#include "budjam/scene.hpp"
#include "budjam/scene_keys.hpp"

#include <filesystem>
#include <span>
#include <string_view>

namespace budjam::tools {

// Whether runs pooled as samples of one protocol may differ in this key: run.*, observe.*,
// growth.max_steps, jamming.targets, jamming.continue_to_phi2 and minimiser.threads.
bool may_differ_between_samples(const SceneKey& key);

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
