#include "budjam/growth.hpp"
#include "budjam/orientation.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace budjam {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDivisionNoise = 5e-5;  // rad, docs/model.md, "Growth": division

double uniform_angle(Rng& rng) { return -kPi + 2.0 * kPi * uniform01(rng); }
double noise(Rng& rng) { return kDivisionNoise * (2.0 * uniform01(rng) - 1.0); }

// Angle in [−π, π).
double wrap_angle(double t) {
  t = std::remainder(t, 2.0 * kPi);  // in [−π, π]
  return t >= kPi ? t - 2.0 * kPi : t;
}

}  // namespace

double draw_innate_rate(const Scene& scene, Rng& rng) {
  return scene.r0 * (1.0 + scene.delta * (uniform01(rng) - 0.5));
}

double grown_bud(double b, double gamma, double dt) {
  // b² + γΔt (D² + b²) equals (1 + γΔt)(D² + b²) − D² but keeps b exactly when γΔt = 0
  // (a bud whose growth factor underflowed must not drift by rounding).
  const double D2 = kMotherDiameter * kMotherDiameter;
  const double b2 = b * b;
  return std::sqrt(b2 + gamma * dt * (D2 + b2));
}

double log_growth_factor(double bud_pressure, std::optional<double> P0) {
  if (!P0) return 0.0;
  if (!(*P0 > 0.0)) throw InputError("growth.P0: must be positive (got " + std::to_string(*P0) + ")");
  if (std::isnan(bud_pressure)) throw std::domain_error("growth_factor: bud pressure is NaN");
  if (bud_pressure <= 0.0) return 0.0;
  return -(bud_pressure / *P0);
}

double factor_from_log(double log_factor) {
  // Below DBL_MIN the factor is an underflow: make it exactly 0 (no denormals, no NaN for −∞).
  static const double log_min = std::log(DBL_MIN);
  if (!(log_factor > log_min)) return 0.0;
  return std::exp(log_factor);
}

double growth_factor(double bud_pressure, std::optional<double> P0) {
  return factor_from_log(log_growth_factor(bud_pressure, P0));
}

CompressedFactor mean_compressed_factor(const std::vector<double>& pressures, std::optional<double> P0) {
  double sum = 0, log_top = -std::numeric_limits<double>::infinity();
  std::size_t n = 0;
  for (double p : pressures) {
    if (!(p > 0)) continue;
    sum += growth_factor(p, P0);
    log_top = std::max(log_top, log_growth_factor(p, P0));
    ++n;
  }
  if (!n) return {};
  double relative = 0;  // Σ exp(ln g_i − ln g_top) ≥ 1
  for (double p : pressures)
    if (p > 0) relative += std::exp(log_growth_factor(p, P0) - log_top);
  return {sum / static_cast<double>(n), log_top + std::log(relative / static_cast<double>(n))};
}

std::vector<double> growth_rates(const Packing& p, const std::vector<double>* bud_pressures, std::optional<double> P0,
                                 double log_scale) {
  std::vector<double> rates(p.gamma0);
  if (bud_pressures && P0) {
    if (bud_pressures->size() != p.size())
      throw std::invalid_argument("growth_rates: one bud pressure per cell expected");
    for (std::size_t i = 0; i < rates.size(); ++i)
      rates[i] *= factor_from_log(log_scale + log_growth_factor((*bud_pressures)[i], P0));
  }
  return rates;
}

