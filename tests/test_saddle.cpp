// Leaving a saddle (budjam/saddle.hpp): the unstable mode by inertia bisection and inverse iteration
// against a known spectrum and the dense eigensolver; the step along it lowers U as ½λs² says; a
// relaxation from there reaches a minimum.
#include "analysed_packing.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/hessian.hpp"
#include "budjam/saddle.hpp"
#include "budjam/stability.hpp"
#include "compressed_packing.hpp"
#include "random_packing.hpp"

#include "io/packing_file.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <vector>

using namespace budjam;
using budjam::testing::analyse;
using budjam::testing::Analysed;

namespace {

Packing test_packing(const char* name) {
  const char* src = std::getenv("BUDJAM_SOURCE_DIR");
  REQUIRE(src != nullptr);
  return io::read_packing(std::filesystem::path(src) / "tests/data" / name).packing;
}

SparseMatrix non_rattler_hessian(const Packing& p, const Analysed& a) {
  return restrict_matrix(hessian(p, load_bearing(a.contacts, a.net)), non_rattler_dofs(a.net));
}

// The periodic chain: (L x)_i = 2x_i − x_{i−1} − x_{i+1}, eigenvalues 2 − 2cos(2πk/n).
SparseMatrix periodic_chain(int n, double shift) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2.0 - shift);
    t.emplace_back(i, (i + 1) % n, -1.0);
    t.emplace_back((i + 1) % n, i, -1.0);
  }
  SparseMatrix H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  return H;
}

// A committed packing whose Hessian (pressed contacts) has one unstable mode, analysed.
struct OneUnstableMode {
  Packing p;
  Analysed a;
  Stability st;
};
OneUnstableMode one_unstable_mode(const char* name) {
  OneUnstableMode x{test_packing(name), {}, {}};
  x.a = analyse(x.p);
  x.st = stability(x.p, x.a.contacts, x.a.net);
  REQUIRE(x.st.unstable_modes == 1);
  return x;
}

// U after FIRE relaxes `p` on to its force resolution (no Newton finish).
double relaxed_on(Packing& p, ForceField& field) {
  FireParams deep;
  deep.force_tol = 0;
  deep.newton_force = 0;
  REQUIRE(minimise(p, field, deep).converged);
  return field.energy(p);
}

}  // namespace

TEST_CASE("The unstable mode of a shifted periodic chain is its uniform mode at minus the shift", "[saddle]") {
  // Spectrum 2 − 2cos(2πk/n) − c: the lowest, −c, is simple (k = 0) with the uniform vector; the
  // next, 2 − 2cos(2π/n) − c, is twice degenerate, 3.9·10⁻³ higher at n = 100.
  const int n = 100;
  for (const double c : {1e-2, 1e-6}) {
    INFO("shift " << c);
    const std::optional<UnstableMode> mode = lowest_unstable_mode(periodic_chain(n, c));
    REQUIRE(mode);
    CHECK(mode->lambda == Approx(-c).epsilon(1e-9));
    CHECK(std::abs(mode->v.sum()) / std::sqrt(double(n)) == Approx(1).epsilon(1e-9));
    CHECK(mode->factorisations < 40);
  }
  CHECK_FALSE(lowest_unstable_mode(periodic_chain(n, 0)));  // positive semidefinite: no unstable mode
}

TEST_CASE("Unstable eigenvalues too close to separate give a direction of negative curvature below both", "[saddle]") {
  // n = 1000, c = 10⁻²: λ₁ = −0.01 and λ₂ = λ₃ = −0.00996 share one bracket of the bisection.
  const int n = 1000;
  const double c = 1e-2;
  const double lambda_2 = 2 - 2 * std::cos(2 * M_PI / n) - c;
  const std::optional<UnstableMode> mode = lowest_unstable_mode(periodic_chain(n, c));
  REQUIRE(mode);
  CHECK(mode->lambda >= -c * (1 + 1e-12));
  CHECK(mode->lambda < lambda_2);
  CHECK(mode->v.dot(periodic_chain(n, c) * mode->v) == Approx(mode->lambda).epsilon(1e-12));
}

