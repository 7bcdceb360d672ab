#include "analysis/jamming_states.hpp"

#include "analysis/run_protocol.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace budjam::tools {

std::vector<std::size_t> jamming_state_ids(std::span<const JammingKey> runs) {
  using Key = std::tuple<double, std::uint64_t, double, double, double>;
  std::map<Key, std::size_t> seen;
  std::vector<std::size_t> ids;
  ids.reserve(runs.size());
  for (const auto& r : runs) {
    const auto [it, inserted] = seen.emplace(Key{r.L, r.seed, r.step_J, r.N_J, r.phi_J}, seen.size());
    ids.push_back(it->second);
  }
  return ids;
}

namespace {

// Per-state means of the finite values, keyed by state index.
std::map<std::size_t, double> state_means(std::span<const double> values, std::span<const std::size_t> state) {
  if (values.size() != state.size()) throw std::invalid_argument("mean_over_states: values and states differ in size");
  std::map<std::size_t, std::pair<double, std::size_t>> acc;
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!std::isfinite(values[k])) continue;
    auto& a = acc[state[k]];
    a.first += values[k];
    ++a.second;
  }
  std::map<std::size_t, double> out;
  for (const auto& [s, a] : acc) out[s] = a.first / static_cast<double>(a.second);
  return out;
}

}  // namespace

MeanSE mean_over_states(std::span<const double> values, std::span<const std::size_t> state) {
  std::vector<double> per_state;
  for (const auto& [s, m] : state_means(values, state)) per_state.push_back(m);
  MeanSE r;
  r.n = per_state.size();
  r.mean = mean(per_state);
  r.se = standard_error(per_state);
  return r;
}

BootstrapResult cluster_bootstrap_mean(std::span<const double> values, std::span<const std::size_t> state,
                                       std::span<const std::uint64_t> cluster, const BootstrapOptions& options) {
  if (cluster.size() != state.size())
    throw std::invalid_argument("cluster_bootstrap_mean: clusters and states differ in size");
  const auto means = state_means(values, state);
  if (means.empty()) throw std::invalid_argument("cluster_bootstrap_mean: no data");
  // one value per state, in the cluster of the state
  std::vector<double> per_state;
  std::vector<std::uint64_t> of;
  std::map<std::size_t, bool> placed;
  for (std::size_t k = 0; k < state.size(); ++k) {
    const auto m = means.find(state[k]);
    if (m == means.end() || placed[state[k]]) continue;
    placed[state[k]] = true;
    per_state.push_back(m->second);
    of.push_back(cluster[k]);
  }
  BootstrapResult b = cluster_bootstrap(
      per_state, of, [](std::span<const double> x) { return mean(x); }, options);
  b.n = per_state.size();
  return b;
}

std::vector<std::vector<std::size_t>> duplicate_runs(std::span<const std::string> fingerprints) {
  std::map<std::string, std::vector<std::size_t>> by_text;
  for (std::size_t k = 0; k < fingerprints.size(); ++k) by_text[fingerprints[k]].push_back(k);
  std::vector<std::vector<std::size_t>> groups;
  for (auto& [text, idx] : by_text)
    if (idx.size() >= 2) groups.push_back(std::move(idx));
  std::sort(groups.begin(), groups.end(), [](const auto& a, const auto& b) { return a.front() < b.front(); });
  return groups;
}

DistinctRuns load_distinct_runs(std::span<const std::filesystem::path> dirs) {
  DistinctRuns d;
  std::vector<std::string> fingerprints;
  const auto sets_the_states = [](const SceneKey& k) { return !may_differ_between_samples(k); };
  for (const auto& dir : dirs) {
    d.runs.push_back(load_run(dir));
    const Scene scene = io::load_scene(dir / io::run_files::scene);
    fingerprints.push_back(protocol_hash(scene, sets_the_states) + " seed " + std::to_string(scene.seed));
  }
  d.later_copy.assign(dirs.size(), false);
  for (const auto& group : duplicate_runs(fingerprints)) {
    std::vector<std::string> names;
    for (std::size_t k : group) {
      names.push_back(dirs[k].string());
      d.later_copy[k] = k != group.front();
    }
    d.copy_groups.push_back(std::move(names));
  }
  return d;
}

}  // namespace budjam::tools
