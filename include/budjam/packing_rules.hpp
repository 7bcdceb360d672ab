#pragma once
// The physical rules every packing obeys, wherever it comes from (a packing file, a checkpoint,
// a grown state); the scene's box rule (src/scene.cpp, box.L) is the same as box_problem's.
//  - the box: L finite, L > 2 (σ_max + skin) with σ_max the largest lobe diameter, so that every
//    neighbour pair has a single periodic image, and L ≤ kMaxBoxSide (scene_keys.hpp, the scene's
//    box.L bound: positions within kMaxBoxesAway boxes then stay below 1e10, which every export
//    format, float32 included, holds); |shear| ≤ kMaxBoxesAway (image shifts stay finite);
//  - each cell: finite x, y, θ within kMaxBoxesAway boxes of the origin (unwrapped positions drift,
//    but not that far), 0 ≤ b ≤ b_max, finite γ0 ≥ 0;
//  - the geometry (packing files): φ < kMaxPackingFraction, and every overlapping pair of lobes of
//    different cells keeps r > kMinContactRatio σ (docs/model.md, "Degenerate packings").
// Each returns the first violation as one line, or nothing.
#include "budjam/packing.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <utility>

namespace budjam {

// Largest bud a budding cell can have: it divides at α = 1 + b/D > 2 α0, and every scene has
// α0 < 2 (cells.alpha0), so no bud reaches 3 D.
inline constexpr double kMaxBudDiameter = 3.0 * kMotherDiameter;
// Largest bud of a grown state with newborn aspect ratio α0 (a bigger one would have divided).
inline double max_bud_diameter(double alpha0) { return (2.0 * alpha0 - 1.0) * kMotherDiameter; }
// Unwrapped coordinates further than this many box sides from the origin are refused. A coordinate
// K box sides out resolves positions only to ~2⁻⁵² K L, and a pair's separation, a difference of two
// such coordinates, no better: near jamming contacts close and open over overlaps of 10⁻⁸ and less,
// so a packing shifted by 10⁵ periods is another contact network. budjam keeps coordinates within
// [−L/2, 3L/2) at the start of every relaxation (fire.cpp), so what it writes is well inside this
// bound, which costs at most 4 bits against coordinates in the box; farther ones are refused, not
// silently read with the digits they no longer hold.
inline constexpr double kMaxBoxesAway = 16;

// Where a contact's overlap reaches half its contact distance, r ≤ σ/2, its prestress stiffness
// f/r = k (σ/r − 1) exceeds the contact stiffness k, and at r = 0 (stacked lobes) the contact has no
// direction: forces, Hessian and spectrum of the harmonic model are undefined or dominated by the
// singular f/r. Grown packings stay clear of it (the demo scene: r/σ ≥ 0.63 at Δφ = 0.4, the largest
// jamming.max_dphi, kMaxDphi); a run that would pass it ends with status overlap_bound.
inline constexpr double kMinContactRatio = 0.5;
// With r > σ/2 for every pair of different cells, and r = σ between a cell's own two lobes, the disks
// of half the lobe radii are disjoint: Σ π (R/2)² < L², i.e. φ = Σ π R² / L² < 4. Checked first,
// since it needs no neighbour search and bounds the lobes per area that the pair check visits.
inline constexpr double kMaxPackingFraction = 4.0;

std::optional<std::string> cell_problem(const Packing& p, std::size_t i, double b_max);
std::optional<std::string> box_problem(const Packing& p, double skin);
// φ ≥ kMaxPackingFraction.
std::optional<std::string> density_problem(const Packing& p);
// The overlapping pair (lobes of different cells, r < σ) with r ≤ kMinContactRatio σ whose lower lobe
// index is smallest (then the other's), naming both cells by row; `first` is set to their rows.
// Needs box_problem to hold (one periodic image per pair). Stops at the first violation, so stacked
// input costs no more than the lobes it has to pass.
std::optional<std::string> overlap_problem(const Packing& p, std::pair<std::size_t, std::size_t>* first = nullptr);

}  // namespace budjam
