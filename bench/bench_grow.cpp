// Speed of growth runs (docs/speed.md). Not a test: prints a table.
//
//   bench_grow [SCENE_DIR]        whole runs with each jamming search (demo scene; L = 15,
//                                 P0 = 1e-3, Δφ = 1e-4, 1e-3, 1e-2 and φ_2) and the
//                                 cost of one growth step above jamming against N (L = 8, 15, 20, 40)
//   bench_grow --runs-only / --steps-only
//
// Whole runs go through GrowthDriver exactly as `budjam grow` does (observers excluded). The
// per-step scaling grows K = 0.35 L²/(π/4) random newborn seeds without the jamming bisection
// (every step accepted) until P > 2e-3, then times 20 further growth steps Δt = 1 with feedback
// P0 = 1e-3: growth, full FIRE minimisation, contacts and bud pressures.
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/growth.hpp"
#include "budjam/growth_driver.hpp"
#include "io/process_memory.hpp"
#include "io/scene_file.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <numbers>
#include <string>
#include <utility>

using namespace budjam;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
// CPU time of this process: the machine may be shared, so wall time alone over-states the cost.
double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

void whole_run(const char* label, Scene scene) {
  scene.progress = false;
  GrowthDriver d(scene);
  const auto t0 = Clock::now();
  const double c0 = cpu_seconds();
  const RunStatus st = d.run();
  const double wall = seconds_since(t0), cpu = cpu_seconds() - c0;
  const RunResult& r = d.result();
  // Cell evaluations: force evaluations weighted by the number of cells at the end (an upper
  // bound of the true Σ N per evaluation; most evaluations happen at the final N near jamming).
  const double n = static_cast<double>(d.packing().size());
  std::printf(
      "%-26s %-8s wall %7.2f s  cpu %7.2f s  N=%4zu  phi_J=%.6f  accepted=%5ld  rejected=%4ld  evals=%8ld  "
      "evals/cpu-s=%7.0f  cell-evals/cpu-s=%.3g\n",
      label, to_string(st), wall, cpu, d.packing().size(), r.jamming ? r.jamming->phi : 0.0, r.accepted, r.rejected,
      r.force_evaluations, r.force_evaluations / cpu, r.force_evaluations * n / cpu);
}

void step_cost(double L) {
  Scene s;
  s.L = L;
  s.P0 = 1e-3;
  s.init = InitialState::random_seeds;
  s.n_seeds = static_cast<std::size_t>(0.35 * L * L / (0.25 * std::numbers::pi * s.alpha0 * s.alpha0));
  Rng rng(1);
  Packing p = random_seeds(s, rng);
  ForceField field(s.skin);
  Eigen::VectorXd F;
  std::vector<double> rates = p.gamma0;
  double P = 0;
  long steps = 0;
  auto one_step = [&](long& evals) {
    grow_step(p, rates, 1.0, s, rng);
    field.invalidate();
    const FireResult fr = minimise(p, field, s.fire);
    evals += fr.evaluations;
    field.invalidate();
    field.evaluate(p, F);
    const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
    P = pressure(contacts, p.box);
    const auto pb = bud_pressures(p, contacts);
    rates = growth_rates(p, P > 1e-9 ? &pb : nullptr, s.P0);
    return fr.converged;
  };
  long evals = 0;
  const auto t_prep = Clock::now();
  while (P < 2e-3 && steps < 20000) {
    if (!one_step(evals)) break;
    ++steps;
  }
  const double prep = seconds_since(t_prep);
  evals = 0;
  const int n_steps = 20;
  const double c0 = cpu_seconds();
  for (int k = 0; k < n_steps; ++k) one_step(evals);
  const double wall = cpu_seconds() - c0;  // CPU seconds
  const double N = static_cast<double>(p.size());
  std::printf(
      "L=%-4g N=%5zu phi=%.4f P=%.2e  per growth step: %8.4f cpu-s  %7.0f evals  %6.2f us/eval  "
      "%5.3f us/eval/cell   (reached in %ld steps, %.1f s)\n",
      L, p.size(), p.packing_fraction(), P, wall / n_steps, static_cast<double>(evals) / n_steps, 1e6 * wall / evals,
      1e6 * wall / evals / N, steps, prep);
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  std::string dir = "data/scenes";
  bool runs = true, steps = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--runs-only"))
      steps = false;
    else if (!std::strcmp(argv[i], "--steps-only"))
      runs = false;
    else
      dir = argv[i];
  }
  if (runs) {
    std::printf("== whole runs (two-cell start), each jamming search ==\n");
    const std::pair<JammingSearch, const char*> searches[] = {{JammingSearch::bisection, " bisection"},
                                                              {JammingSearch::secant, " secant"},
                                                              {JammingSearch::bracket, " bracket"}};
    for (const auto& [search, tag] : searches) {
      Scene demo = io::load_scene(std::filesystem::path(dir) / "demo.toml");
      demo.search = search;
      whole_run((std::string("demo.toml") + tag).c_str(), demo);
      Scene l15 = io::load_scene(std::filesystem::path(dir) / "paper-L15.toml");
      l15.targets = {1e-4, 1e-3, 1e-2};  // and on to φ_2
      l15.checkpoint_every = 0;
      l15.search = search;
      whole_run((std::string("paper-L15 to phi_2") + tag).c_str(), l15);
    }
  }
  if (steps) {
    std::printf("== one growth step above jamming (P ~ 2e-3, P0 = 1e-3) against N ==\n");
    for (double L : {8.0, 15.0, 20.0, 40.0}) step_cost(L);
  }
}
