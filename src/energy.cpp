// Harmonic lobe–lobe energy and its exact gradient over (x, y, θ) of each rigid dumbbell.
#include "budjam/energy.hpp"

#include "budjam/contacts.hpp"

#include <cmath>

namespace budjam {

namespace {

// Round to nearest (ties to even) for |v| < 2^51, as std::nearbyint in the default rounding
// mode, without a library call (nearbyint is not inlined on baseline x86-64): adding 1.5·2^52
// pushes the fraction bits out of the mantissa.
inline double round_nearest(double v) {
  constexpr double magic = 6755399441055744.0;  // 1.5 · 2^52
  return (v + magic) - magic;
}

// Minimum image with a precomputed 1/L (no division or library call per pair). Agrees with
// Box::minimum_image except when |dy| or |dx| is within an ulp of L/2, which no pair within the
// cut-off reaches (the scene requires L > 2 (σ_max + skin)).
struct FastImage {
  double L, inv_L, shift;
  explicit FastImage(const Box& box) : L(box.L), inv_L(1.0 / box.L), shift(box.shear * box.L) {}
  void apply(double& dx, double& dy) const {
    const double ny = round_nearest(dy * inv_L);
    dx -= shift * ny;
    dy -= ny * L;
    dx -= L * round_nearest(dx * inv_L);
  }
};

}  // namespace

ForceField::ForceField(double skin) : list_(skin) {}

void ForceField::invalidate() { list_.invalidate(); }

void ForceField::refresh(const Packing& p) {
  const std::size_t n = p.size();
  if (b_cached_.size() != n) {
    b_cached_.assign(n, -1.0);  // never a bud size: forces recomputation below
    theta_cached_.resize(n);
    mother_offset_.resize(n);
    bud_offset_.resize(n);
  }
  lobes_.x.resize(2 * n);
  lobes_.y.resize(2 * n);
  lobes_.R.resize(2 * n);
  ox_.resize(2 * n);
  oy_.resize(2 * n);
  // The neighbour list's displacement test is gathered here, in the pass that places the lobes.
  const bool tracked = list_.tracks(2 * n);
  NeighbourList::Drift drift;
  for (std::size_t i = 0; i < n; ++i) {
    const double th = p.q[3 * i + 2];
    const bool resized = p.b[i] != b_cached_[i];
    if (resized) {
      const Dumbbell d = Dumbbell::of(p.b[i]);
      b_cached_[i] = p.b[i];
      mother_offset_[i] = d.mother_offset;
      bud_offset_[i] = d.bud_offset;
      lobes_.R[2 * i] = 0.5 * d.D;
      lobes_.R[2 * i + 1] = 0.5 * d.b;
    }
    // The lever arms depend on θ alone: a cell that has not turned (free cells and rattlers in
    // FIRE, whose velocity stays zero) costs no sincos.
    if (resized || th != theta_cached_[i]) {
      theta_cached_[i] = th;
      const double c = std::cos(th), s = std::sin(th);
      ox_[2 * i] = -mother_offset_[i] * c;
      oy_[2 * i] = -mother_offset_[i] * s;
      ox_[2 * i + 1] = bud_offset_[i] * c;
      oy_[2 * i + 1] = bud_offset_[i] * s;
    }
    // x + (−ℓc) rounds exactly as x − ℓc: the same lobes as place_lobes() gives.
    const double x = p.q[3 * i], y = p.q[3 * i + 1];
    for (std::size_t a = 2 * i; a < 2 * i + 2; ++a) {
      lobes_.x[a] = x + ox_[a];
      lobes_.y[a] = y + oy_[a];
      if (tracked) list_.add_drift(a, lobes_.x[a], lobes_.y[a], lobes_.R[a], drift);
    }
  }
  list_.update(lobes_, p.box, drift);
}

double ForceField::evaluate(const Packing& p, Eigen::VectorXd& force) {
  refresh(p);
  ++evaluations_;
  const std::size_t n = p.size();
  if (force.size() != static_cast<Eigen::Index>(3 * n)) force.resize(3 * n);
  force.setZero();
  double* F = force.data();
  const double* X = lobes_.x.data();
  const double* Y = lobes_.y.data();
  const double* R = lobes_.R.data();
  const double* OX = ox_.data();
  const double* OY = oy_.data();
  const FastImage image(p.box);
  double U = 0.0;
  for (const auto& [a, b] : list_.pairs()) {
    double dx = X[a] - X[b], dy = Y[a] - Y[b];
    image.apply(dx, dy);
    const double r2 = dx * dx + dy * dy;
    const double sigma = R[a] + R[b];
    if (!(r2 < sigma * sigma)) continue;  // r ≥ σ: no contact (r = σ exactly included)
    const double r = std::sqrt(r2);
    const double overlap = sigma - r;
    U += 0.5 * kSpring * overlap * overlap;
    double fx, fy;
    if (r > 0.0) {
      const double f_over_r = kSpring * overlap / r;  // one division: f n = (f/r) (dx, dy)
      fx = f_over_r * dx;
      fy = f_over_r * dy;
    } else {
      double nx, ny;
      coincident_normal(p, a, b, nx, ny);
      fx = kSpring * overlap * nx;
      fy = kSpring * overlap * ny;
    }
    const std::size_t i = 3 * cell_of(a), j = 3 * cell_of(b);
    // Force f n on lobe a, −f n on lobe b; torque = lever arm × force (z component).
    F[i] += fx;
    F[i + 1] += fy;
    F[i + 2] += OX[a] * fy - OY[a] * fx;
    F[j] -= fx;
    F[j + 1] -= fy;
    F[j + 2] -= OX[b] * fy - OY[b] * fx;
  }
  return U;
}

double ForceField::energy(const Packing& p) {
  refresh(p);
  ++evaluations_;
  const double* X = lobes_.x.data();
  const double* Y = lobes_.y.data();
  const double* R = lobes_.R.data();
  const FastImage image(p.box);
  double U = 0.0;
  for (const auto& [a, b] : list_.pairs()) {
    double dx = X[a] - X[b], dy = Y[a] - Y[b];
    image.apply(dx, dy);
    const double r2 = dx * dx + dy * dy;
    const double sigma = R[a] + R[b];
    if (!(r2 < sigma * sigma)) continue;
    const double overlap = sigma - std::sqrt(r2);
    U += 0.5 * kSpring * overlap * overlap;
  }
  return U;
}

}  // namespace budjam
