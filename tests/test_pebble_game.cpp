// The (2,3) pebble game against frameworks with known rigidity, and against an independent
// method: the rank of the rigidity matrix of a generic realisation (dense SVD).
#include "budjam/pebble_game.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <set>
#include <utility>
#include <vector>

using namespace budjam;

namespace {

PebbleGame play(std::size_t joints, const std::vector<Bar>& bars) {
  PebbleGame g(joints);
  for (const Bar& e : bars) g.add_bar(e.a, e.b);
  return g;
}

// Internal floppy modes of a generic framework in the plane: free pebbles minus the 3 motions.
long internal_floppy(const PebbleGame& g) { return g.free_pebbles() - 3; }

// Rigidity matrix of a realisation: one row per bar, (p_a − p_b) on a's columns, (p_b − p_a) on b's.
Eigen::MatrixXd rigidity_matrix(const Eigen::MatrixX2d& pos, const std::vector<Bar>& bars) {
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(bars.size()), 2 * pos.rows());
  for (std::size_t k = 0; k < bars.size(); ++k) {
    const Eigen::RowVector2d d = pos.row(bars[k].a) - pos.row(bars[k].b);
    R.block<1, 2>(static_cast<Eigen::Index>(k), 2 * bars[k].a) = d;
    R.block<1, 2>(static_cast<Eigen::Index>(k), 2 * bars[k].b) = -d;
  }
  return R;
}

long rank(const Eigen::MatrixXd& R) {
  if (R.rows() == 0) return 0;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(R);
  const auto& s = svd.singularValues();
  long r = 0;
  for (Eigen::Index k = 0; k < s.size(); ++k)
    if (s[k] > 1e-9 * s[0]) ++r;
  return r;
}

std::vector<Bar> random_graph(std::size_t n, std::size_t m, std::mt19937_64& rng) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  std::vector<Bar> bars;
  std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(n - 1));
  while (bars.size() < m) {
    std::uint32_t a = pick(rng), b = pick(rng);
    if (a == b) continue;
    if (!seen.insert({std::min(a, b), std::max(a, b)}).second) continue;
    bars.push_back({a, b});
  }
  return bars;
}

Eigen::MatrixX2d random_positions(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixX2d p(static_cast<Eigen::Index>(n), 2);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) << u(rng), u(rng);
  return p;
}

// Joint pairs (u < w) that share a rigid cluster.
std::set<std::pair<std::uint32_t, std::uint32_t>> rigid_pairs(const RigidClusters& rc) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> out;
  for (const auto& js : rc.joints)
    for (std::size_t p = 0; p < js.size(); ++p)
      for (std::size_t q = p + 1; q < js.size(); ++q) out.insert({js[p], js[q]});
  return out;
}

}  // namespace

TEST_CASE("a triangle is rigid: no internal floppy mode, three trivial motions, one cluster", "[fast]") {
  PebbleGame g = play(3, {{0, 1}, {1, 2}, {2, 0}});
  CHECK(g.independent_bars() == 3);
  CHECK(g.redundant_bars() == 0);
  CHECK(g.free_pebbles() == 3);
  CHECK(internal_floppy(g) == 0);
  const RigidClusters rc = g.rigid_clusters();
  REQUIRE(rc.size() == 1);
  CHECK(rc.joints[0] == std::vector<std::uint32_t>{0, 1, 2});
  CHECK(g.free_pebbles() == 3);  // decomposition moves pebbles, never creates or loses them
}

TEST_CASE("a square has one floppy mode and four single-bar clusters", "[fast]") {
  PebbleGame g = play(4, {{0, 1}, {1, 2}, {2, 3}, {3, 0}});
  CHECK(g.redundant_bars() == 0);
  CHECK(internal_floppy(g) == 1);
  CHECK(g.rigid_clusters().size() == 4);
}

TEST_CASE("a square with one diagonal is rigid and isostatic", "[fast]") {
  PebbleGame g = play(4, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}});
  CHECK(g.redundant_bars() == 0);
  CHECK(internal_floppy(g) == 0);
  CHECK(g.rigid_clusters().size() == 1);
}

