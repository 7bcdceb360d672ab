// Rigidity of packings: framework construction, floppy-mode conventions against the periodic
// rigidity matrix, rigidity percolation, and the tracker (incremental = from scratch, events).
#include "budjam/contact_network.hpp"
#include "budjam/growth_driver.hpp"
#include "budjam/rigidity.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "random_packing.hpp"
#include "run_budjam.hpp"
#include "scratch.hpp"

#include <sys/wait.h>

#include <unistd.h>
#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

using namespace budjam;

namespace {

// Every pair of lobes on different cells that overlaps (minimum image): an O(N²) oracle, so
// these tests do not depend on the neighbour list.
std::vector<Contact> overlaps(const Packing& p) {
  Lobes lobes;
  place_lobes(p, lobes);
  std::vector<Contact> out;
  for (std::uint32_t i = 0; i < lobes.size(); ++i)
    for (std::uint32_t j = i + 1; j < lobes.size(); ++j) {
      if (cell_of(i) == cell_of(j)) continue;
      double dx = lobes.x[i] - lobes.x[j], dy = lobes.y[i] - lobes.y[j];
      p.box.minimum_image(dx, dy);
      const double r = std::hypot(dx, dy), sigma = lobes.R[i] + lobes.R[j];
      if (r < sigma) out.push_back({i, j, dx / r, dy / r, r, sigma});
    }
  return out;
}

// Random overlapping cells with buds of 0.05–1 (the shared generator, with its θ in (−π, π]).
Packing random_packing(std::size_t n, double phi, std::uint64_t seed) {
  return testing::random_packing(n, phi, seed, 0.05, 1.0);
}

struct Analysed {
  Lobes lobes;
  std::vector<Contact> contacts;
  ContactNetwork net;
};

Analysed analyse(const Packing& p) {
  Analysed a;
  place_lobes(p, a.lobes);
  a.contacts = overlaps(p);
  a.net = analyse_network(p.size(), a.contacts);
  return a;
}

ContactNetwork no_rattlers(std::size_t n) {
  ContactNetwork net;
  net.rattler.assign(n, false);
  return net;
}

// Every observable of two states, cluster by cluster (clusters are in canonical order).
void require_same(const RigidityState& a, const RigidityState& b) {
  REQUIRE(a.cells == b.cells);
  REQUIRE(a.bars == b.bars);
  REQUIRE(a.independent_bars == b.independent_bars);
  REQUIRE(a.redundant_bars == b.redundant_bars);
  REQUIRE(a.floppy_plane == b.floppy_plane);
  REQUIRE(a.clusters.size() == b.clusters.size());
  for (std::size_t c = 0; c < a.clusters.size(); ++c) {
    REQUIRE(a.clusters[c].joints == b.clusters[c].joints);
    REQUIRE(a.clusters[c].bars == b.clusters[c].bars);
    REQUIRE(a.clusters[c].cells == b.clusters[c].cells);
    REQUIRE(a.clusters[c].winding.x == b.clusters[c].winding.x);
    REQUIRE(a.clusters[c].winding.y == b.clusters[c].winding.y);
  }
  REQUIRE(a.largest == b.largest);
  REQUIRE(a.spans_x == b.spans_x);
  REQUIRE(a.spans_y == b.spans_y);
  REQUIRE(a.cell_cluster == b.cell_cluster);
}

// Periodic rigidity matrix on a fixed torus of side L: bar (a, b, s) has vector
// d = p_b + s L − p_a; its row holds −d on a's columns and d on b's.
long periodic_rank(const Eigen::MatrixX2d& pos, const std::vector<Bar>& bars, const std::vector<ImageShift>& shift,
                   double L) {
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(bars.size()), 2 * pos.rows());
  for (std::size_t k = 0; k < bars.size(); ++k) {
    const Eigen::RowVector2d d =
        pos.row(bars[k].b) + L * Eigen::RowVector2d(shift[k].x, shift[k].y) - pos.row(bars[k].a);
    R.block<1, 2>(static_cast<Eigen::Index>(k), 2 * bars[k].a) = -d;
    R.block<1, 2>(static_cast<Eigen::Index>(k), 2 * bars[k].b) = d;
  }
  Eigen::BDCSVD<Eigen::MatrixXd> svd(R);
  const auto& s = svd.singularValues();
  long r = 0;
  for (Eigen::Index k = 0; k < s.size(); ++k)
    if (s[k] > 1e-9 * s[0]) ++r;
  return r;
}

// Free pebbles of a framework given as bars.
long pebbles(std::size_t joints, const std::vector<Bar>& bars) {
  PebbleGame g(joints);
  for (const Bar& e : bars) g.add_bar(e.a, e.b);
  return g.free_pebbles();
}

