// `budjam survival RUNDIR... [-o|--out BASE] [--json] [--quiet] [--epsilon E]`
// Kaplan–Meier survival S(a) of the buds unconstrained at jamming, pooled over the given finished
// runs (each run's last jamming episode): completion is the event, division and the end of the run
// censor. The output convention (io/result_files.hpp): BASE.csv is the curve (a in diameter squared
// and as true area, Ŝ, Greenwood SE and a 95 % band), BASE.json the summary: a_ε with
// u_J S(a_ε) = ε (ε = 1/⟨N_nr,J⟩ unless given) and ∫_0^{a_ε} S da, in both units (paper Eq. 14).
#include "analysis/survival_report.hpp"
#include "commands/command.hpp"
#include "io/run_data.hpp"

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace budjam::cli::survival_command {
namespace {

struct Options {
  std::vector<std::string> runs;
  io::OutputRequest output;
  std::optional<double> epsilon;
};

void run(const Options& o) {
  const std::vector<std::filesystem::path> dirs(o.runs.begin(), o.runs.end());
  std::vector<std::filesystem::path> inputs;
  for (const auto& dir : dirs)
    for (auto& file : tools::run_input_files(dir)) inputs.push_back(std::move(file));
  io::check_output_request(o.output, true, inputs);
  const tools::SurvivalReport report = tools::survival_report(dirs, o.epsilon);
  io::emit(o.output, tools::survival_result(report), std::cout);
}

const bool registered = budjam::cli::register_command(
    {"survival", "Kaplan-Meier survival S(a) of the buds free at jamming, a_eps and the integral of S",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       sub.add_option("RUNDIR", o->runs, "finished run directories (pooled)")->required();
       budjam::cli::add_output_options(sub, o->output, "BASE.json (a_eps, the integral of S) and BASE.csv (the curve)",
                                       true);
       sub.add_option("--epsilon", o->epsilon, "cutoff eps of u_J S(a_eps) = eps (default 1/<N_nr,J>)");
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::survival_command
