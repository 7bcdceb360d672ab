#include "analysis/moduli_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "io/text.hpp"

namespace budjam::tools {

using io::Json;
using io::number_or_null;

namespace {

Json moduli_json(const Moduli& m) {
  return Json{{"B", number_or_null(m.B)},
              {"G_simple", number_or_null(m.G_simple)},
              {"G_pure", number_or_null(m.G_pure)},
              {"G_mean", number_or_null(m.G_mean)}};
}

Json tensor_json(const Eigen::Matrix3d& C) {
  return Json{{"C_xxxx", number_or_null(C(0, 0))}, {"C_yyyy", number_or_null(C(1, 1))},
              {"C_xxyy", number_or_null(C(0, 1))}, {"C_xyxy", number_or_null(C(2, 2))},
              {"C_xxxy", number_or_null(C(0, 2))}, {"C_yyxy", number_or_null(C(1, 2))}};
}

Json stress_json(const Eigen::Matrix2d& S) {
  return Json{{"xx", number_or_null(S(0, 0))},
              {"xy", number_or_null(S(0, 1))},
              {"yx", number_or_null(S(1, 0))},
              {"yy", number_or_null(S(1, 1))}};
}

Json matrix_json(const Response4& R) {
  Json rows = Json::array();
  for (int r = 0; r < 4; ++r) {
    Json row = Json::array();
    for (int c = 0; c < 4; ++c) row.push_back(number_or_null(R(r, c)));
    rows.push_back(row);
  }
  return rows;
}

// Softest and stiffest simple-shear directions (angles in degrees).
Json directions_json(const ShearStability& s) {
  return Json{{"G_min", number_or_null(s.G_min)},
              {"phi_min_deg", number_or_null(s.phi_min * 180 / std::numbers::pi)},
              {"G_max", number_or_null(s.G_max)},
              {"phi_max_deg", number_or_null(s.phi_max * 180 / std::numbers::pi)}};
}

double smallest_overlap(const std::vector<Contact>& lb) {
  double smallest = std::numeric_limits<double>::infinity();
  for (const auto& c : lb) smallest = std::min(smallest, c.overlap());
  return smallest;
}

// Strain step for the finite-strain check: well inside the smallest load-bearing overlap so the
// contact network survives (the reference fits only steps that keep the network).
double automatic_strain(double smallest_overlap) { return std::clamp(0.01 * smallest_overlap, 1e-10, 1e-6); }

Json sweep_json(const StrainSweep& s, double linear, double linear_energy, double h) {
  Json j;
  j["strain_step"] = h;
  j["samples"] = s.samples.size();
  j["used"] = s.used;
  j["all_converged"] = s.all_converged;
  j["finite"] = number_or_null(s.modulus);
  j["linear"] = number_or_null(linear);
  j["relative_difference"] = number_or_null(std::abs(s.modulus - linear) / std::abs(linear));
  j["finite_energy"] = number_or_null(s.modulus_energy);
  j["linear_energy"] = number_or_null(linear_energy);
  j["relative_difference_energy"] =
      number_or_null(std::abs(s.modulus_energy - linear_energy) / std::abs(linear_energy));
  Json rows = Json::array();
  for (const auto& x : s.samples)
    rows.push_back(Json{{"strain", x.strain},
                        {"P", x.P},
                        {"S_xy", x.stress(0, 1)},
                        {"U", x.U},
                        {"same_contacts", x.same_contacts},
                        {"fire_iterations", x.fire.iterations}});
  j["points"] = rows;
  return j;
}

// The modulus from the relaxed energy U(strain) alone (G_energy or B_energy, StrainSweep::energy_modulus)
// against the linear response `linear`.
Json curvature_json(const StrainSweep& s, double linear) {
  Json central = Json::array();
  for (const auto& [strain, value] : s.central_curvatures)
    central.push_back(Json{{"strain", strain}, {"curvature", value}});
  return Json{{"samples", s.samples.size()},
              {"used", s.used},
              {"all_converged", s.all_converged},
              {"finite", number_or_null(s.energy_modulus())},
              {"linear", number_or_null(linear)},
              {"relative_difference", number_or_null(std::abs(s.energy_modulus() - linear) / std::abs(linear))},
              {"energy_slope", number_or_null(s.energy_slope)},
              {"curvature", number_or_null(s.curvature)},
              {"central_differences", central}};
}

}  // namespace

FireParams moduli_fire() {
  FireParams f;
  // FIRE alone: the finite-strain check is a route to the moduli independent of the Hessian that
  // the linear response, and a Newton finish, are built on.
  f.newton_force = 0.0;
  return f;
}

Json elastic_response_json(const ElasticResponse& e) {
  Json j;
  // Headline: the paper's moduli (lobe-centre contact-virial stress; G by Lees–Edwards shear), and
  // the thermodynamic ones (curvatures of the relaxed energy): docs/moduli.md, "Two conventions".
  j["B"] = number_or_null(e.B());
  j["G"] = number_or_null(e.G());
  j["B_energy"] = number_or_null(e.B_energy());
  j["G_energy"] = number_or_null(e.G_energy());
  j["B_ext_mean_field"] = number_or_null(e.B_ext);
  j["G_mean_field"] = number_or_null(e.G_mf);
  j["N"] = e.N;
  j["N_nr"] = e.N_nr;
  j["N_f"] = e.N_f;
  j["N_u"] = e.N_u;
  j["N_u_buds"] = e.N_u_buds;
  j["contacts"] = e.contacts;
  j["L"] = e.L;
  j["phi"] = e.phi;
  j["Z"] = e.Z;
  j["Z_iso"] = e.Z_iso;
  j["dZ"] = e.dZ;
  j["u"] = e.u;
  j["u_buds"] = e.u_buds;
  j["n"] = e.n;
  // false: a saddle. The relaxed moduli are null whenever kernel.unstable_modes > 0, also for a
  // contact-bounded minimum (stationary_point says which).
  j["energy_minimum"] = e.energy_minimum();
  j["stationary_point"] = to_string(e.stationary);
  j["P"] = e.P;
  j["P_energy"] = e.P_energy;
  j["stress"] = stress_json(e.stress);
  j["stress_energy"] = stress_json(e.stress_energy);
  j["moduli"] = moduli_json(e.moduli);
  j["moduli_affine"] = moduli_json(e.moduli_affine);
  j["moduli_energy"] = moduli_json(e.moduli_energy);
  j["moduli_energy_affine"] = moduli_json(e.moduli_energy_affine);
  j["elastic_tensor"] = tensor_json(e.C);
  j["elastic_tensor_affine"] = tensor_json(e.C_affine);
  // G(φ) = (1/A) d²U/dγ² for simple shear along φ; G_min < 0: the box shape is unstable to that shear.
  j["shear_stability"] = directions_json(e.shear);
  j["shear_stability"]["stable"] = e.shear.stable;
  // The same extremes of the lobe-centre-stress slope ê(φ):dS/de:ê(φ): that convention's anisotropy
  // (no energy criterion, hence no "stable").
  j["shear_directions_stress"] = directions_json(e.shear_stress);
  j["response"] = Json{{"order", Json::array({"xx", "xy", "yx", "yy"})},
                       {"dS_de", matrix_json(e.R)},
                       {"dS_de_affine", matrix_json(e.R_affine)},
                       {"dtau_de", matrix_json(e.R_energy)},
                       {"E", matrix_json(e.E)},
                       {"E_affine", matrix_json(e.E_affine)}};
  j["mean_field"] = Json{{"ell_c", number_or_null(e.ell_c)}, {"ell_c2_mean", number_or_null(e.ell_c2_mean)},
                         {"M4", number_or_null(e.M4)},       {"B_ext", number_or_null(e.B_ext)},
                         {"G", number_or_null(e.G_mf)},      {"G_M4_isotropic", number_or_null(e.G_mf_iso)}};
  const KernelTreatment& k = e.kernel;
  j["kernel"] = Json{{"method", to_string(k.method)},
                     {"dofs", k.dofs},
                     {"pinned_translation", k.pinned_translation},
                     {"pinned_lobe_rotation", k.pinned_lobe_rotation},
                     {"pinned_zero_rows", k.pinned_zero_rows},
                     {"reference_cell", k.reference_cell},
                     {"cholesky_failed_column", k.cholesky_failed_column},
                     {"regularisation", k.regularisation},
                     {"unstable_modes", k.unstable_modes},
                     {"refinement_steps", k.refinement_steps},
                     {"iterations", k.iterations},
                     {"solver_tolerance", k.solver_tolerance},
                     {"residual", number_or_null(k.residual)},
                     {"kernel_component", number_or_null(k.kernel_component)},
                     {"rcond", number_or_null(k.rcond)},
                     {"well_posed", k.well_posed}};
  j["conventions"] =
      "strain e_ab = du_a/dx_b of box and centroids (orientations fixed), cells relaxed; S = lobe-centre "
      "contact-virial stress (the paper's), tau = energy stress (centroid virial, = S + the load of the rigid "
      "mother-bud links); B = -A dP/dA, G_simple = dS_xy/dgamma (Lees-Edwards), G_pure = d[(S_xx-S_yy)/2]/dgamma "
      "for e = diag(gamma/2, -gamma/2); G = moduli.G_simple, B = moduli.B; G_energy = (1/A) d2U/dgamma2 = E_xyxy, "
      "B_energy = A d2U/dA2 = moduli_energy.B; C = stiffness of the Lagrangian strain from the energy expansion; "
      "docs/moduli.md";
  return j;
}

FiniteStrainCheck finite_strain_check(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                                      double strain_step) {
  FiniteStrainCheck c;
  c.smallest_overlap = smallest_overlap(load_bearing(contacts, net));
  c.strain_step = strain_step > 0 ? strain_step : automatic_strain(c.smallest_overlap);
  const auto strains = symmetric_strains(c.strain_step, 2);
  c.shear = strain_sweep(p, StrainKind::simple_shear, strains, moduli_fire());
  c.isotropic = strain_sweep(p, StrainKind::isotropic, strains, moduli_fire());
  // The energy is second order in the strain: its curvature is measured on doubling strains up to 32 h.
  const auto wide = doubling_strains(c.strain_step, 6);
  c.shear_energy = strain_sweep(p, StrainKind::simple_shear, wide, moduli_fire());
  c.isotropic_energy = strain_sweep(p, StrainKind::isotropic, wide, moduli_fire());
  return c;
}

Json finite_strain_check_json(const FiniteStrainCheck& check, const ElasticResponse& e) {
  const double h = check.strain_step;
  Json c;
  c["simple_shear_G"] = sweep_json(check.shear, e.G(), e.moduli_energy.G_simple, h);
  c["simple_shear_G"]["energy_curvature"] = curvature_json(check.shear_energy, e.G_energy());
  c["isotropic_B"] = sweep_json(check.isotropic, e.B(), e.B_energy(), h);
  c["isotropic_B"]["energy_curvature"] = curvature_json(check.isotropic_energy, e.B_energy());
  const auto within = [](double finite, double linear, std::size_t used) {
    return used >= 3 && std::abs(finite - linear) <= 0.01 * std::abs(linear);
  };
  c["agree_within_1_percent"] = within(check.shear.modulus, e.G(), check.shear.used) &&
                                within(check.isotropic.modulus, e.B(), check.isotropic.used);
  c["agree_within_1_percent_energy"] =
      within(check.shear_energy.energy_modulus(), e.G_energy(), check.shear_energy.used) &&
      within(check.isotropic_energy.energy_modulus(), e.B_energy(), check.isotropic_energy.used);
  c["smallest_overlap"] = number_or_null(check.smallest_overlap);
  // A contact pressed less than any strain step can keep is at the relaxation's resolution: it opens or
  // closes under every strain, where the linear response counts its stiffness both ways. There the
  // finite strain has no slope to compare, and the check says so rather than disagree.
  if (std::min(check.shear.used, check.isotropic.used) >= 3 &&
      !(std::isfinite(check.shear_energy.curvature) && std::isfinite(check.isotropic_energy.curvature)))
    c["not_applicable"] =
        "the contact network changed under every strain of one sign (shear or isotropic): a "
        "curvature of U at the reference needs states kept on both sides of it";
  if (std::min(check.shear.used, check.isotropic.used) < 3)
    c["not_applicable"] = "fewer than 3 strained states kept the contact network (shear " +
                          std::to_string(check.shear.used) + ", isotropic " + std::to_string(check.isotropic.used) +
                          "): the smallest load-bearing overlap, " + io::format_double(check.smallest_overlap) +
                          ", is below what a strain step of " + io::format_double(check.strain_step) + " keeps";
  return c;
}

}  // namespace budjam::tools
