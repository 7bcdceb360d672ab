// Harmonic lobe–lobe energy and its exact gradient over (x, y, θ) of each rigid dumbbell.
#include "budjam/energy.hpp"

#include "budjam/contacts.hpp"
#include "budjam/orientation.hpp"

#include <algorithm>
#include <cmath>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace budjam {

namespace {

// Round to nearest (ties to even) for |v| < 2^51, as std::nearbyint in the default rounding
// mode, without a library call (nearbyint is not inlined on baseline x86-64): adding 1.5·2^52
// pushes the fraction bits out of the mantissa.
inline double round_nearest(double v) {
  constexpr double magic = 6755399441055744.0;  // 1.5 · 2^52
  return (v + magic) - magic;
}

// Periods of the minimum image of (dx, dy), as Box::minimum_image finds them (with a precomputed
// 1/L; it agrees except when |dy| or |dx| is within an ulp of L/2, which no pair within the
// cut-off reaches).
inline PairImage minimum_image_periods(const Box& box, double inv_L, double dx, double dy) {
  const double ny = round_nearest(dy * inv_L);
  dx -= box.shear * box.L * ny;
  return {round_nearest(dx * inv_L), ny};
}

// The separation of a listed pair from its stored periods.
struct Periodic {
  double L, shift;
  explicit Periodic(const Box& box) : L(box.L), shift(box.shear * box.L) {}
  void apply(const PairImage& image, double& dx, double& dy) const {
    dx -= shift * image.ny;
    dy -= image.ny * L;
    dx -= L * image.nx;
  }
};

// One pair's contribution: the force (fx, fy) on lobe a (−(fx, fy) on lobe b) and its energy.
struct PairForce {
  double U = 0.0, fx = 0.0, fy = 0.0;
};

// The contact law on the pair (a, b); false (and a zero PairForce) when the lobes do not overlap.
inline bool pair_force(const Packing& p, const Periodic& periodic, const PairImage& image, const Lobes& lobes,
                       std::uint32_t a, std::uint32_t b, PairForce& out) {
  double dx = lobes.x[a] - lobes.x[b], dy = lobes.y[a] - lobes.y[b];
  periodic.apply(image, dx, dy);
  const double r2 = dx * dx + dy * dy;
  const double sigma = lobes.R[a] + lobes.R[b];
  if (!(r2 < sigma * sigma)) return false;  // r ≥ σ: no contact (r = σ exactly included)
  const double r = std::sqrt(r2);
  const double overlap = sigma - r;
  out.U = 0.5 * kSpring * overlap * overlap;
  if (r > 0.0) {
    const double f_over_r = kSpring * overlap / r;  // one division: f n = (f/r) (dx, dy)
    out.fx = f_over_r * dx;
    out.fy = f_over_r * dy;
  } else {
    double nx, ny;
    coincident_normal(p, a, b, nx, ny);
    out.fx = kSpring * overlap * nx;
    out.fy = kSpring * overlap * ny;
  }
  return true;
}

int resolve_threads(int requested) {
#ifdef _OPENMP
  return requested == 0 ? omp_get_num_procs() : std::max(requested, 1);
#else
  (void)requested;
  return 1;
#endif
}

}  // namespace

ForceField::ForceField(double skin, int threads) : threads_(resolve_threads(threads)), list_(skin) {}

void ForceField::invalidate() { list_.invalidate(); }

void ForceField::refresh(const Packing& p) {
  place_lobes_of(p);
  // The displacement test stays a pass of its own: folded into the lobe placement it was slower.
  const long near_built = list_.near_rebuilds();
  if (list_.update(lobes_, p.box)) find_pair_images(p.box, lobes_.x, lobes_.y);
  if (list_.near_rebuilds() != near_built) gather_near_pairs();
}

void ForceField::restore_neighbours(const Packing& p, const NeighbourList::Origin& o) {
  place_lobes_of(p);
  list_.restore(o, lobes_, p.box);
  find_pair_images(p.box, o.x0, o.y0);  // the images are found where the pair list was built
  gather_near_pairs();
}

