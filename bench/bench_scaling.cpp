// Scaling of whole growth runs with the number of cells (docs/speed.md).
// Not a test: prints one summary line per run (and, optionally, one CSV row per growth attempt).
//
//   bench_scaling [options] [--set section.key=value]...
//     --scene FILE          base scene (default data/scenes/paper-L15.toml: P0 = 1e-3, seed 1)
//     --L X                 box side (sets box.L)
//     --seeds K             init.kind = "random_seeds" with K newborn cells (default: the scene's
//                           init, i.e. the paper's two-cell start)
//     --targets LIST        jamming.targets (default [1e-3, 1e-2]); the run stops after the last
//                           (jamming.continue_to_phi2 = false, no checkpoints)
//     --max-attempts M      stop after M growth attempts (accepted + rejected) even if unfinished:
//                           a deterministic window for boxes too large to grow to the end
//     --stop-after-rejections R
//                           stop after the R-th rejected trial (a deterministic window that ends
//                           inside the bisection onto φ_J, for boxes too large to bisect to the end)
//     --report-every S      print a window line every S accepted steps (0 = never; default 0)
//     --csv FILE            one row per growth attempt (counters, N, φ, P, E/N of the accepted
//                           state, CPU, wall, and the attempt's own trial: Δt, N, φ, E/N, where its
//                           relaxation started, its verdict, FIRE iterations), flushed per row so
//                           that long runs can be watched
//
// Tables and log–log fits over sizes: scripts/scaling_fit.py DIR/NAME.csv ... (reads NAME.csv and
// this program's standard output saved as NAME.txt); the measured set is in data/reference/scaling/.
//
// Measure one size per process (`for L in 8 15 20 40; do nice -n 5 build/bench_scaling --L $L; done`)
// so that the peak RSS (getrusage ru_maxrss) belongs to that size. The run goes through
// GrowthDriver exactly as `budjam grow` does, without the observers that write files (logs,
// packings); the counters (accepted, rejected, force evaluations) equal summary.json's.
//
// Cost is split by stage of the run:
//   approach  accepted steps before the first rejected trial (unjammed, every step accepted)
//   bisect    from the first rejected trial to the jamming state (bisection onto φ_J; includes
//             unjammed steps accepted in between, and the search for φ_J anew after an unjamming)
//   above     attempts made while a jamming point is known (landing on the targets)
// CPU time is this process's (CLOCK_PROCESS_CPUTIME_ID): the machine is shared, so wall time
// over-states the cost.
#include "budjam/growth_driver.hpp"
#include "io/process_memory.hpp"
#include "io/scene_file.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

using namespace budjam;
using Clock = std::chrono::steady_clock;

namespace {

// The trial of the latest attempt, for its CSV row.
struct TrialLog : Observer {
  std::optional<TrialRelaxed> last;
  std::string name() const override { return "trial_log"; }
  void on_trial(const TrialRelaxed& t) override { last = t; }
};

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

long peak_rss_kib() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;  // KiB on Linux
}

// Counters of one stage of the run.
struct Stage {
  long accepted = 0, rejected = 0, evals = 0;
  double cpu = 0, wall = 0;
  double cell_evals = 0;  // Σ over attempts of (force evaluations × N after the attempt)
  void add(long acc, long rej, long ev, double c, double w, double n) {
    accepted += acc, rejected += rej, evals += ev, cpu += c, wall += w, cell_evals += static_cast<double>(ev) * n;
  }
  void print(const char* name) const {
    const double a = accepted > 0 ? static_cast<double>(accepted) : 1.0;
    std::printf(
        "  %-8s accepted %6ld  rejected %5ld  evals %10ld  evals/acc %9.1f  cpu %9.2f s  cpu/acc %9.5f s  "
        "wall %9.2f s  us/eval/cell %.3f\n",
        name, accepted, rejected, evals, static_cast<double>(evals) / a, cpu, cpu / a, wall,
        cell_evals > 0 ? 1e6 * cpu / cell_evals : 0.0);
  }
};

