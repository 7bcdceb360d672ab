#pragma once
// Compressed test packings without a growth run: random dumbbells (random_packing.hpp) compressed
// with FIRE, either to just above their jamming point (compress_random_dumbbells) or to a target
// pressure (compress_to_pressure).
//
// compress_random_dumbbells (docs/spectrum.md, "Test packings"):
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
#include "budjam/fire.hpp"
#include "budjam/packing.hpp"

#include <cstdint>
#include <vector>

namespace budjam::testing {

struct CompressionProtocol {
  double phi_start = 0.40;
  double dphi_step = 0.01;
  double jam_energy = 1e-12;  // E/N above this after FIRE: jammed
  long probe_iterations = 20000;
  double force_tol = 1e-12;  // FIRE stopping force for the final state
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
void rescale_to(Packing& p, double phi_new);

CompressedPacking compress_random_dumbbells(std::size_t n, std::uint64_t seed, const CompressionProtocol& proto = {});

struct CompressionResult {
  Packing packing;  // relaxed, P within [P_target/ratio, P_target·ratio]
  double P = 0;
  double phi = 0;
  int rescalings = 0;  // isotropic rescalings tried
  long fire_iterations = 0;
  bool converged = false;
};

// Isotropic compression/decompression (box + centroids) with FIRE after each rescaling until the
// relaxed pressure lies within a factor `ratio` of P_target: first expands or compresses by
// factors until the target is bracketed, then bisects in ln φ. Works from any start (overlapping
// or loose).
CompressionResult compress_to_pressure(Packing start, double P_target, const FireParams& fire, double ratio = 1.5,
                                       int max_rescalings = 200);

// Largest difference between two relaxations of the same packing in the position of a lobe that
// carries a contact in `net`, after removing the mean translation (a zero mode of U). Free lobes
// are left out: a rattler, or a contact-free bud turning about its mother, moves at no cost.
double largest_lobe_difference(const Packing& a, const Packing& b, const ContactNetwork& net);

}  // namespace budjam::testing
