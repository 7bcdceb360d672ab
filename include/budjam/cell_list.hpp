#pragma once
// Linked cells + Verlet skin over lobes. One rebuild is O(N); between rebuilds the pair list
// is valid as long as no pair of lobes has closed in by more than the skin since the last build
// (tested conservatively: the two largest lobe displacements sum to less than the skin).
#include <cstdint>
#include <utility>
#include <vector>
#include "budjam/packing.hpp"

namespace budjam {

class NeighbourList {
 public:
  explicit NeighbourList(double skin = 0.15) : skin_(skin) {}

  // Rebuilds if the two largest lobe displacements since the last build add up to the skin or
  // more, if the number of lobes or any radius changed (buds grow between minimisations), or if
  // the box (L or Lees–Edwards shear) changed; returns true when it rebuilt. Throws
  // std::domain_error if a lobe position is not finite.
  bool update(const Lobes& lobes, const Box& box);
  void invalidate() { valid_ = false; }

  // Pairs (a, b), a < b, of lobes on different cells with r < R_a + R_b + skin at build time,
  // sorted by (a, b): the order depends only on the configuration at the last build.
  const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs() const { return pairs_; }
  double skin() const { return skin_; }
  long rebuilds() const { return rebuilds_; }
  // Linked-cell grid of the last build (cells per side); for tests and diagnostics.
  int grid() const { return grid_; }

 private:
  void build(const Lobes& lobes, const Box& box);
  double skin_;
  bool valid_ = false;
  Box box_{};
  std::vector<double> x0_, y0_, R0_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
  long rebuilds_ = 0;
  int grid_ = 0;
  // Build scratch (kept to avoid reallocating at every rebuild).
  std::vector<std::uint32_t> cell_of_lobe_, cell_start_, fill_, sorted_, partners_;
};

// O(N²) reference: every pair of lobes on different cells with r < R_a + R_b + cutoff_extra.
// Only a test oracle; never called in a growth step.
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Lobes& lobes, const Box& box,
                                                                       double cutoff_extra);

}  // namespace budjam
