// Export of a packing as particles and bonds (tools/io/export.hpp). The files are read back by
// independent readers (ASE, gsd, meshio) in tests/python/test_export_readback.py.
#include "budjam/contacts.hpp"
#include "budjam/rigidity.hpp"
#include "compressed_packing.hpp"
#include "io/export.hpp"
#include "io/run_data.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

using namespace budjam;

namespace {

const testing::CompressedPacking& jammed() {
  static const testing::CompressedPacking c = testing::compress_random_dumbbells(40, 7);
  return c;
}

std::size_t count_lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST_CASE("every lobe is one particle: wrapped = unwrapped - image in box vectors, cells whole", "[export]") {
  Packing p = jammed().packing;
  p.box.shear = 0.13;
  // Cells scattered over far periodic images: the export must bring each one back whole.
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] += (static_cast<double>(i % 5) - 2.0) * p.box.L;
    p.q[3 * i + 1] += (static_cast<double>(i % 3) - 1.0) * p.box.L;
  }
  const io::ParticleFrame f = io::particle_frame(p);
  Lobes lobes;
  place_lobes(p, lobes);
  REQUIRE(f.size() == 2 * p.size());
  const double L = p.box.L, g = p.box.shear;
  for (std::size_t k = 0; k < f.size(); ++k) {
    CHECK(f.radius[k] == lobes.R[k]);
    // Unwrapped and wrapped positions are the same point modulo the box vectors.
    CHECK(f.wrapped_x[k] + f.image_x[k] * L + f.image_y[k] * g * L == Approx(f.x[k]).margin(1e-12));
    CHECK(f.wrapped_y[k] + f.image_y[k] * L == Approx(f.y[k]).margin(1e-12));
    // Wrapped lies in the sheared box: fractional coordinates in [0, 1).
    const double fy = f.wrapped_y[k] / L, fx = (f.wrapped_x[k] - g * f.wrapped_y[k]) / L;
    CHECK(fy >= 0.0);
    CHECK(fy < 1.0);
    CHECK(fx >= -1e-12);
    CHECK(fx < 1.0 + 1e-12);
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    // The cell is whole: its lobes keep the separation (D + b)/2 of the dumbbell.
    const double dx = f.x[bud_lobe(i)] - f.x[mother_lobe(i)], dy = f.y[bud_lobe(i)] - f.y[mother_lobe(i)];
    CHECK(std::hypot(dx, dy) == Approx(p.dumbbell(i).separation).epsilon(1e-12));
  }
}

TEST_CASE("bonds are the mother-bud links and the contacts with k(sigma - r); lobes carry their rigid cluster",
          "[export]") {
  const Packing& p = jammed().packing;
  const io::ParticleFrame f = io::particle_frame(p);
  const tools::PackingContacts pc = tools::analyse_contacts(p);
  Lobes lobes;
  place_lobes(p, lobes);
  const RigidityState rigidity = analyse_rigidity(p, lobes, pc.contacts, pc.network);
  REQUIRE(f.bonds.size() == p.size() + pc.contacts.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    CHECK(f.bonds[i].kind == io::BondKind::link);
    CHECK(f.bonds[i].a == mother_lobe(i));
    CHECK(f.bonds[i].b == bud_lobe(i));
  }
  for (std::size_t c = 0; c < pc.contacts.size(); ++c) {
    const io::Bond& b = f.bonds[p.size() + c];
    CHECK(b.kind == io::BondKind::contact);
    CHECK(b.a == pc.contacts[c].i);
    CHECK(b.b == pc.contacts[c].j);
    CHECK(b.force == pc.contacts[c].force());
    CHECK(b.force > 0);
  }
  std::size_t in_clusters = 0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    CHECK(f.cluster[k] == rigidity.cell_cluster[cell_of(k)]);
    CHECK(f.rattler[k] == pc.network.rattler[cell_of(k)]);
    CHECK(f.id[k] == p.id[cell_of(k)]);
    in_clusters += f.cluster[k] >= 0;
  }
  CHECK(in_clusters == 2 * pc.network.N_nr);  // the load-bearing network labels every non-rattler
}

TEST_CASE("link forces close the virial: lobe stress = centroid stress + bar stress in a balanced packing",
          "[export]") {
  // Two independent routes to the stress (contacts.hpp): Σ = Σᶜ − (1/L²) Σ s (F_bud·n̂) n̂n̂ᵀ, and
  // the exported link force is −F_bud·n̂.
  const Packing& p = jammed().packing;
  const io::ParticleFrame f = io::particle_frame(p);
  const std::vector<Contact>& contacts = jammed().contacts;
  Eigen::Matrix2d bars = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d n(std::cos(p.theta(i)), std::sin(p.theta(i)));
    bars += p.dumbbell(i).separation * f.bonds[i].force * n * n.transpose();
  }
  const double area = p.box.L * p.box.L;
  const Eigen::Matrix2d lobe = stress_tensor(contacts, p.box);
  const Eigen::Matrix2d via_bars = centroid_stress_tensor(p, contacts) + bars / area;
  const double scale = lobe.norm();
  REQUIRE(scale > 0);
  CHECK((lobe - via_bars).norm() < 1e-6 * scale);
  // ... and the bars carry a real share of it (the identity is not trivially 0 = 0).
  CHECK(bars.norm() / area > 1e-3 * scale);
}

TEST_CASE("XYZ has one row per lobe and the box as Lattice; VTK one point per lobe and one line per bond", "[export]") {
  const Packing& p = jammed().packing;
  const io::ParticleFrame f = io::particle_frame(p);
  const std::string xyz = io::format_extxyz(f);
  CHECK(count_lines(xyz) == 2 + f.size());
  CHECK(xyz.find("pbc=\"T T F\"") != std::string::npos);
  std::istringstream rows(xyz);
  std::string line;
  std::getline(rows, line);
  CHECK(line == std::to_string(f.size()));
  std::getline(rows, line);
  std::getline(rows, line);
  CHECK(line.rfind("mother ", 0) == 0);
  std::getline(rows, line);
  CHECK(line.rfind("bud ", 0) == 0);

  const std::string vtk = io::format_vtk(f);
  CHECK(vtk.find("POINTS " + std::to_string(f.size()) + " double\n") != std::string::npos);
  CHECK(vtk.find("CELLS " + std::to_string(f.bonds.size()) + " " + std::to_string(3 * f.bonds.size()) + "\n") !=
        std::string::npos);
  CHECK(vtk.find("CELL_DATA " + std::to_string(f.bonds.size()) + "\n") != std::string::npos);
}
