#pragma once
// Finite affine strains of a packing, relaxed with FIRE: the independent check of the linear
// response and the paper's finite-strain definitions of B and G (docs/moduli.md).
//
// The strain maps box and centroids affinely and leaves orientations alone (cells are rigid):
//  - Lees–Edwards simple shear by δγ: box.shear += δγ, x_i += δγ y_i (unwrapped coordinates, so
//    every minimum-image separation transforms exactly as (1 + e) with e_xy = δγ);
//  - isotropic rescaling by a factor λ: L → λL, (x_i, y_i) → λ (x_i, y_i).
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>
#include "budjam/contacts.hpp"
#include "budjam/fire.hpp"
#include "budjam/packing.hpp"

namespace budjam {

void apply_simple_shear(Packing& p, double dgamma);
void apply_isotropic_scaling(Packing& p, double factor);

// One relaxed state of a sweep.
struct StrainSample {
  double strain = 0;    // γ (shear) or ε = ln(A/A0) (rescaling: A = L², so λ = exp(ε/2))
  double U = 0;         // energy after relaxation
  double P = 0;         // lobe-centre contact-virial pressure
  double P_energy = 0;  // −tr τ / 2 (energy stress, moduli.hpp)
  Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();         // S (lobe-centre contact virial)
  Eigen::Matrix2d stress_energy = Eigen::Matrix2d::Zero();  // τ
  Eigen::Matrix2d stress_link = Eigen::Matrix2d::Zero();    // load of the mother–bud links (link_stress)
  bool same_contacts = true;  // the set of contacting lobe pairs equals the unstrained one
  FireResult fire;
};

enum class StrainKind { simple_shear, isotropic };

struct StrainSweep {
  StrainKind kind = StrainKind::simple_shear;
  std::vector<StrainSample> samples;  // includes strain 0 (the reference, relaxed again)
  // Least-squares slopes over the samples that kept the contact set (strain 0 included):
  //   simple shear: G = dS_xy/dγ, G_energy = dτ_xy/dγ (symmetrised);
  //   isotropic:    B = −dP/dε, B_energy = −dP_energy/dε with ε = ln(A/A0) (B = −A dP/dA = φ dP/dφ).
  // NaN where fewer than two samples kept the contact set (fewer than three for the energy's).
  double modulus = std::numeric_limits<double>::quiet_NaN(), modulus_energy = std::numeric_limits<double>::quiet_NaN();
  // The relaxed energy U(s) alone, per reference area A0: a parabola fit over the same samples gives
  // energy_slope = (1/A0) dU/ds and curvature = (1/A0) d²U/ds² at s = 0, and for each strain h
  // whose pair ±h kept the contacts, central_curvatures holds (h, (U(h) − 2U(0) + U(−h)) / (A0 h²)).
  //   simple shear: energy_slope = τ_xy, curvature = G_energy (= E_xyxy);
  //   isotropic (A = A0 e^ε): energy_slope = −P_energy, curvature − energy_slope = B_energy
  //                           (= energy_modulus()).
  // NaN unless three samples kept the contact set with at least one on either side of s = 0.
  double energy_slope = std::numeric_limits<double>::quiet_NaN(), curvature = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<double, double>> central_curvatures;
  // The modulus from the energy alone: G_energy = curvature (shear), B_energy = A d²U/dA² =
  // curvature − energy_slope (isotropic).
  double energy_modulus() const { return kind == StrainKind::simple_shear ? curvature : curvature - energy_slope; }
  std::size_t used = 0;       // samples in the fit
  bool all_converged = true;  // every FIRE relaxation converged
};

// Relaxes `reference` (must already be relaxed; it is relaxed again at strain 0 with `fire`),
// then for each strain s (≠ 0) applies it to a copy of the reference and relaxes. Strains for the
// isotropic kind are ε = ln(A/A0).
StrainSweep strain_sweep(const Packing& reference, StrainKind kind, const std::vector<double>& strains,
                         const FireParams& fire, double skin = kDefaultSkin);

// Symmetric strains ±h, ±2h, …, ±count·h.
std::vector<double> symmetric_strains(double h, int count);
// Symmetric doubling strains ±h, ±2h, ±4h, …, ±2^(count−1)·h: for the energy curvature, whose
// rounding noise (that of the overlaps in U) falls as 1/h², the largest pair that keeps the contacts
// matters most.
std::vector<double> doubling_strains(double h, int count);

// The sorted list of contacting lobe pairs (i < j) of a contact list.
std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs(const std::vector<Contact>& contacts);

}  // namespace budjam
