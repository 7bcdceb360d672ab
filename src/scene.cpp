// budjam::validate — every rule a Scene must satisfy before a run starts: each key's range (the
// knob table, scene_keys.cpp), then the rules between keys. Messages have the form
// "<section>.<key>: <problem> (got <value>)" with the key spelled as in the TOML scene file, so
// a user can find the line to fix (docs/files.md lists the rules).
#include "budjam/scene.hpp"

#include "budjam/scene_keys.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>

namespace budjam {
namespace {

[[noreturn]] void fail(const std::string& key, const std::string& problem, const SceneValue& got) {
  throw InputError(key + ": " + problem + " (got " + value_text(got) + ")");
}

}  // namespace

void validate(const Scene& s) {
  // Each key on its own (types and ranges: the knob table), then the rules between keys.
  for (const SceneKey& k : scene_keys()) k.check(s);

  // Scene files hold TOML integers (signed 64 bit); every seed must be writable into one.
  if (s.seed > static_cast<std::uint64_t>(INT64_MAX))
    throw InputError("run.seed: must be below 2^63 so that the scene can be written to a file (got " +
                     std::to_string(s.seed) + ")");

  // [box]. A bud divides at α = 2α0, so the largest lobe diameter is max(D, (2α0 − 1) D). The
  // neighbour list uses minimum images: every pair within σ_max + skin must have a single
  // periodic image closer than L/2.
  const double lobe_max = std::max(kMotherDiameter, (2 * s.alpha0 - 1) * kMotherDiameter);
  const double L_min = 2 * (lobe_max + s.skin);
  if (!(s.L > L_min))
    fail("box.L",
         "must exceed 2 (largest lobe diameter + minimiser.skin) = " + value_text(L_min) +
             " so that each neighbour pair has one periodic image",
         s.L);

  // [init]
  if (s.init == InitialState::random_seeds) {
    if (s.n_seeds < 1)
      fail("init.cells", "must be at least 1 with init.kind = \"random_seeds\"", std::int64_t(s.n_seeds));
    // Newborn cells fit in disks of diameter α0. Random sequential placement of disks saturates
    // at a covered fraction 0.547; at most 0.4 keeps random non-overlapping placement quick.
    const double disk = 0.25 * std::numbers::pi * s.alpha0 * s.alpha0;
    const double cover = static_cast<double>(s.n_seeds) * disk / (s.L * s.L);
    if (cover > 0.4) {
      const auto n_max = static_cast<std::size_t>(0.4 * s.L * s.L / disk);
      fail("init.cells",
           "too many seeds for the box: at most " + std::to_string(n_max) +
               " fit at random in box.L = " + value_text(s.L),
           std::int64_t(s.n_seeds));
    }
  } else if (s.n_seeds != 0) {
    fail("init.cells", "is only used with init.kind = \"random_seeds\"", std::int64_t(s.n_seeds));
  }

  // [growth]
  if (!(s.dt_min < s.dt)) fail("growth.dt_min", "must be smaller than growth.dt = " + value_text(s.dt), s.dt_min);

  // [jamming]
  if (s.crossing_step > 0 && !s.continuation)
    fail("jamming.crossing_step", "is only used with jamming.continuation = true", s.crossing_step);
  if (s.targets.size() > kMaxTargets)
    fail("jamming.targets", "at most " + std::to_string(kMaxTargets) + " targets (each writes a packing file)",
         s.targets);
  const double target_bytes = static_cast<double>(s.targets.size()) * kPackingBytesPerCell * kCellsPerArea * s.L * s.L;
  if (target_bytes > kMaxTargetOutputBytes)
    fail("jamming.targets",
         "their packings would take about " + value_text(std::round(target_bytes / 1e9)) + " GB at box.L = " +
             value_text(s.L) + ", more than the limit of " + value_text(kMaxTargetOutputBytes / 1e9) +
             " GB (each holds about " + value_text(kPackingBytesPerCell * kCellsPerArea) + " L² bytes)",
         s.targets);
  if (!s.targets.empty()) {
    if (!(s.target_tolerance < s.targets.front()))
      fail("jamming.target_tolerance",
           "must be smaller than the first of jamming.targets, " + value_text(s.targets.front()), s.target_tolerance);
    if (s.targets.back() > s.max_dphi)
      fail("jamming.targets", "must not exceed jamming.max_dphi = " + value_text(s.max_dphi), s.targets);
  }

  // [minimiser]
  const FireParams& f = s.fire;
  if (!(f.dt_min <= f.dt_start))
    fail("minimiser.dt_min", "must not exceed minimiser.dt_start = " + value_text(f.dt_start), f.dt_min);
  if (!(f.dt_start <= f.dt_max))
    fail("minimiser.dt_start", "must not exceed minimiser.dt_max = " + value_text(f.dt_max), f.dt_start);
  // The try is made before the regular hand-over or not at all: a try at or after it would be a key
  // without effect. With active_set_after = 0 (FIRE alone) no try is made whatever the key says.
  if (f.active_set_after > 0 && f.active_set_try_after >= f.active_set_after)
    fail("minimiser.active_set_try_after",
         "must be below minimiser.active_set_after = " + std::to_string(f.active_set_after) + " (0 = no try)",
         std::int64_t(f.active_set_try_after));
  // Below the floor a packing counts as certainly unjammed, so the floor must lie below ε_U.
  if (!(f.energy_floor < s.epsilon_U))
    fail("minimiser.energy_floor", "must be below jamming.epsilon_U = " + value_text(s.epsilon_U), f.energy_floor);
  // A relaxation stopped at |F| < force_tol leaves an energy of order force_tol²/2k in each contact it
  // did not balance (k = 1): the window tells a jammed minimum from an unfinished relaxation only when
  // that residual lies well below its bottom, force_tol² ≤ ε_U / 100 (to rounding: a value written
  // on the bound, such as 1e-13 against 1e-24, passes).
  const double force_tol_max = std::sqrt(kResidualEnergyOverWindow * s.epsilon_U);
  if (!(f.force_tol <= force_tol_max * (1 + 8 * std::numeric_limits<double>::epsilon())))
    fail("minimiser.force_tol",
         "must be at most √(" + value_text(kResidualEnergyOverWindow) +
             " jamming.epsilon_U) = " + value_text(force_tol_max) +
             ": a relaxation stopped at a larger force leaves an energy the jamming window cannot tell from a jammed "
             "packing's",
         f.force_tol);
}

}  // namespace budjam