TEST_CASE("A jamming point FIRE stopped on a saddle: its unstable mode is the dense eigensolver's lowest eigenpair",
          "[saddle]") {
  const Packing p = test_packing("saddle_jamming_L15_seed3.pack");
  const Analysed a = analyse(p);
  const SparseMatrix H = non_rattler_hessian(p, a);
  const std::optional<UnstableMode> mode = lowest_unstable_mode(H);
  REQUIRE(mode);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(H)};
  const double lambda_min = eig.eigenvalues()[0];
  REQUIRE(lambda_min < 0);
  CHECK(mode->lambda == Approx(lambda_min).epsilon(1e-8));
  CHECK(std::abs(mode->v.dot(eig.eigenvectors().col(0))) == Approx(1).epsilon(1e-8));
  INFO("residual " << (H * mode->v - mode->lambda * mode->v).norm() << ", lambda " << mode->lambda);
  CHECK((H * mode->v - mode->lambda * mode->v).norm() < 1e-3 * std::abs(mode->lambda));
}

TEST_CASE("Packings compressed well above jamming have no unstable mode", "[saddle]") {
  FireParams fire;
  fire.force_tol = 1e-13;
  for (const std::uint64_t seed : {1u, 2u}) {
    INFO("seed " << seed);
    const auto c = testing::compress_to_pressure(testing::random_dumbbells(60, 0.4, 0.2, 1.0, seed), 1e-3, fire);
    REQUIRE(c.converged);
    const Analysed a = analyse(c.packing);
    CHECK_FALSE(lowest_unstable_mode(c.packing, a.contacts, a.net));
  }
}

TEST_CASE(
    "A saddle FIRE stops on again is left by a step along its unstable mode: U falls as the mode says and a "
    "relaxation from there reaches a minimum",
    "[saddle]") {
  // A jamming candidate of the paper grid (L = 20, P0 = 1e-5, seed 6) after relaxing on at FIRE's
  // force resolution: still a saddle, one contact short.
  Packing p = test_packing("saddle_after_relaxing_L20_P0_1e-5_seed6.pack");
  FireParams deep;
  deep.force_tol = 0;
  ForceField field;
  REQUIRE(minimise(p, field, deep).converged);
  const Analysed before = analyse(p);
  REQUIRE_FALSE(stability(p, before.contacts, before.net).minimum());  // FIRE alone stays on it
  const std::optional<UnstableMode> mode = lowest_unstable_mode(p, before.contacts, before.net);
  REQUIRE(mode);
  REQUIRE(mode->v.size() == p.q.size());
  CHECK(mode->v.norm() == Approx(1).epsilon(1e-12));
  const Eigen::VectorXd q0 = p.q;
  const SaddleStep step = step_off_saddle(p, field, *mode);
  REQUIRE(step.lowered);
  CHECK(p.q == q0 + step.s * mode->v);
  CHECK(step.U_after == field.energy(p));
  // Half the quadratic decrease ½|λ|s² at least (the step's rule), and more than U resolves.
  CHECK(step.U_before - step.U_after >= 0.25 * std::abs(mode->lambda) * step.s * step.s);
  CHECK(step.U_before - step.U_after > step.U_resolution);
  REQUIRE(minimise(p, field, deep).converged);
  const Analysed after = analyse(p);
  CHECK(stability(p, after.contacts, after.net).minimum());
  CHECK(field.energy(p) < step.U_after);
  // The saddle was one contact short of isostatic; the minimum is not.
  CHECK(before.net.dZ == Approx(-2.0 / static_cast<double>(before.net.N_nr)));
  CHECK(after.net.dZ >= -1e-12);
}

