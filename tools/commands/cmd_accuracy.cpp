// `budjam accuracy [--reference DIR VARIANT_DIR...] [--packings NAME=DIR...] --out DIR`
// Accuracy against cost of the numerical knobs (docs/accuracy.md;
// analysis/accuracy_sweep.hpp): errors of every setting against a tight reference, each knob's Pareto
// front and whether the defaults are on it. Writes DIR/accuracy.csv, DIR/accuracy.json and
// DIR/accuracy.md.
#include "analysis/accuracy_sweep.hpp"
#include "commands/command.hpp"
#include "io/text.hpp"

#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace budjam::cli::accuracy_command {
namespace {

struct Options {
  tools::SweepOptions sweep;
  std::string out;
};

void run(const Options& o) {
  tools::check_sweep_options(o.sweep);
  tools::check_accuracy_out(o.out);
  std::vector<tools::SweepRow> rows;
  if (!o.sweep.reference.empty()) rows = tools::growth_rows(o.sweep);
  for (tools::SweepRow& r : tools::post_rows(o.sweep)) rows.push_back(std::move(r));
  const tools::SweepVerdict verdict = tools::judge_fronts(rows, o.sweep);
  const std::filesystem::path out(o.out);
  tools::write_accuracy_tables(out, o.sweep, rows, verdict);
  std::cerr << "accuracy: " << rows.size() << " settings -> " << io::escape_control((out / "accuracy.csv").string())
            << (verdict.all_on_front ? "; every default is on its front\n"
                                     : "; a default is NOT on its front (accuracy.md)\n");
}

const bool registered = budjam::cli::register_command(
    {"accuracy", "Accuracy against cost of the numerical knobs: errors against a tight reference, Pareto fronts",
     [](CLI::App& sub) {
       auto o = std::make_shared<Options>();
       tools::SweepOptions& s = o->sweep;
       sub.add_option("--reference", s.reference, "folder of the tight reference runs (seed*/)");
       sub.add_option("VARIANT", s.variants,
                      "folders of growth variant runs (seed*/), named <knob>_<value> or default");
       sub.add_option("--packings", s.packings,
                      "NAME=DIR: measure the moduli solvers and ARPACK settings on DIR's packings/*.pack (repeatable)");
       sub.add_option("--out", o->out, "output directory")->required()->check(budjam::cli::names_a_path());
       sub.add_option("--time-noise", s.time_noise,
                      "front rule: relative cost difference that is a tie (post-processing: at least 3x the measured "
                      "timing noise)")
           ->capture_default_str();
       sub.add_option("--error-ratio", s.error_ratio, "front rule: error factor that is a tie")->capture_default_str();
       sub.add_option("--error-floor", s.error_floor, "front rule: errors both below this tie")->capture_default_str();
       sub.add_option("--min-seconds", s.min_seconds,
                      "post-processing: repeat each computation for at least this CPU time")
           ->capture_default_str();
       sub.add_option("--growth-set", s.growth_set, "name of the growth runs' set in the table")->capture_default_str();
       sub.callback([o] { run(*o); });
     }});

}  // namespace
}  // namespace budjam::cli::accuracy_command
