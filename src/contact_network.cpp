#include "budjam/contact_network.hpp"

#include <stdexcept>

namespace budjam {

namespace {

// The rattler rule (docs/model.md, "Contact network"): fewer than 3 contacts, or exactly 3 split 2 + 1 between the
// lobes (the three force lines cannot meet in one point, so force and torque cannot both balance). 3 + 0 is not a
// rattler: the free lobe is an unconstrained lobe (one floppy rotation, counted in N_u).
// The rule is monotone (fewer contacts never turn a rattler into a non-rattler), so the iterative
// removal has a unique fixed point whatever the order of removal.
bool rattler_rule(int mother, int bud) {
  const int total = mother + bud;
  if (total < 3) return true;
  if (total == 3 && mother != 0 && bud != 0) return true;  // 2 + 1 or 1 + 2
  return false;
}

}  // namespace

ContactNetwork analyse_network(std::size_t n_cells, const std::vector<Contact>& contacts) {
  ContactNetwork net;
  net.N = n_cells;
  const std::size_t n_lobes = 2 * n_cells;
  std::vector<int> count(n_lobes, 0);  // contacts per lobe with (still) non-rattler cells
  for (const Contact& c : contacts) {
    if (c.i >= n_lobes || c.j >= n_lobes) throw std::out_of_range("analyse_network: lobe index out of range");
    if (cell_of(c.i) == cell_of(c.j)) throw std::invalid_argument("analyse_network: contact within one cell");
    ++count[c.i];
    ++count[c.j];
    const bool bi = is_bud(c.i), bj = is_bud(c.j);
    if (bi && bj)
      ++net.bud_bud;
    else if (bi || bj)
      ++net.mother_bud;
    else
      ++net.mother_mother;
  }

  // The paper code's single pass on the raw counts.
  for (std::size_t i = 0; i < n_cells; ++i)
    if (rattler_rule(count[mother_lobe(i)], count[bud_lobe(i)])) ++net.N_f_single_pass;

  // Per-cell adjacency (CSR): the contacts each cell takes part in.
  std::vector<std::size_t> start(n_cells + 1, 0);
  for (const Contact& c : contacts) {
    ++start[cell_of(c.i) + 1];
    ++start[cell_of(c.j) + 1];
  }
  for (std::size_t i = 0; i < n_cells; ++i) start[i + 1] += start[i];
  std::vector<std::size_t> fill(start.begin(), start.end() - 1), adj(start[n_cells]);
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    adj[fill[cell_of(contacts[k].i)]++] = k;
    adj[fill[cell_of(contacts[k].j)]++] = k;
  }

  // Iterative rule: discard the contacts of rattlers, re-examine their partners, until nothing changes.
  net.rattler.assign(n_cells, false);
  std::vector<std::size_t> stack;
  for (std::size_t i = n_cells; i-- > 0;) stack.push_back(i);
  while (!stack.empty()) {
    const std::size_t i = stack.back();
    stack.pop_back();
    if (net.rattler[i] || !rattler_rule(count[mother_lobe(i)], count[bud_lobe(i)])) continue;
    net.rattler[i] = true;
    for (std::size_t a = start[i]; a < start[i + 1]; ++a) {
      const Contact& c = contacts[adj[a]];
      const std::size_t other_lobe = cell_of(c.i) == i ? c.j : c.i;
      const std::size_t other = cell_of(other_lobe);
      if (net.rattler[other]) continue;  // already discarded from its side
      --count[other_lobe];
      stack.push_back(other);
    }
  }

  net.lobe_contacts.assign(n_lobes, 0);
  for (std::size_t i = 0; i < n_cells; ++i) {
    if (net.rattler[i]) {
      ++net.N_f;
      continue;
    }
    for (std::size_t lobe : {mother_lobe(i), bud_lobe(i)}) {
      net.lobe_contacts[lobe] = count[lobe];
      net.N_c += static_cast<std::size_t>(count[lobe]);
      if (count[lobe] == 0) {
        ++net.N_u;
        if (is_bud(lobe)) ++net.N_u_buds;
      }
    }
  }
  net.N_nr = n_cells - net.N_f;
  if (net.N_nr > 0) {
    const double nnr = static_cast<double>(net.N_nr);
    net.Z = static_cast<double>(net.N_c) / nnr;
    net.u = static_cast<double>(net.N_u) / nnr;
    net.u_buds = static_cast<double>(net.N_u_buds) / nnr;
    net.Z_iso = 6.0 - 2.0 * net.u - 2.0 / nnr;
    net.dZ = net.Z - net.Z_iso;
  }
  return net;
}

std::vector<Contact> load_bearing(const std::vector<Contact>& contacts, const ContactNetwork& net) {
  std::vector<Contact> out;
  out.reserve(contacts.size());
  for (const Contact& c : contacts)
    if (!net.rattler[cell_of(c.i)] && !net.rattler[cell_of(c.j)]) out.push_back(c);
  return out;
}

}  // namespace budjam
