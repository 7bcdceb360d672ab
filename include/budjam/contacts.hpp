#pragma once
// Lobe–lobe contacts of a relaxed packing and the mechanical observables they carry
// (docs/model.md, "Interaction and energy").
#include <Eigen/Core>
#include <cstdint>
#include <vector>
#include "budjam/packing.hpp"

namespace budjam {

class NeighbourList;

// One overlapping pair of lobes on different cells. `n` is the unit vector from lobe `j` to lobe
// `i` (minimum image), `r` the centre distance, `sigma` = R_i + R_j; the repulsive force on lobe i
// is f n with f = k (σ − r).
struct Contact {
  std::uint32_t i, j;  // lobe indices (cell = lobe/2, bud if odd), i < j
  double nx, ny;
  double r, sigma;
  double force() const { return kSpring * (sigma - r); }
  double overlap() const { return sigma - r; }
};

// All pairs with r < σ, taken from the neighbour list (which must be current for `lobes`).
// r = σ exactly is not a contact. Ordered like the list's pairs (by (i, j)).
std::vector<Contact> find_contacts(const Packing& p, const Lobes& lobes, const NeighbourList& list);

// The normal used when lobes i and j (different cells) have coincident centres, r = 0: the
// minimum-image direction from the centroid of j's cell to the centroid of i's cell, or +x when
// those coincide too. Deterministic and antisymmetric in (i, j) up to the +x fallback.
void coincident_normal(const Packing& p, std::size_t i, std::size_t j, double& nx, double& ny);

// P = (1/(2L²)) Σ f r   (r is the lobe-centre distance)
double pressure(const std::vector<Contact>& contacts, const Box& box);

// Σ_αβ = −(1/L²) Σ f r̂_α r_β with r the lobe-centre vector; P = −(Σ_xx + Σ_yy)/2
Eigen::Matrix2d stress_tensor(const std::vector<Contact>& contacts, const Box& box);

// The stress of an affine deformation of the centroids (cells move rigidly, the box deforms):
// Σᶜ_αβ = −(1/L²) Σ f n_α R_β with R the minimum-image centroid-to-centroid vector of the contact.
// It is exactly (1/L²) ∂U/∂ε_αβ, so Σᶜ_xy = (1/L²) dU/dγ under Lees–Edwards shear of the centroids
// and −tr Σᶜ/2 = −dU/dA under affine compression of the centroids. It is symmetric when every
// cell is torque-balanced. It is NOT stress_tensor (the model's contact virial): in a force- and torque-balanced
// packing Σ = Σᶜ − (1/L²) Σ_cells s (F_bud·n̂) n̂n̂ᵀ, the virial of the rigid mother–bud bars
// (s = lobe separation, F_bud = total contact force on the bud, parallel to n̂ in balance).
Eigen::Matrix2d centroid_stress_tensor(const Packing& p, const std::vector<Contact>& contacts);
// −(Σᶜ_xx + Σᶜ_yy)/2 = −dU/dA under affine compression of box and centroids.
double centroid_pressure(const Packing& p, const std::vector<Contact>& contacts);

// p_i = Σ_{contacts on the bud of i} f / (π b_i), one entry per cell (0 for a bud with no contact).
std::vector<double> bud_pressures(const Packing& p, const std::vector<Contact>& contacts);

}  // namespace budjam