// Triangulated m × h strip of joints (i, j) → i + m j; horizontal and diagonal bars wrap in x
// (image shift +1 across the seam) when `wrap` is set; nothing wraps in y.
void strip(std::size_t m, std::size_t h, bool wrap, std::vector<Bar>& bars, std::vector<ImageShift>& shift) {
  const auto id = [m](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(i + m * j); };
  for (std::size_t j = 0; j < h; ++j)
    for (std::size_t i = 0; i < m; ++i) {
      const bool seam = i + 1 == m;
      if (!seam || wrap) {
        bars.push_back({id(i, j), id((i + 1) % m, j)});
        shift.push_back({seam ? 1 : 0, 0});
      }
      if (j + 1 < h) {
        bars.push_back({id(i, j), id(i, j + 1)});
        shift.push_back({0, 0});
        if (!seam || wrap) {
          bars.push_back({id(i, j), id((i + 1) % m, j + 1)});
          shift.push_back({seam ? 1 : 0, 0});
        }
      }
    }
}

}  // namespace

TEST_CASE("the framework has one bar per included cell and per contact among included cells", "[fast]") {
  Packing p = random_packing(60, 0.95, 3);
  const Analysed a = analyse(p);
  REQUIRE(a.net.N_f > 0);  // the test needs rattlers
  const Framework raw = build_framework(p, a.lobes, a.contacts, a.net, RigidityNetwork::raw);
  CHECK(raw.joints == 120);
  CHECK(raw.cells == 60);
  CHECK(raw.bars.size() == 60 + a.contacts.size());
  const Framework lb = build_framework(p, a.lobes, a.contacts, a.net, RigidityNetwork::load_bearing);
  CHECK(lb.cells == a.net.N_nr);
  CHECK(lb.bars.size() == a.net.N_nr + a.net.N_c / 2);  // N_c counts every contact twice
  for (const Bar& e : lb.bars) {
    CHECK(e.a < e.b);
    CHECK(!a.net.rattler[cell_of(e.a)]);
    CHECK(!a.net.rattler[cell_of(e.b)]);
  }
  CHECK(std::is_sorted(lb.bars.begin(), lb.bars.end(),
                       [](const Bar& u, const Bar& v) { return u.a < v.a || (u.a == v.a && u.b < v.b); }));
}

TEST_CASE("two-cell packings: floppy modes = 3 − min(contacts, 3), redundant = contacts − 3", "[fast]") {
  // Two rigid bodies in the plane: each contact removes one relative degree of freedom until
  // three, any further one is a self-stress. Random placements of the second cell around the first.
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<int> seen(5, 0);
  for (int trial = 0; trial < 4000; ++trial) {
    Packing p;
    p.box.L = 10;
    p.add_cell(5.0, 5.0, 2 * std::numbers::pi * u(rng), 0.2 + 0.8 * u(rng), 0.002, -1);
    p.add_cell(5.0 + 3 * (u(rng) - 0.5), 5.0 + 3 * (u(rng) - 0.5), 2 * std::numbers::pi * u(rng), 0.2 + 0.8 * u(rng),
               0.002, -1);
    Lobes lobes;
    place_lobes(p, lobes);
    const auto contacts = overlaps(p);
    const long c = static_cast<long>(contacts.size());
    ++seen[static_cast<std::size_t>(c)];
    const RigidityState s = analyse_rigidity(p, lobes, contacts, no_rattlers(2), RigidityNetwork::raw);
    INFO("trial " << trial << ": " << c << " contacts");
    CHECK(s.joints == 4);
    CHECK(s.floppy_plane == 3 - std::min(c, 3L));
    CHECK(static_cast<long>(s.redundant_bars) == std::max(0L, c - 3));
    // A cell is held rigidly iff its two joints form a triangle with one lobe of the other cell
    // (two contacts from that lobe to both of its lobes), or the pair is rigid (≥ 3 contacts).
    for (std::uint32_t k = 0; k < 2; ++k) {
      bool triangle = false;
      for (std::uint32_t other = 2 * (1 - k); other < 2 * (1 - k) + 2; ++other) {
        int touches = 0;
        for (const Contact& ct : contacts)
          if ((ct.i == other && cell_of(ct.j) == k) || (ct.j == other && cell_of(ct.i) == k)) ++touches;
        triangle = triangle || touches == 2;
      }
      CHECK(s.bud_rigid(k) == (c >= 3 || triangle));
    }
  }
  CHECK(seen[1] > 0);
  CHECK(seen[2] > 0);
  CHECK(seen[3] > 0);
}

