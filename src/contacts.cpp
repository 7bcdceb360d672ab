// Contacts of a packing and the virial observables built on them (docs/model.md, "Interaction and energy").
#include "budjam/contacts.hpp"

#include "budjam/cell_list.hpp"
#include "budjam/orientation.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace budjam {

void coincident_normal(const Packing& p, std::size_t i, std::size_t j, double& nx, double& ny) {
  const std::size_t ci = cell_of(i), cj = cell_of(j);
  double dx = p.x(ci) - p.x(cj), dy = p.y(ci) - p.y(cj);
  p.box.minimum_image(dx, dy);
  const double d = std::hypot(dx, dy);
  if (d > 0.0) {
    nx = dx / d;
    ny = dy / d;
  } else {
    nx = 1.0;
    ny = 0.0;
  }
}

std::vector<Contact> find_contacts(const Packing& p, const Lobes& lobes, const NeighbourList& list) {
  if (lobes.size() != 2 * p.size())
    throw std::invalid_argument("find_contacts: the lobes do not belong to this packing (" +
                                std::to_string(lobes.size()) + " lobes, " + std::to_string(p.size()) + " cells)");
  std::vector<Contact> out;
  for (const auto& [a, b] : list.pairs()) {
    double dx = lobes.x[a] - lobes.x[b], dy = lobes.y[a] - lobes.y[b];
    p.box.minimum_image(dx, dy);
    const double r2 = dx * dx + dy * dy;
    const double sigma = lobes.R[a] + lobes.R[b];
    if (!(r2 < sigma * sigma)) continue;
    const double r = std::sqrt(r2);
    Contact c{a, b, 0.0, 0.0, r, sigma};
    if (r > 0.0) {
      c.nx = dx / r;
      c.ny = dy / r;
    } else {
      coincident_normal(p, a, b, c.nx, c.ny);
    }
    out.push_back(c);
  }
  return out;
}

double pressure(const std::vector<Contact>& contacts, const Box& box) {
  double virial = 0.0;
  for (const Contact& c : contacts) virial += c.force() * c.r;
  return virial / (2.0 * box.L * box.L);
}

Eigen::Matrix2d stress_tensor(const std::vector<Contact>& contacts, const Box& box) {
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  for (const Contact& c : contacts) {
    const double fr = c.force() * c.r;  // f r̂_α r_β = f r n_α n_β
    s(0, 0) += fr * c.nx * c.nx;
    s(0, 1) += fr * c.nx * c.ny;
    s(1, 1) += fr * c.ny * c.ny;
  }
  s(1, 0) = s(0, 1);
  return -s / (box.L * box.L);
}

Eigen::Matrix2d centroid_stress_tensor(const Packing& p, const std::vector<Contact>& contacts) {
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  // Lever arm of a lobe: its offset from the centroid, ±ℓ n̂ (mother −, bud +).
  auto offset = [&p](std::size_t lobe, double& ox, double& oy) {
    const std::size_t cell = cell_of(lobe);
    const Dumbbell d = p.dumbbell(cell);
    const double l = is_bud(lobe) ? d.bud_offset : -d.mother_offset;
    const Axis n = axis(p.theta(cell));
    ox = l * n.c;
    oy = l * n.s;
  };
  for (const Contact& c : contacts) {
    double oix, oiy, ojx, ojy;
    offset(c.i, oix, oiy);
    offset(c.j, ojx, ojy);
    // Lobe vector r n = (centroid_i + o_i) − (centroid_j + o_j) in the contact's image, so the
    // centroid branch vector of that same image is R = r n − (o_i − o_j).
    const double Rx = c.r * c.nx - (oix - ojx);
    const double Ry = c.r * c.ny - (oiy - ojy);
    const double f = c.force();
    s(0, 0) += f * c.nx * Rx;
    s(0, 1) += f * c.nx * Ry;
    s(1, 0) += f * c.ny * Rx;
    s(1, 1) += f * c.ny * Ry;
  }
  return -s / (p.box.L * p.box.L);
}

double centroid_pressure(const Packing& p, const std::vector<Contact>& contacts) {
  const Eigen::Matrix2d s = centroid_stress_tensor(p, contacts);
  return -0.5 * (s(0, 0) + s(1, 1));
}

std::vector<double> bud_pressures(const Packing& p, const std::vector<Contact>& contacts) {
  std::vector<double> out(p.size(), 0.0);
  for (const Contact& c : contacts) {
    if (is_bud(c.i)) out[cell_of(c.i)] += c.force();
    if (is_bud(c.j)) out[cell_of(c.j)] += c.force();
  }
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i] != 0.0) out[i] /= std::numbers::pi * p.b[i];  // force per bud perimeter π b_i
  return out;
}

}  // namespace budjam
