// Minimum or saddle (budjam/stability.hpp): the LDLᵀ inertia count of unstable modes against the
// dense eigenvalues of the same Hessian, on a real saddle and on stable packings.
#include "analysed_packing.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/hessian.hpp"
#include "budjam/stability.hpp"
#include "compressed_packing.hpp"
#include "random_packing.hpp"

#include "io/packing_file.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>

using namespace budjam;
using budjam::testing::analyse;
using budjam::testing::Analysed;
using budjam::testing::compress_to_pressure;
using budjam::testing::CompressionResult;
using budjam::testing::random_dumbbells;

namespace {

// Eigenvalues of the dense Hessian of the non-rattlers below −δ: the independent count.
std::size_t dense_count_below(const Packing& p, const Analysed& a, double delta) {
  const SparseMatrix H = restrict_matrix(hessian(p, load_bearing(a.contacts, a.net)), non_rattler_dofs(a.net));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(H), Eigen::EigenvaluesOnly};
  return static_cast<std::size_t>((eig.eigenvalues().array() < -delta).count());
}

}  // namespace

TEST_CASE(
    "A jamming point FIRE stopped on a saddle has one unstable mode, counted alike by LDLt inertia and dense "
    "eigenvalues",
    "[stability]") {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const Packing p = io::read_packing(std::filesystem::path(src) / "tests/data/saddle_jamming_L15_seed3.pack").packing;
  const Analysed a = analyse(p);
  const Stability s = stability(p, a.contacts, a.net);
  CHECK_FALSE(s.minimum());
  CHECK(s.unstable_modes == 1);
  CHECK(s.delta > 0);
  CHECK(dense_count_below(p, a, s.delta) == s.unstable_modes);
}

TEST_CASE("Packings compressed well above jamming are minima: no unstable mode, as the dense eigenvalues say",
          "[stability]") {
  FireParams fire;
  fire.force_tol = 1e-13;
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const CompressionResult c = compress_to_pressure(random_dumbbells(60, 0.4, 0.2, 1.0, seed), 1e-3, fire);
    REQUIRE(c.converged);
    const Analysed a = analyse(c.packing);
    const Stability s = stability(c.packing, a.contacts, a.net);
    INFO("seed " << seed);
    CHECK(s.minimum());
    CHECK(dense_count_below(c.packing, a, s.delta) == 0);
  }
}

TEST_CASE("A packing without stressed contacts is a minimum", "[stability]") {
  Packing p;
  p.box.L = 10;
  p.add_cell(2, 2, 0, 0.5, 0.002, -1);
  p.add_cell(7, 7, 1, 0.5, 0.002, -1);
  const Analysed a = analyse(p);
  CHECK(stability(p, a.contacts, a.net).minimum());
}
