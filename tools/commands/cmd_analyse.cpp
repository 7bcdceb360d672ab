// `budjam analyse RUNDIR... --out DIR [--main-L L] [--resamples N] [--seed S] [--require WHAT]`
// `budjam analyse --tables DIR --out DIR2 [...]`: the same estimators on the tables of an earlier analysis
// Ensemble analysis of finished growth runs; the work is analysis/ensemble_analysis.
#include "analysis/ensemble_analysis.hpp"
#include "budjam/errors.hpp"
#include "commands/command.hpp"
#include "io/text.hpp"

#include <iostream>
#include <memory>

namespace budjam::cli::analyse_command {
namespace {

struct Options {
  tools::EnsembleOptions ensemble;
  std::vector<std::string> require;
};

void run(Options o) {
  for (const auto& w : o.require) {
    if (w == "moduli")
      o.ensemble.require_moduli = true;
    else if (w == "dos")
      o.ensemble.require_dos = true;
    else
      throw InputError("--require: unknown item '" + w + "' (known: moduli, dos)");
  }
  if (o.ensemble.bootstrap.resamples < 2) throw InputError("--resamples: must be at least 2");
  // after the work: an error line stands alone
  const tools::EnsembleAccount done = tools::analyse_ensemble(o.ensemble);
  for (const auto& line : done.unchecked) cli::notice("analyse: " + io::one_line(line));
  std::cerr << "analyse: " << io::one_line(done.used) << "\n";
}

const bool registered = budjam::cli::register_command(
    {"analyse", "Ensemble analysis of finished runs: JSON/CSV tables behind every figure and number of the paper",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       auto& e = o->ensemble;
       sub.add_option("RUNDIR", e.inputs, "run directories, or folders holding them");
       sub.add_option("--tables", e.tables,
                      "instead of runs: the runs.csv, targets.csv, dos.csv, survival.csv of an earlier analysis");
       sub.add_option("--out", e.out, "output directory")->required()->check(budjam::cli::names_a_path());
       sub.add_option("--main-L", e.main_L, "system size of the main figures (default 15 if present, else the largest)")
           ->check(budjam::cli::finite_in(0, 1e9, true));
       sub.add_option("--resamples", e.bootstrap.resamples, "bootstrap resamples (default 2000)");
       sub.add_option("--seed", e.bootstrap.seed, "bootstrap seed (default 1)")->check(budjam::cli::seed_range());
       sub.add_option("--require", o->require, "fail if these per-packing results are missing: moduli, dos")
           ->delimiter(',');
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::analyse_command