TEST_CASE("every contact-free lobe of a non-rattler is a hinge: floppy_plane ≥ N_u, those cells are not rigid",
          "[fast]") {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Packing p = random_packing(150, 1.25 + 0.1 * static_cast<double>(seed), seed);
    const Analysed a = analyse(p);
    const RigidityState s = analyse_rigidity(p, a.lobes, a.contacts, a.net);
    INFO("seed " << seed << ": N_nr = " << a.net.N_nr << ", N_u = " << a.net.N_u);
    REQUIRE(a.net.N_nr > 100);
    CHECK(s.cells == a.net.N_nr);
    CHECK(s.floppy_plane >= static_cast<long>(a.net.N_u));
    CHECK(s.floppy_periodic == s.floppy_plane + 1);
    CHECK(s.redundant_bars == s.bars - s.independent_bars);
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (a.net.rattler[i]) {
        CHECK(s.cell_cluster[i] == -1);
        continue;
      }
      const bool free_lobe = a.net.lobe_contacts[mother_lobe(i)] == 0 || a.net.lobe_contacts[bud_lobe(i)] == 0;
      if (free_lobe) CHECK_FALSE(s.bud_rigid(i));
    }
  }
}

TEST_CASE("on packing frameworks, independent bars = generic rigidity-matrix rank, and clusters = rank test",
          "[fast]") {
  const Packing p = random_packing(40, 1.3, 52);
  const Analysed a = analyse(p);
  const Framework fw = build_framework(p, a.lobes, a.contacts, a.net, RigidityNetwork::raw);
  PebbleGame g(fw.joints);
  for (const Bar& e : fw.bars) g.add_bar(e.a, e.b);
  // Generic realisation of the same graph: random joint positions in the plane.
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixX2d pos(static_cast<Eigen::Index>(fw.joints), 2);
  for (Eigen::Index k = 0; k < pos.rows(); ++k) pos.row(k) << u(rng), u(rng);
  const std::vector<ImageShift> none(fw.bars.size());
  const long r = periodic_rank(pos, fw.bars, none, 0.0);  // zero shifts, L = 0: the plain matrix
  CHECK(static_cast<long>(g.independent_bars()) == r);
  // A bar between two joints is redundant exactly when they share a rigid cluster.
  const RigidClusters rc = g.rigid_clusters();
  std::vector<std::vector<int>> member(fw.joints);
  for (std::size_t c = 0; c < rc.size(); ++c)
    for (std::uint32_t j : rc.joints[c]) member[j].push_back(static_cast<int>(c));
  std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(fw.joints - 1));
  int rigid_pairs = 0;
  for (int t = 0; t < 60; ++t) {
    std::uint32_t x = pick(rng), y = pick(rng);
    if (t % 2 == 0 && !rc.joints.empty()) {  // half of the pairs from one cluster, to test both answers
      const auto& js = rc.joints[static_cast<std::size_t>(t) % rc.size()];
      x = js.front();
      y = js.back();
    }
    if (x == y) continue;
    std::vector<Bar> plus(fw.bars);
    plus.push_back({x, y});
    const std::vector<ImageShift> plus_none(plus.size());
    const bool rigid = periodic_rank(pos, plus, plus_none, 0.0) == r;
    bool shared = false;
    for (int c : member[x]) shared = shared || std::count(member[y].begin(), member[y].end(), c) > 0;
    CHECK(shared == rigid);
    rigid_pairs += rigid;
  }
  CHECK(rigid_pairs > 10);
}

TEST_CASE("the raw network counts each isolated cell as a free rigid body: three more free pebbles", "[fast]") {
  Packing p = random_packing(120, 1.25, 8);
  // Wrap the cells into [0, L0)² and double the box: room for a lone cell far from the others.
  const double L0 = p.box.L;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] -= L0 * std::floor(p.x(i) / L0);
    p.q[3 * i + 1] -= L0 * std::floor(p.y(i) / L0);
  }
  p.box.L = 2 * L0;
  p.add_cell(0.75 * p.box.L, 0.75 * p.box.L, 0.3, 0.5, 0.002, -1);
  const Analysed a = analyse(p);
  REQUIRE(a.net.rattler.back());
  const RigidityState lb = analyse_rigidity(p, a.lobes, a.contacts, a.net, RigidityNetwork::load_bearing);
  const RigidityState raw = analyse_rigidity(p, a.lobes, a.contacts, a.net, RigidityNetwork::raw);
  // Remove the lone cell from the raw count: its 2 joints and 1 bar are 3 free pebbles.
  Packing without(p);
  without.b.pop_back();
  without.gamma0.pop_back();
  without.id.pop_back();
  without.parent.pop_back();
  without.q.conservativeResize(3 * static_cast<Eigen::Index>(without.size()));
  const Analysed w = analyse(without);
  const RigidityState raw_without = analyse_rigidity(without, w.lobes, w.contacts, w.net, RigidityNetwork::raw);
  CHECK(raw.free_pebbles == raw_without.free_pebbles + 3);
  CHECK(raw.cells == p.size());
  CHECK(lb.cells == a.net.N_nr);
  CHECK(raw.cell_cluster.back() >= 0);
  CHECK(lb.cell_cluster.back() == -1);
}

