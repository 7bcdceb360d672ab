#include "analysis/dos_report.hpp"

#include "io/atomic_file.hpp"
#include "io/text.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ostream>

namespace budjam::tools {

namespace fs = std::filesystem;
using io::Json;
using io::number_or_null;

DosReport dos_report(const Packing& p, const std::vector<Contact>& contacts, const ContactNetwork& net,
                     const DosRequest& request) {
  DosReport r;
  r.network = net;
  r.L = p.box.L;
  r.phi = p.packing_fraction();
  const auto t0 = std::chrono::steady_clock::now();
  r.result = packing_spectrum(p, contacts, net, request.spectrum, request.rule);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Spectrum& s = r.result.spectrum;
  double omega_max = s.lambda.size() ? signed_omega(s.lambda.maxCoeff()) : 0.0;
  omega_max = omega_max > 0 ? omega_max * (1 + 1e-9) : 1.0;
  r.histogram = dos_histogram(s, request.bins, omega_max, request.rule.lambda_tol);
  if (request.pebble_game) {
    Lobes lobes;
    place_lobes(p, lobes);
    r.rigidity = analyse_rigidity(p, lobes, contacts, net, RigidityNetwork::load_bearing);
    r.has_rigidity = true;
  }
  return r;
}

Json dos_json(const DosReport& r, const DosRequest& request) {
  const Spectrum& s = r.result.spectrum;
  const SpectralSummary& m = r.result.summary;
  const ContactNetwork& net = r.network;
  Json j;
  j["method"] = to_string(s.method);
  j["N"] = net.N;
  j["N_nr"] = net.N_nr;
  j["N_f"] = net.N_f;
  j["L"] = r.L;
  j["phi"] = r.phi;
  j["n_dof"] = s.n_dof;
  j["modes_computed"] = m.computed;
  j["complete"] = s.complete();
  // The three counts of the paper's Fig. F1C (docs/spectrum.md, "Three counts").
  j["lambda_tol"] = m.lambda_tol;
  j["N_zero"] = m.N_zero;
  // The saddle test of `budjam moduli` on the same Hessian; N_negative: computed λ ≤ −lambda_tol.
  j["energy_minimum"] = r.result.energy_minimum();
  j["stationary_point"] = to_string(r.result.stationary);
  j["unstable_modes"] = r.result.stability.unstable_modes;
  j["N_negative"] = m.N_negative;
  j["N_u"] = net.N_u;
  j["N_u_buds"] = net.N_u_buds;
  j["floppy_modes"] = r.has_rigidity ? Json(r.rigidity.floppy_plane) : Json(nullptr);
  j["floppy_modes_periodic_bound"] = r.has_rigidity ? Json(r.rigidity.floppy_periodic) : Json(nullptr);
  Json counts = Json::object();
  for (const auto& [tol, count] : m.zero_counts) counts[io::format_double(tol)] = count;
  j["zero_counts"] = counts;
  j["zero_count_complete"] = m.zero_count_complete;
  // Band edge.
  j["omega_star"] = number_or_null(m.band.omega_star);
  j["band"] = {{"rule",
                "sqrt(mean lambda) of the lowest n_band modes above lambda_tol, "
                "n_band = max(band_min, ceil(band_fraction * (n_dof - N_zero)))"},
               {"band_min", request.rule.band_min},
               {"band_fraction", request.rule.band_fraction},
               {"n_band", m.band.n_band},
               {"modes_needed", m.band.modes_needed},
               {"available", m.band.available}};
  j["Z"] = number_or_null(net.Z);
  j["dZ"] = number_or_null(net.dZ);
  j["Z_minus_6"] = number_or_null(net.Z - 6.0);
  j["lambda_min"] = number_or_null(m.lambda_min);
  j["lambda_max_computed"] = number_or_null(m.lambda_max_computed);
  j["translation_residual"] = number_or_null(m.translation_residual);
  if (s.method == SpectrumMethod::arpack) {
    j["arpack"] = {{"sigma", s.sigma},
                   {"ncv", s.ncv},
                   {"tol", request.spectrum.tol},
                   {"restarts", s.restarts},
                   {"operator_applications", s.operator_applications},
                   {"deflated_local_zero_modes", s.local.size()},
                   {"N_zero_inertia", s.inertia_count >= 0 ? Json(s.inertia_count) : Json(nullptr)},
                   {"inertia_below_top", s.inertia_below_top >= 0 ? Json(s.inertia_below_top) : Json(nullptr)},
                   {"retries", s.retries},
                   {"ritz_residual", s.ritz_residual}};
  } else {
    j["arpack"] = nullptr;
  }
  const DosHistogram& h = r.histogram;
  j["dos"] = {{"normalisation", "D(omega) = (1/n_dof) sum_n delta(omega - omega_n); quasi-zero modes excluded"},
              {"omega_edges", h.edges},
              {"density", h.density},
              {"excluded_quasi_zero", h.excluded},
              {"omega_valid", number_or_null(h.omega_valid)}};
  return j;
}

io::CommandResult dos_result(const DosReport& r, const DosRequest& request) {
  io::CommandResult result{dos_json(r, request), {}, dos_line(r)};
  result.csv = [&r](std::ostream& os) {
    const Spectrum& s = r.result.spectrum;
    os << "mode,lambda,omega,participation,quasi_zero\n";
    for (Eigen::Index n = 0; n < s.lambda.size(); ++n) {
      os << n << ',' << io::format_double(s.lambda[n]) << ',' << io::format_double(signed_omega(s.lambda[n])) << ','
         << (r.result.participation.size() ? io::format_double(r.result.participation[n]) : std::string()) << ','
         << (std::abs(s.lambda[n]) < r.result.summary.lambda_tol ? "true" : "false") << '\n';
    }
  };
  return result;
}

std::vector<fs::path> write_dos_files(const io::Directory& dir, const std::string& stem, const DosReport& r,
                                      const DosRequest& request) {
  return io::write_result_files(dir, stem + ".dos", dos_result(r, request));
}

std::string dos_line(const DosReport& r) {
  const auto& m = r.result.summary;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "dos: %s, %zu non-rattlers, %zu of %zu modes in %.2f s; N_zero %zu (|lambda| < %g), floppy %s, "
                "N_u %zu; omega* %s%s",
                to_string(m.method), r.network.N_nr, m.computed, m.n_dof, r.seconds, m.N_zero, m.lambda_tol,
                r.has_rigidity ? std::to_string(r.rigidity.floppy_plane).c_str() : "-", r.network.N_u,
                m.band.available ? io::format_double(m.band.omega_star).c_str()
                                 : ("n/a (needs " + std::to_string(m.band.modes_needed) + " modes)").c_str(),
                r.result.stability.minimum() ? ""
                                             : ("; a " + std::string(to_string(r.result.stationary)) + ": " +
                                                std::to_string(r.result.stability.unstable_modes) + " unstable modes")
                                                   .c_str());
  return buf;
}

}  // namespace budjam::tools
