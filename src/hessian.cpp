#include "budjam/hessian.hpp"
#include "budjam/errors.hpp"
#include "budjam/orientation.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace budjam {

double lobe_offset(const Packing& p, std::size_t lobe) {
  const Dumbbell d = p.dumbbell(cell_of(lobe));
  return is_bud(lobe) ? d.bud_offset : -d.mother_offset;
}

Eigen::Matrix<double, 2, 6> contact_jacobian(const Packing& p, const Contact& c) {
  const std::size_t i = cell_of(c.i), j = cell_of(c.j);
  const double sa = lobe_offset(p, c.i), sb = lobe_offset(p, c.j);
  const Axis ei = axis(p.theta(i)), ej = axis(p.theta(j));
  Eigen::Matrix<double, 2, 6> J = Eigen::Matrix<double, 2, 6>::Zero();
  // d = r_a − r_b, r_a = X_i + s_a (cos θ_i, sin θ_i)
  J(0, 0) = 1.0;
  J(1, 1) = 1.0;
  J(0, 2) = -sa * ei.s;
  J(1, 2) = sa * ei.c;
  J(0, 3) = -1.0;
  J(1, 4) = -1.0;
  J(0, 5) = sb * ej.s;
  J(1, 5) = -sb * ej.c;
  return J;
}

Eigen::Matrix<double, 6, 6> contact_hessian(const Packing& p, const Contact& c, const HessianTerms& terms) {
  const Eigen::Vector2d n(c.nx, c.ny);
  const double f = c.force();
  Eigen::Matrix2d K = Eigen::Matrix2d::Zero();
  if (terms.stiffness) K += kSpring * n * n.transpose();
  if (terms.prestress) K -= (f / c.r) * (Eigen::Matrix2d::Identity() - n * n.transpose());
  const Eigen::Matrix<double, 2, 6> J = contact_jacobian(p, c);
  Eigen::Matrix<double, 6, 6> h = J.transpose() * K * J;
  if (terms.prestress) {
    // Gradient of the pair energy in d is −f n; the rigid-body map bends: ∂²r_a/∂θ_i² = −s_a ê_i.
    const std::size_t i = cell_of(c.i), j = cell_of(c.j);
    const double sa = lobe_offset(p, c.i), sb = lobe_offset(p, c.j);
    const Axis ei = axis(p.theta(i)), ej = axis(p.theta(j));
    const double ni = c.nx * ei.c + c.ny * ei.s;
    const double nj = c.nx * ej.c + c.ny * ej.s;
    h(2, 2) += f * sa * ni;
    h(5, 5) -= f * sb * nj;
  }
  // Exact symmetry (J ᵀ K J is symmetric only up to rounding).
  return 0.5 * (h + h.transpose());
}

SparseMatrix hessian(const Packing& p, const std::vector<Contact>& contacts, const HessianTerms& terms) {
  const auto n = static_cast<Eigen::Index>(3 * p.size());
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(36 * contacts.size());
  for (const Contact& c : contacts) {
    const std::size_t i = cell_of(c.i), j = cell_of(c.j);
    if (i == j) throw std::invalid_argument("hessian: contact between lobes of one cell (" + std::to_string(i) + ")");
    if (i >= p.size() || j >= p.size())
      throw std::invalid_argument("hessian: contact refers to a cell outside the packing");
    const Eigen::Matrix<double, 6, 6> h = contact_hessian(p, c, terms);
    const Eigen::Index base[2] = {static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j)};
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) t.emplace_back(base[a / 3] + a % 3, base[b / 3] + b % 3, h(a, b));
  }
  SparseMatrix H(n, n);
  H.setFromTriplets(t.begin(), t.end());  // duplicates are summed in input order: deterministic
  H.makeCompressed();
  return H;
}

DofMap keep_cells(const std::vector<bool>& keep) {
  DofMap map;
  map.block.assign(keep.size(), -1);
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) {
      map.block[i] = static_cast<long>(map.cells.size());
      map.cells.push_back(i);
    }
  return map;
}

DofMap non_rattler_dofs(const ContactNetwork& net) {
  std::vector<bool> keep(net.rattler.size());
  for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = !net.rattler[i];
  return keep_cells(keep);
}

SparseMatrix restrict_matrix(const SparseMatrix& H, const DofMap& map) {
  if (H.rows() != static_cast<Eigen::Index>(3 * map.n_cells()) || H.cols() != H.rows())
    throw std::invalid_argument("restrict_matrix: matrix is not 3N × 3N for the map's N");
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(H.nonZeros()));
  for (Eigen::Index col = 0; col < H.outerSize(); ++col) {
    const long bc = map.block[static_cast<std::size_t>(col / 3)];
    if (bc < 0) continue;
    for (SparseMatrix::InnerIterator it(H, col); it; ++it) {
      const long br = map.block[static_cast<std::size_t>(it.row() / 3)];
      if (br < 0) continue;
      t.emplace_back(3 * br + it.row() % 3, 3 * bc + col % 3, it.value());
    }
  }
  SparseMatrix R(map.size(), map.size());
  R.setFromTriplets(t.begin(), t.end());
  R.makeCompressed();
  return R;
}

Eigen::VectorXd restrict_vector(const Eigen::VectorXd& v, const DofMap& map) {
  if (v.size() != static_cast<Eigen::Index>(3 * map.n_cells()))
    throw std::invalid_argument("restrict_vector: vector is not 3N for the map's N");
  Eigen::VectorXd r(map.size());
  for (Eigen::Index k = 0; k < r.size(); ++k) r[k] = v[map.full(k)];
  return r;
}

Eigen::VectorXd expand_vector(const Eigen::VectorXd& v, const DofMap& map) {
  if (v.size() != map.size()) throw std::invalid_argument("expand_vector: vector does not match the map");
  Eigen::VectorXd full = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * map.n_cells()));
  for (Eigen::Index k = 0; k < v.size(); ++k) full[map.full(k)] = v[k];
  return full;
}

void require_dense_fits(std::size_t n, int matrices, const std::string& method, const std::string& alternative) {
  const double bytes = static_cast<double>(matrices) * 8.0 * static_cast<double>(n) * static_cast<double>(n);
  if (bytes > kMaxDenseBytes)
    throw InputError(method + ": " + std::to_string(matrices) + " dense matrices of " + std::to_string(n) +
                     " rows would take " + std::to_string(static_cast<long long>(std::ceil(bytes / 1e9))) +
                     " GB, more than the limit of " + std::to_string(static_cast<int>(kMaxDenseBytes / 1e9)) +
                     " GB; use " + alternative);
}

}  // namespace budjam