TEST_CASE("shifting cells by whole periods (also under Lees–Edwards shear) changes no observable", "[fast]") {
  for (double shear : {0.0, 0.137}) {
    Packing p = random_packing(100, 1.2, 21);
    p.box.shear = shear;
    const Analysed a = analyse(p);
    const RigidityState ref = analyse_rigidity(p, a.lobes, a.contacts, a.net);
    std::mt19937_64 rng(4);
    std::uniform_int_distribution<int> k(-3, 3);
    Packing moved(p);
    for (std::size_t i = 0; i < p.size(); ++i) {
      const int nx = k(rng), ny = k(rng);
      moved.q[3 * i] += nx * p.box.L + shear * p.box.L * ny;
      moved.q[3 * i + 1] += ny * p.box.L;
    }
    const Analysed b = analyse(moved);
    REQUIRE(b.contacts.size() == a.contacts.size());
    INFO("shear " << shear);
    require_same(ref, analyse_rigidity(moved, b.lobes, b.contacts, b.net));
  }
}

TEST_CASE("rigidity percolation: a dense packing spans x and y, a dense band only x, a blob neither", "[fast]") {
  const Packing dense = random_packing(150, 1.8, 2);
  const Analysed a = analyse(dense);
  const RigidityState s = analyse_rigidity(dense, a.lobes, a.contacts, a.net);
  CHECK(s.spans_x);
  CHECK(s.spans_y);
  REQUIRE(s.largest >= 0);
  CHECK(s.clusters[s.largest].winding.x);
  CHECK(s.clusters[s.largest].winding.y);

  // A dense horizontal band, 6 high, in a box of side 16: it closes on itself in x only.
  Packing band;
  band.box.L = 16;
  {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (double area = 0; area < 2.0 * band.box.L * 6;) {
      const double bud = 0.05 + 0.95 * u(rng);
      area += 0.25 * std::numbers::pi * (1 + bud * bud);
      band.add_cell(band.box.L * u(rng), 5 + 6 * u(rng), 2 * std::numbers::pi * u(rng), bud, 0.002, -1);
    }
  }
  const Analysed b = analyse(band);
  const RigidityState t = analyse_rigidity(band, b.lobes, b.contacts, b.net);
  CHECK(t.spans_x);
  CHECK_FALSE(t.spans_y);

  // The dense cells in the middle of a box four times larger: one piece, no winding.
  Packing blob(dense);
  const double L0 = dense.box.L;
  blob.box.L = 4 * L0;
  for (std::size_t i = 0; i < blob.size(); ++i) {
    blob.q[3 * i] = dense.x(i) - L0 * std::floor(dense.x(i) / L0) + 1.5 * L0;
    blob.q[3 * i + 1] = dense.y(i) - L0 * std::floor(dense.y(i) / L0) + 1.5 * L0;
  }
  const Analysed c = analyse(blob);
  const RigidityState w = analyse_rigidity(blob, c.lobes, c.contacts, c.net);
  CHECK(w.largest_cells() > 50);
  CHECK_FALSE(w.spans_x);
  CHECK_FALSE(w.spans_y);
}

TEST_CASE("a periodic triangulated strip is one rigid cluster that wraps in x only", "[fast]") {
  std::vector<Bar> bars;
  std::vector<ImageShift> shift;
  strip(7, 3, true, bars, shift);
  PebbleGame g(21);
  for (const Bar& e : bars) g.add_bar(e.a, e.b);
  const RigidClusters rc = g.rigid_clusters();
  REQUIRE(rc.size() == 1);
  const auto w = cluster_windings(21, bars, shift, rc);
  CHECK(w[0].x);
  CHECK_FALSE(w[0].y);

  SECTION("cut open at the seam: still rigid, no longer wrapping") {
    std::vector<Bar> open;
    std::vector<ImageShift> open_shift;
    strip(7, 3, false, open, open_shift);
    PebbleGame h(21);
    for (const Bar& e : open) h.add_bar(e.a, e.b);
    const RigidClusters oc = h.rigid_clusters();
    REQUIRE(oc.size() == 1);
    const auto ow = cluster_windings(21, open, open_shift, oc);
    CHECK_FALSE(ow[0].x);
    CHECK_FALSE(ow[0].y);
  }
  SECTION("without diagonals the wrapped ladder is floppy: single-bar clusters never wind") {
    std::vector<Bar> ladder;
    std::vector<ImageShift> ladder_shift;
    for (std::size_t k = 0; k < bars.size(); ++k) {
      const bool diagonal = bars[k].b != bars[k].a + 7 && (bars[k].a / 7 != bars[k].b / 7);
      if (diagonal) continue;
      ladder.push_back(bars[k]);
      ladder_shift.push_back(shift[k]);
    }
    PebbleGame h(21);
    for (const Bar& e : ladder) h.add_bar(e.a, e.b);
    const RigidClusters lc = h.rigid_clusters();
    CHECK(lc.size() == ladder.size());
    for (const Winding& x : cluster_windings(21, ladder, ladder_shift, lc)) CHECK_FALSE((x.x || x.y));
  }
}

