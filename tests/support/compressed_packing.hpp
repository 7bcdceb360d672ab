#pragma once
// Jammed test packings without a growth run: random dumbbells compressed with FIRE to just above
// their jamming point. Used by tests/test_spectrum.cpp and bench/bench_spectrum.cpp (header-only
// so that both can include it).
//
// Protocol (docs/spectrum.md, "Test packings"):
//  1. N cells with bud diameters b uniform in [0.01, 1.02] (the range a growing population
//     covers), orientations uniform, centroids uniform in a box at φ = phi_start, placed one by
//     one without overlap (random sequential addition). Overlapping random placement is not
//     an option: FIRE then often stops in tangled local minima (a small bud inside another
//     cell's lobe) with a large energy at low φ.
//  2. Compress affinely (box and centroids) in steps of dphi_step, relaxing with FIRE after each
//     (at most probe_iterations iterations: unjammed states near φ_J relax very slowly and need
//     not be converged). The first state whose E/N stays above jam_energy is relaxed fully
//     (force_tol); if it is still above jam_energy it is the packing: φ_J < φ ≤ φ_J + dphi_step.
//     No bisection: the tests need a jammed packing, not φ_J.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/packing.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace budjam::testing {

struct CompressionProtocol {
  double phi_start = 0.40;
  double dphi_step = 0.01;
  double jam_energy = 1e-12;    // E/N above this after FIRE: jammed
  long probe_iterations = 20000;
  double force_tol = 1e-12;     // FIRE stopping force for the final state
  double b_min = 0.01, b_max = 1.02;
};

struct CompressedPacking {
  Packing packing;
  double phi_below = 0;  // last φ found unjammed (φ_J lies in (phi_below, phi])
  double phi = 0;
  double energy_per_cell = 0;
  long fire_iterations = 0;
  std::vector<Contact> contacts;
  ContactNetwork network;
};

// Scales the box and all centroids so that φ becomes phi_new.
inline void rescale_to(Packing& p, double phi_new) {
  const double f = std::sqrt(p.packing_fraction() / phi_new);
  p.box.L *= f;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] *= f;
    p.q[3 * i + 1] *= f;
  }
}

inline CompressedPacking compress_random_dumbbells(std::size_t n, std::uint64_t seed,
                                                   const CompressionProtocol& proto = {}) {
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

}  // namespace budjam::testing
