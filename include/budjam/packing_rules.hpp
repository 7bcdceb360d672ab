#pragma once
// The physical rules every packing obeys, wherever it comes from (a packing file, a checkpoint,
// a grown state); the scene's box rule (src/scene.cpp, box.L) is the same as box_problem's.
//  - the box: L finite, L > 2 (σ_max + skin) with σ_max the largest lobe diameter, so that every
//    neighbour pair has a single periodic image; |shear| ≤ kMaxBoxesAway (image shifts stay finite);
//  - each cell: finite x, y, θ within kMaxBoxesAway boxes of the origin (unwrapped positions drift,
//    but not that far), 0 ≤ b ≤ b_max, finite γ0 ≥ 0.
// Each returns the first violation as one line, or nothing.
#include "budjam/packing.hpp"

#include <cstddef>
#include <optional>
#include <string>

namespace budjam {

// Largest bud a budding cell can have: it divides at α = 1 + b/D > 2 α0, and every scene has
// α0 < 2 (cells.alpha0), so no bud reaches 3 D.
inline constexpr double kMaxBudDiameter = 3.0 * kMotherDiameter;
// Largest bud of a grown state with newborn aspect ratio α0 (a bigger one would have divided).
inline double max_bud_diameter(double alpha0) { return (2.0 * alpha0 - 1.0) * kMotherDiameter; }
// Unwrapped coordinates further than this many box sides from the origin are refused.
inline constexpr double kMaxBoxesAway = 1e6;

std::optional<std::string> cell_problem(const Packing& p, std::size_t i, double b_max);
std::optional<std::string> box_problem(const Packing& p, double skin);

}  // namespace budjam