TEST_CASE("A saddle whose unstable mode runs into contacts about to close is a minimum of U along it: no step lowers U",
          "[saddle]") {
  // The committed L = 15 saddle: along ±v, within 10⁻⁷ and 10⁻⁵, a pair with no overlap closes
  // and U rises steeply; before that U falls by less than it resolves.
  Packing p = test_packing("saddle_jamming_L15_seed3.pack");
  const Analysed a = analyse(p);
  const std::optional<UnstableMode> mode = lowest_unstable_mode(p, a.contacts, a.net);
  REQUIRE(mode);
  ForceField field;
  const Eigen::VectorXd q0 = p.q;
  const SaddleStep step = step_off_saddle(p, field, *mode);
  CHECK_FALSE(step.lowered);
  CHECK(p.q == q0);
  CHECK(step.U_after == step.U_before);
  for (const double s : {-1e-5, 1e-5}) {
    p.q = q0 + s * mode->v;
    INFO("s = " << s);
    CHECK(field.energy(p) - step.U_before > 0.5 * std::abs(mode->lambda) * s * s);  // the contact, not the mode
  }
}

TEST_CASE(
    "A jamming point whose one unstable mode closes a pair at zero force is a minimum of U: along the mode a contact "
    "forms and U rises, and relaxing on lowers nothing U resolves",
    "[saddle]") {
  // The L = 20 jamming point of the paper grid (no feedback, seed 3): the driver relaxed on, stepped
  // once, and the mode was blocked. One contact short of isostatic.
  auto [p, a, st] = one_unstable_mode("contact_bounded_jamming_L20_seed3.pack");
  CHECK(a.net.dZ == Approx(-2.0 / static_cast<double>(a.net.N_nr)));
  const std::optional<UnstableMode> mode = lowest_unstable_mode(p, a.contacts, a.net);
  REQUIRE(mode);
  ForceField field;
  const double U0 = field.energy(p);
  const Eigen::VectorXd q0 = p.q;
  // Pairs without overlap close at |s| ≈ 10⁻⁵ on one side and 2·10⁻⁵ on the other.
  for (const double s : {-1e-4, 1e-4}) {
    INFO("s = " << s);
    p.q = q0 + s * mode->v;
    CHECK(field.energy(p) - U0 > 100 * 0.5 * std::abs(mode->lambda) * s * s);  // the contacts, not the mode
    // the pairs the mode runs into: more pressed contacts than at the jamming point
    CHECK(find_contacts(p, field.lobes(), field.neighbours()).size() > a.contacts.size());
  }
  p.q = q0;
  CHECK(relaxed_on(p, field) == Approx(U0).epsilon(1e-6));
  p.q = q0;
  CHECK(stationary_point(p, a.contacts, a.net, st.unstable_modes) == StationaryPoint::contact_bounded_minimum);
}

TEST_CASE(
    "A state whose unstable mode is blocked but whose force FIRE left unresolved is a saddle: relaxing on unjams it",
    "[saddle]") {
  // The committed L = 15 state: no step along its mode lowers U (the test above), yet FIRE at its
  // force resolution finds a way down to U = 0. Only the two tests together make a minimum.
  auto [p, a, st] = one_unstable_mode("saddle_jamming_L15_seed3.pack");
  CHECK(stationary_point(p, a.contacts, a.net, st.unstable_modes) == StationaryPoint::saddle);
  ForceField field;
  CHECK(relaxed_on(p, field) / static_cast<double>(p.size()) < 1e-25);
  // One probed mode cannot make a minimum of a Hessian with two unstable modes.
  CHECK(stationary_point(p, a.contacts, a.net, 2) == StationaryPoint::saddle);
}

TEST_CASE("A saddle along whose unstable mode U falls is a saddle", "[saddle]") {
  const auto [p, a, st] = one_unstable_mode("saddle_after_relaxing_L20_P0_1e-5_seed6.pack");
  CHECK(stationary_point(p, a.contacts, a.net, st.unstable_modes) == StationaryPoint::saddle);
}
