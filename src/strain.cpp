#include "budjam/strain.hpp"

#include "budjam/energy.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/moduli.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

namespace budjam {

void apply_simple_shear(Packing& p, double dgamma) {
  p.box.shear += dgamma;
  for (std::size_t i = 0; i < p.size(); ++i) p.q[3 * i] += dgamma * p.q[3 * i + 1];
}

void apply_isotropic_scaling(Packing& p, double factor) {
  if (!(factor > 0)) throw std::invalid_argument("apply_isotropic_scaling: factor must be positive");
  p.box.L *= factor;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] *= factor;
    p.q[3 * i + 1] *= factor;
  }
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs(const std::vector<Contact>& contacts) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(contacts.size());
  for (const Contact& c : contacts) pairs.emplace_back(std::min(c.i, c.j), std::max(c.i, c.j));
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

namespace {

struct Measured {
  StrainSample sample;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
};

Measured relax_and_measure(Packing& p, const FireParams& fire, double skin) {
  ForceField field(skin);
  Measured m;
  m.sample.fire = minimise(p, field, fire);
  Eigen::VectorXd F;
  m.sample.U = field.evaluate(p, F);
  const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
  m.sample.P = pressure(contacts, p.box);
  m.sample.stress = stress_tensor(contacts, p.box);
  m.sample.stress_energy = energy_stress(p, contacts);
  m.sample.stress_link = link_stress(p, contacts);
  m.sample.P_energy = -0.5 * m.sample.stress_energy.trace();
  m.pairs = contact_pairs(contacts);
  return m;
}

// Least-squares polynomial fit of degree `deg`; returns coefficients c0..c_deg. The abscissae are
// scaled to [−1, 1] first: strains of 1e-10 would make the x² column fall below the rank threshold.
Eigen::VectorXd polyfit(const std::vector<double>& x, const std::vector<double>& y, int deg) {
  double scale = 0;
  for (double v : x) scale = std::max(scale, std::abs(v));
  if (scale == 0) scale = 1;
  Eigen::MatrixXd V(static_cast<Eigen::Index>(x.size()), deg + 1);
  Eigen::VectorXd Y(static_cast<Eigen::Index>(x.size()));
  for (std::size_t k = 0; k < x.size(); ++k) {
    double pw = 1;
    for (int d = 0; d <= deg; ++d, pw *= x[k] / scale) V(static_cast<Eigen::Index>(k), d) = pw;
    Y[static_cast<Eigen::Index>(k)] = y[k];
  }
  Eigen::VectorXd c = V.colPivHouseholderQr().solve(Y);
  for (int d = 1; d <= deg; ++d) c[d] /= std::pow(scale, d);
  return c;
}

}  // namespace

std::vector<double> symmetric_strains(double h, int count) {
  std::vector<double> s;
  for (int k = count; k >= 1; --k) s.push_back(-k * h);
  for (int k = 1; k <= count; ++k) s.push_back(k * h);
  return s;
}

std::vector<double> doubling_strains(double h, int count) {
  std::vector<double> s;
  for (int k = count - 1; k >= 0; --k) s.push_back(-std::ldexp(h, k));
  for (int k = 0; k < count; ++k) s.push_back(std::ldexp(h, k));
  return s;
}

