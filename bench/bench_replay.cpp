// Replay of the trials that cost (docs/speed.md): the marginal relaxations of a run,
// saved once, relaxed again with the current minimiser, so that an idea is measured on exactly the
// relaxations where a run's time goes. Not a test.
//
//   bench_replay record SCENE DIR [--min-evaluations E] [--set section.key=value]...
//     runs SCENE as `budjam grow` would (no output files) and saves every trial whose relaxation
//     cost more than E force evaluations (default 100000, summary.json's marginal relaxations) as
//     DIR/trial-<attempt>-<k>.pack: the packing its relaxation started from, with the trial's Δt,
//     its recorded cost and verdict, and the minimiser parameters of that relaxation in the meta
//     lines (`replay.*`). A trial on the branch of a relaxed state (the bracket's lowest overshoot
//     with the same divisions) also gets DIR/trial-<attempt>-<k>.branch: that relaxed state.
//   bench_replay run SCENE DIR|FILE... [--set section.key=value]...
//     relaxes each saved start with the recorded parameters (to convergence: a trial deferred at its
//     budget is relaxed on) with SCENE's force field, and prints per trial the recorded and the
//     replayed FIRE iterations, force evaluations, Newton factorisations, CPU seconds and E/N, and
//     the side of SCENE's jamming window the replayed E/N lies on (marked * where the recorded E/N
//     lies on another: a changed verdict), then the totals with the number of such trials. With
//     jamming.continuation = true a trial with a .branch file first follows that branch to its
//     sizes (as the growth driver does) and FIRE goes on from where it ended; the continuation's
//     steps, events and how the branch ended are printed too; with
//     jamming.crossing_step > 0 the branch crosses its stability losses by FIRE rearrangements, and
//     their number and force evaluations are printed with it.
//
// The saved starts are exact (round-trip text), so a replay with an unchanged minimiser repeats the
// recorded relaxation evaluation for evaluation (an undeferred trial without saddle relaxation).
#include "budjam/continuation.hpp"
#include "budjam/fire.hpp"
#include "budjam/growth_driver.hpp"
#include "budjam/jamming.hpp"
#include "io/packing_file.hpp"
#include "io/process_memory.hpp"
#include "io/scene_file.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

using namespace budjam;
namespace fs = std::filesystem;

namespace {

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

void usage() {
  std::fprintf(stderr,
               "usage: bench_replay record SCENE DIR [--min-evaluations E] [--set section.key=value]...\n"
               "       bench_replay run SCENE DIR|FILE... [--set section.key=value]...\n");
}

// Saves the start of every trial that cost more than `min_evaluations`.
class Recorder : public Observer {
 public:
  Recorder(fs::path dir, long min_evaluations) : dir_(std::move(dir)), min_(min_evaluations) {}
  std::string name() const override { return "replay_recorder"; }
  Needs needs() const override {
    Needs n;
    n.trial_starts = true;
    return n;
  }
  void on_trial(const TrialRelaxed& t) override {
    if (t.force_evaluations <= min_) return;
    // A deferred trial resumed later is a second row of the same attempt.
    const int k = t.attempt == last_attempt_ ? ++repeat_ : (repeat_ = 0);
    last_attempt_ = t.attempt;
    io::PackingMeta meta;
    meta.set_integer("replay.attempt", t.attempt);
    meta.set_number("replay.dt", t.dt);
    meta.set("replay.start", to_string(t.start));
    meta.set("replay.verdict", to_string(t.verdict));
    meta.set_integer("replay.iterations", t.fire_iterations);
    meta.set_integer("replay.evaluations", t.force_evaluations);
    meta.set_number("replay.E_per_cell", t.E_per_cell);
    meta.set_number("replay.energy_floor", t.minimiser.energy_floor);
    meta.set_number("replay.newton_force", t.minimiser.newton_force);
    meta.set_number("replay.force_tol", t.minimiser.force_tol);
    const fs::path file = dir_ / ("trial-" + std::to_string(t.attempt) + "-" + std::to_string(k) + ".pack");
    io::write_packing(file, *t.start_packing, meta);
    if (t.branch_start) io::write_packing(fs::path(file).replace_extension(".branch"), *t.branch_start, {});
    std::printf("saved %s: dt %.10g  N %zu  phi %.10g  %s  evaluations %ld\n", file.c_str(), t.dt, t.N, t.phi,
                to_string(t.verdict), t.force_evaluations);
    std::fflush(stdout);
    ++saved;
  }
  long saved = 0;

