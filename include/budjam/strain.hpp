#pragma once
// Finite affine strains of a packing, relaxed with FIRE: the independent check of the linear
// response (issue 3.5) and the finite-strain definitions of MODEL.md ("Linear-response
// conventions").
//
// The strain maps box and centroids affinely and leaves orientations alone (cells are rigid):
//  - Lees–Edwards simple shear by δγ: box.shear += δγ, x_i += δγ y_i (unwrapped coordinates, so
//    every minimum-image separation transforms exactly as (1 + e) with e_xy = δγ);
//  - isotropic rescaling by a factor λ: L → λL, (x_i, y_i) → λ (x_i, y_i).
#include "budjam/contacts.hpp"
#include "budjam/fire.hpp"
#include "budjam/packing.hpp"
#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

namespace budjam {

void apply_simple_shear(Packing& p, double dgamma);
void apply_isotropic_scaling(Packing& p, double factor);

// One relaxed state of a sweep.
struct StrainSample {
  double strain = 0;         // γ (shear) or ε = ln(A/A0) (rescaling: A = L², so λ = exp(ε/2))
  double U = 0;              // energy after relaxation
  double P = 0;              // MODEL.md contact-virial pressure
  double P_energy = 0;       // −tr τ / 2 (energy stress, moduli.hpp)
  Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();         // MODEL.md S
  Eigen::Matrix2d stress_energy = Eigen::Matrix2d::Zero();  // τ
  bool same_contacts = true; // the set of contacting lobe pairs equals the unstrained one
  FireResult fire;
};

enum class StrainKind { simple_shear, isotropic };

struct StrainSweep {
  StrainKind kind = StrainKind::simple_shear;
  std::vector<StrainSample> samples;  // includes strain 0 (the reference, relaxed again)
  // Least-squares slopes over the samples that kept the contact set (strain 0 included):
  //   simple shear: G = dS_xy/dγ, G_energy = dτ_xy/dγ (symmetrised), and d²U/dγ² / A from a
  //                 parabola fit;
  //   isotropic:    B = −dP/dε, B_energy = −dP_energy/dε with ε = ln(A/A0) (B = −A dP/dA = φ dP/dφ).
  double modulus = 0, modulus_energy = 0, curvature = 0;
  std::size_t used = 0;       // samples in the fit
  bool all_converged = true;  // every FIRE relaxation converged
};

// Relaxes `reference` (must already be relaxed; it is relaxed again at strain 0 with `fire`),
// then for each strain s (≠ 0) applies it to a copy of the reference and relaxes. Strains for the
// isotropic kind are ε = ln(A/A0).
StrainSweep strain_sweep(const Packing& reference, StrainKind kind, const std::vector<double>& strains,
                         const FireParams& fire, double skin = 0.3);

// Symmetric strains ±h, ±2h, …, ±count·h.
std::vector<double> symmetric_strains(double h, int count);

// The sorted list of contacting lobe pairs (i < j) of a contact list.
std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs(const std::vector<Contact>& contacts);

}  // namespace budjam
