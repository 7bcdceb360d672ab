#pragma once
// The checkpoint of a growth run (docs/growth.md, "Checkpoints and resume"): a text file that
// holds the driver's GrowthState and every observer's section, written atomically.
//
// A checkpoint is trusted only if all of these hold (else InputError "<file>:<line>: <problem>",
// exit 2, nothing changed):
//  - format `budjam-checkpoint 7`; its last line `checksum <FNV-1a 64 of everything before>`;
//  - the hash of the effective scene it was written with equals that of the scene resuming it
//    (an edited scene.toml — growth.P0, a target, an observer — is refused);
//  - every number is finite and in range, every counter consistent with the others and with
//    the scene (next target within the targets, attempts within growth.max_steps, ...), the
//    packing obeys the physical rules (packing_rules.hpp), ids are unique;
//  - every stateful observer of the resuming run has its section, and every section with
//    content belongs to one of them.
#include "budjam/growth_driver.hpp"
#include "budjam/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace budjam::io {

inline constexpr int kCheckpointVersion = 7;

// FNV-1a, 64 bit: the content checksum of a checkpoint and the hash of its scene.
std::uint64_t fnv1a64(std::string_view bytes);

// The checkpoint text of `state` of a run of `scene`, with the sections of `observers`
// (save_state of each is called, in order).
std::string format_checkpoint(const Scene& scene, const GrowthState& state, const std::vector<Observer*>& observers);

// format_checkpoint, written atomically to `path`.
void write_checkpoint(const std::filesystem::path& path, const Scene& scene, const GrowthState& state,
                      const std::vector<Observer*>& observers);

// Checks `text` (named `file` in messages) against the resuming run (`scene`, `seed`,
// `observers`), then hands each observer its section (load_state) and returns the state for
// GrowthDriver::restore. Observers' load_state is called only after the whole text was checked.
GrowthState parse_checkpoint(std::string_view text, const std::string& file, const Scene& scene, std::uint64_t seed,
                             const std::vector<Observer*>& observers);

GrowthState read_checkpoint(const std::filesystem::path& path, const Scene& scene, std::uint64_t seed,
                            const std::vector<Observer*>& observers);

}  // namespace budjam::io
