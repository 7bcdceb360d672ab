#pragma once
// Kaplan–Meier survival S(a) of the buds free at jamming, pooled over finished runs (each run's last
// jamming episode; completion is the event, division and the end of the run censor), for `budjam
// survival` and the Python module's survival(): the summary JSON (a_ε with u_J S(a_ε) = ε, ∫_0^{a_ε}
// S da; paper Eq. 14), the curve and the summary line. One serialisation, so that the command line
// and Python name every quantity alike. a = b² − b_J² in diameter squared; *_area = π/4 times it.
#include "budjam/survival.hpp"
#include "io/json.hpp"
#include "io/result_files.hpp"

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

namespace budjam::tools {

struct SurvivalReport {
  std::size_t runs = 0;    // distinct runs pooled
  std::size_t copies = 0;  // directories left out as copies of an earlier one
  io::Json duplicates;     // the groups of directories holding one run
  io::Json L, P0;          // of the runs (one protocol); P0 null without feedback
  KaplanMeierCurve km;
  double u_J = 0, N_nr_J = 0;  // means over the runs
  double epsilon = 0;
  std::optional<double> a_eps;
};

// Reads the runs (a run given twice, copied into another directory, or its seed grown again under
// the same protocol, is one sample: its first copy is used). epsilon: the cutoff of
// u_J S(a_ε) = ε, by default 1/⟨N_nr,J⟩. InputError naming the run that never jammed or has no
// bud_events.csv, or for a negative epsilon.
SurvivalReport survival_report(std::span<const std::filesystem::path> runs, std::optional<double> epsilon);

io::Json survival_json(const SurvivalReport& report);

// The se, lo, hi and se_greenwood cells of a step of a curve pooled from `runs` runs: the 95 % band
// from the variance clustered by run (KaplanMeierStep::clustered_var) and Greenwood's standard error,
// which takes every bud as independent. Empty where a band has fewer than kMinSamplesForError buds at
// risk, and everywhere on a curve of fewer than kMinSamplesForError runs (or an unknown number): the
// buds of one run share its growth, so a run, not a bud, is the sample an error bar needs.
std::array<std::string, 4> band_cells(const KaplanMeierStep& step, std::optional<std::size_t> runs);

// The JSON, the curve's table and the summary line. The table starts at a = 0 with S = 1 and every
// record at risk: a, a_area, S, se (clustered by run), lo and hi (95 % band clipped to [0, 1]),
// se_greenwood, at_risk, events, censored. The CSV writer refers to `report`, which must outlive it.
io::CommandResult survival_result(const SurvivalReport& report);

}  // namespace budjam::tools