void usage() {
  std::fprintf(stderr,
               "usage: bench_scaling [--scene FILE] [--L X] [--seeds K] [--targets LIST] [--max-attempts M]\n"
               "                     [--report-every S] [--csv FILE] [--set section.key=value]...\n");
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  std::string scene_file = "data/scenes/paper-L15.toml", csv_path, targets = "[1e-3, 1e-2]";
  std::vector<std::string> overrides;
  long max_attempts = 0, max_rejections = 0, report_every = 0, seeds = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        usage();
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--scene")
      scene_file = value();
    else if (a == "--L")
      overrides.push_back("box.L=" + value());
    else if (a == "--seeds")
      seeds = std::atol(value().c_str());
    else if (a == "--targets")
      targets = value();
    else if (a == "--max-attempts")
      max_attempts = std::atol(value().c_str());
    else if (a == "--stop-after-rejections")
      max_rejections = std::atol(value().c_str());
    else if (a == "--report-every")
      report_every = std::atol(value().c_str());
    else if (a == "--csv")
      csv_path = value();
    else if (a == "--set")
      overrides.push_back(value());
    else {
      usage();
      return 2;
    }
  }
  // Fixed protocol for every size (the options above, then the user's --set overrides win).
  std::vector<std::string> all = {"jamming.targets=" + targets, "jamming.continue_to_phi2=false",
                                  "observe.checkpoint_every=0"};
  if (seeds > 0) {
    all.push_back("init.kind=random_seeds");
    all.push_back("init.cells=" + std::to_string(seeds));
  }
  all.insert(all.end(), overrides.begin(), overrides.end());

  Scene scene;
  try {
    scene = io::load_scene(scene_file, all);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_scaling: %s\n", e.what());
    return 2;
  }
  scene.progress = false;
  const long rss_start = peak_rss_kib();

  std::unique_ptr<std::FILE, int (*)(std::FILE*)> csv(nullptr, &std::fclose);
  if (!csv_path.empty()) {
    csv.reset(std::fopen(csv_path.c_str(), "w"));
    if (!csv) {
      std::fprintf(stderr, "bench_scaling: cannot write %s\n", csv_path.c_str());
      return 3;
    }
    std::fprintf(csv.get(),
                 "attempt,accepted,step,phase,N,phi,P,E_per_cell,dt,evals,cpu_s,wall_s,"
                 "trial_dt,trial_N,trial_phi,trial_E_per_cell,trial_start,trial_verdict,trial_iterations\n");
  }

  std::printf("bench_scaling: %s, L = %g, init = %s (%zu seeds), P0 = %s, seed %llu, targets %s%s%s\n",
              scene_file.c_str(), scene.L, scene.init == InitialState::two_cells ? "two_cells" : "random_seeds",
              scene.n_seeds, scene.P0 ? std::to_string(*scene.P0).c_str() : "none",
              static_cast<unsigned long long>(scene.seed), targets.c_str(),
              max_attempts > 0 ? (", at most " + std::to_string(max_attempts) + " attempts").c_str() : "",
              max_rejections > 0 ? (", until rejection " + std::to_string(max_rejections)).c_str() : "");
  std::fflush(stdout);

  GrowthDriver d(scene);
  TrialLog trials;
  d.add_observer(trials);
  const auto t0 = Clock::now();
  const double c0 = cpu_seconds();
  Stage approach, bisect, above, window;
  bool seen_rejection = false;
  long prev_acc = 0, prev_rej = 0, prev_ev = 0, attempt = 0;
  double prev_cpu = c0, prev_wall = 0;
  RunStatus st = RunStatus::running;
  const auto wall_now = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };

  while (st == RunStatus::running && (max_attempts <= 0 || attempt < max_attempts) &&
         (max_rejections <= 0 || d.result().rejected < max_rejections)) {
    const bool was_jammed_before = d.result().jamming.has_value();
    st = d.advance();
    const double c = cpu_seconds(), w = wall_now();
    const RunResult& r = d.result();
    const long acc = r.accepted - prev_acc, rej = r.rejected - prev_rej, ev = r.force_evaluations - prev_ev;
    const double n = static_cast<double>(d.packing().size());
    if (acc + rej > 0) ++attempt;  // the first advance() only relaxes the initial state
    // Stage: "above" once a jamming state has been accepted (also this step if it was the jamming
    // state's successor); the jamming state itself is the last step of "bisect".
    Stage& stage = was_jammed_before ? above : (seen_rejection || rej > 0) ? bisect : approach;
    stage.add(acc, rej, ev, c - prev_cpu, w - prev_wall, n);
    window.add(acc, rej, ev, c - prev_cpu, w - prev_wall, n);
    seen_rejection |= rej > 0;
    if (csv) {
      const StateView v = d.view();
      std::fprintf(csv.get(), "%ld,%ld,%ld,%s,%zu,%.10g,%.6g,%.6g,%.6g,%ld,%.6f,%.6f,", attempt, acc, v.step,
                   to_string(v.phase), d.packing().size(), v.phi, v.P, v.E_per_cell, v.dt, ev, c - c0, w);
      if (const std::optional<TrialRelaxed> t = std::exchange(trials.last, std::nullopt))
        std::fprintf(csv.get(), "%.10g,%zu,%.10g,%.6g,%s,%s,%ld\n", t->dt, t->N, t->phi, t->E_per_cell,
                     to_string(t->start), to_string(t->verdict), t->fire_iterations);
      else
        std::fprintf(csv.get(), ",,,,,,\n");  // the first advance() relaxes the initial state: no trial
      std::fflush(csv.get());
    }
    if (report_every > 0 && acc > 0 && r.accepted % report_every == 0) {
      const StateView v = d.view();
      std::printf(
          "  window to step %6ld  N %6zu  phi %.6f  P %.3e  E/N %.3e  %-8s | accepted %4ld rejected %4ld "
          "evals/acc %8.1f  cpu/acc %8.4f s  wall/acc %8.4f s  (cpu so far %.1f s)\n",
          v.step, d.packing().size(), v.phi, v.P, v.E_per_cell, to_string(v.phase), window.accepted, window.rejected,
          static_cast<double>(window.evals) / static_cast<double>(window.accepted),
          window.cpu / static_cast<double>(window.accepted), window.wall / static_cast<double>(window.accepted),
          c - c0);
      std::fflush(stdout);
      window = Stage{};
    }
    prev_acc = r.accepted, prev_rej = r.rejected, prev_ev = r.force_evaluations, prev_cpu = c, prev_wall = w;
  }
  const double cpu = cpu_seconds() - c0, wall = wall_now();
  const RunResult& r = d.result();
  const StateView v = d.view();
  const long rss_peak = peak_rss_kib();
  const double acc = r.accepted > 0 ? static_cast<double>(r.accepted) : 1.0;

  std::printf("status %s  N_final %zu  phi_final %.6f  P_final %.3e",
              st == RunStatus::running ? "stopped (--max-attempts / --stop-after-rejections)" : to_string(st),
              d.packing().size(), v.phi, v.P);
  if (r.jamming)
    std::printf("  N_J %zu  phi_J %.6f  step_J %ld", r.jamming->network.N, r.jamming->phi, r.jamming->step);
  std::printf("  targets landed %zu  unjammings %zu\n", r.targets.size(), r.unjammings.size());
  std::printf(
      "  total    accepted %6ld  rejected %5ld  evals %10ld  evals/acc %9.1f  cpu %9.2f s  cpu/acc %9.5f s  "
      "wall %9.2f s  peak RSS %ld KiB (at start %ld KiB)\n",
      r.accepted, r.rejected, r.force_evaluations, static_cast<double>(r.force_evaluations) / acc, cpu, cpu / acc, wall,
      rss_peak, rss_start);
  std::printf(
      "  cost     search trials %5ld  marginal relaxations %3ld  Newton factorisations %6ld  factor reuses %6ld  "
      "evals initial %ld search %ld above %ld\n",
      r.search_trials, r.marginal_relaxations, r.newton_factorisations, r.newton_factor_reuses,
      r.force_evaluations_initial, r.force_evaluations_search, r.force_evaluations_above_jamming);
  std::printf("  active set steps %ld  factorisations %ld  updates %ld\n", r.active_set_steps,
              r.active_set_factorisations, r.active_set_updates);
  std::printf("  branches %ld  reached %ld  stability lost %ld  branch steps %ld  branch events %ld\n", r.branches,
              r.branches_reached, r.branch_stability_losses, r.branch_steps, r.branch_events);
  approach.print("approach");
  bisect.print("bisect");
  above.print("above");
  return st == RunStatus::finished || st == RunStatus::running ? 0 : 1;
}
