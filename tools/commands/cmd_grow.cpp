// `budjam grow SCENE [--seed N] [--out DIR] [--quiet] [--set KEY=VALUE]...`
// `budjam grow --resume DIR [--quiet]`
// Grows a packing as the scene says (MODEL.md protocol, docs/growth.md) and writes the run
// directory: scene.toml (the effective scene, seed included), steps.csv, divisions.csv,
// bud_events.csv, packings/*.pack, checkpoint.txt while running, summary.json last.
#include "commands/command.hpp"
#include "observers/observers.hpp"
#include "observers/run_outputs.hpp"

#include "budjam/growth_driver.hpp"
#include "io/atomic_file.hpp"
#include "io/scene_file.hpp"

#include <cctype>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace budjam;

struct Options {
  std::string scene;
  std::optional<std::uint64_t> seed;
  std::string out;
  std::string resume;
  bool quiet = false;
  std::vector<std::string> overrides;
};

std::string safe_name(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
  return out.empty() ? "run" : out;
}

// A fresh run starts in an empty directory. A directory that holds an earlier budjam run
// (it has scene.toml) is emptied; anything else is refused rather than overwritten.
void prepare_fresh_dir(const fs::path& dir) {
  if (fs::exists(dir)) {
    if (!fs::is_directory(dir)) throw InputError("--out: " + dir.string() + " exists and is not a directory");
    if (!fs::is_empty(dir)) {
      if (!fs::exists(dir / tools::kSceneFile))
        throw InputError("--out: " + dir.string() + " is not empty and is not a budjam run directory");
      for (const auto& entry : fs::directory_iterator(dir)) fs::remove_all(entry.path());
    }
  }
  fs::create_directories(dir);
}

void run(const Options& o) {
  const bool resuming = !o.resume.empty();
  Scene scene;
  fs::path dir;
  if (resuming) {
    if (!o.scene.empty() || o.seed || !o.overrides.empty() || !o.out.empty())
      throw InputError("--resume: takes no SCENE, --seed, --set or --out (the run directory has them)");
    dir = o.resume;
    if (fs::exists(dir / tools::kSummaryFile))
      throw InputError("--resume: " + dir.string() + " holds a finished run (summary.json exists)");
    if (!fs::exists(dir / tools::kCheckpointFile))
      throw InputError("--resume: no " + std::string(tools::kCheckpointFile) + " in " + dir.string());
    scene = io::load_scene(dir / tools::kSceneFile);
  } else {
    if (o.scene.empty()) throw InputError("SCENE: a scene file is required (or --resume DIR)");
    scene = io::load_scene(o.scene, o.overrides);
    if (o.seed) scene.seed = *o.seed;
    dir = o.out.empty() ? fs::path("runs") / (safe_name(scene.name) + "-seed" + std::to_string(scene.seed))
                        : fs::path(o.out);
    prepare_fresh_dir(dir);
    io::write_atomically(dir / tools::kSceneFile, io::scene_to_toml(scene));
  }

  GrowthDriver driver(scene);
  tools::RunLog log(dir, scene.seed, resuming);
  driver.add_observer(log);
  const tools::ObserverContext ctx{scene, scene.seed, dir, resuming, o.quiet};
  auto observers = tools::make_observers(ctx);
  for (auto& obs : observers) driver.add_observer(*obs);
  if (scene.checkpoint_every > 0)
    driver.set_checkpoint_writer(scene.checkpoint_every, [&dir](const std::string& text) {
      io::write_atomically(dir / tools::kCheckpointFile, text);
    });
  if (resuming) driver.restore(io::read_text_file(dir / tools::kCheckpointFile));

  tools::SessionTiming timing;
  timing.attempts_at_start = driver.view().attempts;
  timing.force_evaluations_at_start = driver.result().force_evaluations;
  const auto t0 = std::chrono::steady_clock::now();
  const RunStatus status = driver.run();
  timing.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  tools::write_summary(dir, driver, timing);
  fs::remove(dir / tools::kCheckpointFile);  // a finished (or failed) run is not resumed
  if (status != RunStatus::finished)
    throw cli::RunFailure(std::string("grow: run failed (") + to_string(status) + "): " + driver.result().message +
                          " [" + (dir / tools::kSummaryFile).string() + "]");
}

const bool registered = budjam::cli::register_command(
    {"grow", "Grow a packing from a scene to jamming, the Δφ targets and φ_2", [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("SCENE", o->scene, "scene file (.toml)");
       sub.add_option("--seed", o->seed, "random seed (overrides the scene's run.seed)");
       sub.add_option("--out", o->out, "run directory (default runs/<name>-seed<seed>)");
       sub.add_option("--resume", o->resume, "continue the interrupted run in DIR from its checkpoint")
           ->type_name("DIR");
       sub.add_option("--set", o->overrides, "override a scene key, e.g. --set growth.P0=1e-4 (repeatable)")
           ->type_name("KEY=VALUE");
       sub.add_flag("--quiet", o->quiet, "no progress on stderr");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
