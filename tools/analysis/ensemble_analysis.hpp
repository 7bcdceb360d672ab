#pragma once
// Ensemble analysis of finished growth runs (docs/analysis.md): every number behind the paper's
// figures and the reproduction report, as JSON and CSV tables, each quantity under budjam's
// definition and, where the paper's own analysis defined it differently, under the paper's too.
// The estimators it applies are in depletion_estimators, structure_estimators and jamming_states.
#include "budjam/statistics.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace budjam::tools {

struct EnsembleOptions {
  std::vector<std::string> inputs;  // run directories, or folders holding them (searched recursively)
  std::string tables;               // or: the tables of an earlier analysis (ensemble_tables.hpp)
  std::string out;                  // output directory
  double main_L = 0;                // 0: 15 if present, else the largest L
  BootstrapOptions bootstrap;
  bool require_moduli = false, require_dos = false;  // their absence is an error, not empty columns
};

struct EnsembleAccount {
  std::string used;                    // one line: what was used and where the tables went
  std::vector<std::string> unchecked;  // one line each: what tables of an earlier format left unchecked
};

// Reads the runs (or the tables), writes the tables listed in docs/analysis.md ("analyse outputs") into
// options.out, and returns the account of what was used. InputError for bad input.
EnsembleAccount analyse_ensemble(const EnsembleOptions& options);

}  // namespace budjam::tools