void ForceField::place_lobes_of(const Packing& p) {
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
  // The lever arms ±ℓ n̂ change only with θ or the bud size: a cell that has not turned (free cells
  // and rattlers in FIRE, whose velocity stays zero) keeps its own. The axes of the others are
  // computed together, several at a time (orientation.hpp).
  turned_.clear();
  turned_theta_.clear();
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
    if (resized || th != theta_cached_[i]) {
      theta_cached_[i] = th;
      turned_.push_back(static_cast<std::uint32_t>(i));
      turned_theta_.push_back(th);
    }
  }
  const std::size_t m = turned_.size();
  turned_c_.resize(m);
  turned_s_.resize(m);
  axes(turned_theta_.data(), m, turned_c_.data(), turned_s_.data());
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t i = turned_[k];
    ox_[2 * i] = -mother_offset_[i] * turned_c_[k];
    oy_[2 * i] = -mother_offset_[i] * turned_s_[k];
    ox_[2 * i + 1] = bud_offset_[i] * turned_c_[k];
    oy_[2 * i + 1] = bud_offset_[i] * turned_s_[k];
  }
  // x + (−ℓc) rounds exactly as x − ℓc: the same lobes as place_lobes() gives.
  auto place = [&](std::size_t i) {
    const double x = p.q[3 * i], y = p.q[3 * i + 1];
    for (std::size_t a = 2 * i; a < 2 * i + 2; ++a) {
      lobes_.x[a] = x + ox_[a];
      lobes_.y[a] = y + oy_[a];
    }
  };
  if (threaded(n)) {
    const long cells = static_cast<long>(n);
#pragma omp parallel for num_threads(threads_) schedule(static)
    for (long i = 0; i < cells; ++i) place(static_cast<std::size_t>(i));
  } else {
    for (std::size_t i = 0; i < n; ++i) place(i);
  }
}

// The force loops run over the near list's pairs, copied out in order with their images so that
// they stream through memory: the same contacts in the same order as over the whole pair list.
void ForceField::gather_near_pairs() {
  const auto& pairs = list_.pairs();
  const auto& near = list_.near();
  near_pairs_.resize(near.size());
  near_images_.resize(near.size());
  for (std::size_t t = 0; t < near.size(); ++t) {
    near_pairs_[t] = pairs[near[t]];
    near_images_[t] = images_[near[t]];
  }
}

void ForceField::find_pair_images(const Box& box, const std::vector<double>& x, const std::vector<double>& y) {
  const auto& pairs = list_.pairs();
  const double inv_L = 1.0 / box.L;
  images_.resize(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    images_[k] = minimum_image_periods(box, inv_L, x[a] - x[b], y[a] - y[b]);
  }
}

double ForceField::evaluate(const Packing& p, Eigen::VectorXd& force) {
  refresh(p);
  ++evaluations_;
  const std::size_t n = p.size();
  if (force.size() != static_cast<Eigen::Index>(3 * n)) force.resize(3 * n);
  force.setZero();
  return threaded(n) ? threaded_pair_loop(p, force.data()) : pair_loop(p, force.data());
}

// Force f n̂ on lobe a, −f n̂ on lobe b; torque = lever arm × force (z component).
double ForceField::pair_loop(const Packing& p, double* F) const {
  const double* OX = ox_.data();
  const double* OY = oy_.data();
  const Periodic periodic(p.box);
  const auto& pairs = near_pairs_;
  double U = 0.0;
  PairForce f;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    if (!pair_force(p, periodic, near_images_[k], lobes_, a, b, f)) continue;
    U += f.U;
    const std::size_t i = 3 * cell_of(a), j = 3 * cell_of(b);
    F[i] += f.fx;
    F[i + 1] += f.fy;
    F[i + 2] += OX[a] * f.fy - OY[a] * f.fx;
    F[j] -= f.fx;
    F[j + 1] -= f.fy;
    F[j + 2] -= OX[b] * f.fy - OY[b] * f.fx;
  }
  return U;
}

