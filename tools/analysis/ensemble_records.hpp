#pragma once
// The in-memory records of an ensemble analysis: one row per jammed run with its Δφ targets, one per
// spectrum, and the pooled survival of each (L, P0) group. Two readers fill them, from finished run
// directories (ensemble_analysis.cpp) and from the tables an earlier analysis wrote
// (ensemble_tables.hpp); the estimators see no difference. The column lists name each record field
// in runs.csv and targets.csv, for the writer and the tables reader alike.
#include "budjam/scene.hpp"
#include "budjam/statistics.hpp"
#include "budjam/survival.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace budjam::tools {

struct TargetRow {
  double dphi = kNaN, phi = kNaN, P = kNaN, Z = kNaN, dZ = kNaN, Z_iso = kNaN, u = kNaN, u_lobes = kNaN;
  double chi_c = kNaN, lambda = kNaN, B_grow = kNaN, B_grow_se = kNaN, N_div = kNaN, N_nr = kNaN;
  double dZ_pred = kNaN;     // ΔZ_0(P) + 2(u_J − u), filled once the branch is known
  double dZ_pred_se = kNaN;  // the SE of ΔZ_0(P) there (the branch's, common to every run)
  // The same as the paper's analysis computes it: ΔZ_0(P) through the no-feedback targets alone,
  // u_J the buds tagged at jamming over this target's N_nr, u the contact-free lobes.
  double dZ_pred_paper = kNaN;
  double B = kNaN, G = kNaN, G_energy = kNaN, B_ext_mf = kNaN;  // from the moduli sidecar
  double G_min = kNaN;  // softest simple shear of the box (moduli sidecar "shear_stability"); < 0: unstable
  bool below_phi2 = false;
};

// φ_2 is the first state after jamming with at most kBudjamTaggedLeft tagged buds still unconstrained
// (ε ~ 1/N_nr,J), in budjam and in the paper's analysis alike; the paper's division figure alone counts
// the divisions up to the first state with none left (docs/analysis.md, "Definitions").
inline constexpr double kBudjamTaggedLeft = 1, kNoneLeft = 0;

