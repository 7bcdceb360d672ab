#include "observers/run_outputs.hpp"

#include "budjam/blas_threads.hpp"
#include "io/packing_file.hpp"
#include "io/text.hpp"
#include "observers/observers.hpp"

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <istream>
#include <ostream>
#include <stdexcept>

namespace budjam::tools {

namespace fs = std::filesystem;
using io::CsvField;
using io::Json;
namespace run_files = io::run_files;

// ---- RunLog -------------------------------------------------------------------------------------

const std::vector<std::string>& RunLog::step_columns() {
  static const std::vector<std::string> c{"step",
                                          "attempts",
                                          "dt",
                                          "N",
                                          "phi",
                                          "P",
                                          "E_per_cell",
                                          "phase",
                                          "N_c",
                                          "N_f",
                                          "N_f_single",
                                          "N_u",
                                          "N_u_buds",
                                          "Z",
                                          "Z_iso",
                                          "dZ",
                                          "chi_c",
                                          "compressed_buds",
                                          "tagged_active",
                                          "tagged_completed",
                                          "tagged_divided",
                                          "divisions_since_jamming"};
  return c;
}

const std::vector<std::string>& RunLog::division_columns() {
  static const std::vector<std::string> c{"step",      "phi",         "phase",        "N",
                                          "mother_id", "daughter_id", "mother_index", "daughter_index",
                                          "x",         "y",           "theta",        "b"};
  return c;
}

RunLog::RunLog(io::RunDirectory& run_dir, std::uint64_t seed, bool resuming)
    : CsvLogObserver(
          run_dir.root(),
          {{std::string(run_files::steps), step_columns()}, {std::string(run_files::divisions), division_columns()}},
          resuming),
      run_dir_(run_dir),
      seed_(seed) {
  if (!resuming) packings();  // every run directory has packings/, also one that never jams
}

void RunLog::on_resumed() {
  run_dir_.remove_recorded_temporaries();
  CsvLogObserver::on_resumed();
}

io::OwnedEntries RunLog::files() {
  io::OwnedEntries out{std::string(run_files::steps), std::string(run_files::divisions)};
  for (const std::string_view stem : {run_files::jammed, run_files::phi2, std::string_view("target_#")})
    for (auto& e : run_files::entries_with_suffixes(run_files::packings, stem, run_files::packing_suffixes()))
      out.push_back(std::move(e));
  return out;
}

io::OwnedEntries run_owned_entries() {
  io::OwnedEntries out{std::string(run_files::scene), std::string(run_files::checkpoint),
                       std::string(run_files::summary), std::string(run_files::timing)};
  for (auto& f : RunLog::files()) out.push_back(std::move(f));
  for (auto& f : declared_observer_files()) out.push_back(std::move(f));
  return out;
}

void RunLog::on_step_accepted(const StepAccepted& e) {
  const StateView& s = e.state;
  // From the first jamming on (unjammed states after it included) the network, χ_c and the tags.
  const bool above = s.after_jamming && s.network;
  const ContactNetwork* n = s.network;
  auto opt = [&](auto v) { return above ? CsvField(v) : CsvField::missing(); };
  log(kSteps).row({s.step,
                   s.attempts,
                   beyond_double_range(s.dt, s.log_dt),
                   s.packing->size(),
                   s.phi,
                   s.P,
                   s.E_per_cell,
                   to_string(s.phase),
                   above ? CsvField(n->N_c) : CsvField::missing(),
                   above ? CsvField(n->N_f) : CsvField::missing(),
                   above ? CsvField(n->N_f_single_pass) : CsvField::missing(),
                   above ? CsvField(n->N_u) : CsvField::missing(),
                   above ? CsvField(n->N_u_buds) : CsvField::missing(),
                   above ? CsvField(n->Z) : CsvField::missing(),
                   above ? CsvField(n->Z_iso) : CsvField::missing(),
                   above ? CsvField(n->dZ) : CsvField::missing(),
                   above ? beyond_double_range(s.chi_c, s.log_chi_c) : CsvField::missing(),
                   opt(s.compressed_buds),
                   opt(s.buds->active()),
                   opt(s.buds->completed()),
                   opt(s.buds->divided()),
                   s.phase == Phase::jammed ? CsvField(s.divisions_since_jamming) : CsvField::missing()});
}

void RunLog::on_divided(const Divided& e) {
  const Division& d = e.division;
  log(kDivisions)
      .row({e.state.step, e.state.phi, to_string(e.state.phase), e.state.packing->size(), d.mother_id, d.daughter_id,
            d.mother_index, d.daughter_index, d.x, d.y, d.theta, d.b});
}

void RunLog::write_pack(const std::string& stem, const StateView& s, const std::string& kind,
                        std::optional<double> dphi) {
  io::write_packing(packings(), stem + ".pack", *s.packing, io::state_meta(s, kind, seed_, dphi));
}

void RunLog::on_unjammed(const Unjammed&) {
  // The jamming point, the targets and φ_2 of the lost episode are void (summary.json drops
  // them too); they are written again when reached in the next episode.
  const io::Directory dir = packings();
  for (const std::string& name : dir.names()) {
    const fs::path p(name);
    const auto st = dir.entry(name);
    if (st && S_ISREG(st->st_mode) && p.extension() == ".pack" && run_files::is_run_packing_stem(p.stem().string()))
      dir.remove(name);
  }
}

void RunLog::on_jammed(const Jammed& e) { write_pack(std::string(run_files::jammed), e.state, "jammed", std::nullopt); }
void RunLog::on_depleted(const Depleted& e) { write_pack(std::string(run_files::phi2), e.state, "phi2", std::nullopt); }
void RunLog::on_target_reached(const TargetReached& e) {
  write_pack(run_files::target_stem(e.target.index), e.state, "target", e.target.dphi);
}

io::StepsLog RunLog::resumed_steps() const { return io::read_steps(resumed_text(kSteps), resumed_file(kSteps)); }

void RunLog::check_resumed_state(const GrowthState& s, const Scene& scene, const io::CheckpointLines& at,
                                 const std::string& checkpoint_file) const {
  const io::Directory& root = run_dir_.root();
  if (!root.entry(run_files::packings)) {
    if (s.result.jamming)
      throw InputError(io::escape_control(checkpoint_file + ":" + std::to_string(at.jamming) +
                                          ": the record has no saved packing (no packings/ directory)"));
    // Without records no packing is read: the run directory stands in for packings/.
    io::check_against_run(s, scene, at, checkpoint_file, resumed_cut(kSteps), resumed_steps(), resumed_cut(kDivisions),
                          root);
    return;
  }
  io::check_against_run(s, scene, at, checkpoint_file, resumed_cut(kSteps), resumed_steps(), resumed_cut(kDivisions),
                        root.subdirectory(run_files::packings, false));
}

// ---- summary.json --------------------------------------------------------------------------------

Json summary_json(const GrowthDriver& driver) {
  const RunResult& r = driver.result();
  const Scene& sc = driver.scene();
  const StateView now = driver.view();
  Json j;
  j["format"] = "budjam-summary";
  j["version"] = run_files::summary_version;
  j["status"] = to_string(r.status);
  j["message"] = r.message;
  j["scene"] = sc.name;
  j["seed"] = driver.seed();
  j["blas"] = blas_library();  // the bits of every factorisation depend on it (docs/speed.md)
  j["L"] = sc.L;
  j["P0"] = sc.P0 ? Json(*sc.P0) : Json(nullptr);
  const auto& J = r.jamming;
  auto jv = [&](auto get) { return J ? Json(get(*J)) : Json(nullptr); };
  j["N_J"] = jv([](const JammingRecord& x) { return x.network.N; });
  j["phi_J"] = jv([](const JammingRecord& x) { return x.phi; });
  j["P_J"] = jv([](const JammingRecord& x) { return x.P; });
  j["E_J"] = jv([](const JammingRecord& x) { return x.E_per_cell; });
  j["Z_J"] = jv([](const JammingRecord& x) { return x.network.Z; });
  j["Z_iso_J"] = jv([](const JammingRecord& x) { return x.network.Z_iso; });
  j["dZ_J"] = jv([](const JammingRecord& x) { return x.network.dZ; });
  j["u_J"] = jv([](const JammingRecord& x) { return x.network.u_buds; });
  j["u_J_lobes"] = jv([](const JammingRecord& x) { return x.network.u; });
  j["n_J"] = jv([](const JammingRecord& x) { return x.n_J; });
  j["N_nr_J"] = jv([](const JammingRecord& x) { return x.network.N_nr; });
  j["N_f_J"] = jv([](const JammingRecord& x) { return x.network.N_f; });
  j["tagged_J"] = jv([](const JammingRecord& x) { return x.tagged; });
  j["step_J"] = jv([](const JammingRecord& x) { return x.step; });
  j["jamming_episode"] = jv([](const JammingRecord& x) { return x.episode; });
  const auto& D = r.depletion;
  j["phi_2"] = D ? Json(D->phi) : Json(nullptr);
  j["P_2"] = D ? Json(D->P) : Json(nullptr);
  j["N_2"] = D ? Json(D->network.N) : Json(nullptr);
  j["Z_2"] = D ? Json(D->network.Z) : Json(nullptr);
  j["dZ_2"] = D ? Json(D->network.dZ) : Json(nullptr);
  j["N_div_2"] = D ? Json(D->divisions_since_jamming) : Json(nullptr);
  j["step_2"] = D ? Json(D->step) : Json(nullptr);
  j["phi_2_tagged_left"] = sc.phi2_tagged_left;  // the definition of φ_2: at most this many tagged buds left
  Json targets = Json::array();
  for (const TargetRecord& t : r.targets) {
    Json x;
    x["index"] = t.index;
    x["dphi"] = t.dphi;
    x["phi"] = t.phi;
    x["phi_target"] = t.phi_target;
    x["P"] = t.P;
    x["E_per_cell"] = t.E_per_cell;
    const NetworkSummary& n = t.network;
    x["N"] = n.N;
    x["N_nr"] = n.N_nr;
    x["Z"] = n.Z;
    x["u"] = n.u;
    x["u_buds"] = n.u_buds;
    x["Z_iso"] = n.Z_iso;
    x["dZ"] = n.dZ;
    x["N_c"] = n.N_c;
    x["N_u"] = n.N_u;
    x["N_u_buds"] = n.N_u_buds;
    x["N_f"] = n.N_f;
    x["N_f_single"] = n.N_f_single_pass;
    x["chi_c"] = t.chi_c;
    x["N_div"] = t.divisions_since_jamming;
    x["step"] = t.step;
    targets.push_back(x);
  }
  j["targets"] = targets;
  Json unj = Json::array();
  for (const UnjamRecord& u : r.unjammings)
    unj.push_back(Json{{"episode", u.episode},
                       {"step", u.step},
                       {"phi", u.phi},
                       {"phi_J", u.phi_J},
                       {"targets_lost", u.targets_lost}});
  j["unjammings"] = unj;
  j["final"] = Json{
      {"step", now.step}, {"phase", to_string(now.phase)}, {"phi", now.phi}, {"P", now.P}, {"N", now.packing->size()}};
  j["accepted_steps"] = r.accepted;
  j["rejected_steps"] = r.rejected;
  j["divisions"] = r.divisions;
  j["force_evaluations"] = r.force_evaluations;
  j["fire_iterations"] = r.fire_iterations;
  j["saddles_relaxed"] = r.saddles_relaxed;
  j["saddle_escapes"] = r.saddle_escapes;
  j["search_trials"] = r.search_trials;
  j["marginal_relaxations"] = r.marginal_relaxations;
  j["newton_factorisations"] = r.newton_factorisations;
  j["newton_factor_reuses"] = r.newton_factor_reuses;
  j["active_set_steps"] = r.active_set_steps;
  j["active_set_factorisations"] = r.active_set_factorisations;
  j["active_set_updates"] = r.active_set_updates;
  j["force_evaluations_initial"] = r.force_evaluations_initial;
  j["force_evaluations_search"] = r.force_evaluations_search;
  j["force_evaluations_above_jamming"] = r.force_evaluations_above_jamming;
  j["branches"] = r.branches;
  j["branches_reached"] = r.branches_reached;
  j["branch_stability_losses"] = r.branch_stability_losses;
  j["branch_rearrangements"] = r.branch_rearrangements;
  j["branch_steps"] = r.branch_steps;
  j["branch_events"] = r.branch_events;
  return j;
}

void write_summary(const io::Directory& run_dir, const GrowthDriver& driver, const SessionTiming& timing) {
  const RunResult& r = driver.result();
  const long evals = r.force_evaluations - timing.force_evaluations_at_start;
  const long attempts = driver.view().attempts - timing.attempts_at_start;
  Json t;
  t["note"] = "not deterministic; this session only (a resumed run counts from the resume)";
  t["wall_seconds"] = timing.wall_seconds;
  t["growth_steps"] = attempts;
  t["growth_steps_per_second"] = timing.wall_seconds > 0 ? attempts / timing.wall_seconds : 0.0;
  t["force_evaluations"] = evals;
  t["force_evaluations_per_second"] = timing.wall_seconds > 0 ? evals / timing.wall_seconds : 0.0;
  t["final_N"] = driver.packing().size();
  io::write_json(run_dir, run_files::timing, t);
  io::write_json(run_dir, run_files::summary, summary_json(driver));  // last: marks the run complete
}

}  // namespace budjam::tools
