// `budjam moduli PACKING [--check] [--strain H] [--relax] [--timing] [--solver cholesky|ldlt|dense|cg]
//                [--cg-tol T] [--cg-preconditioner ichol|diagonal] [--refine N] [--refine-above R]
//                [--out BASE] [--json] [--quiet]`
// Non-affine linear elastic response of a relaxed packing (docs/moduli.md) as JSON: BASE.json with
// --out, on stdout with --json, else a summary line (io/result_files.hpp).
// --check adds the independent finite-strain measurement (Lees–Edwards shear and isotropic
// rescaling relaxed by FIRE) and the relative differences.
#include "analysis/moduli_report.hpp"
#include "commands/command.hpp"

#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/errors.hpp"
#include "budjam/moduli.hpp"
#include "io/json.hpp"
#include "io/packing_file.hpp"
#include "io/text.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

namespace budjam::cli::moduli_command {
namespace {

using io::Json;

struct Options {
  std::string packing;
  bool check = false;
  std::optional<double> strain;  // none: automatic
  bool relax = false;
  bool timing = false;
  std::string solver = to_string(ModuliOptions{}.solver);
  double cg_tol = ModuliOptions{}.cg_tolerance;
  std::string cg_preconditioner = "ichol";
  int refine = ModuliOptions{}.direct_refinement_steps;
  double refine_above = ModuliOptions{}.refinement_threshold;
  io::OutputRequest output;
};

// Why a packing whose Hessian has unstable modes has no relaxed moduli (NaN in the response).
std::string no_linear_response(const ElasticResponse& e) {
  if (e.stationary == StationaryPoint::contact_bounded_minimum)
    return "is a minimum of U held by a pair at zero force: U rises along both signs of the one unstable mode of "
           "its Hessian (pressed contacts only), where a pair without overlap closes; the response is one-sided, so "
           "no relaxed moduli; its JSON has the affine moduli";
  return "is a saddle, not an energy minimum (" + std::to_string(e.kernel.unstable_modes) +
         " unstable modes): no relaxed response; its JSON has the affine moduli";
}

// G is the paper's: the contact-virial stress slope under Lees–Edwards simple shear, named as such.
// Without relaxed moduli the line says why instead of printing NaN.
std::string summary_line(const ElasticResponse& e) {
  char buf[256];
  if (!e.linear_response()) {
    std::snprintf(buf, sizeof buf,
                  "moduli: N = %zu, N_nr = %zu, phi = %.6f, P = %.4g, B, G_simple: none (%s: %zu unstable modes)", e.N,
                  e.N_nr, e.phi, e.P, to_string(e.stationary), e.kernel.unstable_modes);
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "moduli: N = %zu, N_nr = %zu, phi = %.6f, P = %.4g, B = %.6g, G_simple = %.6g (G: Lees-Edwards simple "
                "shear)",
                e.N, e.N_nr, e.phi, e.P, e.B(), e.G());
  return buf;
}

// The linear-solver options (bad values: InputError naming the option, exit 2).
ModuliOptions moduli_options(const Options& o) {
  ModuliOptions m;
  m.solver = parse_moduli_solver(o.solver, "--solver");
  m.cg_tolerance = o.cg_tol;
  m.cg_preconditioner = parse_cg_preconditioner(o.cg_preconditioner, "--cg-preconditioner");
  if (o.refine < 0 || o.refine > 100)
    throw InputError("--refine: must be in [0, 100], got " + std::to_string(o.refine));
  m.direct_refinement_steps = o.refine;
  m.refinement_threshold = o.refine_above;
  return m;
}

// The finite-strain check of the linear response strains the packing up to 32 steps of --strain:
// at most 1e-3 (linear response), at least 1e-10, where the stress change of one step still holds
// ~ε/γ ≈ 2e-6 of relative rounding (below it the finite difference is noise; docs/moduli.md).
constexpr double kMinStrainStep = 1e-10, kMaxStrainStep = 1e-3;

void run(const Options& o) {
  io::check_output_request(o.output, false, {o.packing});
  const ModuliOptions options = moduli_options(o);
  io::PackingFile file = io::read_packing(o.packing);
  Packing& p = file.packing;
  ForceField field;
  if (o.relax) minimise(p, field, tools::moduli_fire());
  Eigen::VectorXd F;
  field.evaluate(p, F);
  const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  const ContactNetwork net = analyse_network(p.size(), contacts);
  // The three steps of elastic_response, so that --timing can report the relaxation alone.
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const ResponseProblem problem = response_problem(p, contacts, net);
  const auto t1 = Clock::now();
  const Relaxation relaxation = cli::naming_input("moduli", o.packing, [&] { return relax(problem, options); });
  const auto t2 = Clock::now();
  ElasticResponse e = elastic_response(problem, relaxation);
  const auto t3 = Clock::now();
  e.stationary = stationary_point(p, contacts, net, e.kernel.unstable_modes);
  require_relaxed_moduli(e, "moduli: " + o.packing);
  Json j;
  j["file"] = o.packing;
  const Json body = tools::elastic_response_json(e);  // named: items() of a temporary would dangle
  for (const auto& [k, v] : body.items()) j[k] = v;
  if (o.check)
    j["check"] =
        tools::finite_strain_check_json(tools::finite_strain_check(p, contacts, net, o.strain.value_or(0.0)), e);
  if (o.timing) {
    j["seconds"] = std::chrono::duration<double>(t3 - t0).count();
    j["solve_seconds"] = std::chrono::duration<double>(t2 - t1).count();
  }
  io::emit(o.output, {j, {}, summary_line(e)}, std::cout);
  if (!e.linear_response()) throw cli::Finding("moduli: " + o.packing + " " + no_linear_response(e));
  if (e.G() < 0)
    cli::notice("moduli: " + o.packing + ": G_simple = " + io::format_double(e.G()) +
                " is negative: the contact-virial shear stress falls under Lees-Edwards simple shear (small packings "
                "near jamming; its shear_stability in the JSON; docs/moduli.md, \"Shear stability of the box\")");
}

const bool registered = budjam::cli::register_command(
    {"moduli", "Elastic moduli (B, G, C_ijkl) of a relaxed packing by non-affine linear response", [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("PACKING", o->packing, "packing file (.pack), relaxed")->required();
       sub.add_flag("--check", o->check,
                    "also measure G, B (stress slopes) and G_energy, B_energy (energy curvatures) by finite "
                    "Lees-Edwards shear and isotropic rescaling with FIRE");
       sub.add_option("--strain", o->strain,
                      "strain step of --check, in [1e-10, 1e-3] (default: 1% of the smallest overlap, in [1e-10, "
                      "1e-6])")
           ->check(budjam::cli::finite_in(kMinStrainStep, kMaxStrainStep));
       sub.add_flag("--relax", o->relax, "FIRE-minimise the packing first");
       sub.add_flag(
           "--timing", o->timing,
           "add the computation time and that of the relaxation (pinned solve) alone (seconds; not deterministic)");
       sub.add_option("--solver", o->solver,
                      "linear solver of the pinned system: cholesky (CHOLMOD LLt + refinement), ldlt (CHOLMOD "
                      "simplicial LDLt + refinement), dense (Eigen LDLt, small systems), cg (conjugate gradients)")
           ->capture_default_str();
       sub.add_option("--cg-tol", o->cg_tol, "cg: relative residual per strain column, in (0, 1)")
           ->capture_default_str()
           ->check(budjam::cli::finite_in(0, 1, true, true));
       sub.add_option("--cg-preconditioner", o->cg_preconditioner, "cg: ichol (incomplete Cholesky) or diagonal")
           ->capture_default_str();
       sub.add_option("--refine", o->refine, "cholesky, ldlt, dense: at most this many iterative-refinement steps")
           ->capture_default_str();
       sub.add_option("--refine-above", o->refine_above,
                      "cholesky, ldlt, dense: refine only while the relative residual exceeds this, in [0, 1)")
           ->capture_default_str()
           ->check(budjam::cli::finite_in(0, 1, false, true));
       budjam::cli::add_output_options(sub, o->output, "BASE.json");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::moduli_command