struct RunRow {
  std::filesystem::path dir;
  double L = kNaN;
  std::optional<double> P0;
  std::string P0_label;
  std::uint64_t seed = 0;
  std::string status;
  std::size_t state = 0;  // distinct jamming state (jamming_states.hpp)
  // The run's protocol within its group and its cell parameters (run_protocol.hpp, protocol_hash);
  // empty where tables from before those columns do not say.
  std::string protocol, cells, jamming_model;
  bool depleted = false;
  double step_J = kNaN, phi_J = kNaN, u_J = kNaN, n_J = kNaN, N_J = kNaN, N_nr_J = kNaN, Z_J = kNaN, dZ_J = kNaN,
         P_J = kNaN;
  double u_J_lobes = kNaN;  // contact-free lobes, mothers included, over N_nr (reported beside u_J, the buds)
  double tagged = kNaN, lc2_J = kNaN;
  double phi_2 = kNaN, dphi_2 = kNaN, P_2 = kNaN, Z_2 = kNaN, dZ_2 = kNaN, u_2 = kNaN, N_div_2 = kNaN;
  // χ̄ and λ̄_c: plain means over the accepted states of [φ_J, φ_2] (Eq. 13 averages over a)
  double chi_bar = kNaN, lambda_bar = kNaN;
  // λ̄_c with u the contact-free lobes, as the paper's analysis reads u, over the states of
  // [first φ_J, φ_2_first] that have non-rattlers
  double lambda_bar_lobes = kNaN;
  // The paper's analysis anchors at the run's first jamming (a run that unjammed has a later one,
  // budjam's φ_J): φ_J, N_J, N_nr and the buds tagged there, and its φ_2 scan runs through every
  // later state, the unjammed ones included, which follow those tags until a new jamming tags
  // others (docs/analysis.md, "Definitions"). Equal to budjam's where the run never unjammed; NaN
  // where its logs are from before the tags were followed through an unjamming.
  double step_J_first = kNaN, phi_J_first = kNaN, N_J_first = kNaN, N_nr_J_first = kNaN, tagged_J_first = kNaN;
  double phi_2_first = kNaN, dphi_2_first = kNaN, P_2_first = kNaN, chi_bar_first = kNaN;
  double G_2_first = kNaN;  // where the run saved that state (packings/phi2.pack)
  // The paper's selection: the fewest divisions (from the episode's jamming) at the end of a target
  // run that reached phi_2_first, each target a run of its own ending where the trajectory first lands
  // on it; NaN where none did. Admitted with at most kPaperMaxDivisions.
  double selection_divisions_first = kNaN;
  // From the first jamming as well: the first state with no tagged bud left, its φ, P and the
  // divisions after the first φ_J up to it (the paper's division figure)
  double phi_2_none_left = kNaN, dphi_2_none_left = kNaN, P_2_none_left = kNaN, N_div_2_none_left = kNaN;
  double N_div_end = kNaN;  // divisions after φ_J at the end of the run
  // The definition of the φ_2 the run saved (packings/phi2.pack, summary.json phi_2): at most this
  // many tagged buds left (jamming.phi2_tagged_left; 1 in runs from before that key). The other
  // definition's φ_2 comes from steps.csv, without a packing.
  double phi2_tagged_left = kBudjamTaggedLeft;
  double a_eps = kNaN, int_S = kNaN, pred_area = kNaN, pred_d2 = kNaN;  // per-run KM, ε = 1/N_nr,J
  // Eq. 14 as the paper's analysis computes it: a as diameter², a_ε the first completion with Ŝ ≤
  // 1/tagged in floating point, no slack (so an exact level such as 1/5 can step one completion on);
  // φ_J, n_J, u_J, the level's tagged count and χ̄ from the first jamming, Ŝ of the last episode's
  // tags (its code keeps one cohort file, rewritten at each jamming)
  double pred_paper = kNaN;
  double G_2 = kNaN, G_2_energy = kNaN, B_2 = kNaN, G_min_2 = kNaN;  // at budjam's φ_2, if saved there
  double G_2_none_left = kNaN;  // at the first state with none left (from the first jamming), where the run saved it
  double h_gamma = kNaN;
  // As the paper's analysis takes Π(g): every cell, rattlers included, at Δφ = 3·10⁻³; the fraction
  // growing at g = 1 exactly (no bud pressure) is the weight of its spike.
  double h_gamma_all_cells = kNaN, g1_fraction_all_cells = kNaN;
  // The records the run gave the pooled survival of its group: NaN where it recorded no bud events
  // (observe.bud_events off), and so contributed no run to that pool.
  double bud_records = kNaN;
  double target_rows = kNaN;  // the targets the run landed: its rows of targets.csv
  std::vector<double> g;      // growth factors of the non-rattler cells at Δφ = 3·10⁻³
  std::vector<SurvivalRecord> survival;
  std::vector<TargetRow> targets;
  // curves on the Δφ grid
  std::vector<double> remaining;  // tagged_active / tagged (NaN beyond the run)
  std::vector<double> divisions;  // cumulative divisions after φ_J
};

struct DosRow {
  std::string run, packing;
  double L = kNaN;
  std::string P0_label;
  double dphi = kNaN, omega_star = kNaN, dZ = kNaN, Z = kNaN, N_zero = kNaN, N_u = kNaN, N_u_buds = kNaN;
  long N_c = 0, N_nr = 0;  // integer counts: the sign of ΔZ without rounding
  std::size_t state = 0;   // the run's jamming state (a jammed packing is shared by its runs)
  std::uint64_t seed = 0;  // the run's seed: its runs at every P0 share their start (one sample)
  bool target = false;     // a Δφ-target packing (the paper's ω* figure uses only these)
};

// The P0 column of the tables is empty for no feedback (tables of earlier versions say "none");
// in memory a group's label is "none" or the number's text, as analysis.json "P0_label" has it.
inline std::string P0_csv(const std::string& label) { return label == "none" ? std::string() : label; }
inline std::string P0_label_from_csv(const std::string& field) { return field.empty() ? "none" : field; }

struct GroupKey {
  double L;
  std::optional<double> P0;
  bool operator<(const GroupKey& o) const {
    if (L != o.L) return L < o.L;
    // none first, then decreasing P0 (weak → strong feedback), as in the paper's figures
    if (P0.has_value() != o.P0.has_value()) return !P0.has_value();
    return P0 && *P0 > *o.P0;
  }
};

