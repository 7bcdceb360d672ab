// What accuracy costs in the vibrational spectrum (docs/spectrum.md, "What accuracy costs").
//
//   bench_spectrum [--cache DIR] [--accuracy-n N] [--sizes N1,N2,...] [--modes K] [--seed S]
//                  [--skip-accuracy] [--skip-scaling]
//
// Packings: FIRE-compressed random dumbbells just above jamming (tests/support/compressed_packing.hpp;
// φ_J < φ ≤ φ_J + 0.01), cached as DIR/compressed-N<n>-seed<s>.pack so that reruns time only the
// spectrum. Two tables (Markdown on stdout):
//  1. accuracy: on one packing (default 1000 cells) the dense spectrum is the reference; ARPACK
//     shift-invert runs over the number of modes K, Lanczos vectors ncv and tolerance report wall
//     time (factorisation + Lanczos), operator applications and the largest eigenvalue error
//     (relative on the band λ > 1e-6, absolute on the quasi-zero modes).
//  2. scaling: time of the lowest K (default 100) modes against N; the error is measured against
//     the dense spectrum where N ≤ 1500, else against a second ARPACK run with twice the Lanczos
//     vectors and machine-precision tolerance. N_zero is cross-checked by Sylvester inertia.
#include "compressed_packing.hpp"

#include "budjam/spectrum.hpp"
#include "io/packing_file.hpp"
#include "io/process_memory.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace budjam;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Loaded {
  Packing packing;
  std::vector<Contact> contacts;
  ContactNetwork network;
  double phi = 0;
};

Loaded packing(std::size_t n, std::uint64_t seed, const fs::path& cache) {
  fs::create_directories(cache);
  const fs::path file = cache / ("compressed-N" + std::to_string(n) + "-seed" + std::to_string(seed) + ".pack");
  Loaded out;
  if (fs::exists(file)) {
    out.packing = io::read_packing(file).packing;
  } else {
    const auto t0 = Clock::now();
    auto cp = testing::compress_random_dumbbells(n, seed);
    std::fprintf(stderr, "bench_spectrum: compressed N=%zu in %.1f s (%ld FIRE iterations), phi %.4f\n", n,
                 seconds_since(t0), cp.fire_iterations, cp.phi);
    io::PackingMeta meta;
    meta.set("kind", "compressed");
    meta.set_number("phi_below", cp.phi_below);
    io::write_packing(file, cp.packing, meta);
    out.packing = std::move(cp.packing);
  }
  ForceField field;
  Eigen::VectorXd f;
  field.evaluate(out.packing, f);
  out.contacts = find_contacts(out.packing, field.lobes(), field.neighbours());
  out.network = analyse_network(out.packing.size(), out.contacts);
  out.phi = out.packing.packing_fraction();
  return out;
}

struct Error {
  double band_rel = 0;  // max |Δλ|/λ over λ > 1e-6
  double zero_abs = 0;  // max |Δλ| over the quasi-zero modes
};

Error compare(const Eigen::VectorXd& ref, const Eigen::VectorXd& got) {
  Error e;
  for (Eigen::Index k = 0; k < got.size(); ++k) {
    const double d = std::abs(got[k] - ref[k]);
    if (ref[k] > 1e-6)
      e.band_rel = std::max(e.band_rel, d / ref[k]);
    else
      e.zero_abs = std::max(e.zero_abs, d);
  }
  return e;
}

