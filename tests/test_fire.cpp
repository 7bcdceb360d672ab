// FIRE 2.0 minimiser: reaches its tolerance, relaxes unjammed packings to zero energy, returns
// balanced forces, and classifies states at the jamming threshold E/N = 1e-16 reliably.
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "compressed_packing.hpp"
#include "random_packing.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

using namespace budjam;
using budjam::testing::random_packing;

namespace {

constexpr double kEpsilonU = 1e-16;  // the jamming threshold ε_U on E/N (docs/model.md)

// FIRE on its own (no Newton finish), at the force tolerance these tests' bounds were set for.
FireParams fire_alone() {
  FireParams f;
  f.newton_force = 0.0;
  f.force_tol = 1e-12;
  return f;
}

// Random placement in which no two lobes overlap by more than `max_overlap`: real overlaps, but
// no interpenetration deep enough to lock a lobe in the waist of another cell (deep random
// overlaps of dumbbells can be local minima of U with E > 0 even in a dilute box).
Packing shallow_packing(std::size_t n, double phi, std::uint64_t seed, double max_overlap) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> b(n);
  double area = 0;
  for (auto& bi : b) {
    bi = 0.01 + 1.01 * u(rng);
    area += 0.25 * std::numbers::pi * (1 + bi * bi);
  }
  Packing p;
  p.box.L = std::sqrt(area / phi);
  Lobes l;
  for (std::size_t i = 0; i < n; ++i) {
    for (int attempt = 0;; ++attempt) {
      REQUIRE(attempt < 100000);
      Packing trial = p;
      // x, y, θ drawn in this order (the order of evaluation of function arguments is unspecified)
      const double x = p.box.L * u(rng), y = p.box.L * u(rng), theta = std::numbers::pi * (2 * u(rng) - 1);
      trial.add_cell(x, y, theta, b[i], 0.002, -1);
      place_lobes(trial, l);
      bool ok = true;
      for (std::size_t a = 2 * i; a < 2 * i + 2 && ok; ++a)
        for (std::size_t c = 0; c < 2 * i && ok; ++c) {
          double dx = l.x[a] - l.x[c], dy = l.y[a] - l.y[c];
          trial.box.minimum_image(dx, dy);
          ok = std::hypot(dx, dy) > l.R[a] + l.R[c] - max_overlap;
        }
      if (ok) {
        p = trial;
        break;
      }
    }
  }
  return p;
}

// Largest generalised force component (θ as τ/r_g) recomputed from the contact list, i.e. not by
// ForceField::evaluate: Σ f n and Σ (lever arm × f n) per cell.
double contact_force_residual(const Packing& p) {
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
  Eigen::VectorXd G = Eigen::VectorXd::Zero(3 * p.size());
  for (const Contact& c : contacts) {
    const double f = c.force();
    for (int side = 0; side < 2; ++side) {
      const std::size_t lobe = side == 0 ? c.i : c.j;
      const double sign = side == 0 ? 1.0 : -1.0;
      const std::size_t cell = cell_of(lobe);
      const Dumbbell d = p.dumbbell(cell);
      const double l = is_bud(lobe) ? d.bud_offset : -d.mother_offset;
      const double ox = l * std::cos(p.theta(cell)), oy = l * std::sin(p.theta(cell));
      G[3 * cell] += sign * f * c.nx;
      G[3 * cell + 1] += sign * f * c.ny;
      G[3 * cell + 2] += sign * f * (ox * c.ny - oy * c.nx) / d.gyration;
    }
  }
  return G.lpNorm<Eigen::Infinity>();
}

// Box and centroids rescaled affinely to packing fraction φ.
Packing at_phi(const Packing& p, double phi) {
  Packing q = p;
  const double lambda = std::sqrt(p.packing_fraction() / phi);
  q.box.L *= lambda;
  for (std::size_t i = 0; i < p.size(); ++i) {
    q.q[3 * i] *= lambda;
    q.q[3 * i + 1] *= lambda;
  }
  return q;
}

double energy_per_cell(const Packing& p) {
  ForceField field;
  return field.energy(p) / static_cast<double>(p.size());
}

// A relaxed packing of n cells just above its jamming point, compressed step by step from a
// loose random placement without overlaps. A random overlapping start relaxed at φ = 0.92 may hold
// a small bud locked in another cell's waist, a tangle that keeps E > 0 even when decompressed far
// below jamming; the step-by-step compression never forms one.
Packing jammed_start(std::size_t n, std::uint64_t seed) {
  const testing::CompressedPacking c = testing::compress_random_dumbbells(n, seed);
  REQUIRE(c.energy_per_cell > kEpsilonU);
  return c.packing;
}

