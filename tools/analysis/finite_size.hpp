#pragma once
// Finite-size study (docs/analysis.md, "Finite size"): for each feedback strength that was run at
// several box sizes, the per-size values of the quantities fixed at jamming (u_J, n_J, φ_J) and at
// the depletion point (Δφ_2 both ways, divisions, G_2/P_max), and their extrapolation to N → ∞.
//
// Model: q(N_J) = q_∞ + c/N_J, the leading correction of the finite-size counting (the +2 of the
// isostatic count and the discreteness of u = N_u/N_nr are O(1/N)). It is fitted by weighted least
// squares on the per-size means (medians for G_2 and divisions) with their standard errors; the fit's
// χ²/dof says whether 1/N describes the data. Sizes whose value has no finite error bar are left out.
#include "io/json.hpp"

namespace budjam::tools {

// `groups`: the "groups" array that analyse writes to analysis.json, one entry per (L, P0). Returns
// one entry per P0 present at two sizes or more: its per-size rows and, with three sizes or more,
// the extrapolation of every quantity.
io::Json finite_size_json(const io::Json& groups);

}  // namespace budjam::tools
