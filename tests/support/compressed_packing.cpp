#include "compressed_packing.hpp"

#include "budjam/energy.hpp"
#include "budjam/moduli.hpp"
#include "budjam/strain.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>

namespace budjam::testing {

void rescale_to(Packing& p, double phi_new) {
  const double f = std::sqrt(p.packing_fraction() / phi_new);
  p.box.L *= f;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] *= f;
    p.q[3 * i + 1] *= f;
  }
}

CompressedPacking compress_random_dumbbells(std::size_t n, std::uint64_t seed, const CompressionProtocol& proto) {
  std::mt19937_64 rng(seed);
  auto u01 = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  Packing p;
  double area = 0;
  std::vector<double> buds(n);
  for (auto& b : buds) {
    b = proto.b_min + (proto.b_max - proto.b_min) * u01();
    area += 0.25 * std::numbers::pi * (1 + b * b);
  }
  p.box.L = std::sqrt(area / proto.phi_start);
  // Random sequential addition on a grid of bins ≥ 2.1 wide (a cell is at most 2.02 long, so
  // cells whose centroids are more than one bin apart cannot overlap).
  const double L = p.box.L;
  const int nb = std::max(1, static_cast<int>(L / 2.1));
  const double w = L / nb;
  std::vector<std::vector<std::size_t>> bins(static_cast<std::size_t>(nb) * nb);
  auto bin_of = [&](double v) { return std::min(nb - 1, static_cast<int>(v / w)); };
  Lobes mine;
  for (std::size_t i = 0; i < n; ++i) {
    for (long attempt = 0;; ++attempt) {
      if (attempt > 100000) throw std::runtime_error("compress_random_dumbbells: box too crowded to place cells");
      const double x = L * u01(), y = L * u01();
      const double th = std::numbers::pi * (2 * u01() - 1);
      Packing one;
      one.box = p.box;
      one.add_cell(x, y, th, buds[i], 0.002, -1);
      place_lobes(one, mine);
      bool free = true;
      const int bx = bin_of(x), by = bin_of(y);
      for (int dx = -1; dx <= 1 && free; ++dx)
        for (int dy = -1; dy <= 1 && free; ++dy) {
          const auto& bin = bins[static_cast<std::size_t>((bx + dx + nb) % nb) * nb + (by + dy + nb) % nb];
          for (std::size_t j : bin) {
            const Dumbbell d = p.dumbbell(j);
            const double c = std::cos(p.theta(j)), s = std::sin(p.theta(j));
            const double ox[2] = {p.x(j) - d.mother_offset * c, p.x(j) + d.bud_offset * c};
            const double oy[2] = {p.y(j) - d.mother_offset * s, p.y(j) + d.bud_offset * s};
            const double oR[2] = {0.5 * d.D, 0.5 * d.b};
            for (int a = 0; a < 2 && free; ++a)
              for (int b = 0; b < 2 && free; ++b) {
                double ddx = mine.x[a] - ox[b], ddy = mine.y[a] - oy[b];
                p.box.minimum_image(ddx, ddy);
                if (ddx * ddx + ddy * ddy < (mine.R[a] + oR[b]) * (mine.R[a] + oR[b])) free = false;
              }
            if (!free) break;
          }
        }
      if (!free) continue;
      p.add_cell(x, y, th, buds[i], 0.002, -1);
      bins[static_cast<std::size_t>(bx) * nb + by].push_back(i);
      break;
    }
  }

  CompressedPacking out;
  ForceField field;
  auto relax = [&](Packing& q, double force_tol, long max_iterations) {
    FireParams fire;
    fire.newton_force = 0.0;  // FIRE alone, as the tests' packings were calibrated
    fire.force_tol = force_tol;
    fire.max_iterations = max_iterations;
    field.invalidate();
    const FireResult r = minimise(q, field, fire);
    out.fire_iterations += r.iterations;
    return r;
  };

  double phi = p.packing_fraction();
  relax(p, 1e-10, proto.probe_iterations);
  for (;;) {
    phi += proto.dphi_step;
    rescale_to(p, phi);
    if (relax(p, 1e-10, proto.probe_iterations).energy / static_cast<double>(n) <= proto.jam_energy) {
      out.phi_below = phi;
      continue;
    }
    const FireResult r = relax(p, proto.force_tol, 10000000);
    if (!r.converged) throw std::runtime_error("compress_random_dumbbells: FIRE did not converge");
    out.energy_per_cell = r.energy / static_cast<double>(n);
    if (out.energy_per_cell > proto.jam_energy) break;
    out.phi_below = phi;
  }
  out.phi = p.packing_fraction();
  field.invalidate();
  Eigen::VectorXd f;
  field.evaluate(p, f);
  out.contacts = find_contacts(p, field.lobes(), field.neighbours());
  out.network = analyse_network(p.size(), out.contacts);
  out.packing = std::move(p);
  return out;
}

CompressionResult compress_to_pressure(Packing start, double P_target, const FireParams& fire, double ratio,
                                       int max_rescalings) {
  if (!(P_target > 0) || !(ratio > 1))
    throw std::invalid_argument("compress_to_pressure: need P_target > 0, ratio > 1");
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
    if (cur.P < P_target / ratio)
      lo = cur;
    else
      hi = cur;
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

double largest_lobe_difference(const Packing& a, const Packing& b, const ContactNetwork& net) {
  Lobes la, lb;
  place_lobes(a, la);
  place_lobes(b, lb);
  double mx = 0, my = 0, n = 0;
  for (std::size_t l = 0; l < la.size(); ++l)
    if (net.lobe_contacts[l] > 0) mx += lb.x[l] - la.x[l], my += lb.y[l] - la.y[l], n += 1;
  double d = 0;
  for (std::size_t l = 0; l < la.size(); ++l)
    if (net.lobe_contacts[l] > 0)
      d = std::max({d, std::abs(lb.x[l] - la.x[l] - mx / n), std::abs(lb.y[l] - la.y[l] - my / n)});
  return d;
}

}  // namespace budjam::testing