StrainSweep strain_sweep(const Packing& reference, StrainKind kind, const std::vector<double>& strains,
                         const FireParams& fire, double skin) {
  StrainSweep sweep;
  sweep.kind = kind;
  Packing ref = reference;
  Measured m0 = relax_and_measure(ref, fire, skin);
  m0.sample.strain = 0;
  std::vector<StrainSample> samples{m0.sample};
  for (double s : strains) {
    if (s == 0) continue;
    Packing p = ref;
    if (kind == StrainKind::simple_shear) apply_simple_shear(p, s);
    else apply_isotropic_scaling(p, std::exp(0.5 * s));
    Measured m = relax_and_measure(p, fire, skin);
    m.sample.strain = s;
    m.sample.same_contacts = (m.pairs == m0.pairs);
    samples.push_back(m.sample);
  }
  std::sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.strain < b.strain; });
  sweep.samples = samples;

  std::vector<double> x, y, ye, u;
  for (const auto& s : sweep.samples) {
    sweep.all_converged = sweep.all_converged && s.fire.converged;
    if (!s.same_contacts) continue;
    x.push_back(s.strain);
    u.push_back(s.U);
    if (kind == StrainKind::simple_shear) {
      y.push_back(s.stress(0, 1));
      ye.push_back(0.5 * (s.stress_energy(0, 1) + s.stress_energy(1, 0)));
    } else {
      y.push_back(-s.P);
      ye.push_back(-s.P_energy);
    }
  }
  sweep.used = x.size();
  if (x.size() >= 2) {
    sweep.modulus = polyfit(x, y, 1)[1];
    sweep.modulus_energy = polyfit(x, ye, 1)[1];
  }
  const double A = reference.box.L * reference.box.L;
  if (x.size() >= 3) {
    const Eigen::VectorXd c = polyfit(x, u, 2);
    sweep.energy_slope = c[1] / A;
    sweep.curvature = 2.0 * c[2] / A;
  }
  // Central second differences about the relaxed reference (samples sorted by strain).
  const auto zero = std::find_if(sweep.samples.begin(), sweep.samples.end(), [](const auto& s) { return s.strain == 0; });
  for (const StrainSample& plus : sweep.samples) {
    if (!(plus.strain > 0) || !plus.same_contacts) continue;
    const auto minus = std::find_if(sweep.samples.begin(), sweep.samples.end(),
                                    [&](const auto& s) { return s.strain == -plus.strain && s.same_contacts; });
    if (minus == sweep.samples.end()) continue;
    const double h = plus.strain;
    sweep.central_curvatures.emplace_back(h, (plus.U - 2 * zero->U + minus->U) / (A * h * h));
  }
  return sweep;
}

Packing random_dumbbells(std::size_t n, double phi, double b_min, double b_max, std::uint64_t seed) {
  if (n == 0 || !(phi > 0 && phi < 0.6) || !(b_min >= 0) || !(b_max >= b_min) || b_max > 1.2 * kMotherDiameter)
    throw std::invalid_argument("random_dumbbells: need n > 0, 0 < phi < 0.6, 0 ≤ b_min ≤ b_max ≤ 1.2");
  std::mt19937_64 rng(seed);
  auto uni = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  std::vector<double> b(n);
  double area = 0;
  for (auto& bi : b) {
    bi = b_min + (b_max - b_min) * uni();
    area += 0.25 * std::numbers::pi * (kMotherDiameter * kMotherDiameter + bi * bi);
  }
  Packing p;
  p.box.L = std::sqrt(area / phi);
  const double L = p.box.L;
  // Random sequential addition: no overlaps, so FIRE never starts from interpenetrated cells
  // (a lobe trapped between the two lobes of another cell is a self-stressed local minimum).
  // Grid of centroids with cells of side ≥ 2 × the largest centroid-to-lobe-edge distance.
  const double reach = 0.5 * (kMotherDiameter + 1.2) + 0.6;
  const int g = std::max(1, static_cast<int>(L / (2 * reach)));
  const double cell = L / g;
  std::vector<std::vector<std::size_t>> grid(static_cast<std::size_t>(g * g));
  auto lobes_of = [&](double x, double y, double th, double bi, double out[2][3]) {
    const Dumbbell d = Dumbbell::of(bi);
    out[0][0] = x - d.mother_offset * std::cos(th), out[0][1] = y - d.mother_offset * std::sin(th), out[0][2] = 0.5 * d.D;
    out[1][0] = x + d.bud_offset * std::cos(th), out[1][1] = y + d.bud_offset * std::sin(th), out[1][2] = 0.5 * d.b;
  };
  std::vector<std::array<double, 6>> placed;  // lobe centres and radii of placed cells
  for (std::size_t i = 0; i < n; ++i) {
    bool ok = false;
    for (int attempt = 0; attempt < 100000 && !ok; ++attempt) {
      const double x = L * uni(), y = L * uni(), th = 2 * std::numbers::pi * (uni() - 0.5);
      double lo[2][3];
      lobes_of(x, y, th, b[i], lo);
      const int gx = std::min(g - 1, static_cast<int>(x / cell)), gy = std::min(g - 1, static_cast<int>(y / cell));
      ok = true;
      for (int dx = -1; dx <= 1 && ok; ++dx)
        for (int dy = -1; dy <= 1 && ok; ++dy) {
          if (g < 3 && (dx != 0 || dy != 0)) continue;  // tiny box: one cell holds everything
          const auto& bucket = grid[static_cast<std::size_t>(((gx + dx + g) % g) * g + (gy + dy + g) % g)];
          for (std::size_t k : bucket) {
            const auto& o = placed[k];
            for (int a = 0; a < 2 && ok; ++a)
              for (int c = 0; c < 2 && ok; ++c) {
                double ddx = lo[a][0] - o[3 * c], ddy = lo[a][1] - o[3 * c + 1];
                p.box.minimum_image(ddx, ddy);
                if (std::hypot(ddx, ddy) < lo[a][2] + o[3 * c + 2]) ok = false;
              }
            if (!ok) break;
          }
        }
      if (ok) {
        p.add_cell(x, y, th, b[i], 0.002, -1);
        placed.push_back({lo[0][0], lo[0][1], lo[0][2], lo[1][0], lo[1][1], lo[1][2]});
        grid[static_cast<std::size_t>(gx * g + gy)].push_back(i);
      }
    }
    if (!ok) throw std::invalid_argument("random_dumbbells: cannot place cell " + std::to_string(i) + " at phi = " + std::to_string(phi));
  }
  return p;
}