// Bisection in φ by affine decompression of a relaxed jammed packing, until the relaxed E/N lies in
// [e_lo, e_hi] and the bracket is narrower than `width`. Returns the jammed end of the bracket and,
// in `below`, the relaxed unjammed end.
Packing near_jamming(Packing jammed, double e_lo, double e_hi, double width, Packing* below = nullptr,
                     const FireParams& params = fire_alone()) {
  ForceField field;
  double hi = jammed.packing_fraction(), lo = hi - 0.15;
  Packing unjammed = at_phi(jammed, lo);
  REQUIRE(minimise(unjammed, field, params).converged);
  REQUIRE(energy_per_cell(unjammed) < kEpsilonU);
  for (int k = 0; k < 80; ++k) {
    const double e = energy_per_cell(jammed);
    if (e >= e_lo && e <= e_hi && hi - lo < width) break;
    const double mid = 0.5 * (lo + hi);
    Packing trial = at_phi(jammed, mid);
    const FireResult r = minimise(trial, field, params);
    REQUIRE(r.converged);
    if (r.energy / static_cast<double>(trial.size()) >= e_lo) {
      hi = mid;
      jammed = trial;
    } else {
      lo = mid;
      unjammed = trial;
    }
  }
  if (below) *below = unjammed;
  return jammed;
}

}  // namespace

TEST_CASE("FIRE reaches its force tolerance on a random overlapping packing", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Packing p = random_packing(100, 1.0, seed);
    ForceField field;
    const FireParams params = fire_alone();
    const FireResult r = minimise(p, field, params);
    INFO("seed " << seed << " iterations " << r.iterations);
    CHECK(r.converged);
    CHECK(r.stop == MinimiserStop::force);
    CHECK(r.max_force < params.force_tol);
    CHECK(r.energy / 100 > 1e-4);  // φ = 1 is far above jamming: stopped by the force rule
    CHECK(r.energy == Approx(ForceField().energy(p)).epsilon(1e-12));
    // Independent recomputation of the residual from the contacts.
    CHECK(contact_force_residual(p) < 1.5 * params.force_tol);
    CHECK(r.iterations < 20000);
  }
}

TEST_CASE("FIRE relaxes a dilute overlapping packing to E/N below 1e-20 quickly", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Packing p = shallow_packing(60, 0.45, seed, 0.1);
    ForceField field;
    const double U0 = field.energy(p);
    REQUIRE(U0 > 1e-3);  // it starts with real overlaps
    const FireResult r = minimise(p, field, fire_alone());
    INFO("seed " << seed << " evaluations " << r.evaluations);
    CHECK(r.converged);
    CHECK(r.stop == MinimiserStop::energy_floor);
    CHECK(r.energy / 60 < 1e-20);
    CHECK(energy_per_cell(p) < 1e-20);
    CHECK(r.evaluations < 3000);
  }
}

TEST_CASE("a relaxed jammed packing has balanced forces and torques on every cell", "[fast]") {
  Packing p = random_packing(80, 0.95, 21);
  ForceField field;
  const FireResult r = minimise(p, field, fire_alone());
  REQUIRE(r.converged);
  CHECK(r.energy / 80 > 1e-8);
  // Σ f n and Σ τ/r_g per cell, from the contacts, vanish to the tolerance, while single contact
  // forces are many orders of magnitude larger.
  const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
  double f_typical = 0;
  for (const Contact& c : contacts) f_typical += c.force() / static_cast<double>(contacts.size());
  CHECK(f_typical > 1e-4);
  CHECK(contact_force_residual(p) < 1.5 * fire_alone().force_tol);
}

TEST_CASE("FIRE counts its force evaluations and is deterministic", "[fast]") {
  Packing a = random_packing(70, 0.9, 31), b = a;
  ForceField fa, fb;
  const FireResult ra = minimise(a, fa, fire_alone());
  const FireResult rb = minimise(b, fb, fire_alone());
  CHECK(ra.evaluations == fa.evaluations());
  CHECK(ra.evaluations == ra.iterations + 1);
  CHECK(ra.iterations == rb.iterations);
  CHECK(a.q == b.q);  // bit for bit
  // An already relaxed packing costs one evaluation.
  const FireResult again = minimise(a, fa, fire_alone());
  CHECK(again.converged);
  CHECK(again.evaluations == 1);
  CHECK(again.iterations == 0);
}

