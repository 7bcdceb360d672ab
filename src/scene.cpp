// budjam::validate — every rule a Scene must satisfy before a run starts. Messages have the form
// "<section>.<key>: <problem> (got <value>)" with the key spelled as in the TOML scene file, so
// a user can find the line to fix (docs/files.md lists the rules).
#include "budjam/scene.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace budjam {
namespace {

// Shortest text that reads back as the same double (so "(got 0.002)", not "0.0020000000000000001").
std::string show(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}
std::string show(long v) { return std::to_string(v); }
std::string show(int v) { return std::to_string(v); }
std::string show(std::size_t v) { return std::to_string(v); }
std::string show(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + show(v[i]);
  return s + "]";
}

template <class T>
[[noreturn]] void fail(const std::string& key, const std::string& problem, const T& got) {
  throw InputError(key + ": " + problem + " (got " + show(got) + ")");
}

void finite(const std::string& key, double v) {
  if (!std::isfinite(v)) fail(key, "must be a finite number", v);
}
void positive(const std::string& key, double v) {
  finite(key, v);
  if (!(v > 0)) fail(key, "must be positive", v);
}
void non_negative(const std::string& key, long v) {
  if (v < 0) fail(key, "must be zero or positive", v);
}

void validate_schedule(const std::string& section, const Schedule& s) {
  non_negative(section + ".every", s.every);
}

}  // namespace

