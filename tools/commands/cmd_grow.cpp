// `budjam grow SCENE [--seed N] [--out DIR] [--overwrite] [--quiet] [--set KEY=VALUE]...`
// `budjam grow --resume DIR [--quiet]`   (both: [--threads N])
// Grows a packing as the scene says (docs/growth.md) and writes the run directory
// (io/run_directory.hpp: claimed with a marker and a lock): scene.toml (the effective scene, seed
// included), steps.csv, divisions.csv, bud_events.csv, packings/*.pack, checkpoint.txt while
// running (io/checkpoint.hpp), summary.json last. SIGTERM/SIGINT: checkpoint (or the last one
// kept), exit 128 + signal.
// A run that reaches growth.max_steps is an expected stop (status step_limit, a notice, exit 0);
// the other failures (step-size underflow, minimiser failure) exit 1.
#include "commands/command.hpp"
#include "commands/stop_signals.hpp"
#include "observers/observers.hpp"
#include "observers/run_outputs.hpp"

#include "budjam/growth_driver.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "io/run_directory.hpp"
#include "io/scene_file.hpp"
#include "io/text.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

namespace budjam::cli::grow_command {
namespace {

namespace fs = std::filesystem;
namespace run_files = io::run_files;

struct Options {
  std::string scene;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  std::string out;
  std::string resume;
  bool quiet = false;
  bool overwrite = false;
  std::vector<std::string> overrides;
};

std::string safe_name(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
  // A leading dot would hide the run directory from ls.
  const std::size_t dots = std::min(out.find_first_not_of('.'), out.size());
  if (dots > 0) out.replace(0, dots, "_");
  return out.empty() ? "run" : out;
}

// The step limit is an expected end (a run with strong feedback all but stops growing): one line
// saying what was recorded, and exit 0. The other failures are errors (exit 1).
std::string step_limit_notice(const Scene& scene, const RunResult& r, const fs::path& summary) {
  std::string line =
      "budjam: grow: run stopped at the step limit (growth.max_steps = " + std::to_string(scene.max_steps) +
      " growth steps); recorded: ";
  if (!r.jamming) return line + "not jammed [" + summary.string() + "]";
  line += "jamming at φ_J = " + io::format_double(r.jamming->phi) + ", " + std::to_string(r.targets.size()) + " of " +
          std::to_string(scene.targets.size()) + " Δφ targets";
  if (!r.targets.empty()) line += " (up to " + io::format_double(r.targets.back().dphi) + ")";
  if (scene.continue_to_phi2) line += r.depletion ? ", φ_2 reached" : ", φ_2 not reached";
  return line + " [" + summary.string() + "]";
}

void run(const Options& o) {
  // Before any file is written: a signal that came between the first file and the handler would
  // end the process with a run directory it cannot resume.
  const cli::StopSignals stop;
  const bool resuming = !o.resume.empty();
  Scene scene;
  std::optional<io::RunDirectory> run_dir;
  if (resuming) {
    if (!o.scene.empty() || o.seed || !o.overrides.empty() || !o.out.empty() || o.overwrite)
      throw InputError("--resume: takes no SCENE, --seed, --set, --out or --overwrite (the run directory has them)");
    run_dir.emplace(io::RunDirectory::resume(o.resume, tools::run_owned_entries()));
    const io::RunDirectory& d = *run_dir;
    if (d.root().entry(run_files::summary))
      throw InputError("--resume: " + d.path().string() + " holds a finished run (" + std::string(run_files::summary) +
                       " exists)");
    if (!d.root().entry(run_files::checkpoint))
      throw InputError("--resume: no " + std::string(run_files::checkpoint) + " in " + d.path().string());
    scene = io::parse_scene(io::read_text_file(d.root(), run_files::scene), (d / run_files::scene).string());
    if (o.threads) scene.threads = *o.threads;  // not in the checkpoint's scene hash: results do not change
  } else {
    if (o.scene.empty()) throw InputError("SCENE: a scene file is required (or --resume DIR)");
    scene = io::load_scene(o.scene, o.overrides);
    if (o.seed) scene.seed = *o.seed;
    if (o.threads) scene.threads = *o.threads;
    validate(scene);  // with the overrides, before anything is written
    const fs::path out = o.out.empty()
                             ? fs::path("runs") / (safe_name(scene.name) + "-seed" + std::to_string(scene.seed))
                             : fs::path(o.out);
    run_dir.emplace(io::RunDirectory::create(out, o.overwrite, tools::run_owned_entries()));
    io::write_atomically(run_dir->root(), run_files::scene, io::scene_to_toml(scene));
  }
  const fs::path dir = run_dir->path();
  const io::Directory& root = run_dir->root();

  GrowthDriver driver(scene);
  tools::RunLog log(*run_dir, scene.seed, resuming);
  const tools::ObserverContext ctx{scene, scene.seed, *run_dir, resuming, o.quiet};
  auto owned = tools::make_observers(ctx);
  std::vector<Observer*> observers{&log};
  for (auto& obs : owned) observers.push_back(obs.get());
  for (Observer* obs : observers) driver.add_observer(*obs);
  if (resuming) {
    // Everything is checked before anything changes: a refused resume leaves the run as it was.
    io::CheckpointLines lines;
    GrowthState state = io::read_checkpoint(root, run_files::checkpoint, scene, scene.seed, observers, &lines);
    const std::string checkpoint = (dir / run_files::checkpoint).string();
    log.check_resumed_state(state, scene, lines, checkpoint);
    for (Observer* obs : observers) obs->check_resumed(state);
    driver.restore(std::move(state), checkpoint);  // the observers' on_resumed() comes with its first event
    if (const std::string blas = io::checkpoint_blas(); lines.blas != blas)
      std::cerr << "budjam: grow: "
                << io::one_line("resuming under another BLAS than the checkpoint was computed with (" + lines.blas +
                                "; now " + blas +
                                "): the run goes on, but its last bits can differ from an "
                                "uninterrupted run's")
                << std::endl;
  }

  // Checkpoints as io::CheckpointSchedule says; a signal then ends the run (resumable). A state that
  // holds less than the run depends on (a kept Newton factor) is not saved: the run then resumes,
  // exactly, from its last checkpoint.
  struct Moment {
    long step, attempts;
  };
  const auto moment = [&] { return Moment{driver.view().step, driver.view().attempts}; };
  const auto text = [](const Moment& m) {
    return "growth attempt " + std::to_string(m.attempts) + " (step " + std::to_string(m.step) + ")";
  };
  std::optional<Moment> last_checkpoint;
  if (resuming) last_checkpoint = moment();
  // Force evaluations of the growth attempts, without the initial relaxation's.
  const auto attempt_evaluations = [&] {
    return driver.result().force_evaluations - driver.result().force_evaluations_initial;
  };
  io::CheckpointSchedule schedule(scene.checkpoint_every, moment().step, attempt_evaluations());
  driver.set_checkpoint_hook([&] {
    const Moment now = moment();
    const int signal = cli::StopSignals::received();
    if (schedule.due(now.step, attempt_evaluations(), signal != 0, driver.state_is_complete())) {
      io::write_checkpoint(root, run_files::checkpoint, scene, driver.state(), observers);
      last_checkpoint = now;
    }
    if (!signal || now.step == 0) return;  // a signal is honoured from the first accepted step on
    const std::string stopped =
        "grow: stopped by " + std::string(signal == SIGINT ? "SIGINT" : "SIGTERM") + " at " + text(now);
    if (last_checkpoint && last_checkpoint->attempts == now.attempts)
      throw cli::Interrupted(signal,
                             stopped + ", checkpoint written; resume with: budjam grow --resume " + dir.string());
    const std::string why = " (a Newton factor kept in memory is not saved, so that state would not resume exactly)";
    if (last_checkpoint)
      throw cli::Interrupted(signal, stopped + "; the checkpoint of " + text(*last_checkpoint) + " is kept" + why +
                                         "; resume with: budjam grow --resume " + dir.string());
    throw cli::Interrupted(signal, stopped + "; no checkpoint yet" + why + "; start the run again with --overwrite");
  });
  // Inside a relaxation, every observe.checkpoint_evaluations force evaluations of it and at a
  // signal, which then ends the run there: a marginal relaxation of a large packing runs for hours.
  driver.set_relaxation_checkpoints(
      scene.checkpoint_evaluations, [] { return cli::StopSignals::received() != 0; },
      [&](const GrowthState& s) {
        io::write_checkpoint(root, run_files::checkpoint, scene, s, observers);
        const Moment now{s.step, s.relaxation->attempts};
        last_checkpoint = Moment{s.step, s.attempts};
        if (const int signal = cli::StopSignals::received())
          throw cli::Interrupted(signal, "grow: stopped by " + std::string(signal == SIGINT ? "SIGINT" : "SIGTERM") +
                                             " in a relaxation of " + text(now) +
                                             ", checkpoint written; resume with: budjam grow --resume " + dir.string());
      });

  tools::SessionTiming timing;
  timing.attempts_at_start = driver.view().attempts;
  timing.force_evaluations_at_start = driver.result().force_evaluations;
  const auto t0 = std::chrono::steady_clock::now();
  const RunStatus status = driver.run();
  timing.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  tools::write_summary(root, driver, timing);
  root.remove(run_files::checkpoint);  // a finished (or failed) run is not resumed
  if (status == RunStatus::step_limit) {
    std::cerr << io::one_line(step_limit_notice(scene, driver.result(), dir / run_files::summary)) << std::endl;
    return;
  }
  if (status != RunStatus::finished)
    throw cli::RunFailure(std::string("grow: run failed (") + to_string(status) + "): " + driver.result().message +
                          " [" + (dir / run_files::summary).string() + "]");
}

const bool registered = budjam::cli::register_command(
    {"grow", "Grow a packing from a scene to jamming, the Δφ targets and φ_2", [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("SCENE", o->scene, "scene file (.toml)");
       sub.add_option("--seed", o->seed, "random seed (overrides the scene's run.seed)")
           ->check(budjam::cli::seed_range());
       sub.add_option("--threads", o->threads,
                      "threads of a force evaluation, in [0, 1024], 0 = one per core (overrides minimiser.threads)")
           ->check(CLI::Range(0, budjam::kMaxThreads));
       sub.add_option("--out", o->out, "run directory (default runs/<name>-seed<seed>)")
           ->check(budjam::cli::names_a_path());
       sub.add_option("--resume", o->resume, "continue the interrupted run in DIR from its checkpoint")
           ->type_name("DIR");
       sub.add_option("--set", o->overrides, "override a scene key, e.g. --set growth.P0=1e-4 (repeatable)")
           ->type_name("KEY=VALUE");
       sub.add_flag("--overwrite", o->overwrite,
                    "replace the budjam run already in --out (only the files budjam wrote are removed)");
       sub.add_flag("--quiet", o->quiet, "no progress on stderr");
       sub.footer(budjam::tools::observers_help());
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::grow_command
