#include "analysis/run_protocol.hpp"

#include "budjam/errors.hpp"
#include "budjam/number_text.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <optional>
#include <set>
#include <string>
#include <variant>

namespace budjam::tools {

bool may_differ_between_samples(const SceneKey& k) {
  static const std::set<std::string> keys{"growth.max_steps", "jamming.targets", "jamming.continue_to_phi2",
                                          "minimiser.threads"};
  return k.section == "run" || k.section.starts_with("observe") || keys.contains(k.key());
}

bool group_protocol_key(const SceneKey& k) { return !cells_key(k) && !may_differ_between_samples(k); }

bool cells_key(const SceneKey& k) { return k.section == "cells"; }

bool jamming_model_key(const SceneKey& k) {
  static const std::set<std::string> keys{"growth.dt", "jamming.epsilon_U", "jamming.check_minimum"};
  return k.section == "cells" || k.section == "init" || keys.contains(k.key());
}

std::string protocol_text(const Scene& scene, bool (*selected)(const SceneKey&)) {
  std::string text;
  for (const SceneKey& k : scene_keys()) {
    if (!selected(k)) continue;
    const SceneValue v = k.get(scene);
    std::string value;
    if (const auto* list = std::get_if<std::vector<double>>(&v)) {
      // value_text shortens a long list for messages; a name of the protocol must hold every value
      value = "[";
      for (std::size_t i = 0; i < list->size(); ++i) value += (i ? ", " : "") + shortest_text((*list)[i]);
      value += "]";
    } else {
      value = value_text(v);
    }
    text += k.key() + " = " + value + "\n";
  }
  return text;
}

std::string protocol_hash(const Scene& scene, bool (*selected)(const SceneKey&)) {
  return io::hex64(io::fnv1a64(protocol_text(scene, selected)));
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