 private:
  fs::path dir_;
  long min_;
  long last_attempt_ = -1;
  int repeat_ = 0;
};

int record(const Scene& scene, const fs::path& dir, long min_evaluations) {
  fs::create_directories(dir);
  GrowthDriver driver(scene);
  Recorder recorder(dir, min_evaluations);
  driver.add_observer(recorder);
  const double c0 = cpu_seconds();
  const RunStatus status = driver.run();
  const RunResult& r = driver.result();
  std::printf("run %s: %ld search trials, %ld marginal relaxations, %ld force evaluations, %.2f CPU s; saved %ld\n",
              to_string(status), r.search_trials, r.marginal_relaxations, r.force_evaluations, cpu_seconds() - c0,
              recorder.saved);
  return status == RunStatus::finished ? 0 : 1;
}

std::vector<fs::path> replay_files(const std::vector<std::string>& args) {
  std::vector<fs::path> files;
  for (const std::string& a : args) {
    if (!fs::is_directory(a)) {
      files.emplace_back(a);
      continue;
    }
    std::vector<fs::path> in_dir;
    for (const auto& e : fs::directory_iterator(a))
      if (e.path().extension() == ".pack") in_dir.push_back(e.path());
    std::sort(in_dir.begin(), in_dir.end());
    files.insert(files.end(), in_dir.begin(), in_dir.end());
  }
  return files;
}

int replay(const Scene& scene, const std::vector<fs::path>& files) {
  std::printf("%-28s %8s %6s %10s %10s %10s %10s %7s %9s %11s %11s %7s\n", "trial", "verdict", "N", "rec_iter",
              "rec_eval", "iter", "eval", "factor", "cpu_s", "rec_E/N", "E/N", "side");
  long rec_evals = 0, evals = 0, factorisations = 0, sides_changed = 0;
  const JammingWindow window = jamming_window(scene);
  double cpu = 0;
  for (const fs::path& file : files) {
    io::PackingFile pf = io::read_packing(file);
    FireParams params = scene.fire;
    params.energy_floor = pf.meta.number("replay.energy_floor");
    params.newton_force = pf.meta.number("replay.newton_force");
    params.force_tol = pf.meta.number("replay.force_tol");
    ForceField field(scene.skin, scene.threads);
    const fs::path branch_file = fs::path(file).replace_extension(".branch");
    const bool follow = scene.continuation && fs::exists(branch_file);
    const Packing branch = follow ? io::read_packing(branch_file).packing : Packing{};
    const double c0 = cpu_seconds();
    ContinuationResult cr;
    if (follow) {
      ContinuationParams cp;
      cp.energy_floor = params.energy_floor * static_cast<double>(pf.packing.size());
      if (scene.crossing_step > 0) {
        cp.rearrangement = params;
        cp.crossing_step = scene.crossing_step;
      }
      cr = start_on_branch(pf.packing, branch, field, cp);
    }
    const FireResult fr = minimise(pf.packing, field, params);
    const double c = cpu_seconds() - c0;
    if (follow)
      std::printf(
          "  branch: %s at t = %.6g, %ld steps (%ld halved), %zu events, %ld factorisations, %ld chord steps, "
          "%ld evaluations, %ld rearrangements (%ld evaluations), E/N there %.4e\n",
          to_string(cr.end), cr.t, cr.steps, cr.rejected_steps, cr.events.size(), cr.factorisations, cr.chord_steps,
          cr.evaluations, cr.rearrangements, cr.rearrangement_evaluations,
          cr.energy / static_cast<double>(pf.packing.size()));
    if (fr.active_set_steps > 0)
      std::printf("  active set: %ld steps, %ld factorisations, %ld rank-1 updates, %ld tries undone\n",
                  fr.active_set_steps, fr.active_set_factorisations, fr.active_set_updates, fr.active_set_tries_undone);
    const long factored = fr.newton_iterations + fr.active_set_factorisations + cr.factorisations;
    const double n = static_cast<double>(pf.packing.size());
    // The side of the scene's window that each E/N lies on: a change is a changed verdict, the
    // trial's run would have gone on along another path.
    const double rec_E = pf.meta.number("replay.E_per_cell");
    const WindowSide side = window.side(fr.energy / n);
    const bool changed = side != window.side(rec_E);
    sides_changed += changed;
    std::printf("%-28s %8s %6zu %10lld %10lld %10ld %10ld %7ld %9.3f %11.4e %11.4e %6s%s\n", file.filename().c_str(),
                pf.meta.get("replay.verdict").value_or("?").c_str(), pf.packing.size(),
                static_cast<long long>(pf.meta.integer("replay.iterations")),
                static_cast<long long>(pf.meta.integer("replay.evaluations")), fr.iterations,
                fr.evaluations + cr.evaluations, factored, c, rec_E, fr.energy / n, to_string(side),
                changed ? "*" : " ");
    std::fflush(stdout);
    rec_evals += pf.meta.integer("replay.evaluations");
    evals += fr.evaluations + cr.evaluations;
    factorisations += factored;
    cpu += c;
  }
  std::printf(
      "total: %zu trials, recorded evaluations %ld, replayed evaluations %ld, factorisations %ld, CPU %.3f s, "
      "window side changed in %ld\n",
      files.size(), rec_evals, evals, factorisations, cpu, sides_changed);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  if (argc < 4) {
    usage();
    return 2;
  }
  const std::string mode = argv[1], scene_file = argv[2];
  std::vector<std::string> overrides, rest;
  long min_evaluations = kMarginalEvaluations;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--set" || a == "--min-evaluations") && i + 1 >= argc) {
      usage();
      return 2;
    }
    if (a == "--set")
      overrides.push_back(argv[++i]);
    else if (a == "--min-evaluations")
      min_evaluations = std::atol(argv[++i]);
    else
      rest.push_back(a);
  }
  if ((mode != "record" && mode != "run") || rest.empty() || (mode == "record" && rest.size() != 1)) {
    usage();
    return 2;
  }
  try {
    Scene scene = io::load_scene(scene_file, overrides);
    scene.progress = false;
    return mode == "record" ? record(scene, rest[0], min_evaluations) : replay(scene, replay_files(rest));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_replay: %s\n", e.what());
    return 2;
  }
}
