#pragma once
// Linked cells + Verlet skin over lobes, with a second, thinner skin inside it. One rebuild is
// O(N); between rebuilds the pair list is valid as long as no pair of lobes has closed in by more
// than the skin since the last build (tested conservatively: the two largest lobe displacements
// sum to less than the skin). The near list, the listed pairs within the thin skin, is rebuilt
// from the pair list alone, so near force balance, where lobes move by far less than a skin, the
// force loop visits little more than the contacts.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>
#include "budjam/packing.hpp"

namespace budjam {

// The Verlet skin every neighbour list, force field and scene (minimiser.skin) starts from: the
// results do not depend on it (pairs are sorted); 0.15 is the cheapest of 0.1–0.3 in whole runs
// (docs/minimiser.md, "Neighbour list").
inline constexpr double kDefaultSkin = 0.15;

class NeighbourList {
 public:
  // The near skin is a fifth of the skin: thin enough that the near list holds few pairs out of
  // contact, thick enough that FIRE's steps near force balance rarely expire it.
  explicit NeighbourList(double skin = kDefaultSkin) : skin_(skin), near_skin_(skin / 5) {}

  // Rebuilds if the number of lobes or any radius changed (buds grow between minimisations), if
  // the box (L or Lees–Edwards shear) changed, or if the near list has expired (the two largest
  // lobe displacements since its build add up to the near skin) and the pair list has too (those
  // since the pair list's build, plus the near skin, exceed the skin); returns true when it
  // rebuilt the pair list. An expired near list is rebuilt from the pair list. Throws
  // std::domain_error if a lobe position is not finite.
  bool update(const Lobes& lobes, const Box& box);
  void invalidate() { valid_ = false; }

  // The lobe positions the pair list (x0, y0) and the near list (x1, y1) were last built at: with
  // the radii and the box, all that decides the lists and when update() rebuilds them.
  struct Origin {
    std::vector<double> x0, y0, x1, y1;
  };
  Origin origin() const { return {x0_, y0_, x1_, y1_}; }
  // Why `o` cannot be the origin of lists that are current for `lobes` (a list expires before its
  // lobes move further than this list's skins allow), or nullopt.
  std::optional<std::string> misfit(const Origin& o, const Lobes& lobes) const;
  // The lists as they were when origin() returned `o`, current for `lobes` in `box`: the same pairs
  // in the same order, expiring at the same displacements (a minimisation resumed from a
  // checkpoint, fire.hpp). Throws std::invalid_argument with misfit()'s reason.
  void restore(const Origin& o, const Lobes& lobes, const Box& box);

  // Pairs (a, b), a < b, of lobes on different cells with r < R_a + R_b + skin at build time,
  // sorted by (a, b): the order depends only on the configuration at the last build.
  const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs() const { return pairs_; }
  // Indices into pairs(), ascending, of the pairs with r < R_a + R_b + near_skin() at the near
  // list's last build: until the next update() rebuilds it, every pair in contact is among them.
  const std::vector<std::uint32_t>& near() const { return near_; }
  double skin() const { return skin_; }
  double near_skin() const { return near_skin_; }
  long rebuilds() const { return rebuilds_; }
  long near_rebuilds() const { return near_rebuilds_; }
  // Linked-cell grid of the last build (cells per side); for tests and diagnostics.
  int grid() const { return grid_; }

 private:
  void build(const Lobes& lobes, const Box& box);
  void build_near(const Lobes& lobes, const Box& box);
  double skin_, near_skin_;
  bool valid_ = false;
  Box box_{};
  // Lobe positions at the pair list's build (x0, y0) and at the near list's (x1, y1).
  std::vector<double> x0_, y0_, R0_, x1_, y1_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
  std::vector<std::uint32_t> near_;
  long rebuilds_ = 0, near_rebuilds_ = 0;
  int grid_ = 0;
  // Build scratch (kept to avoid reallocating at every rebuild).
  std::vector<std::uint32_t> cell_of_lobe_, cell_start_, fill_, sorted_, partners_;
};

// O(N²) reference: every pair of lobes on different cells with r < R_a + R_b + cutoff_extra.
// Only a test oracle; never called in a growth step.
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Lobes& lobes, const Box& box,
                                                                       double cutoff_extra);

}  // namespace budjam
