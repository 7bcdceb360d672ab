// Linked cells + Verlet skin against the O(N²) oracle, in ordinary, sheared, tiny and huge boxes.
#include "budjam/cell_list.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include "random_packing.hpp"

using namespace budjam;

namespace {

using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

// N cells with bud diameters uniform in [b_min, b_max] at packing fraction φ, uniformly placed and
// oriented; centroids are then shifted by random whole periods, since q is never wrapped.
Packing random_packing(std::size_t n, double phi, std::uint64_t seed, double b_min = 0.01, double b_max = 1.02) {
  return budjam::testing::random_packing(n, phi, seed, b_min, b_max, /*periods=*/3);
}

PairList sorted(PairList v) {
  std::sort(v.begin(), v.end());
  return v;
}

PairList built_pairs(const Lobes& lobes, const Box& box, double skin) {
  NeighbourList list(skin);
  list.update(lobes, box);
  return list.pairs();
}

}  // namespace

TEST_CASE("linked-cell pairs equal brute-force pairs within sigma + skin", "[fast]") {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    for (double phi : {0.1, 0.5, 0.9, 1.3}) {
      const Packing p = random_packing(150, phi, seed);
      Lobes lobes;
      place_lobes(p, lobes);
      for (double skin : {0.05, 0.3, 0.7}) {
        const PairList cells = built_pairs(lobes, p.box, skin);
        INFO("seed " << seed << " phi " << phi << " skin " << skin);
        CHECK(cells == sorted(cells));  // documented order: by (a, b)
        CHECK(cells == brute_force_pairs(lobes, p.box, skin));
      }
    }
  }
}

TEST_CASE("linked-cell pairs equal brute-force pairs under Lees-Edwards shear", "[fast]") {
  for (double shear : {0.1, 0.37, -0.8, 1.3, 1e-9, 0.5}) {
    for (std::uint64_t seed = 11; seed <= 14; ++seed) {
      Packing p = random_packing(200, 1.0, seed);
      p.box.shear = shear;
      Lobes lobes;
      place_lobes(p, lobes);
      INFO("shear " << shear << " seed " << seed);
      CHECK(built_pairs(lobes, p.box, 0.3) == brute_force_pairs(lobes, p.box, 0.3));
    }
  }
}

TEST_CASE("linked-cell pairs equal brute-force pairs in boxes of one to four grid cells", "[fast]") {
  // L from below 2 cut-offs (grid 1) to about 4 cut-offs; dense and sheared variants.
  for (double L : {2.0, 2.7, 3.5, 4.2, 5.5}) {
    for (double shear : {0.0, 0.3, -0.55}) {
      for (std::uint64_t seed = 21; seed <= 25; ++seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        Packing p;
        p.box = {L, shear};
        const int n = 2 + static_cast<int>(L * L / 2);
        for (int i = 0; i < n; ++i)
          p.add_cell(L * (u(rng) + 2), L * (u(rng) - 1), 7 * u(rng), 0.01 + u(rng), 0.002, -1);
        Lobes lobes;
        place_lobes(p, lobes);
        NeighbourList list(0.3);
        list.update(lobes, p.box);
        INFO("L " << L << " shear " << shear << " seed " << seed << " grid " << list.grid());
        CHECK(list.grid() <= 4);
        CHECK(list.pairs() == brute_force_pairs(lobes, p.box, 0.3));
      }
    }
  }
}

TEST_CASE("Verlet list and its near list keep every contact until their skin criteria trigger rebuilds", "[fast]") {
  Packing p = random_packing(200, 0.9, 31);
  const double skin = 0.3;
  NeighbourList list(skin);
  REQUIRE(list.near_skin() > 0.0);
  REQUIRE(list.near_skin() < skin);
  Lobes lobes;
  place_lobes(p, lobes);
  REQUIRE(list.update(lobes, p.box));
  std::mt19937_64 rng(32);
  std::normal_distribution<double> g(0.0, 1.0);
  long rebuilds = 0, steps = 0;
  const long near_before = list.near_rebuilds();
  std::size_t listed = 0, near = 0;
  for (int step = 0; step < 300; ++step) {
    // Small random moves of every cell (translations and rotations).
    for (std::size_t i = 0; i < p.size(); ++i) {
      p.q[3 * i] += 0.002 * g(rng);
      p.q[3 * i + 1] += 0.002 * g(rng);
      p.q[3 * i + 2] += 0.004 * g(rng);
    }
    place_lobes(p, lobes);
    rebuilds += list.update(lobes, p.box) ? 1 : 0;
    ++steps;
    // Every pair within σ must be listed, and be in the near list.
    const PairList contacts = brute_force_pairs(lobes, p.box, 0.0);
    const PairList& have = list.pairs();
    std::vector<bool> is_near(have.size(), false);
    for (std::uint32_t k : list.near()) is_near.at(k) = true;
    REQUIRE(std::is_sorted(list.near().begin(), list.near().end()));
    for (const auto& c : contacts) {
      const auto it = std::lower_bound(have.begin(), have.end(), c);
      REQUIRE(it != have.end());
      REQUIRE(*it == c);
      REQUIRE(is_near[static_cast<std::size_t>(it - have.begin())]);
    }
    listed += have.size();
    near += list.near().size();
  }
  const long near_rebuilds = list.near_rebuilds() - near_before;
  CHECK(rebuilds > 0);
  CHECK(rebuilds < steps / 3);      // the skin actually saves rebuilds
  CHECK(near_rebuilds > rebuilds);  // most expiries of the near list leave the pair list valid
  CHECK(near_rebuilds < steps);     // the near skin saves near rebuilds too
  CHECK(5 * near < 4 * listed);     // and the near list is markedly shorter (62 % here)
}

