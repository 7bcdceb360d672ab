#pragma once
// Reading the tables an earlier `budjam analyse` wrote (runs.csv, targets.csv, dos.csv,
// survival.csv) back into the records the run-directory reader fills, so that the same estimators
// can be applied again when the run directories are gone (docs/analysis.md, "Analysis from stored
// tables"). The tables hold each run's per-run results, not its step log, bud events or packings:
// whatever needs those is listed in Ensemble::unavailable with what it needs, never left silently
// empty. Tables of an earlier format (fewer columns) are read as far as they go.
#include "analysis/ensemble_records.hpp"

#include <filesystem>

namespace budjam::tools {

// InputError naming the file (and line, column) for a missing runs.csv / targets.csv, a malformed
// row, a target or spectrum of a run runs.csv does not list, or a run listed twice.
Ensemble read_ensemble_tables(const std::filesystem::path& dir);

}  // namespace budjam::tools