TEST_CASE("FIRE gives up after max_iterations and reports it", "[fast]") {
  Packing p = random_packing(50, 1.0, 41);
  ForceField field;
  FireParams params = fire_alone();
  params.max_iterations = 10;
  const FireResult r = minimise(p, field, params);
  CHECK_FALSE(r.converged);
  CHECK(r.stop == MinimiserStop::iteration_cap);
  CHECK(r.iterations == 10);
  CHECK(r.max_force > params.force_tol);
}

TEST_CASE("centroids far outside the box are brought back by whole periods without changing U", "[fast]") {
  Packing p = random_packing(40, 0.5, 51);
  p.box.shear = 0.3;
  Packing far = p;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double ky = static_cast<double>(static_cast<int>(i % 7) - 3) * 3;  // up to ±9 boxes in y
    far.q[3 * i] += (static_cast<double>(i % 5) - 2) * 4 * p.box.L + ky * p.box.shear * p.box.L;
    far.q[3 * i + 1] += ky * p.box.L;
  }
  CHECK(energy_per_cell(far) == Approx(energy_per_cell(p)).epsilon(1e-10));
  ForceField field;
  FireParams params = fire_alone();
  params.max_iterations = 1;
  minimise(far, field, params);
  const double L = p.box.L;
  for (std::size_t i = 0; i < p.size(); ++i) {
    CHECK(far.x(i) >= -0.5 * L - 1);
    CHECK(far.x(i) < 1.5 * L + 1);
    CHECK(far.y(i) >= -0.5 * L - 1);
    CHECK(far.y(i) < 1.5 * L + 1);
  }
}

TEST_CASE("force resolution grows with the box: the tolerance stays reachable", "[fast]") {
  Packing p = random_packing(10, 0.5, 61);
  CHECK(force_resolution(p) < 1e-13);  // does not override the default tolerance in small boxes
  p.box.L = 1e4;
  CHECK(force_resolution(p) > 1e-12);
}

TEST_CASE("a packing just above jamming stays above the threshold; just below it relaxes fully", "[fast]") {
  // Jammed state with ε_U < E/N < 10 ε_U, by bisection of an affine decompression.
  // Seed 73: the bisection's last unjammed trial relaxes to the energy floor, so (3) is checked on a
  // state below φ_J (with seeds 71, 72, 76, 77, 80 it stops at 0 < E/N < ε_U, jammed but under the
  // threshold, and (3) fails).
  const Packing start = jammed_start(40, 73);
  ForceField field;
  Packing below;
  const Packing jam = near_jamming(start, 1.5 * kEpsilonU, 10 * kEpsilonU, 1.0, &below);
  const double e = energy_per_cell(jam);
  REQUIRE(e >= 1.5 * kEpsilonU);
  REQUIRE(e <= 10 * kEpsilonU);
  INFO("E/N at the jammed state " << e << ", phi " << jam.packing_fraction());

  // (1) Relaxing further with a much tighter tolerance changes E by a negligible amount: the
  //     stopping rule had resolved the energy.
  Packing tight = jam;
  FireParams strict = fire_alone();
  strict.force_tol = 1e-30;  // i.e. down to force_resolution()
  strict.max_iterations = 200000;
  minimise(tight, field, strict);
  CHECK(energy_per_cell(tight) == Approx(e).epsilon(1e-6));

  // (2) Perturbed far below the overlaps (~1e-8) and relaxed again with the defaults: same energy,
  //     never reported below the threshold.
  std::mt19937_64 rng(72);
  std::normal_distribution<double> g(0.0, 1e-11);
  for (int k = 0; k < 3; ++k) {
    Packing q = jam;
    for (Eigen::Index c = 0; c < q.q.size(); ++c) q.q[c] += g(rng);
    const FireResult r = minimise(q, field, fire_alone());
    CHECK(r.converged);
    CHECK(r.energy / 40 >= kEpsilonU);
    CHECK(r.energy / 40 == Approx(e).epsilon(1e-5));
  }

  // (3) The unjammed end of the bracket was proven unjammed (E/N below the floor).
  CHECK(energy_per_cell(below) < 1e-20);
  CHECK(below.packing_fraction() < jam.packing_fraction());
}