Division divide(Packing& p, std::size_t i, const Scene& scene, Rng& rng) {
  Division d;
  d.mother_index = i;
  d.mother_id = p.id[i];
  d.x = p.x(i);
  d.y = p.y(i);
  d.theta = p.theta(i);
  d.b = p.b[i];
  const Axis n = axis(d.theta);
  const double c = n.c, s = n.s;
  const double half = 0.5 * scene.alpha0;  // centroids at (x,y) ± (α0/2) n̂
  const double b0 = newborn_bud(scene.alpha0);

  auto orientation = [&](bool daughter) {
    switch (scene.division) {
      case DivisionRule::random: return wrap_angle(uniform_angle(rng) + noise(rng));
      case DivisionRule::aligned: return wrap_angle(d.theta + noise(rng));
      case DivisionRule::opposite:  // buds point away from each other, along the old axis
        return wrap_angle(d.theta + (daughter ? 0.0 : kPi) + noise(rng));
    }
    throw std::logic_error("divide: unknown division rule");
  };

  // Mother side keeps index and identity.
  const double g_m = draw_innate_rate(scene, rng);
  const double th_m = orientation(false);
  const double g_d = draw_innate_rate(scene, rng);
  const double th_d = orientation(true);

  p.q[3 * i] = d.x - half * c;
  p.q[3 * i + 1] = d.y - half * s;
  p.q[3 * i + 2] = th_m;
  p.b[i] = b0;
  p.gamma0[i] = g_m;
  d.daughter_index = p.add_cell(d.x + half * c, d.y + half * s, th_d, b0, g_d, d.mother_id);
  d.daughter_id = p.id[d.daughter_index];
  return d;
}

std::vector<Division> grow_step(Packing& p, const std::vector<double>& rates, double dt, const Scene& scene, Rng& rng) {
  const std::size_t n = p.size();  // cells born in this step are appended past n: not grown
  if (rates.size() != n) throw std::invalid_argument("grow_step: one rate per cell expected");
  std::vector<Division> divisions;
  for (std::size_t i = 0; i < n; ++i) {
    p.b[i] = grown_bud(p.b[i], rates[i], dt);
    if (ready_to_divide(p.b[i], scene.alpha0)) divisions.push_back(divide(p, i, scene, rng));
  }
  return divisions;
}

std::optional<Eigen::VectorXd> coordinates_before_divisions(const Packing& further,
                                                            const std::vector<Division>& further_divisions,
                                                            const std::vector<Division>& divisions) {
  if (further_divisions.size() > further.size())
    throw std::invalid_argument("coordinates_before_divisions: more divisions than cells");
  const std::size_t n = further.size() - further_divisions.size();  // cells present before either step
  Eigen::VectorXd q(3 * (n + divisions.size()));
  q.head(3 * n) = further.q.head(3 * n);
  auto next = divisions.begin();
  for (const Division& fd : further_divisions) {
    const std::size_t m = fd.mother_index;
    if (next != divisions.end() && next->mother_index == m) {
      if (next->daughter_index != n + static_cast<std::size_t>(next - divisions.begin()))
        throw std::invalid_argument("coordinates_before_divisions: the steps did not start from the same cells");
      q.segment<3>(3 * next->daughter_index) = further.q.segment<3>(3 * fd.daughter_index);
      ++next;
      continue;
    }
    double dx = further.x(fd.daughter_index) - further.x(m), dy = further.y(fd.daughter_index) - further.y(m);
    further.box.minimum_image(dx, dy);
    q[3 * m] = further.x(m) + 0.5 * dx;
    q[3 * m + 1] = further.y(m) + 0.5 * dy;
    q[3 * m + 2] = std::atan2(dy, dx);
  }
  if (next != divisions.end()) return std::nullopt;
  return q;
}

Packing two_cell_start(const Scene& scene, Rng& rng) {
  const double a0 = scene.alpha0;
  const double arg = 2.5 * a0 - (a0 - 1.0) * (a0 - 1.0) - 2.0;
  if (!(arg > 0.0)) throw InputError("cells.alpha0: the two-cell start needs 2.5 α0 − (α0−1)² − 2 > 0");
  const double b_second = std::sqrt(arg) * kMotherDiameter;  // α = 1 + √(…)
  Packing p;
  p.box.L = scene.L;
  const double bs[2] = {newborn_bud(a0), b_second};
  const double ys[2] = {0.5 * scene.L - 0.5, 0.5 * scene.L + 0.5};
  for (int k = 0; k < 2; ++k) {
    const double g0 = draw_innate_rate(scene, rng);
    const double th = uniform_angle(rng);
    p.add_cell(0.5 * scene.L, ys[k], th, bs[k], g0, -1);
  }
  return p;
}

