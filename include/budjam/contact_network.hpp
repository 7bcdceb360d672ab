#pragma once
// Rattlers, unconstrained lobes and Maxwell counting of a relaxed packing
// (docs/model.md, "Contact network").
#include <cstddef>
#include <vector>
#include "budjam/contacts.hpp"

namespace budjam {

// The Maxwell count of a relaxed packing's contact network: what the run records (jamming point,
// targets, φ_2) keep of it. Rattlers are removed by the iterative rule before counting.
struct NetworkSummary {
  std::size_t N = 0;                // cells
  std::size_t N_nr = 0;             // non-rattlers, N − N_f
  std::size_t N_f = 0;              // rattlers (iterative rule)
  std::size_t N_f_single_pass = 0;  // rattlers by the paper code's single pass over the raw counts
  std::size_t N_c = 0;              // contacts among non-rattlers, counted twice (once per end)
  std::size_t N_u = 0;              // contact-free lobes (bud or mother) of non-rattlers: one floppy rotation each
  std::size_t N_u_buds = 0;         // contact-free buds of non-rattlers
  double Z = 0.0;                   // mean contact number N_c / N_nr
  double u = 0.0;                   // N_u / N_nr
  double u_buds = 0.0;              // N_u_buds / N_nr (budjam's u_J at jamming; the paper's u_J ≃ 0.23 is u)
  double Z_iso = 0.0;               // isostatic contact number 6 − 2u − 2/N_nr      (Eq. 4)
  double dZ = 0.0;                  // excess contact number Z − Z_iso               (Eq. 5)
};

// The summary plus the per-cell and per-lobe detail it was counted from.
struct ContactNetwork : NetworkSummary {
  std::vector<bool> rattler;                                   // per cell, after the iterative rule
  std::vector<int> lobe_contacts;                              // per lobe, contacts with non-rattlers (0 for rattlers)
  std::size_t mother_mother = 0, mother_bud = 0, bud_bud = 0;  // physical contacts by kind

  const NetworkSummary& summary() const { return *this; }
  bool unconstrained_bud(std::size_t cell) const { return !rattler[cell] && lobe_contacts[bud_lobe(cell)] == 0; }
};

ContactNetwork analyse_network(std::size_t n_cells, const std::vector<Contact>& contacts);

// The contacts whose both cells are non-rattlers.
std::vector<Contact> load_bearing(const std::vector<Contact>& contacts, const ContactNetwork& net);

}  // namespace budjam
