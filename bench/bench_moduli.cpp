// Time of one modulus computation (what `budjam moduli` does after reading the file: forces and
// contacts, contact network, elastic_response) against the number of cells.
//
//   bench_moduli [N_max=10000] [P=1e-3] [repeats=3] [solvers=cholesky]
//
// solvers: a comma-separated list of ModuliOptions solvers (cholesky, ldlt, dense, cg), each timed on
// the same packings (one row each), e.g. `bench_moduli 10000 1e-3 3 cholesky,ldlt`.
//
// Packings: random dumbbells (buds uniform in [0.01, 1.02], the range a growing population spans)
// placed without overlap at φ = 0.4 and compressed isotropically with FIRE to P ≈ 1e-3 by
// compress_to_pressure (tests/support/compressed_packing.hpp). N = 200 is an L ≈ 15 packing. Reported: the best of
// `repeats` timings, and the split between the contact analysis and the response itself.
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/moduli.hpp"
#include "compressed_packing.hpp"
#include "io/process_memory.hpp"
#include "random_packing.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

using namespace budjam;
using budjam::testing::compress_to_pressure;
using budjam::testing::CompressionResult;
using budjam::testing::random_dumbbells;
using Clock = std::chrono::steady_clock;

static double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  const std::size_t n_max = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 10000;
  const double P = argc > 2 ? std::atof(argv[2]) : 1e-3;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  std::vector<ModuliOptions> solvers;
  {
    std::stringstream list(argc > 4 ? argv[4] : "cholesky");
    for (std::string name; std::getline(list, name, ',');) {
      ModuliOptions o;
      o.solver = parse_moduli_solver(name, "solvers");
      solvers.push_back(o);
    }
  }
  FireParams fire;
  fire.dt_max = 0.4;
  std::printf("# bench_moduli: P_target %.1e, best of %d\n", P, repeats);
  std::printf("# %7s %7s %7s %8s %10s %10s %12s %12s %12s %10s %10s\n", "N", "L", "N_nr", "dofs", "P", "t_make[s]",
              "t_contacts[s]", "t_response[s]", "t_total[s]", "B", "G");
  for (std::size_t n : {100, 200, 300, 1000, 3000, 10000, 30000}) {
    if (n > n_max) break;
    const auto t0 = Clock::now();
    const CompressionResult c = compress_to_pressure(random_dumbbells(n, 0.4, 0.01, 1.02, 1), P, fire);
    const double t_make = seconds_since(t0);
    if (!c.converged) {
      std::printf("  %7zu compression did not converge (P %.3e)\n", n, c.P);
      continue;
    }
    for (const ModuliOptions& options : solvers) {
      double best_contacts = 1e300, best_response = 1e300, best_total = 1e300;
      ElasticResponse e;
      for (int k = 0; k < repeats; ++k) {
        const auto a = Clock::now();
        ForceField field;
        Eigen::VectorXd F;
        field.evaluate(c.packing, F);
        const auto contacts = find_contacts(c.packing, field.lobes(), field.neighbours());
        const ContactNetwork net = analyse_network(c.packing.size(), contacts);
        const double t_contacts = seconds_since(a);
        const auto b = Clock::now();
        e = elastic_response(c.packing, contacts, net, options);
        const double t_response = seconds_since(b);
        best_contacts = std::min(best_contacts, t_contacts);
        best_response = std::min(best_response, t_response);
        best_total = std::min(best_total, seconds_since(a));
      }
      std::printf("  %7zu %7.2f %7zu %8zu %10.3e %10.2f %12.4f %12.4f %12.4f %10.4f %10.5f  %s\n", n, c.packing.box.L,
                  e.N_nr, e.kernel.dofs, e.P, t_make, best_contacts, best_response, best_total, e.moduli.B,
                  e.moduli.G_simple, to_string(e.kernel.method));
      std::fflush(stdout);
    }
  }
  return 0;
}
