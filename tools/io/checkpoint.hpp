#pragma once
// A checkpoint: the packing plus whatever the driver needs to continue exactly (random stream,
// phase, φ_J, next target, counters, tagged buds, CsvLog::bytes() of each log, ...), in ONE file
// written atomically, so a run killed at any instant has either the previous or the new
// checkpoint, never a mixture. Layout (JSON):
//   {"format": "budjam-checkpoint", "version": 1,
//    "packing": "<the packing file text, io/packing_file.hpp>", "state": { driver-defined }}
// Doubles inside "state" read back bit-identically (nlohmann writes shortest round-trip text).
#include "io/json.hpp"
#include "io/packing_file.hpp"

#include <filesystem>

namespace budjam::io {

inline constexpr int kCheckpointFormatVersion = 1;

struct Checkpoint {
  PackingFile packing;
  Json state;
};

void write_checkpoint(const std::filesystem::path& path, const Packing& packing, const PackingMeta& meta,
                      const Json& state);

// InputError "<path>: ..." for anything but a complete checkpoint of this version; errors in
// the embedded packing read "<path>[packing]:<line>: ...".
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace budjam::io