TEST_CASE("a square with both diagonals (K4) has exactly one redundant bar, whatever the order", "[fast]") {
  std::vector<Bar> k4{{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}, {1, 3}};
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    std::shuffle(k4.begin(), k4.end(), rng);
    PebbleGame g = play(4, k4);
    CHECK(g.independent_bars() == 5);
    CHECK(g.redundant_bars() == 1);
    CHECK(internal_floppy(g) == 0);
    CHECK(!g.independent(5));  // the last bar closes the over-constrained K4
    const RigidClusters rc = g.rigid_clusters();
    REQUIRE(rc.size() == 1);
    CHECK(std::all_of(rc.of_bar.begin(), rc.of_bar.end(), [](int c) { return c == 0; }));
  }
}

TEST_CASE("K5 has three redundant bars (10 bars, 2·5 − 3 = 7 independent)", "[fast]") {
  std::vector<Bar> bars;
  for (std::uint32_t a = 0; a < 5; ++a)
    for (std::uint32_t b = a + 1; b < 5; ++b) bars.push_back({a, b});
  PebbleGame g = play(5, bars);
  CHECK(g.independent_bars() == 7);
  CHECK(g.redundant_bars() == 3);
}

TEST_CASE("two-cell dumbbell systems: each contact removes one mode until the pair is rigid", "[fast]") {
  // Joints 0,1 = mother, bud of cell 0; 2,3 = cell 1. A cell alone has 3 free pebbles.
  PebbleGame g(4);
  g.add_bar(0, 1);
  g.add_bar(2, 3);
  CHECK(internal_floppy(g) == 3);  // relative motion of two free rigid bodies
  g.add_bar(0, 2);                 // mother–mother contact: both buds still swing
  CHECK(internal_floppy(g) == 2);
  g.add_bar(1, 3);  // bud–bud contact: a four-bar linkage
  CHECK(internal_floppy(g) == 1);
  g.add_bar(0, 3);  // mother–bud contact: rigid
  CHECK(internal_floppy(g) == 0);
  g.add_bar(1, 2);  // the fourth possible contact can only be redundant
  CHECK(g.redundant_bars() == 1);
  CHECK(internal_floppy(g) == 0);
}

TEST_CASE("a bud hanging on its mother alone adds exactly one floppy mode", "[fast]") {
  std::mt19937_64 rng(11);
  // A rigid base: a triangulated strip of 10 joints.
  std::vector<Bar> base;
  for (std::uint32_t i = 0; i + 1 < 10; ++i) base.push_back({i, i + 1});
  for (std::uint32_t i = 0; i + 2 < 10; ++i) base.push_back({i, i + 2});
  PebbleGame g = play(10, base);
  REQUIRE(internal_floppy(g) == 0);
  const std::uint32_t bud = g.add_joint();
  CHECK(internal_floppy(g) == 2);  // a free joint: two translations
  g.add_bar(4, bud);
  CHECK(internal_floppy(g) == 1);  // hanging on one bar: its rotation about the mother
  const RigidClusters rc = g.rigid_clusters();
  CHECK(rc.size() == 2);
  CHECK(rc.joints[rc.of_bar.back()] == std::vector<std::uint32_t>{4, bud});
  g.add_bar(6, bud);  // one contact on a rigid neighbour pins it
  CHECK(internal_floppy(g) == 0);
  CHECK(g.rigid_clusters().size() == 1);
}

TEST_CASE("hand-built rigid clusters: a bowtie hinges at its shared joint; two triangles need three links", "[fast]") {
  SECTION("two triangles sharing joint 2") {
    PebbleGame g = play(5, {{0, 1}, {1, 2}, {2, 0}, {2, 3}, {3, 4}, {4, 2}});
    CHECK(internal_floppy(g) == 1);
    const RigidClusters rc = g.rigid_clusters();
    REQUIRE(rc.size() == 2);
    CHECK(rc.joints[0] == std::vector<std::uint32_t>{0, 1, 2});
    CHECK(rc.joints[1] == std::vector<std::uint32_t>{2, 3, 4});
    CHECK(rc.of_bar == std::vector<int>{0, 0, 0, 1, 1, 1});
  }
  SECTION("triangles 012 and 345 linked by bars 0-3 and 1-4, then 2-5") {
    PebbleGame g = play(6, {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}});
    CHECK(internal_floppy(g) == 1);
    RigidClusters rc = g.rigid_clusters();
    REQUIRE(rc.size() == 4);
    CHECK(rc.joints[0] == std::vector<std::uint32_t>{0, 1, 2});
    CHECK(rc.joints[1] == std::vector<std::uint32_t>{0, 3});
    CHECK(rc.joints[2] == std::vector<std::uint32_t>{1, 4});
    CHECK(rc.joints[3] == std::vector<std::uint32_t>{3, 4, 5});
    g.add_bar(2, 5);
    CHECK(internal_floppy(g) == 0);
    rc = g.rigid_clusters();
    REQUIRE(rc.size() == 1);
    CHECK(rc.joints[0].size() == 6);
  }
}