struct ModuliFiles {
  std::size_t found = 0;
  std::size_t saddles = 0;  // "energy_minimum": false — no relaxed B, G (NaN here, left out of every statistic)
  std::size_t contact_bounded = 0;  // minima held by a pair at zero force: no relaxed B, G either (saddle.hpp)
};

struct Ensemble {
  std::vector<RunRow> rows;
  std::vector<DosRow> dos_rows;
  std::vector<std::string> failed;                   // jammed runs that stopped early, with their status
  std::vector<std::string> never_jammed;             // runs that never jammed, with their status
  std::vector<std::vector<std::string>> duplicates;  // copies of one run: the used one first
  ModuliFiles moduli;
  std::size_t dos_found = 0;
  std::size_t runs = 0;
  std::map<GroupKey, KaplanMeierCurve> survival;  // pooled over the runs of each group
  // How many runs each pooled curve pools (those that recorded bud events); absent where tables from
  // before survival.csv's `runs` column do not say.
  std::map<GroupKey, std::size_t> survival_runs;
  // One line each on what the inputs did not allow to be checked (tables of an earlier format), for
  // stderr and analysis.json "inputs.unchecked".
  std::vector<std::string> unchecked;
  // The cell parameters and initial state the runs were grown with (the scene defaults, which are the
  // paper's, for tables: they record none).
  Scene growth_scene;
  // What the inputs could not give, with the reason: quantity → "needs …" (the tables hold less
  // than the run directories). Empty for run directories.
  std::map<std::string, std::string> unavailable;
};

// A number of a record under its column name in runs.csv / targets.csv; `legacy` is the name tables
// of earlier versions gave the same number.
struct RunColumn {
  // `source` is required: what the column is computed from, for the account of a column that tables
  // of an earlier format lack.
  constexpr RunColumn(const char* name, double RunRow::*field, const char* source, const char* legacy = nullptr)
      : name(name), field(field), source(source), legacy(legacy) {}
  const char* name;
  double RunRow::*field;
  const char* source;
  const char* legacy;
};
inline constexpr const char kSummary[] = "summary.json";
inline constexpr const char kSteps[] = "steps.csv";
inline constexpr const char kBudEvents[] = "bud_events.csv";
inline constexpr const char kModuliAtPhi2[] = "the moduli at φ_2";
inline constexpr const char kGrowthFactors[] = "the growth factor of each cell at Δφ = 3·10⁻³";
inline constexpr const char kJammedPacking[] = "the jammed packing";
struct TargetColumn {
  const char* name;
  double TargetRow::*field;
};