TEST_CASE("neighbour list rebuilds on changed radii, count or box, and not otherwise", "[fast]") {
  Packing p = random_packing(50, 0.8, 41);
  NeighbourList list(0.3);  // near skin 0.06
  Lobes lobes;
  place_lobes(p, lobes);
  CHECK(list.update(lobes, p.box));
  CHECK_FALSE(list.update(lobes, p.box));
  lobes.R[7] += 1e-12;  // a bud grew a little
  CHECK(list.update(lobes, p.box));
  CHECK_FALSE(list.update(lobes, p.box));
  p.box.shear = 1e-6;
  CHECK(list.update(lobes, p.box));
  p.box.L *= 1.0000001;
  CHECK(list.update(lobes, p.box));
  p.add_cell(1, 1, 0, 0.01, 0.002, -1);
  place_lobes(p, lobes);
  CHECK(list.update(lobes, p.box));
  CHECK(list.pairs() == brute_force_pairs(lobes, p.box, 0.3));
  // Moves below the near skin rebuild nothing; moves beyond it rebuild the near list alone while
  // they stay below the skin minus the near skin; a single lobe moving by most of a skin
  // rebuilds both.
  const long near_built = list.near_rebuilds();
  lobes.x[0] += 0.02;
  lobes.x[5] += 0.02;
  CHECK_FALSE(list.update(lobes, p.box));
  CHECK(list.near_rebuilds() == near_built);
  lobes.x[0] += 0.09;
  lobes.x[5] += 0.09;
  CHECK_FALSE(list.update(lobes, p.box));
  CHECK(list.near_rebuilds() == near_built + 1);
  // Now d₁ + d₂ = 0.29 since the pair list's build: still below the skin, but the next near list
  // could live until 0.29 + 0.06 > 0.3, so the pair list is rebuilt with it.
  lobes.x[0] += 0.035;
  lobes.x[5] += 0.035;
  CHECK(list.update(lobes, p.box));
  CHECK(list.near_rebuilds() == near_built + 2);
  lobes.x[9] += 0.25;
  CHECK(list.update(lobes, p.box));
  CHECK(list.near_rebuilds() == near_built + 3);
  list.invalidate();
  CHECK(list.update(lobes, p.box));
}

TEST_CASE("neighbour list refuses non-finite lobe positions", "[fast]") {
  Packing p = random_packing(10, 0.5, 51);
  NeighbourList list(0.3);
  Lobes lobes;
  place_lobes(p, lobes);
  list.update(lobes, p.box);
  lobes.x[3] = std::nan("");
  CHECK_THROWS_AS(list.update(lobes, p.box), std::domain_error);
}

TEST_CASE("huge box with two cells: capped grid finds the pair across the corner", "[.hard]") {
  for (double shear : {0.0, 0.25}) {
    Packing p;
    p.box = {1000.0, shear};
    // Two cells overlapping across the corner of the box (images in x and y).
    p.add_cell(999.8, 999.9, 0.3, 1.0, 0.002, -1);
    p.add_cell(0.2 - shear * 1000.0, 0.1, 2.0, 0.5, 0.002, -1);  // its image above is at x + γL
    Lobes lobes;
    place_lobes(p, lobes);
    NeighbourList list(0.3);
    list.update(lobes, p.box);
    INFO("shear " << shear);
    CHECK(list.grid() <= 4);  // not 757² cells for four lobes
    CHECK_FALSE(brute_force_pairs(lobes, p.box, 0.0).empty());
    CHECK(list.pairs() == brute_force_pairs(lobes, p.box, 0.3));
  }
}

TEST_CASE("neighbour pairs of a tiny box (L = 2, two cells) equal brute force", "[.hard]") {
  for (double shear : {0.0, 0.4}) {
    for (int k = 0; k < 50; ++k) {
      Packing p;
      p.box = {2.0, shear};
      p.add_cell(0.1 * k, 1.9 - 0.03 * k, 0.4 * k, 0.01 + 0.02 * k, 0.002, -1);
      p.add_cell(1.7 + 0.01 * k, 0.05 * k, -0.3 * k, 1.02 - 0.02 * k, 0.002, -1);
      Lobes lobes;
      place_lobes(p, lobes);
      INFO("k " << k << " shear " << shear);
      CHECK(built_pairs(lobes, p.box, 0.3) == brute_force_pairs(lobes, p.box, 0.3));
    }
  }
}