TEST_CASE("floppy-mode conventions against the rank of the periodic rigidity matrix", "[fast]") {
  // Exact periodic count on a fixed torus: 2·joints − 2 − rank. It equals floppy_plane = F − 3
  // when a self-stressed rigid cluster winds (its rotation is blocked), and floppy_periodic =
  // F − 2 when no cycle winds or the winding cluster carries no self-stress.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  const double L = 6;
  SECTION("triangular lattice on the torus (spans x and y, self-stressed): F − 3") {
    const std::size_t m = 6;
    std::vector<Bar> bars;
    std::vector<ImageShift> shift;
    Eigen::MatrixX2d pos(m * m, 2);
    const auto id = [m](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>((i % m) + m * (j % m)); };
    for (std::size_t j = 0; j < m; ++j)
      for (std::size_t i = 0; i < m; ++i) {
        pos.row(id(i, j)) << i + u(rng), j + u(rng);
        bars.push_back({id(i, j), id(i + 1, j)});
        shift.push_back({i + 1 == m ? 1 : 0, 0});
        bars.push_back({id(i, j), id(i, j + 1)});
        shift.push_back({0, j + 1 == m ? 1 : 0});
        bars.push_back({id(i, j), id(i + 1, j + 1)});
        shift.push_back({i + 1 == m ? 1 : 0, j + 1 == m ? 1 : 0});
      }
    // Pendant joints (one bar each): one floppy mode apiece in both counts.
    Eigen::MatrixX2d all(m * m + 3, 2);
    all.topRows(m * m) = pos;
    for (std::uint32_t k = 0; k < 3; ++k) {
      all.row(m * m + k) << 2.5 + u(rng), 1.7 * k + u(rng);
      bars.push_back({5 * k, static_cast<std::uint32_t>(m * m + k)});
      shift.push_back({0, 0});
    }
    const std::size_t n = m * m + 3;
    const long F = pebbles(n, bars);
    const long exact = 2 * static_cast<long>(n) - 2 - periodic_rank(all, bars, shift, static_cast<double>(m));
    CHECK(exact == 3);
    CHECK(exact == F - 3);
  }
  SECTION("no cycle winds: F − 2") {
    std::vector<Bar> bars;
    std::vector<ImageShift> shift;
    strip(5, 3, false, bars, shift);
    bars.push_back({2, 15});  // plus a floppy appendage
    shift.push_back({0, 0});
    Eigen::MatrixX2d pos(16, 2);
    for (Eigen::Index k = 0; k < 15; ++k) pos.row(k) << (k % 5) + u(rng), (k / 5) + u(rng);
    pos.row(15) << 2 + u(rng), 4 + u(rng);
    const long F = pebbles(16, bars);
    const long exact = 32 - 2 - periodic_rank(pos, bars, shift, L);
    CHECK(exact == 2);  // the strip's rotation and the appendage's swing
    CHECK(exact == F - 2);
  }
  SECTION("a triangle closed around the box without self-stress is a mechanism: F − 2") {
    const std::vector<Bar> bars{{0, 1}, {1, 2}, {2, 0}};
    const std::vector<ImageShift> shift{{0, 0}, {0, 0}, {1, 0}};
    Eigen::MatrixX2d pos(3, 2);
    pos << 0.5 + u(rng), 1 + u(rng), 2.5 + u(rng), 2 + u(rng), 4.5 + u(rng), 0.8 + u(rng);
    const long F = pebbles(3, bars);
    CHECK(F == 3);
    const long exact = 6 - 2 - periodic_rank(pos, bars, shift, L);
    CHECK(exact == F - 2);
  }
}

