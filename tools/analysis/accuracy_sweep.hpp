#pragma once
// Accuracy against cost of the numerical knobs (docs/accuracy.md).
//
// Growth knobs: each variant directory and the reference hold run directories seed<k>/ grown from the
// same scene and seeds, differing in one knob (the reference has every knob tight). A variant directory
// is named <knob>_<value> (ftol_1e-11, epsU_1e-15, tol_1e-7, dt_2) or "default". Per variant: mean cost
// per run (CPU seconds from cpu_time.json when the Makefile wrote it, else wall seconds from
// timing.json; the front compares force evaluations at the mean CPU time per evaluation, which does
// not depend on the machine's load) and the mean over seeds of the error against the same seed of the
// reference: |Δ| of φ_J, u_J, Z_J; relative error, averaged over the targets, of P, B, G, ω* (B,
// G, ω* from the .moduli.json / .dos.json beside the target packings). φ_2 is a property of the whole
// trajectory (which tagged bud completes last), which a perturbation at any step may switch to
// another branch, tighter settings included: it is judged as an ensemble quantity, by the mean over
// seeds of the signed difference and that mean's resolution of 2 standard errors (budjam/pareto.hpp),
// from 5 seeds or more; with fewer it has no resolution and is not judged (no part in any front).
//
// Post-processing knobs (packing sets NAME=DIR): the moduli's linear solver and ARPACK's tol and ncv,
// measured on every packings/*.pack below DIR (analysis/accuracy_post.hpp).
//
// For every knob the default and that knob's variants form one group; the default is "on the front"
// when no variant dominates it (budjam/pareto.hpp: no more than the cost tie band dearer, no error
// worse beyond a factor error_ratio unless both ≤ error_floor, and better in one of them). The cost
// tie band is time_noise, for a post-processing set widened to 3× its measured timing noise (the
// default is timed twice in the same rounds: row "… (timed again)", knob "repeat"). A knob measured
// on several packing sets is judged on its joint front, and a knob whose default the model fixes is
// reported, not judged.
#include "io/json.hpp"

#include <cstddef>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace budjam::tools {

struct SweepOptions {
  std::string reference;              // folder of the tight reference runs (seed*/); empty: no growth knobs
  std::vector<std::string> variants;  // folders of growth variant runs, named <knob>_<value> or default
  std::vector<std::string> packings;  // post-processing packing sets, NAME=DIR
  std::string growth_set = "growth runs";
  double time_noise = 0.10;   // relative cost difference that is a tie
  double error_ratio = 2.0;   // error factor that is a tie
  double error_floor = 1e-9;  // errors both below this tie
  double min_seconds = 0.2;   // post-processing: CPU time each computation is repeated for
};

// One setting of one knob: its cost and its errors against the reference.
struct SweepRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string family, knob, variant, set, unit;
  bool is_default = false, is_reference = false;
  std::size_t n = 0, failures = 0;
  double seconds = kNaN;  // measured: CPU seconds per run / per computation
  double cost = kNaN;     // what the front compares (seconds; growth: counted work at common rates)
  double wall_seconds = kNaN, force_evaluations = kNaN, newton_factorisations = kNaN;
  std::map<std::string, double> err;      // by quantity; absent = n/a
  std::map<std::string, double> max_err;  // post-processing: the worst packing
  // Ensemble quantities (φ_2): err is |mean over seeds of the signed difference|, and this its
  // resolution, 2 standard errors of that mean (absent with fewer than 5 seeds: not judged).
  std::map<std::string, double> resolution;
  double max_residual = kNaN;
  bool well_posed = true;
  bool on_front = true;  // of its knob (a default: of every knob of its family and set)
};

// The fronts of every knob and what they say about the defaults.
struct SweepVerdict {
  io::Json timing_noise = io::Json::array(), groups = io::Json::array(), joint_groups = io::Json::array();
  bool all_on_front = true;
  std::vector<std::string> off_front;  // "<set>: <knob>" whose default a variant dominates
  std::string noise_md, joint_md;      // Markdown lines for accuracy.md
};

// CPU seconds per force evaluation and per factorisation of the growth runs, fitted to their CPU
// times by least squares (non-negative; per_factorisation = 0 when the runs do not resolve it).
struct GrowthCostRates {
  double per_evaluation = 0, per_factorisation = 0;
};
GrowthCostRates growth_cost_rates(const std::vector<SweepRow>& rows);

// Throws InputError for an inconsistent or empty request.
void check_sweep_options(const SweepOptions& options);
// The growth settings (variants, then the reference) against the reference runs.
std::vector<SweepRow> growth_rows(const SweepOptions& options);
// The post-processing settings of every packing set.
std::vector<SweepRow> post_rows(const SweepOptions& options);
// Judges every knob's front and marks the rows on it.
SweepVerdict judge_fronts(std::vector<SweepRow>& rows, const SweepOptions& options);
// InputError naming --out unless write_accuracy_tables can write in `dir` (io::check_output_directory);
// changes nothing: call it before the measurements.
void check_accuracy_out(const std::filesystem::path& dir);
// DIR/accuracy.csv (one row per setting), DIR/accuracy.json (rows, groups with their fronts, the
// verdict) and DIR/accuracy.md (the table as Markdown).
void write_accuracy_tables(const std::filesystem::path& dir, const SweepOptions& options,
                           const std::vector<SweepRow>& rows, const SweepVerdict& verdict);

}  // namespace budjam::tools