CompressionResult compress_to_pressure(Packing start, double P_target, const FireParams& fire, double ratio,
                                       int max_rescalings) {
  if (!(P_target > 0) || !(ratio > 1)) throw std::invalid_argument("compress_to_pressure: need P_target > 0, ratio > 1");
  CompressionResult res;
  ForceField field;
  struct State {
    Packing p;
    double lphi = 0, P = 0, B = 0;  // ln φ, pressure, dP/d ln φ (linear response; 0 if unjammed)
  };
  auto relax = [&](Packing q) {
    State s;
    const FireResult fr = minimise(q, field, fire);
    res.fire_iterations += fr.iterations;
    Eigen::VectorXd F;
    field.evaluate(q, F);
    const auto contacts = find_contacts(q, field.lobes(), field.neighbours());
    s.P = pressure(contacts, q.box);
    s.lphi = std::log(q.packing_fraction());
    if (s.P > 0) {
      const ContactNetwork net = analyse_network(q.size(), contacts);
      try {
        const ElasticResponse r = elastic_response(q, contacts, net);
        if (r.kernel.well_posed && r.moduli.B > 0) s.B = r.moduli.B;
      } catch (const std::runtime_error&) {
        // not at a minimum yet (FIRE stopped early): no slope, bisect instead
      }
    }
    s.p = std::move(q);
    return s;
  };
  auto rescaled = [](const Packing& from, double lphi) {
    Packing q = from;
    apply_isotropic_scaling(q, std::exp(0.5 * (std::log(q.packing_fraction()) - lphi)));
    return q;
  };
  State cur = relax(std::move(start));
  std::optional<State> lo, hi;  // below / above the window
  double step = 0.02;
  for (res.rescalings = 0; res.rescalings < max_rescalings; ++res.rescalings) {
    if (cur.P >= P_target / ratio && cur.P <= P_target * ratio) {
      res.converged = true;
      break;
    }
    if (cur.P < P_target / ratio) lo = cur;
    else hi = cur;
    double next;
    const Packing* from;
    if (!hi) {  // still below: compress by growing steps
      next = lo->lphi + step;
      step *= 1.5;
      from = &lo->p;
    } else {
      // Decompress from the jammed end (its network survives small steps, FIRE is fast there):
      // Newton with the linear-response slope B = dP/d ln φ, kept inside the bracket.
      next = hi->B > 0 ? hi->lphi - std::min((hi->P - P_target) / hi->B, 0.05) : hi->lphi - step;
      if (lo) {
        const double w = hi->lphi - lo->lphi;
        if (!(next > lo->lphi + 0.05 * w && next < hi->lphi - 0.05 * w)) next = 0.5 * (lo->lphi + hi->lphi);
      }
      from = &hi->p;
    }
    cur = relax(rescaled(*from, next));
  }
  res.packing = std::move(cur.p);
  res.P = cur.P;
  res.phi = res.packing.packing_fraction();
  return res;
}

}  // namespace budjam
