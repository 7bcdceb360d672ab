#pragma once
// Harmonic lobe–lobe repulsion U = Σ (k/2)(σ − r)² and generalised forces F = −∂U/∂q on the
// (x, y, θ) of every cell (F_θ is the torque about the centroid).
//
// Conventions at the edges of the contact law (docs/minimiser.md):
// - r = σ exactly is not a contact (U and F are continuous there: both vanish).
// - r = 0 (coincident centres of lobes of different cells): U = kσ²/2 and the force has magnitude
//   kσ along coincident_normal() (contacts.hpp): the centroid-to-centroid direction, or +x when
//   the centroids coincide too. Every direction is a one-sided derivative of U there; this
//   choice is finite, deterministic and separates the cells.
#include <Eigen/Core>
#include <cstdint>
#include <vector>
#include "budjam/cell_list.hpp"
#include "budjam/packing.hpp"

namespace budjam {

// The minimum image of a listed pair of lobes (a, b) as whole periods: the separation is
// r_a − r_b − (nx L + ny γL, ny L). Found once per neighbour-list rebuild. Between rebuilds no pair
// closes in by more than the skin, and the scene requires L > 2 (σ_max + skin), so a pair in
// contact keeps the image it had at the build, and a pair out of contact in that image is out of
// contact in every image: U and F are bit for bit those of rounding to the minimum image afresh at
// every evaluation, without its two roundings per pair.
struct PairImage {
  double nx, ny;
};

// Keeps the lobe positions and the Verlet neighbour list current for a packing whose
// coordinates move (FIRE) or whose cells change (growth, division). Invariant: after
// evaluate(), `lobes()` and `neighbours()` describe the packing that was passed in.
//
// Threads (OpenMP): lobe placement and the pair loop of evaluate() run on `threads` threads
// for packings of at least kThreadedCells cells. The results are bit-identical for every thread
// count, and to the serial loop: each pair's force is computed once, into its own slot, and each
// cell then sums its pairs' forces in pair-list order, as the serial loop does; U is summed over
// the pairs in order (docs/minimiser.md, "Threads").
class ForceField {
 public:
  // threads: 1 = serial, 0 = one per core. Without OpenMP every count means one thread.
  explicit ForceField(double skin = kDefaultSkin, int threads = 1);

  // Smaller packings always use one thread: their evaluation (≈ 40 µs at 512 cells) is too short
  // to pay for the synchronisation of the threads.
  static constexpr std::size_t kThreadedCells = 512;
  // The thread count evaluations use (≥ 1).
  int threads() const { return threads_; }

  // U, and F = −∂U/∂q (size 3N) for the packing as it is now. O(N); allocates nothing once
  // `force` and the internal buffers have their size.
  double evaluate(const Packing& p, Eigen::VectorXd& force);
  // U only.
  double energy(const Packing& p);

  // Call after the number of cells or any bud size changed: forces a neighbour rebuild.
  // (A changed radius or count is also detected by the neighbour list itself.)
  void invalidate();

  // The neighbour list as it was when it had origin `o` (NeighbourList::restore), for the packing
  // `p` as it is now: evaluations from here repeat those of the field that had it, bit for bit,
  // rebuilds included (a minimisation resumed from a checkpoint, fire.hpp).
  void restore_neighbours(const Packing& p, const NeighbourList::Origin& o);
  const Lobes& lobes() const { return lobes_; }
  const NeighbourList& neighbours() const { return list_; }
  long evaluations() const { return evaluations_; }

 private:
  void refresh(const Packing& p);
  void place_lobes_of(const Packing& p);
  // The images of the listed pairs from lobe positions (x, y): those of the pair list's build.
  void find_pair_images(const Box& box, const std::vector<double>& x, const std::vector<double>& y);
  void gather_near_pairs();
  double pair_loop(const Packing& p, double* F) const;
  double threaded_pair_loop(const Packing& p, double* F);
  void index_pairs_by_cell(std::size_t n);
  bool threaded(std::size_t n) const { return threads_ > 1 && n >= kThreadedCells; }
  int threads_;
  Lobes lobes_;
  NeighbourList list_;
  long evaluations_ = 0;
  // Minimum-image periods (nx, ny) of each listed pair, found at the list's last rebuild.
  std::vector<PairImage> images_;
  // The pairs of the near list and their images, in pair-list order.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> near_pairs_;
  std::vector<PairImage> near_images_;
  // Per-cell dumbbell geometry, recomputed only when a bud size changes.
  std::vector<double> b_cached_, mother_offset_, bud_offset_;
  // Lobe offsets from their cell's centroid, (ox, oy) = ±ℓ n̂: the lever arms of the torques,
  // recomputed only when the cell's θ (theta_cached_) or bud size changes.
  std::vector<double> ox_, oy_, theta_cached_;
  // The cells whose axis is recomputed at this refresh, their θ and their axes (cos θ, sin θ).
  std::vector<std::uint32_t> turned_;
  std::vector<double> turned_theta_, turned_c_, turned_s_;
  // Threaded path: each pair's (U, fx, fy), and for each cell its pairs in pair-list order
  // (entry 2k + s: pair k, the cell holding its first lobe if s = 0, its second if s = 1),
  // rebuilt with the neighbour list.
  std::vector<double> pair_U_, pair_f_;
  std::vector<std::uint32_t> cell_pairs_start_, cell_pairs_;
  long indexed_rebuild_ = -1;
};

}  // namespace budjam
