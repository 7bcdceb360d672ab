#include "analysis/run_protocol.hpp"

#include "budjam/errors.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"

#include <optional>
#include <set>
#include <string>

namespace budjam::tools {

bool may_differ_between_samples(const SceneKey& k) {
  static const std::set<std::string> keys{"growth.max_steps", "jamming.targets", "jamming.continue_to_phi2",
                                          "minimiser.threads"};
  return k.section == "run" || k.section.starts_with("observe") || keys.contains(k.key());
}

void require_same_keys(const RunScene& run, const RunScene& first, bool (*compared)(const SceneKey&),
                       std::string_view why, std::string_view remedy) {
  for (const SceneKey& k : scene_keys()) {
    if (!compared(k)) continue;
    const SceneValue value = k.get(run.scene), first_value = k.get(first.scene);
    if (value == first_value) continue;
    throw InputError(run.file.string() + ": " + k.key() + " = " + value_text(value) + ", but " + first.file.string() +
                     " has " + value_text(first_value) + " (" + std::string(why) + "): " + std::string(remedy));
  }
}

void require_one_protocol(std::span<const std::filesystem::path> run_dirs, std::string_view remedy) {
  if (run_dirs.size() < 2) return;  // nothing to compare
  std::optional<RunScene> first;
  for (const auto& dir : run_dirs) {
    const auto file = dir / io::run_files::scene;
    RunScene run{file, io::load_scene(file)};
    if (!first) {
      first.emplace(std::move(run));
      continue;
    }
    require_same_keys(
        run, *first, [](const SceneKey& k) { return !may_differ_between_samples(k); },
        "the runs pooled here are samples of one protocol", remedy);
  }
}

}  // namespace budjam::tools
