#pragma once
// Accuracy against cost of the post-processing knobs: the linear solver of the moduli and
// ARPACK's tolerance and Lanczos vectors. They do not change the packing, so every setting is
// measured on the same packings against a reference computed on each of them:
//  - moduli: B, G of elastic_response with each solver against the dense LDLᵀ solve (with refinement);
//  - spectrum: ω* and the band eigenvalues (the n_band modes ω* averages) of ARPACK with each tol /
//    ncv against the dense eigensolver.
// Cost: CPU seconds of one computation (the library call that `budjam moduli` / `budjam dos` make,
// contacts excluded), the best of repeated runs, averaged over the packings. All settings of a
// packing are timed in interleaved rounds (A B C A B C …), at least min_rounds times and until
// min_seconds of CPU time each (at most max_repeats; once for a computation over 1 s), so that a
// changing load on a shared machine affects them alike. Errors: relative, mean over the packings
// (and the maximum).
#include <filesystem>
#include <string>
#include <vector>

namespace budjam::tools {

struct PostRow {
  std::string family;   // "moduli" | "spectrum"
  std::string knob;     // "solver" | "arpack_tol" | "arpack_ncv" | "default" (in every knob of its family) |
                        // "reference" | "repeat" (the default timed a second time: the timing noise, no setting)
  std::string variant;  // e.g. "cg-ichol tol=1e-6" (no commas: a CSV field)
  std::string set;      // name of the packing set
  bool is_default = false, is_reference = false;
  std::size_t packings = 0, failures = 0;  // packings measured; computations that threw (left out)
  double seconds = 0;                      // mean over packings of the best CPU time of one computation
  double err_B = 0, err_G = 0, err_omega_star = 0, err_band = 0;  // mean relative errors (NaN: n/a)
  double max_err_B = 0, max_err_G = 0, max_err_omega_star = 0, max_err_band = 0;
  double max_residual = 0;     // moduli: largest verified residual (KernelTreatment::residual)
  bool all_well_posed = true;  // moduli: every computation passed the residual verification
};

struct PostOptions {
  int min_rounds = 10;       // time every computation at least this often …
  double min_seconds = 0.2;  // … and until this much CPU time is spent on it …
  int max_repeats = 100;     // … but at most this often (a computation over 1 s: once)
};

// All *.pack files below `dir` that lie in a directory called "packings", sorted.
std::vector<std::filesystem::path> find_packings(const std::filesystem::path& dir);

// Every moduli-solver and ARPACK setting on the packings of one set. Packings without non-rattler
// cells are skipped.
std::vector<PostRow> measure_postprocessing(const std::string& set, const std::vector<std::filesystem::path>& packings,
                                            const PostOptions& options = {});

}  // namespace budjam::tools