Packing random_seeds(const Scene& scene, Rng& rng) {
  Packing p;
  p.box.L = scene.L;
  const double L = scene.L;
  const double b0 = newborn_bud(scene.alpha0);
  const Dumbbell db = Dumbbell::of(b0);
  // Every lobe of a newborn lies within `reach` of its centroid.
  const double reach = std::max(db.mother_offset + 0.5 * db.D, db.bud_offset + 0.5 * db.b);
  // Bins at least 2·reach wide, and no more than about two per seed: a huge box with few seeds
  // must not allocate (L / reach)² bins (the cell list caps its grid the same way). Counts are
  // bounded in floating point before any conversion to int.
  const double fit = std::floor(L / (2.0 * reach));
  const double cap = std::floor(std::sqrt(2.0 * static_cast<double>(scene.n_seeds) + 9.0));
  const int nbin = static_cast<int>(std::max(1.0, std::min(fit, cap)));
  const double bin = L / nbin;
  std::vector<std::vector<std::size_t>> bins(static_cast<std::size_t>(nbin) * nbin);
  auto bin_of = [&](double v) { return static_cast<int>(std::clamp(std::floor(v / bin), 0.0, nbin - 1.0)); };
  auto lobes_of = [&](double x, double y, double th, double out[2][3]) {
    const Axis n = axis(th);
    const double c = n.c, s = n.s;
    out[0][0] = x - db.mother_offset * c, out[0][1] = y - db.mother_offset * s, out[0][2] = 0.5 * db.D;
    out[1][0] = x + db.bud_offset * c, out[1][1] = y + db.bud_offset * s, out[1][2] = 0.5 * db.b;
  };
  const Box box = p.box;
  const long max_attempts = 100000;
  for (std::size_t k = 0; k < scene.n_seeds; ++k) {
    bool placed = false;
    for (long attempt = 0; attempt < max_attempts && !placed; ++attempt) {
      const double x = L * uniform01(rng), y = L * uniform01(rng), th = uniform_angle(rng);
      double mine[2][3];
      lobes_of(x, y, th, mine);
      bool free = true;  // (with fewer than 3 bins a side the stencil revisits bins: harmless)
      const int bx = bin_of(x), by = bin_of(y);
      for (int dx = -1; dx <= 1 && free; ++dx)
        for (int dy = -1; dy <= 1 && free; ++dy) {
          const int cx = ((bx + dx) % nbin + nbin) % nbin, cy = ((by + dy) % nbin + nbin) % nbin;
          for (std::size_t j : bins[static_cast<std::size_t>(cx) * nbin + cy]) {
            double other[2][3];
            lobes_of(p.x(j), p.y(j), p.theta(j), other);
            for (auto& a : mine)
              for (auto& o : other) {
                double ddx = a[0] - o[0], ddy = a[1] - o[1];
                box.minimum_image(ddx, ddy);
                const double sig = a[2] + o[2];
                if (ddx * ddx + ddy * ddy < sig * sig) free = false;
              }
            if (!free) break;
          }
        }
      if (!free) continue;
      const double g0 = draw_innate_rate(scene, rng);
      const std::size_t idx = p.add_cell(x, y, th, b0, g0, -1);
      bins[static_cast<std::size_t>(bx) * nbin + by].push_back(idx);
      placed = true;
    }
    if (!placed)
      throw InputError("init.n_seeds: cannot place " + std::to_string(scene.n_seeds) +
                       " non-overlapping newborn cells in a box of side " + std::to_string(L) + " (placed " +
                       std::to_string(k) + ")");
  }
  return p;
}

Packing initial_state(const Scene& scene, Rng& rng) {
  switch (scene.init) {
    case InitialState::two_cells: return two_cell_start(scene, rng);
    case InitialState::random_seeds: return random_seeds(scene, rng);
  }
  throw std::logic_error("initial_state: unknown initial state");
}

}  // namespace budjam
