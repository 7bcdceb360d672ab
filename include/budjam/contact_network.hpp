#pragma once
// Rattlers, unconstrained lobes and Maxwell counting of a relaxed packing
// (docs/model.md, "Contact network").
#include <cstddef>
#include <vector>
#include "budjam/contacts.hpp"

namespace budjam {

struct ContactNetwork {
  std::vector<bool> rattler;       // per cell, after the iterative rule
  std::vector<int> lobe_contacts;  // per lobe, contacts with non-rattlers (0 for rattlers)
  std::size_t N = 0;
  std::size_t N_f = 0;                                         // rattlers (iterative rule)
  std::size_t N_f_single_pass = 0;                             // rattlers by the paper code's single pass
  std::size_t N_nr = 0;                                        // N − N_f
  std::size_t N_c = 0;                                         // contacts among non-rattlers, counted twice
  std::size_t N_u = 0;                                         // contact-free lobes (bud or mother) of non-rattlers
  std::size_t N_u_buds = 0;                                    // contact-free buds of non-rattlers
  std::size_t mother_mother = 0, mother_bud = 0, bud_bud = 0;  // physical contacts by kind
  double Z = 0.0;                                              // N_c / N_nr
  double u = 0.0;                                              // N_u / N_nr
  double u_buds = 0.0;                                         // N_u_buds / N_nr (the paper's u_J at jamming)
  double Z_iso = 0.0;                                          // 6 − 2u − 2/N_nr            (Eq. 4)
  double dZ = 0.0;                                             // Z − Z_iso                    (Eq. 5)

  bool unconstrained_bud(std::size_t cell) const { return !rattler[cell] && lobe_contacts[bud_lobe(cell)] == 0; }
};

ContactNetwork analyse_network(std::size_t n_cells, const std::vector<Contact>& contacts);

// The contacts whose both cells are non-rattlers.
std::vector<Contact> load_bearing(const std::vector<Contact>& contacts, const ContactNetwork& net);

}  // namespace budjam