// runs.csv after its leading columns run, L, P0, seed, status, jamming_state, protocol, cells.
inline constexpr RunColumn kRunColumns[] = {{"phi_J", &RunRow::phi_J, kSummary},
                                            {"u_J", &RunRow::u_J, kSummary},
                                            {"u_J_lobes", &RunRow::u_J_lobes, kSummary},
                                            {"n_J", &RunRow::n_J, kSummary},
                                            {"N_J", &RunRow::N_J, kSummary},
                                            {"N_nr_J", &RunRow::N_nr_J, kSummary},
                                            {"Z_J", &RunRow::Z_J, kSummary},
                                            {"dZ_J", &RunRow::dZ_J, kSummary},
                                            {"phi_2", &RunRow::phi_2, kSummary},
                                            {"dphi_2", &RunRow::dphi_2, kSummary},
                                            {"P_2", &RunRow::P_2, kSummary},
                                            {"Z_2", &RunRow::Z_2, kSummary},
                                            {"dZ_2", &RunRow::dZ_2, kSummary},
                                            {"u_2", &RunRow::u_2, kSteps},
                                            {"N_div_2", &RunRow::N_div_2, kSummary},
                                            {"chi_bar", &RunRow::chi_bar, kSteps},
                                            {"lambda_bar", &RunRow::lambda_bar, kSteps},
                                            {"lambda_bar_lobes", &RunRow::lambda_bar_lobes, kSteps},
                                            {"phi_2_none_left", &RunRow::phi_2_none_left, kSteps, "phi_2_paper"},
                                            {"dphi_2_none_left", &RunRow::dphi_2_none_left, kSteps, "dphi_2_paper"},
                                            {"P_2_none_left", &RunRow::P_2_none_left, kSteps, "P_2_paper"},
                                            {"N_div_2_none_left", &RunRow::N_div_2_none_left, kSteps, "N_div_2_paper"},
                                            {"N_div_end", &RunRow::N_div_end, kSteps},
                                            {"phi_2_tagged_left", &RunRow::phi2_tagged_left, kSummary},
                                            {"a_eps", &RunRow::a_eps, kBudEvents},
                                            {"integral_S", &RunRow::int_S, kBudEvents},
                                            {"dphi_2_pred_area", &RunRow::pred_area, kBudEvents},
                                            {"dphi_2_pred_diameter_sq", &RunRow::pred_d2, kBudEvents},
                                            {"dphi_2_pred_paper", &RunRow::pred_paper, kBudEvents},
                                            {"B_2", &RunRow::B_2, kModuliAtPhi2},
                                            {"G_2", &RunRow::G_2, kModuliAtPhi2},
                                            {"G_2_energy", &RunRow::G_2_energy, kModuliAtPhi2},
                                            {"G_min_2", &RunRow::G_min_2, kModuliAtPhi2},
                                            {"G_2_none_left", &RunRow::G_2_none_left, kModuliAtPhi2, "G_2_paper"},
                                            {"h_gamma", &RunRow::h_gamma, kGrowthFactors},
                                            {"h_gamma_all_cells", &RunRow::h_gamma_all_cells, kGrowthFactors},
                                            {"g1_fraction_all_cells", &RunRow::g1_fraction_all_cells, kGrowthFactors},
                                            {"lc2_J", &RunRow::lc2_J, kJammedPacking},
                                            {"P_J", &RunRow::P_J, kSummary},
                                            {"step_J", &RunRow::step_J, kSummary},
                                            {"tagged_J", &RunRow::tagged, kSummary},
                                            {"step_J_first", &RunRow::step_J_first, kSteps},
                                            {"phi_J_first", &RunRow::phi_J_first, kSteps},
                                            {"N_J_first", &RunRow::N_J_first, kSteps},
                                            {"N_nr_J_first", &RunRow::N_nr_J_first, kSteps},
                                            {"tagged_J_first", &RunRow::tagged_J_first, kSteps},
                                            {"phi_2_first", &RunRow::phi_2_first, kSteps},
                                            {"dphi_2_first", &RunRow::dphi_2_first, kSteps},
                                            {"P_2_first", &RunRow::P_2_first, kSteps},
                                            {"chi_bar_first", &RunRow::chi_bar_first, kSteps},
                                            {"G_2_first", &RunRow::G_2_first, kModuliAtPhi2},
                                            {"selection_divisions_first", &RunRow::selection_divisions_first, kSteps},
                                            {"bud_records", &RunRow::bud_records, kBudEvents},
                                            {"target_rows", &RunRow::target_rows, kSummary}};

// targets.csv after its leading columns run, L, P0, seed, dphi; below_phi2 follows.
inline constexpr TargetColumn kTargetColumns[] = {{"phi", &TargetRow::phi},
                                                  {"P", &TargetRow::P},
                                                  {"Z", &TargetRow::Z},
                                                  {"Z_iso", &TargetRow::Z_iso},
                                                  {"dZ", &TargetRow::dZ},
                                                  {"dZ_pred", &TargetRow::dZ_pred},
                                                  {"u", &TargetRow::u},
                                                  {"u_lobes", &TargetRow::u_lobes},
                                                  {"chi_c", &TargetRow::chi_c},
                                                  {"lambda_c", &TargetRow::lambda},
                                                  {"B_grow", &TargetRow::B_grow},
                                                  {"B_grow_se", &TargetRow::B_grow_se},
                                                  {"B", &TargetRow::B},
                                                  {"G", &TargetRow::G},
                                                  {"G_energy", &TargetRow::G_energy},
                                                  {"G_min", &TargetRow::G_min},
                                                  {"B_ext_mean_field", &TargetRow::B_ext_mf},
                                                  {"N_div", &TargetRow::N_div},
                                                  {"N_nr", &TargetRow::N_nr}};

}  // namespace budjam::tools