TEST_CASE("packing 1e-9 above jamming: the default minimiser classifies it as a strict one does", "[.hard]") {
  const Packing start = jammed_start(40, 81);
  ForceField field;
  // Bracket the jamming point to 1e-9 in φ with a strict minimiser (no energy floor, forces down to
  // the resolution): its jammed end has a true minimum E/N > 1e-24 (~(1e-9)²), its other end none.
  FireParams strict = fire_alone();
  strict.force_tol = 1e-30;  // i.e. force_resolution()
  strict.energy_floor = 0.0;
  strict.max_iterations = 2000000;
  Packing below;
  const Packing jam = near_jamming(start, 1e-24, 1e-12, 1e-9, &below, strict);
  const double e = energy_per_cell(jam);
  INFO("E/N " << e << " at phi " << jam.packing_fraction());
  CHECK(e > 1e-24);
  CHECK(jam.packing_fraction() - below.packing_fraction() < 1e-9);
  CHECK(energy_per_cell(below) < 1e-24);
  // The defaults, from slightly perturbed copies: converged, finite, and on the same side of ε_U.
  std::mt19937_64 rng(82);
  std::normal_distribution<double> g(0.0, 1e-12);
  for (int k = 0; k < 3; ++k) {
    Packing q = jam;
    for (Eigen::Index c = 0; c < q.q.size(); ++c) q.q[c] += g(rng);
    const FireResult r = minimise(q, field, fire_alone());
    CHECK(r.converged);
    CHECK(std::isfinite(r.energy));
    CHECK((r.energy / 40 < kEpsilonU) == (e < kEpsilonU));
  }
}

TEST_CASE("cells crossing the periodic boundary during minimisation relax as a shifted copy does", "[.hard]") {
  // A cluster of overlapping cells around the corner of the box: relaxing pushes centroids across
  // both boundaries. The same cluster shifted into the middle of the box must give the same
  // relative configuration.
  std::mt19937_64 rng(91);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Packing corner;
  corner.box = {12.0, 0.0};
  for (int i = 0; i < 8; ++i) corner.add_cell(0.6 * u(rng), 0.6 * u(rng), 3 * u(rng), 0.5 + 0.5 * u(rng), 0.002, -1);
  Packing middle = corner;
  for (std::size_t i = 0; i < middle.size(); ++i) {
    middle.q[3 * i] += 6.0;
    middle.q[3 * i + 1] += 6.0;
  }
  const Packing before = corner;
  ForceField fc, fm;
  const FireResult rc = minimise(corner, fc, fire_alone());
  const FireResult rm = minimise(middle, fm, fire_alone());
  CHECK(rc.converged);
  CHECK(rm.converged);
  CHECK(rc.energy / 8 < 1e-20);
  CHECK(rm.energy / 8 < 1e-20);
  int crossed = 0;
  for (std::size_t i = 0; i < corner.size(); ++i) {
    crossed += (before.x(i) < 0) != (corner.x(i) < 0) || (before.y(i) < 0) != (corner.y(i) < 0);
    CHECK(std::abs(corner.x(i) - (middle.x(i) - 6.0)) < 1e-6);
    CHECK(std::abs(corner.y(i) - (middle.y(i) - 6.0)) < 1e-6);
    CHECK(std::abs(corner.theta(i) - middle.theta(i)) < 1e-6);
  }
  CHECK(crossed > 0);
}

TEST_CASE("after an uphill step FIRE steps half back and restarts from rest along the force", "[fast]") {
  // FIRE 2.0 (Guénolé et al. 2020, Algorithm 2): when P = F·v ≤ 0, x ← x − ½Δt v and v ← 0, so the
  // step that follows is ½ back plus Δt² F: its move part m = Δx + ½ m_previous is parallel to F.
  // Seen from outside, from the iterates x_k (max_iterations = k on copies; the path is
  // deterministic) in FIRE's scaled coordinates (x, y, r_g θ), with the force scaled alike: after an
  // ordinary step m_k = Δx_k = Δt v_k, so F(x_k)·m_k ≤ 0 is FIRE's own uphill test. Keeping the
  // velocity would leave a component along m_k in the next move part.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Packing start = random_packing(30, 1.0, seed);
    const std::size_t n = start.size();
    ForceField field;
    const auto scaled = [&](const Packing& p) {
      Eigen::VectorXd x = p.q;
      for (std::size_t i = 0; i < n; ++i) x[3 * i + 2] *= p.dumbbell(i).gyration;
      return x;
    };
    const auto scaled_force = [&](const Packing& p) {
      Eigen::VectorXd F;
      field.evaluate(p, F);
      for (std::size_t i = 0; i < n; ++i) F[3 * i + 2] /= p.dumbbell(i).gyration;
      return F;
    };
    Eigen::VectorXd x_prev = scaled(start), m = Eigen::VectorXd::Zero(x_prev.size()), F = scaled_force(start);
    bool restart = true;  // the first iteration starts from rest (P = 0)
    int uphill = 0;
    for (long k = 1; k <= 200; ++k) {
      Packing p = start;
      FireParams params;
      params.max_iterations = k;
      REQUIRE_FALSE(minimise(p, field, params).converged);
      const Eigen::VectorXd x = scaled(p), dx = x - x_prev;
      const Eigen::VectorXd move = restart ? Eigen::VectorXd(dx + 0.5 * m) : dx;
      if (restart && k > 1) {
        ++uphill;
        INFO("seed " << seed << ", iteration " << k);
        CHECK(move.dot(F) / (move.norm() * F.norm()) > 1 - 1e-6);
      }
      m = move;
      x_prev = x;
      F = scaled_force(p);
      const double cosine = F.dot(m) / (F.norm() * m.norm());
      if (std::abs(cosine) < 1e-6) break;  // too close to call: the rest of the path is not followed
      restart = cosine <= 0;
    }
    INFO("seed " << seed);
    CHECK(uphill >= 3);  // the path went uphill (else the check above tested nothing)
  }
}

