#pragma once
// Random packings of dumbbells for the tests and benchmarks (no growth run needed). Bud diameters
// are uniform in [b_min, b_max]; the default range is the one a growing population covers.
#include "budjam/packing.hpp"
#include "budjam/packing_rules.hpp"

#include <cstddef>
#include <cstdint>
#include <utility>

namespace budjam::testing {

// Random overlapping dumbbells at packing fraction φ, for the mechanics tests. `periods` > 0 puts
// centroids up to that many box lengths outside the box, to exercise the minimum image.
Packing random_packing(std::size_t n, double phi, std::uint64_t seed, double b_min = 0.01, double b_max = 1.02,
                       int periods = 0);

// n cells at uniformly random centroids and orientations, without overlaps (random sequential
// addition), in a square box sized for packing fraction phi < 0.6 (loose: compress it with
// compress_to_pressure); bud diameters uniform in [b_min, b_max]. Throws std::invalid_argument if
// a cell cannot be placed.
Packing random_dumbbells(std::size_t n, double phi, double b_min, double b_max, std::uint64_t seed);

// Draws anew, with draw(i), the position of the later cell of each pair of lobes that the packing
// reader refuses (overlapping by half their contact distance or more, packing_rules.hpp) until none
// is left: random packings that must survive a packing file.
template <class Draw>
void redraw_refused_overlaps(Packing& p, Draw draw) {
  std::pair<std::size_t, std::size_t> cells;
  while (overlap_problem(p, &cells)) draw(cells.second);
}

}  // namespace budjam::testing
