// Linked-cell neighbour search with a Verlet skin, periodic with Lees–Edwards images.
#include "budjam/cell_list.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>

namespace budjam {

namespace {

// Distance² between lobes a and b by the box's minimum-image convention.
inline double distance2(const Lobes& lobes, const Box& box, std::size_t a, std::size_t b) {
  double dx = lobes.x[a] - lobes.x[b];
  double dy = lobes.y[a] - lobes.y[b];
  box.minimum_image(dx, dy);
  return dx * dx + dy * dy;
}

inline int wrap_index(long c, int n) {
  const long m = c % n;
  return static_cast<int>(m < 0 ? m + n : m);
}

// d₁ + d₂, the two largest lobe displacements from (x, y); NaN if a position is not finite, or
// if `R0` is given and a radius differs from it.
double closing_bound(const Lobes& lobes, const std::vector<double>& x, const std::vector<double>& y,
                     const std::vector<double>* R0 = nullptr) {
  double m1 = 0.0, m2 = 0.0;
  bool valid = true;
  for (std::size_t i = 0; i < lobes.size(); ++i) {
    if (R0) valid &= lobes.R[i] == (*R0)[i];
    const double dx = lobes.x[i] - x[i], dy = lobes.y[i] - y[i];
    const double d2 = dx * dx + dy * dy;
    if (d2 > m2) {
      if (d2 > m1) {
        m2 = m1;
        m1 = d2;
      } else {
        m2 = d2;
      }
    }
    valid &= std::isfinite(d2);  // a NaN fails every comparison above
  }
  return valid ? std::sqrt(m1) + std::sqrt(m2) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

bool NeighbourList::update(const Lobes& lobes, const Box& box) {
  const std::size_t n = lobes.size();
  bool rebuild = !valid_ || n != x0_.size() || box.L != box_.L || box.shear != box_.shear;
  if (!rebuild) {
    // A pair's distance shrinks by at most d₁ + d₂. A changed radius or a non-finite
    // displacement fails both tests and forces a rebuild (which throws on the latter).
    const double near_bound = closing_bound(lobes, x1_, y1_, &R0_);
    if (near_bound < near_skin_) return false;
    // A pair outside the pair list has closed in by less than this until the near list expires.
    rebuild = std::isnan(near_bound) || !(closing_bound(lobes, x0_, y0_) + near_skin_ <= skin_);
  }
  if (rebuild) build(lobes, box);
  build_near(lobes, box);
  return rebuild;
}

std::optional<std::string> NeighbourList::misfit(const Origin& o, const Lobes& lobes) const {
  const std::size_t n = lobes.size();
  if (o.x0.size() != n || o.y0.size() != n || o.x1.size() != n || o.y1.size() != n)
    return "an origin of " + std::to_string(o.x0.size()) + " lobes for " + std::to_string(n) + " lobes";
  // update() keeps d₁ + d₂ from the near list's build below the near skin, and from the pair list's
  // build below the skin (with a margin for the rounding of the two sums).
  if (!(closing_bound(lobes, o.x1, o.y1) < near_skin_))
    return "the lobes moved further from the near list's build than its skin allows";
  if (!(closing_bound(lobes, o.x0, o.y0) <= skin_ * (1 + 1e-12)))
    return "the lobes moved further from the pair list's build than its skin allows";
  return std::nullopt;
}

void NeighbourList::restore(const Origin& o, const Lobes& lobes, const Box& box) {
  if (const auto problem = misfit(o, lobes)) throw std::invalid_argument("neighbour list: " + *problem);
  build(Lobes{o.x0, o.y0, lobes.R}, box);
  build_near(Lobes{o.x1, o.y1, lobes.R}, box);
}

void NeighbourList::build_near(const Lobes& lobes, const Box& box) {
  near_.clear();
  for (std::uint32_t k = 0; k < pairs_.size(); ++k) {
    const auto [a, b] = pairs_[k];
    const double reach = lobes.R[a] + lobes.R[b] + near_skin_;
    if (distance2(lobes, box, a, b) < reach * reach) near_.push_back(k);
  }
  x1_.assign(lobes.x.begin(), lobes.x.end());
  y1_.assign(lobes.y.begin(), lobes.y.end());
  ++near_rebuilds_;
}

void NeighbourList::build(const Lobes& lobes, const Box& box) {
  const std::size_t n = lobes.size();
  if (!(box.L > 0.0) || !std::isfinite(box.L) || !std::isfinite(box.shear))
    throw std::domain_error("neighbour list: box side must be positive and finite (L = " + std::to_string(box.L) +
                            ", shear = " + std::to_string(box.shear) + ")");
  double R_max = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(lobes.x[i]) || !std::isfinite(lobes.y[i]) || !std::isfinite(lobes.R[i]))
      throw std::domain_error("neighbour list: lobe " + std::to_string(i) + " of cell " + std::to_string(cell_of(i)) +
                              " has a non-finite position or radius");
    R_max = std::max(R_max, lobes.R[i]);
  }
  const double L = box.L;
  const double cutoff = 2.0 * R_max + skin_;