TEST_CASE("the tracker, updated incrementally, agrees with an analysis from scratch at every state", "[fast]") {
  for (RemovalPolicy policy : {RemovalPolicy::retest, RemovalPolicy::rebuild}) {
    Packing p = random_packing(120, 1.1, 40);
    const Analysed full = analyse(p);
    std::mt19937_64 rng(9);
    // States: growing subsets of the contacts (insertions only), then random removals, then a
    // newborn cell appended to the packing.
    std::vector<Contact> order(full.contacts);
    std::shuffle(order.begin(), order.end(), rng);
    RigidityTracker tracker(RigidityNetwork::load_bearing, policy);
    std::vector<std::vector<Contact>> states;
    for (std::size_t k = order.size() / 2; k <= order.size(); k += order.size() / 10)
      states.emplace_back(order.begin(), order.begin() + k);
    states.push_back(order);
    for (int r = 0; r < 4; ++r) {
      std::vector<Contact> fewer;
      std::bernoulli_distribution keep(0.97);
      for (const Contact& c : states.back())
        if (keep(rng)) fewer.push_back(c);
      states.push_back(fewer);
      states.push_back(order);
    }
    std::size_t retests = 0;
    for (std::size_t k = 0; k < states.size(); ++k) {
      const ContactNetwork net = analyse_network(p.size(), states[k]);
      tracker.update(p, full.lobes, states[k], net);
      retests += tracker.last_update().retested;
      INFO("state " << k);
      require_same(tracker.state(), analyse_rigidity(p, full.lobes, states[k], net));
      if (k > 0 && tracker.last_update().bars_removed == 0) {
        CHECK_FALSE(tracker.last_update().rebuilt);  // pure insertions are played incrementally
        CHECK(tracker.last_update().bars_added > 0);
      }
      if (tracker.last_update().bars_removed > 0)
        CHECK(tracker.last_update().rebuilt == (policy == RemovalPolicy::rebuild));
    }
    if (policy == RemovalPolicy::retest) CHECK(retests > 0);  // independent bars did leave
    // A newborn cell near cell 0, with its contacts: joints are appended, nothing is replayed
    // unless contacts disappeared.
    p.add_cell(p.x(0) + 0.3, p.y(0) + 0.2, 1.0, 0.6, 0.002, 0);
    const Analysed grown = analyse(p);
    tracker.update(p, grown.lobes, grown.contacts, grown.net);
    require_same(tracker.state(), analyse_rigidity(p, grown.lobes, grown.contacts, grown.net));
    CHECK(tracker.game().joints() == 2 * p.size());
  }
}

TEST_CASE("tracker events: a bud pinned by two contacts becomes rigid and removes one floppy mode", "[fast]") {
  const Packing p = random_packing(150, 1.8, 77);
  const Analysed a = analyse(p);
  const RigidityState s0 = analyse_rigidity(p, a.lobes, a.contacts, a.net);
  // A cell of the largest rigid cluster whose bud has ≥ 2 contacts, all with cells of that cluster,
  // and whose mother keeps the cell a non-rattler (≥ 3 contacts) when the bud's contacts go.
  // Then the bud's bars do nothing but pin the bud: dropping them frees exactly one mode, the
  // bud's rotation about its mother, provided the rest of the cluster stays rigid (checked below).
  std::vector<std::size_t> candidates;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!s0.in_largest(i) || a.net.lobe_contacts[bud_lobe(i)] < 2 || a.net.lobe_contacts[mother_lobe(i)] < 3) continue;
    bool partners_in_largest = true;
    for (const Contact& c : a.contacts) {
      if (c.i == bud_lobe(i)) partners_in_largest = partners_in_largest && s0.in_largest(cell_of(c.j));
      if (c.j == bud_lobe(i)) partners_in_largest = partners_in_largest && s0.in_largest(cell_of(c.i));
    }
    if (partners_in_largest) candidates.push_back(i);
  }
  REQUIRE(!candidates.empty());
  std::size_t cell = p.size();
  std::vector<Contact> without;
  ContactNetwork net_without;
  for (std::size_t i : candidates) {
    without.clear();
    for (const Contact& c : a.contacts)
      if (c.i != bud_lobe(i) && c.j != bud_lobe(i)) without.push_back(c);
    net_without = analyse_network(p.size(), without);
    const RigidityState s1 = analyse_rigidity(p, a.lobes, without, net_without);
    if (!net_without.rattler[i] && s1.largest_cells() + 1 == s0.largest_cells() && s1.N == s0.N &&
        net_without.N_nr == a.net.N_nr) {
      cell = i;
      break;
    }
  }
  REQUIRE(cell < p.size());

  RigidityTracker tracker;
  const auto& first = tracker.update(p, a.lobes, without, net_without);
  REQUIRE(first.size() >= 1);
  CHECK(first[0].kind == RigidityEventKind::floppy_modes);
  CHECK(first[0].before == -1);
  const long floppy_without = tracker.state().floppy_plane;
  CHECK_FALSE(tracker.state().bud_rigid(cell));
  const bool spanning_reported = std::any_of(
      first.begin(), first.end(), [](const RigidityEvent& e) { return e.kind == RigidityEventKind::first_spanning; });
  CHECK(spanning_reported == (tracker.state().spans_x || tracker.state().spans_y));

  const auto events = tracker.update(p, a.lobes, a.contacts, a.net);
  CHECK_FALSE(tracker.last_update().rebuilt);
  CHECK(tracker.state().floppy_plane == floppy_without - 1);
  const auto find = [&](const std::vector<RigidityEvent>& ev, RigidityEventKind kind, std::int64_t id) {
    return std::count_if(ev.begin(), ev.end(), [&](const RigidityEvent& e) { return e.kind == kind && e.cell == id; });
  };
  CHECK(find(events, RigidityEventKind::floppy_modes, -1) == 1);
  CHECK(find(events, RigidityEventKind::bud_rigid, p.id[cell]) == 1);
  CHECK(find(events, RigidityEventKind::joined_largest, p.id[cell]) == 1);
  CHECK(find(events, RigidityEventKind::first_spanning, -1) == 0);  // reported once, at most

  const auto back = tracker.update(p, a.lobes, without, net_without);
  CHECK(find(back, RigidityEventKind::bud_released, p.id[cell]) == 1);
  CHECK(find(back, RigidityEventKind::left_largest, p.id[cell]) == 1);
  CHECK(tracker.state().floppy_plane == floppy_without);
  for (const RigidityEvent& e : back)
    if (e.kind == RigidityEventKind::floppy_modes) {
      CHECK(e.before == floppy_without - 1);
      CHECK(e.after == floppy_without);
    }
}

