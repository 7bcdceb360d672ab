#pragma once
// Registry of growth-run observers. A tools/observers/observe_<name>.cpp file adds itself with
//
//   namespace {
//   const budjam::tools::ObserverRegistration reg{"moduli", [](const budjam::tools::ObserverContext& c)
//       -> std::unique_ptr<budjam::Observer> {
//     if (!c.scene.moduli.any()) return nullptr;        // the scene does not ask for it: not built
//     return std::make_unique<ModuliObserver>(c.scene, c.run_dir);
//   }};
//   }
//
// and `budjam grow` builds every registered observer whose factory does not return nullptr, in
// name order (static-initialisation order across files is unspecified; name order is not).
// Observers write their files under ctx.run_dir, atomically (io/atomic_file.hpp), and must
// survive --resume: when ctx.resuming is true the run directory already holds their files up to
// the checkpoint and their load_state() is called with what save_state() wrote.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>
#include "budjam/growth_driver.hpp"
#include "budjam/scene.hpp"

namespace budjam::tools {

struct ObserverContext {
  const Scene& scene;
  std::uint64_t seed;             // the run's seed (scene.seed or --seed)
  std::filesystem::path run_dir;  // exists when the factory is called
  bool resuming = false;          // continuing from run_dir/checkpoint.txt
  bool quiet = false;             // --quiet: nothing on stderr
};

using ObserverFactory = std::function<std::unique_ptr<Observer>(const ObserverContext&)>;

struct ObserverEntry {
  std::string name;
  ObserverFactory factory;
};

// Function-local static: safe to use from other files' static initialisers.
std::vector<ObserverEntry>& observer_registry();

struct ObserverRegistration {
  ObserverRegistration(std::string name, ObserverFactory factory);
};

// Every observer the scene asks for, in registry-name order. Throws InputError if two
// registrations share a name.
std::vector<std::unique_ptr<Observer>> make_observers(const ObserverContext& ctx);

}  // namespace budjam::tools
