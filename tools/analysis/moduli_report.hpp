#pragma once
// The elastic response of one relaxed packing as JSON (docs/moduli.md), for `budjam moduli`: the
// non-affine linear response, and its independent finite-strain check (Lees–Edwards shear and
// isotropic rescaling relaxed by FIRE) with the relative differences between the two.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/fire.hpp"
#include "budjam/moduli.hpp"
#include "budjam/packing.hpp"
#include "budjam/strain.hpp"
#include "io/json.hpp"

#include <vector>

namespace budjam::tools {

// FIRE settings tight enough for finite-strain moduli (also the optional relaxation beforehand).
FireParams moduli_fire();

io::Json elastic_response_json(const ElasticResponse& e);

// The finite-strain measurement of the moduli of one packing.
struct FiniteStrainCheck {
  double strain_step = 0;
  double smallest_overlap = 0;                 // of the load-bearing contacts: what the automatic step is set by
  StrainSweep shear, isotropic;                // strains ±h, ±2h: stress slopes G and B
  StrainSweep shear_energy, isotropic_energy;  // doubling strains up to 32 h: energy curvatures
};

// strain_step 0: automatic, well inside the smallest load-bearing overlap.
FiniteStrainCheck finite_strain_check(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                      double strain_step);

// The check against the linear response e, with "agree_within_1_percent" verdicts.
io::Json finite_strain_check_json(const FiniteStrainCheck& check, const ElasticResponse& e);

}  // namespace budjam::tools