TEST_CASE("the first spanning rigid cluster is reported once, when it appears", "[fast]") {
  const Packing p = random_packing(150, 1.8, 5);
  const Analysed a = analyse(p);
  std::vector<Contact> order(a.contacts);
  std::mt19937_64 rng(3);
  std::shuffle(order.begin(), order.end(), rng);
  RigidityTracker tracker;
  int reported = 0;
  bool spanned_before = false;
  for (std::size_t k = 0; k <= order.size(); k += std::max<std::size_t>(1, order.size() / 40)) {
    const std::vector<Contact> sub(order.begin(), order.begin() + k);
    const ContactNetwork net = analyse_network(p.size(), sub);
    const auto& ev = tracker.update(p, a.lobes, sub, net);
    const bool spans = tracker.state().spans_x || tracker.state().spans_y;
    const auto n = std::count_if(ev.begin(), ev.end(),
                                 [](const RigidityEvent& e) { return e.kind == RigidityEventKind::first_spanning; });
    CHECK(n == ((spans && !spanned_before) ? 1 : 0));
    reported += static_cast<int>(n);
    spanned_before = spanned_before || spans;
  }
  CHECK(spanned_before);
  CHECK(reported == 1);
}

TEST_CASE("a tracker restored from another's memory reports the same events for the next state", "[fast]") {
  const Packing p = random_packing(150, 1.8, 13);
  const Analysed a = analyse(p);
  std::vector<Contact> order(a.contacts);
  std::mt19937_64 rng(8);
  std::shuffle(order.begin(), order.end(), rng);
  const std::vector<Contact> first(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(order.size() * 8 / 10));
  std::vector<Contact> second(order.begin() + 40, order.end());  // some contacts lost, others gained
  const ContactNetwork n1 = analyse_network(p.size(), first), n2 = analyse_network(p.size(), second);

  RigidityTracker original;
  original.update(p, a.lobes, first, n1);
  RigidityTracker resumed;
  resumed.restore(original.memory());
  const std::vector<RigidityEvent> expected = original.update(p, a.lobes, second, n2);
  const std::vector<RigidityEvent> got = resumed.update(p, a.lobes, second, n2);
  CHECK(resumed.last_update().rebuilt);
  REQUIRE(got.size() == expected.size());
  REQUIRE(!got.empty());
  for (std::size_t k = 0; k < got.size(); ++k) {
    CHECK(got[k].kind == expected[k].kind);
    CHECK(got[k].cell == expected[k].cell);
    CHECK(got[k].before == expected[k].before);
    CHECK(got[k].after == expected[k].after);
  }
  require_same(resumed.state(), original.state());
  RigidityMemory unsorted = original.memory();
  std::reverse(unsorted.cells.begin(), unsorted.cells.end());
  CHECK_THROWS_AS(resumed.restore(unsorted), std::invalid_argument);
}

