#pragma once
// Registry of growth-run observers. A tools/observers/observe_<name>.cpp file adds itself with
//
//   namespace {
//   const budjam::tools::ObserverRegistration reg{"moduli", "observe.moduli.*", {"moduli.csv"},
//       [](const budjam::tools::ObserverContext& c) -> std::unique_ptr<budjam::Observer> {
//     if (!c.scene.moduli.any()) return nullptr;        // the scene does not ask for it: not built
//     return std::make_unique<ModuliObserver>(c.scene, c.run_dir.root());
//   }};
//   }
//
// and `budjam grow` builds every registered observer whose factory does not return nullptr, in
// name order (static-initialisation order across files is unspecified; name order is not). The
// second argument names the scene keys that switch it on (`observe.moduli.*`: every key of that
// section); `budjam grow --help` and the table of docs/growth.md (`budjam validate
// --observers-markdown`) list the registry.
// The third argument declares every entry the observer may write in a run directory, as
// io::OwnedEntries patterns, whether or not a given scene enables it: `--overwrite` removes
// exactly the declared entries of an earlier run (run_owned_entries), so an observer writes
// nothing it has not declared. Observers write their files relative to ctx.run_dir, atomically
// (io/atomic_file.hpp), and must survive --resume: when ctx.resuming is true the run directory
// already holds their files up to the checkpoint, their load_state() is called with what
// save_state() wrote, and on_resumed() once the resume was accepted.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>
#include "budjam/growth_driver.hpp"
#include "budjam/scene.hpp"
#include "io/run_directory.hpp"

namespace budjam::tools {

struct ObserverContext {
  const Scene& scene;
  std::uint64_t seed;               // the run's seed (scene.seed or --seed)
  const io::RunDirectory& run_dir;  // claimed when the factory is called
  bool resuming = false;            // continuing from run_dir/checkpoint.txt
  bool quiet = false;               // --quiet: nothing on stderr
};

using ObserverFactory = std::function<std::unique_ptr<Observer>(const ObserverContext&)>;

struct ObserverEntry {
  std::string name;
  std::string switched_on_by;  // scene keys, e.g. "observe.trials" or "observe.dos.*"
  io::OwnedEntries files;
  ObserverFactory factory;
};

// Function-local static: safe to use from other files' static initialisers.
std::vector<ObserverEntry>& observer_registry();

struct ObserverRegistration {
  ObserverRegistration(std::string name, std::string switched_on_by, io::OwnedEntries files, ObserverFactory factory);
};

// Every observer the scene asks for, in registry-name order. Throws InputError if two
// registrations share a name.
std::vector<std::unique_ptr<Observer>> make_observers(const ObserverContext& ctx);

// The entries every registered observer declares.
io::OwnedEntries declared_observer_files();

// The registry as a Markdown table (observer, the keys that switch it on, the files it writes),
// in name order: the table of docs/growth.md, "Observers".
std::string observers_markdown();
// The registry as one paragraph of `budjam grow --help`.
std::string observers_help();

}  // namespace budjam::tools