std::vector<std::size_t> parse_sizes(const std::string& s) {
  std::vector<std::size_t> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::stoul(item));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  fs::path cache = "bench-cache";
  std::size_t accuracy_n = 1000;
  std::vector<std::size_t> sizes = {1000, 2000, 5000, 10000};
  int modes = 100;
  std::uint64_t seed = 1;
  bool accuracy = true, scaling = true;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto next = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error(arg + ": needs a value");
      return argv[++a];
    };
    if (arg == "--cache")
      cache = next();
    else if (arg == "--accuracy-n")
      accuracy_n = std::stoul(next());
    else if (arg == "--sizes")
      sizes = parse_sizes(next());
    else if (arg == "--modes")
      modes = std::stoi(next());
    else if (arg == "--seed")
      seed = std::stoull(next());
    else if (arg == "--skip-accuracy")
      accuracy = false;
    else if (arg == "--skip-scaling")
      scaling = false;
    else {
      std::cerr << "usage: bench_spectrum [--cache DIR] [--accuracy-n N] [--sizes N1,N2,..] [--modes K] [--seed S] "
                   "[--skip-accuracy] [--skip-scaling]\n";
      return 2;
    }
  }

  if (accuracy) {
    const Loaded L = packing(accuracy_n, seed, cache);
    const VibrationalProblem prob = vibrational_problem(L.packing, L.contacts, L.network);
    SpectrumOptions opt;
    opt.method = SpectrumMethod::dense;
    opt.vectors = false;
    auto t0 = Clock::now();
    const Spectrum ref = solve_spectrum(prob.H, prob.mass, opt);
    const double t_dense = seconds_since(t0);
    const std::size_t nz = count_below(ref.lambda, 1e-6);
    std::printf("## Accuracy against cost: N = %zu cells (N_nr = %zu, %zu modes, N_zero = %zu, phi = %.4f)\n\n",
                accuracy_n, L.network.N_nr, ref.n_dof, nz, L.phi);
    std::printf("Dense reference (Eigen, eigenvalues only): %.2f s\n\n", t_dense);
    std::printf(
        "| K | ncv | tol | deflated | Lanczos nev | time [s] | factor [s] | OP applications | restarts | max rel. "
        "error (band) | max abs. error (zero modes) |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    auto row = [&](const SpectrumOptions& a) {
      const auto t1 = Clock::now();
      const Spectrum s = solve_spectrum(prob.H, prob.mass, a);
      const double t = seconds_since(t1);
      const Error e = compare(ref.lambda, s.lambda);
      std::printf("| %d | %d | %g | %zu | %ld | %.3f | %.3f | %d | %d | %.1e | %.1e |\n", a.modes, s.ncv, a.tol,
                  s.local.size(), static_cast<long>(s.lambda.size()) - static_cast<long>(s.local.size()), t,
                  s.seconds_factorise, s.operator_applications, s.restarts, e.band_rel, e.zero_abs);
      std::fflush(stdout);
    };
    for (int K : {10, 50, 100, 200, 400}) {
      if (static_cast<std::size_t>(K) >= ref.n_dof / 2) continue;
      for (int ncv_factor : {0, 3, 4}) {  // 0: default max(2K+1, K+20)
        const int ncv = ncv_factor == 0 ? 0 : std::max(ncv_factor * K, K + 20);
        for (double tol : {0.0, 1e-12, 1e-10, 1e-6, 1e-3}) {
          if (ncv_factor != 0 && tol != SpectrumOptions{}.tol) continue;  // ncv scan at the default tol only
          SpectrumOptions a;
          a.method = SpectrumMethod::arpack;
          a.modes = K;
          a.ncv = ncv;
          a.tol = tol;
          a.vectors = false;
          row(a);
        }
      }
    }
    // The shift: σ only sets how the spectrum is stretched around 0.
    std::printf(
        "\nShift scan at K = 100 (default tol, ncv):\n\n| sigma | time [s] | OP applications | max rel. error (band) "
        "|\n|---|---|---|---|\n");
    for (double sigma : {-1e-5, -1e-4, -1e-3, -1e-2, -1e-1}) {
      SpectrumOptions a;
      a.method = SpectrumMethod::arpack;
      a.modes = 100;
      a.sigma = sigma;
      a.vectors = false;
      const auto t1 = Clock::now();
      const Spectrum s = solve_spectrum(prob.H, prob.mass, a);
      std::printf("| %g | %.3f | %d | %.1e |\n", sigma, seconds_since(t1), s.operator_applications,
                  compare(ref.lambda, s.lambda).band_rel);
      std::fflush(stdout);
    }
    std::printf("\nWithout deflation of the cell-local zero modes (default tol, ncv):\n\n");
    std::printf(
        "| K | ncv | tol | deflated | Lanczos nev | time [s] | factor [s] | OP applications | restarts | max rel. "
        "error (band) | max abs. error (zero modes) |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    // Without deflating the cell-local zero modes: Lanczos must resolve the whole degenerate zero
    // cluster (the inertia count makes it take all of it).
    for (int K : {10, 100}) {
      SpectrumOptions a;
      a.method = SpectrumMethod::arpack;
      a.modes = K;
      a.vectors = false;
      a.deflate_local = false;
      row(a);
    }
    std::printf("\n");
  }

  if (scaling) {
    std::printf(
        "## Time against N: lowest %d modes (ARPACK shift-invert, sigma = -1e-3, default tol = 1e-10 and ncv)\n\n",
        modes);
    std::printf(
        "| N | N_nr | dof | N_u | phi | factor [s] | Lanczos [s] | total [s] | OP applications | lambda_K | N_zero "
        "(inertia) | max rel. error (band) | max abs. error (zero) | reference |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (std::size_t n : sizes) {
      const Loaded L = packing(n, seed, cache);
      const VibrationalProblem prob = vibrational_problem(L.packing, L.contacts, L.network);
      SpectrumOptions a;
      a.method = SpectrumMethod::arpack;
      a.modes = modes;
      a.vectors = true;  // as `budjam dos` computes them (participation ratios)
      auto t0 = Clock::now();
      const Spectrum s = solve_spectrum(prob.H, prob.mass, a);
      const double t = seconds_since(t0);
      const long inertia = count_below_by_inertia(prob.H, prob.mass, 1e-6);
      Eigen::VectorXd ref;
      std::string ref_name;
      if (prob.mass.size() <= 4500) {
        SpectrumOptions d;
        d.method = SpectrumMethod::dense;
        d.vectors = false;
        ref = solve_spectrum(prob.H, prob.mass, d).lambda;
        ref_name = "dense";
      } else {
        SpectrumOptions b = a;
        b.ncv = 4 * modes;
        b.tol = 0.0;
        b.vectors = false;
        ref = solve_spectrum(prob.H, prob.mass, b).lambda;
        ref_name = "ARPACK ncv=" + std::to_string(b.ncv) + ", tol=0";
      }
      const Error e = compare(ref, s.lambda);
      std::printf("| %zu | %zu | %zu | %zu | %.4f | %.2f | %.2f | %.2f | %d | %.3e | %ld | %.1e | %.1e | %s |\n", n,
                  L.network.N_nr, s.n_dof, L.network.N_u, L.phi, s.seconds_factorise, s.seconds_lanczos, t,
                  s.operator_applications, s.lambda[s.lambda.size() - 1], inertia, e.band_rel, e.zero_abs,
                  ref_name.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}