TEST_CASE("budjam rigidity PACKING --json prints the library's analysis of the packing as JSON", "[fast]") {
  namespace fs = std::filesystem;
  const fs::path dir = testing::work_dir();
  Packing p = random_packing(120, 1.6, 4);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  testing::redraw_refused_overlaps(p, [&](std::size_t i) {
    p.q[3 * i] = p.box.L * u(rng);
    p.q[3 * i + 1] = p.box.L * u(rng);
  });
  io::write_packing(dir / "p.pack", p);
  const Analysed a = analyse(p);  // brute-force contacts: the command finds them by neighbour list
  const auto run = [&](const std::string& args) {
    return testing::run_budjam("rigidity '" + (dir / "p.pack").string() + "' --json " + args);
  };
  for (RigidityNetwork which : {RigidityNetwork::load_bearing, RigidityNetwork::raw}) {
    const bool lb = which == RigidityNetwork::load_bearing;
    const auto [code, text, err] = run(lb ? "" : "--network raw");
    REQUIRE(code == 0);
    const io::Json j = io::Json::parse(text);
    const RigidityState s = analyse_rigidity(p, a.lobes, a.contacts, a.net, which);
    CHECK(j["N"] == p.size());
    CHECK(j["N_nr"] == a.net.N_nr);
    CHECK(j["N_u"] == a.net.N_u);
    CHECK(j["contacts"] == a.contacts.size());
    CHECK(j["redundant_bars"] == s.redundant_bars);
    CHECK(j["floppy_modes"]["plane"] == s.floppy_plane);
    CHECK(j["floppy_modes"]["periodic"] == s.floppy_periodic);
    CHECK(j["rigid_clusters"]["count"] == s.clusters.size());
    CHECK(j["rigid_clusters"]["largest_cells"] == s.largest_cells());
    CHECK(j["spans_x"] == s.spans_x);
    CHECK(j["spans_y"] == s.spans_y);
    // --out BASE: the same JSON, and BASE.csv with each cell's cluster and bud rigidity
    const fs::path base = dir / (lb ? "lb" : "raw");
    REQUIRE(run((lb ? "" : "--network raw ") + std::string("--out '") + base.string() + "'").code == 0);
    CHECK(testing::slurp(base.string() + ".json") == text);
    std::string expected = "cell,cluster,bud_rigid\n";
    for (std::size_t i = 0; i < p.size(); ++i)
      expected += std::to_string(i) + ',' + std::to_string(s.cell_cluster[i]) + ',' +
                  (s.bud_rigid(i) ? "true" : "false") + '\n';
    CHECK(testing::slurp(base.string() + ".csv") == expected);
  }
  CHECK(run("--network nonsense").code == 2);  // bad input
}

TEST_CASE("along a real growth run above jamming: tracker = scratch at every state, floppy modes = N_u at jamming",
          "[.hard]") {
  // Packings a hair above jamming (E/N ~ 1e-16, nearly isostatic), then compressed by growth with
  // divisions, contact losses and gains: the incremental tracker must agree with a fresh analysis
  // at every accepted state, and at jamming every floppy mode is an unconstrained lobe.
  struct Check : Observer {
    RigidityTracker tracker;
    Lobes lobes;
    long states = 0, incremental = 0, jammings = 0;
    std::string name() const override { return "rigidity-check"; }
    Needs needs() const override {
      Needs n;
      n.contacts = n.network = true;
      return n;
    }
    void on_step_accepted(const StepAccepted& e) override {
      const StateView& s = e.state;
      if (s.phase != Phase::jammed || !s.contacts || !s.network) return;
      place_lobes(*s.packing, lobes);
      tracker.update(*s.packing, lobes, *s.contacts, *s.network);
      const RigidityState fresh = analyse_rigidity(*s.packing, lobes, *s.contacts, *s.network);
      INFO("step " << s.step);
      require_same(tracker.state(), fresh);
      CHECK(fresh.floppy_plane >= static_cast<long>(s.network->N_u));
      ++states;
      incremental += tracker.last_update().rebuilt ? 0 : 1;
    }
    void on_jammed(const Jammed& e) override {
      ++jammings;
      const RigidityState& r = tracker.state();
      CHECK(r.floppy_plane == static_cast<long>(e.jamming.network.N_u));
      CHECK((r.spans_x && r.spans_y));
      CHECK(r.redundant_bars >= 1);  // the pressure at jamming needs a state of self-stress
    }
  };
  for (std::uint64_t seed : {1u, 2u}) {
    Scene scene;
    scene.L = 8.0;
    scene.seed = seed;
    scene.P0 = 1e-3;
    scene.targets = {1e-3, 1e-2, 3e-2};
    Check check;
    GrowthDriver driver(scene);
    driver.add_observer(check);
    REQUIRE(driver.run() == RunStatus::finished);
    CHECK(check.jammings >= 1);
    CHECK(check.states > 20);
    // Only the first jammed state is a full game; every later one, also the first after an unjamming,
    // is updated from the state before (cells are never removed, so the game never has too many joints).
    CHECK(check.states - check.incremental == 1);
  }
}