namespace {

// A checkpoint a minimisation offered: its coordinates and its progress.
struct Offered {
  Eigen::VectorXd q;
  FireProgress progress;
};

}  // namespace

TEST_CASE("a minimisation resumed from any of its checkpoints ends in the bits of the uninterrupted one", "[fast]") {
  // The default minimiser (the Newton finish included) with an active-set try after 100 evaluations
  // that is undone (every step counts as a rearrangement) and a hand-over after 400, so that the
  // checkpoints fall before and after both, with neighbour-list rebuilds between them.
  const Packing start = random_packing(100, 1.0, 2);
  FireParams params;
  params.active_set_try_after = 100;
  params.active_set_try_move = 1e-12;
  params.active_set_after = 400;
  Packing plain = start;
  ForceField plain_field;
  const FireResult uninterrupted = minimise(plain, plain_field, params);
  REQUIRE(uninterrupted.converged);

  std::vector<Offered> offered;
  FireCheckpoints every;
  every.every = 17;
  every.save = [&](const Packing& p, const FireProgress& f) { offered.push_back({p.q, f}); };
  Packing checkpointed = start;
  ForceField field;
  const FireResult with = minimise(checkpointed, field, params, nullptr, &every);
  CHECK(checkpointed.q == plain.q);  // offering checkpoints changes nothing
  CHECK(with.evaluations == uninterrupted.evaluations);

  // The paths this test is for arose.
  REQUIRE(offered.size() > 10);
  CHECK(uninterrupted.active_set_tries_undone == 1);
  CHECK(uninterrupted.active_set_steps > 1);
  CHECK(offered.front().progress.so_far.active_set_steps == 0);
  CHECK(offered.back().progress.so_far.active_set_tries_undone == 1);
  bool rebuilt_between = false;
  for (std::size_t k = 1; k < offered.size(); ++k)
    rebuilt_between |= offered[k].progress.neighbours.x0 != offered[k - 1].progress.neighbours.x0;
  CHECK(rebuilt_between);

  for (const Offered& o : offered) {
    INFO("resumed at iteration " << o.progress.iteration << ", " << o.progress.so_far.evaluations << " evaluations");
    Packing p = start;
    p.q = o.q;
    ForceField fresh;
    FireCheckpoints from;
    from.resume = &o.progress;
    const FireResult r = minimise(p, fresh, params, nullptr, &from);
    CHECK(p.q == plain.q);
    CHECK(r.energy == uninterrupted.energy);
    CHECK(r.iterations == uninterrupted.iterations);
    CHECK(r.evaluations == uninterrupted.evaluations);
    CHECK(r.newton_iterations == uninterrupted.newton_iterations);
    CHECK(r.active_set_steps == uninterrupted.active_set_steps);
    CHECK(r.active_set_tries_undone == uninterrupted.active_set_tries_undone);
  }
}

TEST_CASE("a minimisation offers no checkpoint while its Newton factor is kept", "[fast]") {
  Packing p = random_packing(100, 1.0, 2);
  FireParams params;
  params.active_set_after = 0;
  NewtonWorkspace newton;
  long offered = 0, offered_with_factor = 0;
  FireCheckpoints every;
  every.every = 1;
  every.save = [&](const Packing&, const FireProgress&) {
    ++offered;
    offered_with_factor += newton.factored;
  };
  ForceField field;
  const FireResult r = minimise(p, field, params, &newton, &every);
  REQUIRE(r.newton_iterations > 0);
  CHECK(offered > 0);
  CHECK(offered_with_factor == 0);
}