void ForceField::index_pairs_by_cell(std::size_t n) {
  if (indexed_rebuild_ == list_.near_rebuilds() && cell_pairs_start_.size() == n + 1) return;
  const auto& pairs = near_pairs_;
  cell_pairs_start_.assign(n + 1, 0);
  for (const auto& [a, b] : pairs) {
    ++cell_pairs_start_[cell_of(a) + 1];
    ++cell_pairs_start_[cell_of(b) + 1];
  }
  for (std::size_t i = 0; i < n; ++i) cell_pairs_start_[i + 1] += cell_pairs_start_[i];
  cell_pairs_.resize(2 * pairs.size());
  std::vector<std::uint32_t> fill(cell_pairs_start_.begin(), cell_pairs_start_.end() - 1);
  for (std::uint32_t k = 0; k < pairs.size(); ++k) {  // in pair order: each cell's entries ascend
    cell_pairs_[fill[cell_of(pairs[k].first)]++] = 2 * k;
    cell_pairs_[fill[cell_of(pairs[k].second)]++] = 2 * k + 1;
  }
  indexed_rebuild_ = list_.near_rebuilds();
}

// The serial loop's sums in the serial loop's order: pair forces in parallel (a zero force where
// there is no contact adds nothing: sums that start at +0 never reach −0), then each cell adds
// its pairs' in pair order, and U its pairs' energies in pair order.
double ForceField::threaded_pair_loop(const Packing& p, double* F) {
  const auto& pairs = near_pairs_;
  const std::size_t n = p.size();
  const long n_pairs = static_cast<long>(pairs.size()), cells = static_cast<long>(n);
  index_pairs_by_cell(n);
  pair_U_.resize(pairs.size());
  pair_f_.resize(2 * pairs.size());
  const double* OX = ox_.data();
  const double* OY = oy_.data();
  const Periodic periodic(p.box);
  double U = 0.0;
#pragma omp parallel num_threads(threads_)
  {
#pragma omp for schedule(static)
    for (long k = 0; k < n_pairs; ++k) {
      PairForce f;
      pair_force(p, periodic, near_images_[k], lobes_, pairs[k].first, pairs[k].second, f);
      pair_U_[k] = f.U;
      pair_f_[2 * k] = f.fx;
      pair_f_[2 * k + 1] = f.fy;
    }
#pragma omp single nowait
    for (double u : pair_U_) U += u;
#pragma omp for schedule(dynamic, 64)
    for (long ci = 0; ci < cells; ++ci) {
      const auto i = static_cast<std::size_t>(ci);
      double fx = 0.0, fy = 0.0, tau = 0.0;
      for (std::uint32_t t = cell_pairs_start_[i]; t < cell_pairs_start_[i + 1]; ++t) {
        const std::uint32_t e = cell_pairs_[t], k = e / 2;
        const double pfx = pair_f_[2 * k], pfy = pair_f_[2 * k + 1];
        if (e % 2 == 0) {
          const std::uint32_t a = pairs[k].first;
          fx += pfx;
          fy += pfy;
          tau += OX[a] * pfy - OY[a] * pfx;
        } else {
          const std::uint32_t b = pairs[k].second;
          fx -= pfx;
          fy -= pfy;
          tau -= OX[b] * pfy - OY[b] * pfx;
        }
      }
      F[3 * i] = fx;
      F[3 * i + 1] = fy;
      F[3 * i + 2] = tau;
    }
  }
  return U;
}

double ForceField::energy(const Packing& p) {
  refresh(p);
  ++evaluations_;
  const double* X = lobes_.x.data();
  const double* Y = lobes_.y.data();
  const double* R = lobes_.R.data();
  const Periodic periodic(p.box);
  const auto& pairs = near_pairs_;
  double U = 0.0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    double dx = X[a] - X[b], dy = Y[a] - Y[b];
    periodic.apply(near_images_[k], dx, dy);
    const double r2 = dx * dx + dy * dy;
    const double sigma = R[a] + R[b];
    if (!(r2 < sigma * sigma)) continue;
    const double overlap = sigma - std::sqrt(r2);
    U += 0.5 * kSpring * overlap * overlap;
  }
  return U;
}

}  // namespace budjam
