#pragma once
// Analytic Hessian ∂²U/∂q∂q of U = Σ_contacts (k/2)(σ − r)² in the generalised coordinates of
// Packing::q, q = [x0, y0, θ0, x1, y1, θ1, …] ((x, y) the area-weighted centroid, θ the angle of
// n̂ = mother → bud; NOT the FIRE-scaled θ̃ = r_g θ). Derivation in docs/moduli.md.
//
// For a contact between lobe a (cell i, offset s_a along n̂_i: −mother_offset or +bud_offset) and
// lobe b (cell j) with separation d = r_a − r_b, unit vector n = d/r, force f = k(σ − r):
//   pair stiffness in d:  K = k n nᵀ − (f/r)(1 − n nᵀ)        (stiffness term, prestress term)
//   Jacobian of d:        ∂d/∂q_i = J_a = [1₂ | s_a ê⊥_i],  ∂d/∂q_j = −J_b,  ê⊥ = (−sin θ, cos θ)
//   H_ii += J_aᵀ K J_a,  H_jj += J_bᵀ K J_b,  H_ij = H_jiᵀ += −J_aᵀ K J_b
//   plus the curvature of the rigid-body map (also a prestress term):
//   H_θiθi += f s_a (n·ê_i),   H_θjθj −= f s_b (n·ê_j).
// Periodic images and Lees–Edwards shear only enter through n and r, which the contact carries.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"

namespace budjam {

using SparseMatrix = Eigen::SparseMatrix<double>;  // column-major, int indices

// Which parts of H to assemble. The spectrum's "stiffness only" variant drops the prestress.
struct HessianTerms {
  bool stiffness = true;  // k (J n)(J n)ᵀ
  bool prestress = true;  // −(f/r) transverse part and the rigid-body curvature terms (∝ f)
};

// The 3N × 3N Hessian of the packing from `contacts` (as found for the current q; any subset, e.g.
// load_bearing()). Both triangles stored, exactly symmetric (H_ba is written from the same
// numbers as H_ab). Cells without contacts give zero rows. O(contacts).
SparseMatrix hessian(const Packing& p, const std::vector<Contact>& contacts, const HessianTerms& terms = {});

// The 6 × 6 block of one contact in the order (x_i, y_i, θ_i, x_j, y_j, θ_j), i = cell of c.i,
// j = cell of c.j. Exposed for the moduli and for tests.
Eigen::Matrix<double, 6, 6> contact_hessian(const Packing& p, const Contact& c, const HessianTerms& terms = {});

// ∂d/∂q of one contact: columns (x_i, y_i, θ_i, x_j, y_j, θ_j), rows (d_x, d_y).
Eigen::Matrix<double, 2, 6> contact_jacobian(const Packing& p, const Contact& c);

// Offset of a lobe's centre from its cell's centroid along n̂: −mother_offset or +bud_offset.
double lobe_offset(const Packing& p, std::size_t lobe);

// Selection of cells and where their dofs go in a reduced system (e.g. non-rattlers only).
struct DofMap {
  std::vector<long> block;         // per cell of the packing: its block index in the reduced system, −1 if dropped
  std::vector<std::size_t> cells;  // the kept cells, increasing; reduced dofs 3k, 3k+1, 3k+2 belong to cells[k]
  Eigen::Index size() const { return static_cast<Eigen::Index>(3 * cells.size()); }
  std::size_t n_cells() const { return block.size(); }
  // Full dof index of reduced dof r.
  Eigen::Index full(Eigen::Index r) const { return static_cast<Eigen::Index>(3 * cells[r / 3]) + r % 3; }
};

// Keeps the cells with keep[i] == true, in index order.
DofMap keep_cells(const std::vector<bool>& keep);
// Keeps the non-rattlers of the network.
DofMap non_rattler_dofs(const ContactNetwork& net);

// Rows and columns of the kept cells (a principal submatrix; both triangles kept).
SparseMatrix restrict_matrix(const SparseMatrix& H, const DofMap& map);
Eigen::VectorXd restrict_vector(const Eigen::VectorXd& v, const DofMap& map);
// Reduced vector back to 3N, zeros on the dropped cells.
Eigen::VectorXd expand_vector(const Eigen::VectorXd& v, const DofMap& map);

// The dense methods (the dense spectrum, the dense moduli solver) hold a few n × n matrices of
// doubles: O(n²) memory against the sparse methods' O(n). Above this much they are refused before
// anything is allocated (10⁴ cells' spectrum would need 36 GB); the sparse methods have no such bound.
inline constexpr double kMaxDenseBytes = 4e9;
// InputError "<method>: ..." naming the memory, the limit and `alternative` unless `matrices` n × n
// dense matrices of doubles fit within kMaxDenseBytes.
void require_dense_fits(std::size_t n, int matrices, const std::string& method, const std::string& alternative);

}  // namespace budjam