void validate(const Scene& s) {
  // [run]
  if (s.name.empty()) throw InputError("run.name: must not be empty (got \"\")");
  if (s.name.find_first_of("\n\r") != std::string::npos)
    throw InputError("run.name: must be a single line (got a line break)");
  // Scene files hold TOML integers (signed 64 bit); every seed must be writable into one.
  if (s.seed > static_cast<std::uint64_t>(INT64_MAX))
    fail("run.seed", "must be below 2^63 so that the scene can be written to a file", std::size_t{s.seed});

  // [cells] first: the box rule depends on the largest cell.
  positive("cells.r0", s.r0);
  finite("cells.delta", s.delta);
  // γ0 = r0 (1 + δ (U − 1/2)) must stay positive for U in [0, 1): δ < 2.
  if (!(s.delta >= 0 && s.delta < 2)) fail("cells.delta", "must lie in [0, 2) so that every γ0 > 0", s.delta);
  finite("cells.alpha0", s.alpha0);
  if (!(s.alpha0 > 1 && s.alpha0 < 2)) fail("cells.alpha0", "must lie in (1, 2)", s.alpha0);

  // [minimiser] skin before [box]: it enters the box rule too.
  positive("minimiser.skin", s.skin);

  // [box]. A bud divides at α = 2α0, so the largest lobe diameter is max(D, (2α0 − 1) D). The
  // neighbour list uses minimum images: every pair within σ_max + skin must have a single
  // periodic image closer than L/2.
  finite("box.L", s.L);
  const double lobe_max = std::max(kMotherDiameter, (2 * s.alpha0 - 1) * kMotherDiameter);
  const double L_min = 2 * (lobe_max + s.skin);
  if (!(s.L > L_min))
    fail("box.L",
         "must exceed 2 (largest lobe diameter + minimiser.skin) = " + show(L_min) +
             " so that each neighbour pair has one periodic image",
         s.L);

  // [init]
  if (s.init == InitialState::random_seeds) {
    if (s.n_seeds < 1) fail("init.cells", "must be at least 1 with init.kind = \"random_seeds\"", s.n_seeds);
    // Newborn cells fit in disks of diameter α0. Random sequential placement of disks saturates
    // at a covered fraction 0.547; at most 0.4 keeps random non-overlapping placement quick.
    const double disk = 0.25 * std::numbers::pi * s.alpha0 * s.alpha0;
    const double cover = static_cast<double>(s.n_seeds) * disk / (s.L * s.L);
    if (cover > 0.4) {
      const auto n_max = static_cast<std::size_t>(0.4 * s.L * s.L / disk);
      fail("init.cells",
           "too many seeds for the box: at most " + std::to_string(n_max) + " fit at random in L = " + show(s.L),
           s.n_seeds);
    }
  } else if (s.n_seeds != 0) {
    fail("init.cells", "is only used with init.kind = \"random_seeds\"", s.n_seeds);
  }

  // [growth]
  if (s.P0) {
    finite("growth.P0", *s.P0);
    if (!(*s.P0 > 0)) fail("growth.P0", "must be positive, or \"none\" for no feedback", *s.P0);
  }
  positive("growth.dt", s.dt);
  positive("growth.dt_min", s.dt_min);
  if (!(s.dt_min < s.dt)) fail("growth.dt_min", "must be smaller than growth.dt = " + show(s.dt), s.dt_min);
  if (s.max_steps <= 0) fail("growth.max_steps", "must be positive", s.max_steps);
  finite("growth.adaptive_floor", s.adaptive_floor);
  if (!(s.adaptive_floor > 0 && s.adaptive_floor <= 1))
    fail("growth.adaptive_floor", "must lie in (0, 1]", s.adaptive_floor);
  // The adaptive step is dt / max(g_max, floor): it must stay finite, or a bud whose growth factor
  // is exactly 0 would grow by 0 · ∞ = NaN.
  if (s.adaptive_floor < std::numeric_limits<double>::min() || !std::isfinite(s.dt / s.adaptive_floor))
    fail("growth.adaptive_floor", "must be at least " + show(std::numeric_limits<double>::min()) +
                                      " and keep growth.dt / adaptive_floor finite", s.adaptive_floor);

  // [jamming]
  positive("jamming.epsilon_U", s.epsilon_U);
  positive("jamming.target_tolerance", s.target_tolerance);
  positive("jamming.max_dphi", s.max_dphi);
  for (std::size_t i = 0; i < s.targets.size(); ++i) {
    const double t = s.targets[i];
    if (!std::isfinite(t)) fail("jamming.targets", "must be finite numbers", s.targets);
    if (!(t > 0)) fail("jamming.targets", "must be positive (Δφ above jamming)", s.targets);
    if (i > 0 && !(t > s.targets[i - 1])) fail("jamming.targets", "must be strictly increasing", s.targets);
  }
  if (!s.targets.empty()) {
    if (!(s.target_tolerance < s.targets.front()))
      fail("jamming.target_tolerance", "must be smaller than the first target " + show(s.targets.front()),
           s.target_tolerance);
    if (s.targets.back() > s.max_dphi)
      fail("jamming.targets", "must not exceed jamming.max_dphi = " + show(s.max_dphi), s.targets);
  }

  // [minimiser] FIRE 2.0 parameters (Guénolé et al. 2020, Table 1 gives the usual values).
  const FireParams& f = s.fire;
  positive("minimiser.dt_start", f.dt_start);
  positive("minimiser.dt_max", f.dt_max);
  positive("minimiser.dt_min", f.dt_min);
  if (!(f.dt_min <= f.dt_start))
    fail("minimiser.dt_min", "must not exceed minimiser.dt_start = " + show(f.dt_start), f.dt_min);
  if (!(f.dt_start <= f.dt_max))
    fail("minimiser.dt_start", "must not exceed minimiser.dt_max = " + show(f.dt_max), f.dt_start);
  if (f.n_delay < 0) fail("minimiser.n_delay", "must be zero or positive", f.n_delay);
  finite("minimiser.f_inc", f.f_inc);
  if (!(f.f_inc > 1)) fail("minimiser.f_inc", "must exceed 1", f.f_inc);
  finite("minimiser.f_dec", f.f_dec);
  if (!(f.f_dec > 0 && f.f_dec < 1)) fail("minimiser.f_dec", "must lie in (0, 1)", f.f_dec);
  finite("minimiser.alpha_start", f.alpha_start);
  if (!(f.alpha_start > 0 && f.alpha_start < 1)) fail("minimiser.alpha_start", "must lie in (0, 1)", f.alpha_start);
  finite("minimiser.f_alpha", f.f_alpha);
  if (!(f.f_alpha > 0 && f.f_alpha <= 1)) fail("minimiser.f_alpha", "must lie in (0, 1]", f.f_alpha);
  positive("minimiser.force_tol", f.force_tol);
  finite("minimiser.energy_floor", f.energy_floor);
  if (f.energy_floor < 0) fail("minimiser.energy_floor", "must be zero or positive", f.energy_floor);
  // Below the floor a packing counts as certainly unjammed, so the floor must lie below ε_U.
  if (!(f.energy_floor < s.epsilon_U))
    fail("minimiser.energy_floor", "must be below jamming.epsilon_U = " + show(s.epsilon_U), f.energy_floor);
  if (f.max_iterations <= 0) fail("minimiser.max_iterations", "must be positive", f.max_iterations);
  finite("minimiser.newton_force", f.newton_force);
  if (f.newton_force < 0) fail("minimiser.newton_force", "must be zero (off) or positive", f.newton_force);

  // [observe]
  validate_schedule("observe.moduli", s.moduli);
  validate_schedule("observe.dos", s.dos);
  non_negative("observe.checkpoint_every", s.checkpoint_every);
}

}  // namespace budjam
