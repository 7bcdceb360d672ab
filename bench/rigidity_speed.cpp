// Cost of the rigidity analysis against N: one full pebble game, the rigid-cluster decomposition,
// the percolation search, and the tracker's incremental updates (insertions, removals, a small
// compression step as in growth). Packings: random cells (b uniform in [0.05, 1]) at φ = 0.95,
// relaxed by FIRE, so the contact networks are those of real jammed packings.
//
//   rigidity_speed [--out DIR] [N ...]      (default N: 200 1000 3000 10000)
// With --out, every relaxed packing is written as DIR/jammed-N.pack (for `budjam rigidity`).
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/rigidity.hpp"
#include "io/packing_file.hpp"
#include "random_packing.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

using namespace budjam;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Median wall time of `repeat` calls of f.
template <class F>
double timed(int repeat, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < repeat; ++r) {
    const auto t0 = Clock::now();
    f();
    t.push_back(seconds_since(t0));
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

struct State {
  Lobes lobes;
  std::vector<Contact> contacts;
  ContactNetwork net;
};

State relaxed_state(Packing& p, ForceField& field) {
  FireParams fp;
  fp.force_tol = 1e-10;
  const FireResult fr = minimise(p, field, fp);
  if (!fr.converged) std::fprintf(stderr, "warning: FIRE did not converge (N = %zu)\n", p.size());
  State s;
  s.lobes = field.lobes();
  s.contacts = find_contacts(p, s.lobes, field.neighbours());
  s.net = analyse_network(p.size(), s.contacts);
  return s;
}

// Random overlapping cells with buds of 0.05–1 (the shared generator, with its θ in (−π, π]).
Packing random_packing(std::size_t n, double phi, std::uint64_t seed) {
  return testing::random_packing(n, phi, seed, 0.05, 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes;
  std::filesystem::path out;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--out" && k + 1 < argc) {
      out = argv[++k];
      std::filesystem::create_directories(out);
    } else {
      sizes.push_back(std::stoul(a));
    }
  }
  if (sizes.empty()) sizes = {200, 1000, 3000, 10000};

  std::printf("%6s %6s %6s %6s %5s %5s | %9s %9s %9s %9s | %9s %9s | %9s %9s %9s | %9s %5s %5s %5s\n", "N", "N_nr",
              "bars", "redund", "flop", "span", "game", "clusters", "winding", "analyse", "ins/bar", "ins1%", "rm1_ret",
              "rm1_reb", "rm_retst", "grow_upd", "rebl", "+bars", "-bars");
  for (std::size_t n : sizes) {
    Packing p = random_packing(n, 0.95, 1000 + n);
    ForceField field;
    const auto t_fire = Clock::now();
    State s = relaxed_state(p, field);
    const double fire_s = seconds_since(t_fire);
    if (!out.empty()) {
      io::PackingMeta meta;
      meta.set("source", "bench/rigidity_speed: random cells at phi = 0.95, FIRE-relaxed");
      meta.set_number("phi", p.packing_fraction());
      io::write_packing(out / ("jammed-" + std::to_string(n) + ".pack"), p, meta);
    }
    const int repeat = n <= 1000 ? 7 : 3;

    // From scratch, in parts.
    const Framework fw = build_framework(p, s.lobes, s.contacts, s.net, RigidityNetwork::load_bearing);
    PebbleGame game;
    const std::vector<std::size_t> order = play_order(fw, s.lobes, p.box);  // as analyse_rigidity
    const double t_game = timed(repeat, [&] {
      game.reset(fw.joints);
      for (std::size_t k : order) game.add_bar(fw.bars[k].a, fw.bars[k].b);
    });
    RigidClusters rc;
    const double t_clusters = timed(repeat, [&] { rc = game.rigid_clusters(); });
    std::vector<Bar> played;  // the game's bar order, which the clusters refer to
    std::vector<ImageShift> played_shift;
    for (std::size_t k = 0; k < game.bars(); ++k) {
      played.push_back(game.bar(k));
      const auto at = std::lower_bound(fw.bars.begin(), fw.bars.end(), game.bar(k), [](const Bar& u, const Bar& v) {
        return u.a < v.a || (u.a == v.a && u.b < v.b);
      });
      played_shift.push_back(fw.shift[static_cast<std::size_t>(at - fw.bars.begin())]);
    }
    const double t_winding = timed(repeat, [&] { cluster_windings(fw.joints, played, played_shift, rc); });
    RigidityState st;
    const double t_analyse = timed(repeat, [&] { st = analyse_rigidity(p, s.lobes, s.contacts, s.net); });

    // Incremental insertion: the game without 1 % of the contacts, then the missing ones added.
    std::mt19937_64 rng(7);
    std::vector<Contact> shuffled(s.contacts);
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    const std::size_t k1 = std::max<std::size_t>(1, shuffled.size() / 100);
    const std::vector<Contact> fewer(shuffled.begin() + static_cast<std::ptrdiff_t>(k1), shuffled.end());
    double t_ins = 0, t_ins_update = 0;
    {
      std::vector<double> per_bar, per_update;
      for (int r = 0; r < repeat; ++r) {
        PebbleGame g(fw.joints);
        std::vector<Bar> missing;
        const Framework few = build_framework(p, s.lobes, fewer, s.net, RigidityNetwork::load_bearing);
        for (const Bar& e : few.bars) g.add_bar(e.a, e.b);
        std::vector<Bar> all(fw.bars), have(few.bars);
        const auto less = [](const Bar& u, const Bar& v) { return u.a < v.a || (u.a == v.a && u.b < v.b); };
        std::set_difference(all.begin(), all.end(), have.begin(), have.end(), std::back_inserter(missing), less);
        const auto t0 = Clock::now();
        for (const Bar& e : missing) g.add_bar(e.a, e.b);
        per_bar.push_back(seconds_since(t0) / static_cast<double>(std::max<std::size_t>(1, missing.size())));
        // The same through the tracker: framework, diff, insertions, clusters, percolation, events.
        RigidityTracker tr;
        tr.update(p, s.lobes, fewer, s.net);
        const auto t1 = Clock::now();
        tr.update(p, s.lobes, s.contacts, s.net);
        per_update.push_back(seconds_since(t1));
        if (tr.last_update().rebuilt) std::fprintf(stderr, "unexpected rebuild on insertions\n");
      }
      std::sort(per_bar.begin(), per_bar.end());
      std::sort(per_update.begin(), per_update.end());
      t_ins = per_bar[per_bar.size() / 2];
      t_ins_update = per_update[per_update.size() / 2];
    }

    // Removal of one contact (an independent bar): re-test vs replaying the game, game only.
    double t_rm_retest = 0, t_rm_rebuild = 0;
    std::size_t retested = 0;
    {
      std::vector<Bar> played_bars;
      for (std::size_t k : order) played_bars.push_back(fw.bars[k]);
      PebbleGame g(fw.joints);
      for (const Bar& e : played_bars) g.add_bar(e.a, e.b);
      std::size_t victim = 0;
      for (std::size_t k = 0; k < g.bars(); ++k)
        if (g.independent(k) && !is_cell_bar(g.bar(k))) {
          victim = k;
          break;
        }
      std::vector<bool> mask(g.bars(), false);
      mask[victim] = true;
      std::vector<Bar> kept;
      for (std::size_t k = 0; k < played_bars.size(); ++k)
        if (!mask[k]) kept.push_back(played_bars[k]);
      std::vector<double> a, b;
      for (int r = 0; r < repeat; ++r) {
        PebbleGame h(fw.joints);
        for (const Bar& e : played_bars) h.add_bar(e.a, e.b);
        auto t0 = Clock::now();
        retested = h.remove_bars(mask);
        a.push_back(seconds_since(t0));
        t0 = Clock::now();
        h.reset(fw.joints);
        for (const Bar& e : kept) h.add_bar(e.a, e.b);
        b.push_back(seconds_since(t0));
      }
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      t_rm_retest = a[a.size() / 2];
      t_rm_rebuild = b[b.size() / 2];
    }

    // A growth-like step: every bud area × (1 + 10⁻³), relax, update the tracker.
    RigidityTracker tracker;
    tracker.update(p, s.lobes, s.contacts, s.net);
    for (std::size_t i = 0; i < p.size(); ++i) p.b[i] = std::sqrt((1 + 1e-3) * (1 + p.b[i] * p.b[i]) - 1);
    field.invalidate();
    const State s2 = relaxed_state(p, field);
    const auto t_g = Clock::now();
    tracker.update(p, s2.lobes, s2.contacts, s2.net);
    const double t_grow = seconds_since(t_g);
    const RigidityUpdate& up = tracker.last_update();

    std::printf(
        "%6zu %6zu %6zu %6zu %5ld %2d%-3d | %9.2e %9.2e %9.2e %9.2e | %9.2e %9.2e | %9.2e %9.2e %9zu | %9.2e %5d %5zu "
        "%5zu\n",
        n, st.cells, st.bars, st.redundant_bars, st.floppy_plane, int(st.spans_x), int(st.spans_y), t_game, t_clusters,
        t_winding, t_analyse, t_ins, t_ins_update, t_rm_retest, t_rm_rebuild, retested, t_grow, int(up.rebuilt),
        up.bars_added, up.bars_removed);
    std::fprintf(stderr, "  (N = %zu: FIRE %.1f s, N_u = %zu, Z = %.3f, largest cluster %zu cells)\n", n, fire_s,
                 s.net.N_u, s.net.Z, st.largest_cells());
    std::fflush(stdout);
  }
}