TEST_CASE("independent bars equal the rank of the generic rigidity matrix on random graphs", "[fast]") {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = 5 + static_cast<std::size_t>(trial % 30);
    // from sparse (floppy) to dense (over-constrained): m/n between 1 and ~3
    const std::size_t m = std::min(n * (n - 1) / 2, n + static_cast<std::size_t>(trial) % (2 * n + 1));
    const std::vector<Bar> bars = random_graph(n, m, rng);
    const Eigen::MatrixX2d pos = random_positions(n, rng);
    PebbleGame g = play(n, bars);
    const Eigen::MatrixXd R = rigidity_matrix(pos, bars);
    INFO("n = " << n << ", m = " << m);
    CHECK(static_cast<long>(g.independent_bars()) == rank(R));
    // Bar by bar: the game's verdict is the greedy basis of the matroid, so bar k is
    // independent exactly when it raises the rank of the bars before it.
    long before = 0;
    for (std::size_t k = 0; k < bars.size(); ++k) {
      const long now = rank(R.topRows(static_cast<Eigen::Index>(k + 1)));
      CHECK(g.independent(k) == (now > before));
      before = now;
    }
  }
}

TEST_CASE("two joints share a rigid cluster exactly when a bar between them would not raise the rank", "[fast]") {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 12; ++trial) {
    const std::size_t n = 14;
    const std::size_t m = 16 + 2 * static_cast<std::size_t>(trial);  // floppy to rigid
    const std::vector<Bar> bars = random_graph(n, m, rng);
    const Eigen::MatrixX2d pos = random_positions(n, rng);
    PebbleGame g = play(n, bars);
    const auto pairs = rigid_pairs(g.rigid_clusters());
    const Eigen::MatrixXd R = rigidity_matrix(pos, bars);
    const long r = rank(R);
    for (std::uint32_t u = 0; u < n; ++u)
      for (std::uint32_t w = u + 1; w < n; ++w) {
        std::vector<Bar> plus(bars);
        plus.push_back({u, w});
        const bool rigid = rank(rigidity_matrix(pos, plus)) == r;
        INFO("trial " << trial << ", joints " << u << ", " << w);
        CHECK(pairs.count({u, w}) == (rigid ? 1u : 0u));
      }
  }
}

TEST_CASE("incremental insertion and removal agree with a game played from scratch", "[fast]") {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t n = 40;
    std::vector<Bar> bars = random_graph(n, 60 + 2 * static_cast<std::size_t>(trial), rng);
    // Insert in one order, one bar at a time, asking for the decomposition on the way.
    PebbleGame inc(n);
    for (std::size_t k = 0; k < bars.size(); ++k) {
      inc.add_bar(bars[k].a, bars[k].b);
      if (k % 17 == 0) inc.rigid_clusters();  // moves pebbles; must not change anything
    }
    // From scratch in another order.
    std::vector<Bar> shuffled(bars);
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    PebbleGame ref = play(n, shuffled);
    CHECK(inc.independent_bars() == ref.independent_bars());
    CHECK(inc.free_pebbles() == ref.free_pebbles());
    CHECK(rigid_pairs(inc.rigid_clusters()) == rigid_pairs(ref.rigid_clusters()));

    // Remove a random third of the bars; compare with a fresh game on the survivors.
    std::vector<bool> remove(bars.size());
    std::vector<Bar> kept;
    std::bernoulli_distribution coin(1.0 / 3.0);
    for (std::size_t k = 0; k < bars.size(); ++k) {
      remove[k] = coin(rng);
      if (!remove[k]) kept.push_back(bars[k]);
    }
    inc.remove_bars(remove);
    REQUIRE(inc.bars() == kept.size());
    for (std::size_t k = 0; k < kept.size(); ++k) CHECK((inc.bar(k).a == kept[k].a && inc.bar(k).b == kept[k].b));
    PebbleGame fresh = play(n, kept);
    CHECK(inc.independent_bars() == fresh.independent_bars());
    const RigidClusters a = inc.rigid_clusters(), b = fresh.rigid_clusters();
    CHECK(a.joints == b.joints);  // canonical order: identical decompositions
    CHECK(a.of_bar == b.of_bar);
  }
}