  // Cells per side: each at least `cutoff` wide, so that a 3×3 stencil holds every partner; at
  // most about one cell per lobe, so that a huge box with few lobes does not allocate a huge grid.
  const double fit = std::floor(L / cutoff);
  const double cap = std::floor(std::sqrt(2.0 * static_cast<double>(n) + 9.0));
  const int g = static_cast<int>(std::max(1.0, std::min(fit, cap)));
  grid_ = g;
  const double w = L / g;

  // Lobes into cells (counting sort). A lobe is binned by its image in the primary box: a shift
  // of k boxes in y moves x by k·γL (Lees–Edwards), as in Box::minimum_image.
  const std::size_t n_cells = static_cast<std::size_t>(g) * static_cast<std::size_t>(g);
  cell_of_lobe_.resize(n);
  cell_start_.assign(n_cells + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double ky = std::floor(lobes.y[i] / L);
    double yw = lobes.y[i] - ky * L;
    double xw = lobes.x[i] - ky * box.shear * L;
    xw -= std::floor(xw / L) * L;
    // Clamped before the conversion: a far-away or rounding-off coordinate must not overflow int.
    const int cx = static_cast<int>(std::clamp(xw / w, 0.0, g - 1.0));
    const int cy = static_cast<int>(std::clamp(yw / w, 0.0, g - 1.0));
    const auto c = static_cast<std::uint32_t>(cy * g + cx);
    cell_of_lobe_[i] = c;
    ++cell_start_[c + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  sorted_.resize(n);
  fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) sorted_[fill_[cell_of_lobe_[i]]++] = static_cast<std::uint32_t>(i);

  // Lees–Edwards offset of the image row above, in cell widths: s = γL mod L.
  double s = std::fmod(box.shear * L, L);
  if (s < 0) s += L;
  const double o = s / w;

  pairs_.clear();
  std::array<int, 12> stencil{};
  std::vector<std::uint32_t>& partners = partners_;
  for (std::size_t a = 0; a < n; ++a) {
    const int c = static_cast<int>(cell_of_lobe_[a]);
    const int cx = c % g, cy = c / g;
    int m = 0;
    for (int dy = -1; dy <= 1; ++dy) {
      const int row = cy + dy;
      if (row >= 0 && row < g) {
        for (int dx = -1; dx <= 1; ++dx) stencil[m++] = row * g + wrap_index(cx + dx, g);
      } else {
        // Row across the y boundary: its lobes' images are shifted by +s (row above) or −s (row
        // below); partners within `cutoff` lie in four columns (three when s = 0).
        const int wrapped = row < 0 ? g - 1 : 0;
        const double shift = row < 0 ? o : -o;
        const long lo = static_cast<long>(std::floor(cx - 1 + shift));
        const int cols = s == 0.0 ? 3 : 4;
        for (int k = 0; k < cols; ++k) stencil[m++] = wrapped * g + wrap_index(lo + k, g);
      }
    }
    // Small grids (g < 4) repeat cells in the stencil: visit each once.
    const auto used = std::span(stencil).first(static_cast<std::size_t>(m));
    std::sort(used.begin(), used.end());
    m = static_cast<int>(std::unique(used.begin(), used.end()) - used.begin());

    partners.clear();
    const std::size_t ca = cell_of(a);
    for (int k = 0; k < m; ++k) {
      const auto cell = static_cast<std::size_t>(stencil[k]);
      for (std::uint32_t t = cell_start_[cell]; t < cell_start_[cell + 1]; ++t) {
        const std::uint32_t b = sorted_[t];
        if (b <= a || cell_of(b) == ca) continue;
        const double reach = lobes.R[a] + lobes.R[b] + skin_;
        if (distance2(lobes, box, a, b) < reach * reach) partners.push_back(b);
      }
    }
    std::sort(partners.begin(), partners.end());
    for (std::uint32_t b : partners) pairs_.emplace_back(static_cast<std::uint32_t>(a), b);
  }

  x0_.assign(lobes.x.begin(), lobes.x.end());
  y0_.assign(lobes.y.begin(), lobes.y.end());
  R0_.assign(lobes.R.begin(), lobes.R.end());
  box_ = box;
  valid_ = true;
  ++rebuilds_;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Lobes& lobes, const Box& box,
                                                                       double cutoff_extra) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  const std::size_t n = lobes.size();
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      if (cell_of(a) == cell_of(b)) continue;
      const double reach = lobes.R[a] + lobes.R[b] + cutoff_extra;
      if (distance2(lobes, box, a, b) < reach * reach)
        out.emplace_back(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
    }
  return out;
}

}  // namespace budjam
