#pragma once
// The state of a budding-cell packing: rigid mother–bud dumbbells in a periodic square box
// (docs/model.md, "One cell"). Units: mother diameter D0 = 1, spring constant k = 1.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>
#include "budjam/orientation.hpp"

namespace budjam {

inline constexpr double kMotherDiameter = 1.0;  // D0
inline constexpr double kSpring = 1.0;          // k

// Periodic square box; `shear` is the Lees–Edwards strain γ (an image one box up in y is
// shifted by γL in x). Zero except while measuring a shear response.
struct Box {
  double L = 0.0;
  double shear = 0.0;

  // Minimum-image separation vector (dx, dy), in place.
  void minimum_image(double& dx, double& dy) const {
    const double ny = std::nearbyint(dy / L);
    dx -= shear * L * ny;
    dy -= ny * L;
    dx -= L * std::nearbyint(dx / L);
  }
};

// Geometry and inertia of one dumbbell about its area-weighted centroid.
struct Dumbbell {
  double D;              // mother diameter
  double b;              // bud diameter
  double separation;     // s = (D + b)/2, lobe centres tangent
  double mother_offset;  // |centroid → mother centre| = s b²/(D² + b²)
  double bud_offset;     // |centroid → bud centre|    = s D²/(D² + b²)
  double area;           // (π/4)(D² + b²)
  double mass;           // 1 + (b/D)²  (mother mass 1 at uniform areal density)
  double inertia;        // Σ_lobes m (ℓ² + R²/2)
  double gyration;       // r_g = sqrt(I/m): scales θ into a length for FIRE

  static Dumbbell of(double b, double D = kMotherDiameter) {
    Dumbbell d{};
    d.D = D;
    d.b = b;
    d.separation = 0.5 * (D + b);
    const double D2 = D * D, b2 = b * b;
    d.mother_offset = d.separation * b2 / (D2 + b2);
    d.bud_offset = d.separation * D2 / (D2 + b2);
    d.area = 0.25 * std::numbers::pi * (D2 + b2);
    const double m_mother = 1.0, m_bud = b2 / D2;
    d.mass = m_mother + m_bud;
    d.inertia = m_mother * (d.mother_offset * d.mother_offset + 0.125 * D2) +
                m_bud * (d.bud_offset * d.bud_offset + 0.125 * b2);
    d.gyration = std::sqrt(d.inertia / d.mass);
    return d;
  }
};

// Lobe indexing used everywhere: lobe 2i is the mother of cell i, lobe 2i+1 its bud.
inline constexpr std::size_t mother_lobe(std::size_t cell) { return 2 * cell; }
inline constexpr std::size_t bud_lobe(std::size_t cell) { return 2 * cell + 1; }
inline constexpr std::size_t cell_of(std::size_t lobe) { return lobe / 2; }
inline constexpr bool is_bud(std::size_t lobe) { return lobe % 2 == 1; }

// Structure of arrays. Coordinates live in one Eigen vector q = [x0, y0, θ0, x1, y1, θ1, …]
// so that the minimiser, the Hessian and the solvers share one layout. (x, y) is the
// area-weighted centroid, θ the angle of n̂ (mother → bud); positions are not wrapped.
struct Packing {
  Box box;
  Eigen::VectorXd q;                 // 3N generalised coordinates
  std::vector<double> b;             // bud diameters
  std::vector<double> gamma0;        // innate growth rates γ0_i
  std::vector<std::int64_t> id;      // lineage identity
  std::vector<std::int64_t> parent;  // id of the mother cell, −1 for founders
  std::int64_t next_id = 0;

  std::size_t size() const { return b.size(); }
  double x(std::size_t i) const { return q[3 * i]; }
  double y(std::size_t i) const { return q[3 * i + 1]; }
  double theta(std::size_t i) const { return q[3 * i + 2]; }
  Dumbbell dumbbell(std::size_t i) const { return Dumbbell::of(b[i]); }

  // φ = Σ A_cell / L² (overlaps not subtracted)
  double packing_fraction() const {
    double area = 0.0;
    for (double bi : b) area += 0.25 * std::numbers::pi * (kMotherDiameter * kMotherDiameter + bi * bi);
    return area / (box.L * box.L);
  }

  // Appends a cell; returns its index.
  std::size_t add_cell(double x, double y, double theta, double bud, double g0, std::int64_t parent_id) {
    const auto n = size();
    q.conservativeResize(3 * (n + 1));
    q[3 * n] = x;
    q[3 * n + 1] = y;
    q[3 * n + 2] = theta;
    b.push_back(bud);
    gamma0.push_back(g0);
    id.push_back(next_id++);
    parent.push_back(parent_id);
    return n;
  }
};

// Centres and radii of all 2N lobes (mother 2i, bud 2i+1), recomputed from q.
struct Lobes {
  std::vector<double> x, y, R;
  std::size_t size() const { return R.size(); }
};

inline void place_lobes(const Packing& p, Lobes& lobes) {
  const auto n = p.size();
  lobes.x.resize(2 * n);
  lobes.y.resize(2 * n);
  lobes.R.resize(2 * n);
  std::vector<double> theta(n), c(n), s(n);
  for (std::size_t i = 0; i < n; ++i) theta[i] = p.theta(i);
  axes(theta.data(), n, c.data(), s.data());  // the force field's axes, bit for bit
  for (std::size_t i = 0; i < n; ++i) {
    const Dumbbell d = p.dumbbell(i);
    lobes.x[2 * i] = p.x(i) - d.mother_offset * c[i];
    lobes.y[2 * i] = p.y(i) - d.mother_offset * s[i];
    lobes.R[2 * i] = 0.5 * d.D;
    lobes.x[2 * i + 1] = p.x(i) + d.bud_offset * c[i];
    lobes.y[2 * i + 1] = p.y(i) + d.bud_offset * s[i];
    lobes.R[2 * i + 1] = 0.5 * d.b;
  }
}

}  // namespace budjam