TEST_CASE("any sequence of insertions, removals and decompositions keeps the rank of a fresh game", "[fast]") {
  // Exercises the known-rigid-region shortcuts, which must never outlive what certifies them.
  std::size_t quick = 0;
  for (int seed = 0; seed < 300; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    const std::size_t n = 10 + static_cast<std::size_t>(seed % 20);
    const std::vector<Bar> pool = random_graph(n, 2 * n, rng);
    PebbleGame g(n);
    std::vector<Bar> current;
    std::vector<bool> present(pool.size(), false);
    for (int op = 0; op < 30; ++op) {
      const auto kind = rng() % 3;
      if (kind == 0 || current.empty()) {
        for (std::size_t k = 0; k < pool.size(); ++k)
          if (!present[k] && rng() % 3 == 0) {
            g.add_bar(pool[k].a, pool[k].b);
            current.push_back(pool[k]);
            present[k] = true;
          }
      } else if (kind == 1) {
        std::vector<bool> remove(current.size());
        std::vector<Bar> kept;
        for (std::size_t k = 0; k < current.size(); ++k) {
          remove[k] = rng() % 5 == 0;
          if (!remove[k]) kept.push_back(current[k]);
        }
        g.remove_bars(remove);
        current = kept;
        std::fill(present.begin(), present.end(), false);
        for (const Bar& e : current)
          for (std::size_t k = 0; k < pool.size(); ++k)
            if (pool[k].a == e.a && pool[k].b == e.b) present[k] = true;
      } else {
        g.rigid_clusters();
      }
      PebbleGame fresh = play(n, current);
      INFO("seed " << seed << ", operation " << op);
      REQUIRE(g.independent_bars() == fresh.independent_bars());
    }
    quick += g.work().quick_rejections;
  }
  CHECK(quick > 100);  // the shortcuts were taken
}

TEST_CASE("removing only redundant bars costs no re-test", "[fast]") {
  std::vector<Bar> k4{{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}, {1, 3}};
  PebbleGame g = play(4, k4);
  REQUIRE(!g.independent(5));
  const std::size_t tested = g.work().bars_tested;
  CHECK(g.remove_bars({false, false, false, false, false, true}) == 0);
  CHECK(g.work().bars_tested == tested);
  CHECK(g.redundant_bars() == 0);
  CHECK(g.free_pebbles() == 3);
  // Removing an independent bar of the rigid square+diagonal frees one mode.
  CHECK(g.remove_bars({false, false, false, false, true}) == 0);
  CHECK(g.free_pebbles() == 4);
}

TEST_CASE("a redundant bar becomes independent when a bar of its circuit is removed", "[fast]") {
  // Square + diagonal 0-2, then diagonal 1-3 is redundant; removing 0-2 makes 1-3 independent.
  PebbleGame g = play(4, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}, {1, 3}});
  REQUIRE(g.redundant_bars() == 1);
  CHECK(g.remove_bars({false, false, false, false, true, false}) == 1);
  CHECK(g.independent_bars() == 5);
  CHECK(g.redundant_bars() == 0);
  CHECK(g.free_pebbles() == 3);
}

TEST_CASE("bad bars are rejected with an exception", "[fast]") {
  PebbleGame g(3);
  CHECK_THROWS_AS(g.add_bar(1, 1), std::invalid_argument);
  CHECK_THROWS_AS(g.add_bar(0, 3), std::invalid_argument);
  CHECK_THROWS_AS(g.remove_bars({true}), std::invalid_argument);
}
