#pragma once
// Which runs are independent samples. Runs of one scene with the same seed share their growth up to
// jamming (feedback acts only above φ_J), so they usually reach one and the same jamming state in
// every P0 group: quantities fixed at jamming (φ_J, u_J, n_J, the jammed spectrum) then have as many
// independent samples as distinct states, not as runs. And a run directory copied twice is one run.
#include "budjam/statistics.hpp"
#include "io/run_data.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace budjam::tools {

// What identifies a jamming state: runs of one size and seed that jam at the same step with the
// same number of cells at bit-identical φ_J grew identically up to there.
struct JammingKey {
  double L = 0;
  std::uint64_t seed = 0;
  double step_J = 0, N_J = 0, phi_J = 0;
};

// State index of each run (0, 1, … in order of first appearance); equal keys share an index.
std::vector<std::size_t> jamming_state_ids(std::span<const JammingKey> runs);

// Mean ± SE with one sample per state: the values of the runs in one state are averaged first
// (they are equal for a quantity fixed at jamming), the SE is over states (n = states).
// Non-finite values are left out. Throws std::invalid_argument for mismatched sizes.
MeanSE mean_over_states(std::span<const double> values, std::span<const std::size_t> state);

// Bootstrap of the mean resampling whole clusters (seeds) with replacement: each resample's
// statistic is the mean over the states of the drawn clusters (a state lies in one cluster).
// Deterministic for a given seed of `options`. Throws std::invalid_argument for no data.
BootstrapResult cluster_bootstrap_mean(std::span<const double> values, std::span<const std::size_t> state,
                                       std::span<const std::uint64_t> cluster, const BootstrapOptions& options = {});

// Groups of two or more runs with identical fingerprints: runs of one protocol grown from one seed
// (a run copied into several directories, or grown again under another name or step limit), which
// are one sample. Indices ascending within a group; groups in order of their first index.
std::vector<std::vector<std::size_t>> duplicate_runs(std::span<const std::string> fingerprints);

// Run directories read in order, each later run of a protocol and seed marked: one sample, not two.
// The fingerprint is the seed with the hash of every scene key that sets which states a run reaches
// (all but those may_differ_between_samples allows to differ: run.*, observe.*, the step limit, ...).
struct DistinctRuns {
  std::vector<RunData> runs;
  std::vector<bool> later_copy;                       // runs[k] repeats an earlier run
  std::vector<std::vector<std::string>> copy_groups;  // directories of one run, the used one first
};
DistinctRuns load_distinct_runs(std::span<const std::filesystem::path> dirs);

}  // namespace budjam::tools
