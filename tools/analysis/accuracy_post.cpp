#include "analysis/accuracy_post.hpp"

#include "io/run_data.hpp"
#include "io/run_directory.hpp"

#include "budjam/errors.hpp"
#include "budjam/moduli.hpp"
#include "budjam/spectrum.hpp"
#include "budjam/statistics.hpp"
#include "io/packing_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>
#include <limits>
#include <stdexcept>

namespace budjam::tools {

namespace fs = std::filesystem;

namespace {

// 1e-06 → "1e-6", 0 → "0", 1.25 → "1.25" (variant names).
std::string label(double v) {
  if (v == 0) return "0";
  const double e = std::round(std::log10(std::abs(v)));
  if (std::abs(v - std::pow(10.0, e)) <= 1e-12 * std::abs(v)) return "1e" + std::to_string(static_cast<int>(e));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Times computations in interleaved rounds (A B C A B C …) so that a change of the machine's load
// during the measurement affects every setting alike; the best CPU time of each is kept (see
// accuracy_post.hpp for the number of rounds). A computation that throws is not timed again.
struct Interleaved {
  std::vector<std::function<void()>> jobs;
  std::vector<double> best, total;
  std::vector<int> count;
  std::vector<bool> failed;

  std::size_t add(std::function<void()> f) {
    jobs.push_back(std::move(f));
    best.push_back(std::numeric_limits<double>::infinity());
    total.push_back(0);
    count.push_back(0);
    failed.push_back(false);
    return jobs.size() - 1;
  }
  bool wants(std::size_t k, const PostOptions& o) const {
    if (failed[k]) return false;
    if (count[k] == 0) return true;
    if (best[k] > 1.0) return false;  // a long computation: once is enough
    return count[k] < o.min_rounds || (total[k] < o.min_seconds && count[k] < o.max_repeats);
  }
  void run(const PostOptions& o) {
    for (bool any = true; any;) {
      any = false;
      for (std::size_t k = 0; k < jobs.size(); ++k) {
        if (!wants(k, o)) continue;
        any = true;
        const double t0 = cpu_now();
        try {
          jobs[k]();
        } catch (const std::exception&) {
          failed[k] = true;
          continue;
        }
        const double t = cpu_now() - t0;
        best[k] = std::min(best[k], t);
        total[k] += t;
        ++count[k];
      }
    }
  }
};

double rel(double v, double ref) { return std::abs(v - ref) / std::abs(ref); }

struct ModuliVariant {
  std::string knob, name;
  ModuliOptions options;
  bool is_default = false, is_reference = false;
};

std::vector<ModuliVariant> moduli_variants() {
  std::vector<ModuliVariant> v;
  const ModuliOptions d;
  v.push_back({"default", "ldlt", d, true, false});
  v.push_back({"repeat", "ldlt (timed again)", d, false, false});  // timing-noise probe, not a setting
  ModuliOptions o = d;
  o.direct_refinement_steps = 0;
  v.push_back({"solver", "ldlt refine=0", o, false, false});
  o = d;
  o.refinement_threshold = 1e-15;
  v.push_back({"solver", "ldlt refine_above=1e-15", o, false, false});
  o = d;
  o.solver = ModuliSolver::cholesky;
  v.push_back({"solver", "cholesky", o, false, false});
  o.refinement_threshold = 1e-15;
  v.push_back({"solver", "cholesky refine_above=1e-15", o, false, false});
  for (const double t : {1e-4, 1e-6, 1e-8, 1e-10}) {
    o = d;
    o.solver = ModuliSolver::cg;
    o.cg_tolerance = t;
    v.push_back({"solver", "cg-ichol tol=" + label(t), o, false, false});
  }
  for (const double t : {1e-6, 1e-10}) {
    o = d;
    o.solver = ModuliSolver::cg;
    o.cg_preconditioner = CgPreconditioner::diagonal;
    o.cg_tolerance = t;
    v.push_back({"solver", "cg-diagonal tol=" + label(t), o, false, false});
  }
  o = d;
  o.solver = ModuliSolver::dense;
  v.push_back({"reference", "dense", o, false, true});
  return v;
}

struct SpectrumVariant {
  std::string knob, name;
  SpectrumMethod method = SpectrumMethod::arpack;
  double tol = SpectrumOptions{}.tol;
  double ncv_factor = 0;  // ncv = max(K + 1, ⌈factor·K⌉) for K Lanczos modes; 0: the default max(2K+1, K+20)
  bool is_default = false, is_reference = false;
};

std::vector<SpectrumVariant> spectrum_variants() {
  std::vector<SpectrumVariant> v;
  v.push_back({"default", "arpack tol=1e-10 ncv=auto", SpectrumMethod::arpack, 1e-10, 0, true, false});
  v.push_back({"repeat", "arpack tol=1e-10 ncv=auto (timed again)", SpectrumMethod::arpack, 1e-10, 0, false, false});
  for (const double t : {1e-3, 1e-6, 0.0})
    v.push_back({"arpack_tol", "arpack tol=" + label(t), SpectrumMethod::arpack, t, 0, false, false});
  for (const double f : {1.25, 4.0})
    v.push_back({"arpack_ncv", "arpack ncv=" + label(f) + "K", SpectrumMethod::arpack, 1e-10, f, false, false});
  v.push_back({"reference", "dense", SpectrumMethod::dense, 0, 0, false, true});
  return v;
}

// The n lowest eigenvalues at or above lambda_tol, ascending.
std::vector<double> band(const Spectrum& s, double lambda_tol, std::size_t n) {
  std::vector<double> l(s.lambda.data(), s.lambda.data() + s.lambda.size());
  std::sort(l.begin(), l.end());
  std::vector<double> b;
  for (double x : l)
    if (x >= lambda_tol && b.size() < n) b.push_back(x);
  return b;
}

struct Accumulator {
  std::vector<double> seconds, B, G, omega, bandv, residual;
  std::size_t failures = 0;
  bool well_posed = true;
};

double mean_of(const std::vector<double>& v) { return v.empty() ? kNaN : mean(v); }
double max_of(const std::vector<double>& v) { return v.empty() ? kNaN : *std::max_element(v.begin(), v.end()); }

}  // namespace

std::vector<fs::path> find_packings(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : input_directory(dir, true))
    if (e.regular_file && e.path.extension() == ".pack" && e.path.parent_path().filename() == io::run_files::packings)
      out.push_back(e.path);
  if (out.empty()) throw InputError(dir.string() + ": holds no packings/*.pack");
  return out;
}

std::vector<PostRow> measure_postprocessing(const std::string& set, const std::vector<fs::path>& packings,
                                            const PostOptions& options) {
  const auto mv = moduli_variants();
  const auto sv = spectrum_variants();
  std::vector<Accumulator> ma(mv.size()), sa(sv.size());
  std::size_t measured = 0;
  for (const fs::path& path : packings) {
    const io::PackingFile f = io::read_packing(path);
    const PackingContacts pc = analyse_contacts(f.packing);
    if (pc.network.N_nr == 0) continue;
    ++measured;
    const Packing& p = f.packing;

    // Every setting of both families timed in interleaved rounds; the results of the last run kept.
    Interleaved timer;
    std::vector<ElasticResponse> mres(mv.size());
    std::vector<std::size_t> mjob(mv.size());
    for (std::size_t k = 0; k < mv.size(); ++k)
      mjob[k] = timer.add([&, k] { mres[k] = elastic_response(p, pc.contacts, pc.network, mv[k].options); });

    // Spectra: ARPACK with the number of modes ω* needs (as packing_spectrum chooses it), dense reference.
    const BandEdgeRule rule;
    const std::size_t n_dof = 3 * pc.network.N_nr - 2;
    const int K = modes_for_band_edge(n_dof, pc.network.N_u, rule) - static_cast<int>(pc.network.N_u);
    std::vector<PackingSpectrum> sres(sv.size());
    std::vector<std::size_t> sjob(sv.size());
    for (std::size_t k = 0; k < sv.size(); ++k) {
      SpectrumOptions so;
      so.method = sv[k].method;
      so.tol = sv[k].tol;
      so.modes = K;
      if (sv[k].ncv_factor > 0)
        so.ncv = std::min(static_cast<int>(n_dof), std::max(K + 1, static_cast<int>(std::ceil(sv[k].ncv_factor * K))));
      sjob[k] = timer.add([&, k, so] { sres[k] = packing_spectrum(p, pc.contacts, pc.network, so, rule); });
    }
    timer.run(options);

    const auto ref_k = static_cast<std::size_t>(
        std::find_if(mv.begin(), mv.end(), [](const auto& v) { return v.is_reference; }) - mv.begin());
    const auto ref_s = static_cast<std::size_t>(
        std::find_if(sv.begin(), sv.end(), [](const auto& v) { return v.is_reference; }) - sv.begin());
    if (timer.failed[mjob[ref_k]] || timer.failed[sjob[ref_s]])
      throw std::runtime_error(path.string() + ": the dense reference failed");
    const ElasticResponse& ref = mres[ref_k];
    for (std::size_t k = 0; k < mv.size(); ++k) {
      if (timer.failed[mjob[k]]) {
        ++ma[k].failures;
        continue;
      }
      const ElasticResponse& e = mres[k];
      ma[k].seconds.push_back(timer.best[mjob[k]]);
      ma[k].B.push_back(rel(e.moduli.B, ref.moduli.B));
      ma[k].G.push_back(rel(e.moduli.G_simple, ref.moduli.G_simple));
      ma[k].residual.push_back(e.kernel.residual);
      ma[k].well_posed = ma[k].well_posed && e.kernel.well_posed;
    }
    const PackingSpectrum& dref = sres[ref_s];
    const std::vector<double> band_ref = band(dref.spectrum, rule.lambda_tol, dref.summary.band.n_band);
    for (std::size_t k = 0; k < sv.size(); ++k) {
      if (timer.failed[sjob[k]]) {
        ++sa[k].failures;
        continue;
      }
      const PackingSpectrum& s = sres[k];
      sa[k].seconds.push_back(timer.best[sjob[k]]);
      const double w = s.summary.band.available ? s.summary.band.omega_star : kNaN;
      sa[k].omega.push_back(rel(w, dref.summary.band.omega_star));
      const std::vector<double> b = band(s.spectrum, rule.lambda_tol, band_ref.size());
      double worst = b.size() == band_ref.size() ? 0.0 : kNaN;
      for (std::size_t i = 0; i < b.size() && i < band_ref.size(); ++i) worst = std::max(worst, rel(b[i], band_ref[i]));
      sa[k].bandv.push_back(worst);
    }
  }

  std::vector<PostRow> rows;
  auto finish = [&](PostRow r, const Accumulator& a) {
    r.set = set;
    r.packings = measured;
    r.failures = a.failures;
    r.seconds = mean_of(a.seconds);
    r.err_B = mean_of(a.B), r.max_err_B = max_of(a.B);
    r.err_G = mean_of(a.G), r.max_err_G = max_of(a.G);
    r.err_omega_star = mean_of(a.omega), r.max_err_omega_star = max_of(a.omega);
    r.err_band = mean_of(a.bandv), r.max_err_band = max_of(a.bandv);
    r.max_residual = max_of(a.residual);
    r.all_well_posed = a.well_posed;
    rows.push_back(r);
  };
  for (std::size_t k = 0; k < mv.size(); ++k) {
    PostRow r;
    r.family = "moduli", r.knob = mv[k].knob, r.variant = mv[k].name;
    r.is_default = mv[k].is_default, r.is_reference = mv[k].is_reference;
    if (r.is_reference) r.err_B = r.err_G = 0;
    finish(r, ma[k]);
  }
  for (std::size_t k = 0; k < sv.size(); ++k) {
    PostRow r;
    r.family = "spectrum", r.knob = sv[k].knob, r.variant = sv[k].name;
    r.is_default = sv[k].is_default, r.is_reference = sv[k].is_reference;
    finish(r, sa[k]);
  }
  for (auto& r : rows) {  // a family's errors only: the moduli do not have ω*, the spectra no B, G
    if (r.family == "moduli")
      r.err_omega_star = r.err_band = r.max_err_omega_star = r.max_err_band = kNaN;
    else
      r.err_B = r.err_G = r.max_err_B = r.max_err_G = r.max_residual = kNaN;
    if (r.is_reference) r.err_B = r.err_G = r.err_omega_star = r.err_band = kNaN;
  }
  return rows;
}

}  // namespace budjam::tools
