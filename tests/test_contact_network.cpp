// Rattler rules and Maxwell counting (docs/model.md, "Contact network") on hand-built contact lists.
#include "budjam/contact_network.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

using namespace budjam;

namespace {

// A contact between two lobes (geometry irrelevant to the counting).
Contact touch(std::size_t lobe_a, std::size_t lobe_b) {
  return Contact{static_cast<std::uint32_t>(lobe_a), static_cast<std::uint32_t>(lobe_b), 1.0, 0.0, 0.9, 1.0};
}
std::size_t M(std::size_t cell) { return mother_lobe(cell); }
std::size_t B(std::size_t cell) { return bud_lobe(cell); }

// Ring of n cells: mother–mother and bud–bud contacts between neighbours (4 contacts, 2 + 2 each).
std::vector<Contact> ring(std::size_t n) {
  std::vector<Contact> c;
  for (std::size_t i = 0; i < n; ++i) {
    c.push_back(touch(M(i), M((i + 1) % n)));
    c.push_back(touch(B(i), B((i + 1) % n)));
  }
  return c;
}

// The rule applied to counts among the given non-rattlers.
bool is_fixed_point(std::size_t n, const std::vector<Contact>& contacts, const ContactNetwork& net) {
  std::vector<int> cnt(2 * n, 0);
  for (const Contact& c : contacts)
    if (!net.rattler[cell_of(c.i)] && !net.rattler[cell_of(c.j)]) ++cnt[c.i], ++cnt[c.j];
  for (std::size_t i = 0; i < n; ++i) {
    if (net.rattler[i]) continue;
    const int m = cnt[M(i)], b = cnt[B(i)];
    if (m + b < 3 || (m + b == 3 && m > 0 && b > 0)) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("fewer than 3 contacts or a 2+1 split make a rattler; 3+0 does not", "[network]") {
  // Cells 0..4: a ring (non-rattlers). Cell 5: three contacts on its mother (3 + 0).
  // Cell 6: two on its mother, one on its bud (2 + 1). Cell 7: two contacts. Cell 8: none.
  auto c = ring(5);
  c.push_back(touch(M(5), M(0)));
  c.push_back(touch(M(5), M(1)));
  c.push_back(touch(M(5), M(2)));
  c.push_back(touch(M(6), M(3)));
  c.push_back(touch(M(6), M(4)));
  c.push_back(touch(B(6), B(0)));
  c.push_back(touch(B(7), M(2)));
  c.push_back(touch(M(7), B(3)));
  const auto net = analyse_network(9, c);
  for (std::size_t i = 0; i < 6; ++i) CHECK_FALSE(net.rattler[i]);
  CHECK(net.rattler[6]);
  CHECK(net.rattler[7]);
  CHECK(net.rattler[8]);
  CHECK(net.N_f == 3);
  CHECK(net.N_f_single_pass == 3);
  CHECK(net.N_nr == 6);
  // contacts among non-rattlers, counted twice: ring 10 + cell 5's 3
  CHECK(net.N_c == 26);
  CHECK(net.Z == Approx(26.0 / 6));
  // cell 5's bud is contact-free: the only unconstrained lobe
  CHECK(net.N_u == 1);
  CHECK(net.N_u_buds == 1);
  CHECK(net.unconstrained_bud(5));
  CHECK_FALSE(net.unconstrained_bud(6));  // a rattler's bud is not "unconstrained"
  CHECK(net.u == Approx(1.0 / 6));
  CHECK(net.u_buds == Approx(1.0 / 6));
  CHECK(net.Z_iso == Approx(6 - 2.0 / 6 - 2.0 / 6));
  CHECK(net.dZ == Approx(26.0 / 6 - (6 - 4.0 / 6)));
  // per-lobe counts exclude contacts with rattlers and are 0 for rattlers
  CHECK(net.lobe_contacts[M(3)] == 2);  // ring only: cell 6 is a rattler
  CHECK(net.lobe_contacts[B(0)] == 2);
  CHECK(net.lobe_contacts[M(2)] == 3);  // ring + cell 5 (cell 7 is a rattler)
  CHECK(net.lobe_contacts[M(6)] == 0);
  // physical contacts by kind, rattlers included
  CHECK(net.mother_mother == 5 + 3 + 2);
  CHECK(net.bud_bud == 5 + 1);
  CHECK(net.mother_bud == 2);
  CHECK(net.N == 9);
}

TEST_CASE("removing rattlers cascades: the iterative rule strips an open chain that one pass does not", "[network]") {
  // An open chain of 6 cells with mm and bb contacts between neighbours: the end cells have 2
  // contacts (rattlers), which leaves their neighbours with 2, and so on.
  const std::size_t n = 6;
  std::vector<Contact> c;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    c.push_back(touch(M(i), M(i + 1)));
    c.push_back(touch(B(i), B(i + 1)));
  }
  const auto net = analyse_network(n, c);
  CHECK(net.N_f_single_pass == 2);
  CHECK(net.N_f == n);
  CHECK(net.N_nr == 0);
  CHECK(net.N_c == 0);
  CHECK(net.Z == 0.0);  // defined as 0 when nothing is left
  CHECK(load_bearing(c, net).empty());

  // Closing the chain into a ring makes everything rigid under both rules.
  const auto closed = analyse_network(n, ring(n));
  CHECK(closed.N_f == 0);
  CHECK(closed.N_f_single_pass == 0);
  CHECK(closed.Z == Approx(4.0));
}

TEST_CASE("a 3+1 cell losing a contact to a rattler becomes a 2+1 rattler in the second round", "[network]") {
  // Cells 0..3 ring. Cell 4: M4–M0, M4–M1, B4–B2 and M4–M5 (3 + 1 = 4: not a rattler alone).
  // Cell 5 touches only cell 4 (1 contact): rattler, and then cell 4 is 2 + 1.
  auto c = ring(4);
  c.push_back(touch(M(4), M(0)));
  c.push_back(touch(M(4), M(1)));
  c.push_back(touch(B(4), B(2)));
  c.push_back(touch(M(4), M(5)));
  const auto net = analyse_network(6, c);
  CHECK(net.N_f_single_pass == 1);
  CHECK(net.rattler[5]);
  CHECK(net.rattler[4]);
  CHECK(net.N_f == 2);
  CHECK(net.N_c == 16);
  const auto lb = load_bearing(c, net);
  CHECK(lb.size() == 8);
  for (const Contact& k : lb) {
    CHECK(cell_of(k.i) < 4);
    CHECK(cell_of(k.j) < 4);
  }
}

TEST_CASE("the iterative rule reaches the same fixed point whatever the contact order", "[network]") {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 30;
    std::vector<Contact> c;
    const int m = 20 + static_cast<int>(rng() % 70);
    for (int k = 0; k < m; ++k) {
      std::size_t a = rng() % (2 * n), b = rng() % (2 * n);
      if (cell_of(a) == cell_of(b)) continue;
      c.push_back(touch(a, b));
    }
    const auto net = analyse_network(n, c);
    CHECK(is_fixed_point(n, c, net));
    CHECK(net.N_f >= net.N_f_single_pass);
    CHECK(net.N_c == 2 * load_bearing(c, net).size());
    auto shuffled = c;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    for (Contact& k : shuffled)
      if (rng() % 2) std::swap(k.i, k.j);
    const auto net2 = analyse_network(n, shuffled);
    CHECK(net2.rattler == net.rattler);
    CHECK(net2.lobe_contacts == net.lobe_contacts);
    CHECK(net2.N_f_single_pass == net.N_f_single_pass);
    // Maximality: no rattler can be put back (alone) and satisfy the rule.
    for (std::size_t i = 0; i < n; ++i) {
      if (!net.rattler[i]) continue;
      int mm = 0, bb = 0;
      for (const Contact& k : c) {
        const std::size_t li = cell_of(k.i) == i ? k.i : (cell_of(k.j) == i ? k.j : SIZE_MAX);
        if (li == SIZE_MAX) continue;
        const std::size_t other = cell_of(li == k.i ? k.j : k.i);
        if (net.rattler[other]) continue;
        (is_bud(li) ? bb : mm)++;
      }
      CHECK((mm + bb < 3 || (mm + bb == 3 && mm > 0 && bb > 0)));
    }
  }
}

TEST_CASE("contacts inside one cell or beyond the lobe range are refused", "[network]") {
  CHECK_THROWS(analyse_network(2, {touch(M(0), B(0))}));
  CHECK_THROWS(analyse_network(2, {touch(M(0), B(2))}));
}
