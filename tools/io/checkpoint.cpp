#include "io/checkpoint.hpp"

#include "budjam/scene.hpp"  // InputError

namespace budjam::io {

void write_checkpoint(const std::filesystem::path& path, const Packing& packing, const PackingMeta& meta,
                      const Json& state) {
  Json j;
  j["format"] = "budjam-checkpoint";
  j["version"] = kCheckpointFormatVersion;
  j["packing"] = format_packing(packing, meta);
  j["state"] = state;
  write_json(path, j);
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  const Json j = read_json(path);
  const std::string where = path.string();
  if (!j.is_object() || !j.contains("format") || j["format"] != "budjam-checkpoint")
    throw InputError(where + ": not a budjam checkpoint (no \"format\": \"budjam-checkpoint\")");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != kCheckpointFormatVersion)
    throw InputError(where + ": unsupported checkpoint version " + (j.contains("version") ? j["version"].dump() : "(none)") +
                     " (this budjam reads version " + std::to_string(kCheckpointFormatVersion) + ")");
  if (!j.contains("packing") || !j["packing"].is_string()) throw InputError(where + ": checkpoint has no packing");
  if (!j.contains("state") || !j["state"].is_object()) throw InputError(where + ": checkpoint has no state object");
  Checkpoint c;
  c.packing = parse_packing(j["packing"].get<std::string>(), where + "[packing]");
  c.state = j["state"];
  return c;
}

}  // namespace budjam::io
