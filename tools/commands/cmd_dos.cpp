// `budjam dos PACKING [--method auto|dense|arpack] [--modes K] [--tol T] [--ncv M] [--sigma S]
//                     [--lambda-tol T] [--bins B] [--dense-max-dof D] [--no-pebble] [--out BASE] [--json] [--quiet]`
// Vibrational spectrum of a relaxed packing (docs/spectrum.md). The output convention
// (io/result_files.hpp): --out BASE writes BASE.csv (eigenvalues, frequencies, participation
// ratios) and BASE.json (N_zero at four cutoffs, ω*, N_u from the contact network, floppy modes
// from the pebble game, D(ω), the method used); `--out packings/<name>.dos` gives the sidecar
// files of a run's packing that `budjam analyse` reads.
#include "analysis/dos_report.hpp"
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include "budjam/errors.hpp"
#include "io/packing_file.hpp"

#include <iostream>
#include <memory>
#include <string>

namespace budjam::cli::dos_command {
namespace {

// Ranges of the floating options (docs/spectrum.md, "Outputs"). --tol: ARPACK's relative Ritz
// residual; above 1e-4 the eigenvalues are too rough to classify against lambda_tol. --sigma: below
// the zero modes by more than their rounding (|σ| ≥ 1e-12 k/m), and near enough that λ = σ + 1/θ keeps
// its digits (it loses ε|σ| ≤ 2e-12 for |σ| ≤ 1e4, four decades below the smallest zero cutoff 1e-8).
constexpr double kMaxTol = 1e-4, kMinSigma = 1e-12, kMaxSigma = 1e4, kMaxLambdaTol = 1e-2;
// More bins than a 10⁵-cell packing has modes resolve nothing; the bound keeps the JSON finite.
constexpr std::size_t kMaxBins = 100000;

struct Options {
  std::string packing;
  std::string method = "auto";
  int modes = 0;
  double tol = SpectrumOptions{}.tol;
  int ncv = 0;
  double sigma = SpectrumOptions{}.sigma;
  double lambda_tol = 1e-6;
  std::size_t bins = 50;
  std::size_t dense_max_dof = SpectrumOptions{}.dense_max_dof;
  bool no_pebble = false;
  io::OutputRequest output;
};

void run(const Options& o) {
  io::check_output_request(o.output, true, {o.packing});
  tools::DosRequest req;
  req.spectrum.method = parse_spectrum_method(o.method, "--method");
  if (o.modes < 0) throw InputError("--modes: must be ≥ 0 (0 = as many as ω* needs), got " + std::to_string(o.modes));
  if (o.ncv < 0) throw InputError("--ncv: must be ≥ 0 (0 = automatic)");
  req.spectrum.modes = o.modes;
  req.spectrum.tol = o.tol;
  req.spectrum.ncv = o.ncv;
  req.spectrum.sigma = o.sigma;
  req.spectrum.dense_max_dof = o.dense_max_dof;
  req.rule.lambda_tol = o.lambda_tol;
  req.bins = o.bins;
  req.pebble_game = !o.no_pebble;

  const io::PackingFile f = io::read_packing(o.packing);
  const tools::PackingContacts pc = tools::analyse_contacts(f.packing);
  if (o.ncv > 0 && o.modes > 0 && o.ncv <= o.modes)
    throw InputError("--ncv: must exceed --modes (got " + std::to_string(o.ncv) + " ≤ " + std::to_string(o.modes) +
                     ")");
  if (pc.network.N_nr == 0)  // no answer, as `moduli` of the same packing: a notice and exit 1
    throw cli::Finding("dos: " + o.packing +
                       ": no non-rattler cells (an unjammed packing has no vibrational spectrum)");
  const std::size_t n_dof = 3 * pc.network.N_nr - 2;
  if (req.spectrum.method == SpectrumMethod::arpack && o.modes > 0 && static_cast<std::size_t>(o.modes) >= n_dof)
    throw InputError("--modes: ARPACK computes fewer modes than the packing has (" + std::to_string(o.modes) + " ≥ " +
                     std::to_string(n_dof) + "); use --method dense");
  const tools::DosReport report =
      cli::naming_input("dos", o.packing, [&] { return tools::dos_report(f.packing, pc.contacts, pc.network, req); });
  io::emit(o.output, tools::dos_result(report, req), std::cout);
  // As `budjam moduli`: the spectrum of a Hessian with unstable modes is written, then a notice and exit 1.
  if (report.result.stationary == StationaryPoint::contact_bounded_minimum)
    throw cli::Finding("dos: " + o.packing +
                       " is a minimum of U held by a pair at zero force: its Hessian (pressed contacts only) has one "
                       "negative eigenvalue, along whose mode a pair without overlap closes, so no harmonic spectrum "
                       "describes it (docs/spectrum.md, \"Saddles\")");
  if (!report.result.energy_minimum())
    throw cli::Finding(
        "dos: " + o.packing + " is a saddle, not an energy minimum (" +
        std::to_string(report.result.stability.unstable_modes) +
        " unstable modes): its eigenvalues at or below -lambda_tol (N_negative in the JSON) are not counted "
        "as zero modes, shallower ones are (docs/spectrum.md, \"Saddles\")");
}

const bool registered = budjam::cli::register_command(
    {"dos", "Vibrational spectrum of a packing: eigenvalues (CSV) and N_zero, ω*, N_u, floppy modes (JSON)",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack)")->required();
       sub.add_option("--method", o->method, "auto (dense up to --dense-max-dof modes, else ARPACK), dense, arpack")
           ->capture_default_str();
       sub.add_option("--modes", o->modes,
                      "ARPACK: K Lanczos modes besides the deflated cell-local zero modes (so at least the lowest K); "
                      "0 = as many as ω* needs (n_band + 16)")
           ->capture_default_str();
       sub.add_option("--tol", o->tol, "ARPACK relative residual tolerance, in [0, 1e-4]; 0 = machine precision")
           ->capture_default_str()
           ->check(budjam::cli::finite_in(0, kMaxTol));
       sub.add_option("--ncv", o->ncv, "ARPACK Lanczos vectors; 0 = max(2K+1, K+20)")->capture_default_str();
       sub.add_option("--sigma", o->sigma, "ARPACK shift (k/m), in [-1e4, -1e-12]")
           ->capture_default_str()
           ->check(budjam::cli::finite_in(-kMaxSigma, -kMinSigma));
       sub.add_option("--lambda-tol", o->lambda_tol, "quasi-zero cutoff on |λ| = ω², in (0, 1e-2]")
           ->capture_default_str()
           ->check(budjam::cli::finite_in(0, kMaxLambdaTol, true));
       sub.add_option("--bins", o->bins, "D(ω) histogram bins, in [1, 1e5]")
           ->capture_default_str()
           ->check(CLI::Range(std::size_t{1}, kMaxBins));
       sub.add_option("--dense-max-dof", o->dense_max_dof, "auto: largest problem solved densely")
           ->capture_default_str()
           ->check(budjam::cli::non_negative());
       sub.add_flag("--no-pebble", o->no_pebble, "skip the pebble-game count of floppy modes");
       budjam::cli::add_output_options(sub, o->output, "BASE.json (the observables) and BASE.csv (the eigenvalues)");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::dos_command
