// Cost of one force evaluation inside FIRE (docs/speed.md). Not a
// test: prints a table.
//
//   bench_evaluate [--threads T] [--sizes N1,N2,...] [--work W]
//
// For each N: random overlapping dumbbells (random_packing, seed 1) at φ = 0.9 relaxed by FIRE,
// the minimisation repeated from the same start until N × evaluations ≥ W (default W = 10⁷).
// Every cell moves at every evaluation, so lobe placement and the pair loop run at full cost, as
// in a minimisation of a jammed packing. Prints
// N, evaluations, wall and CPU seconds (CPU summed over threads), µs per evaluation and U at the
// end (the same for every thread count and every build of the same physics).
//
// Compiles against a library without threads too, for side-by-side timing against an older build.
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "random_packing.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

using namespace budjam;
using Clock = std::chrono::steady_clock;

namespace {

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

template <class Field = ForceField>
Field make_field(int threads) {
  if constexpr (std::is_constructible_v<Field, double, int>)
    return Field(0.3, threads);
  else
    return Field(0.3);  // a library without threads
}

std::vector<std::size_t> parse_sizes(const char* text) {
  std::vector<std::size_t> sizes;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) sizes.push_back(std::stoul(item));
  return sizes;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 1;
  double work = 1e7;
  std::vector<std::size_t> sizes{200, 1400, 10000};
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--threads"))
      threads = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--sizes"))
      sizes = parse_sizes(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--work"))
      work = std::stod(argv[i + 1]);
  }
  std::printf("| N | threads | evaluations | wall s | CPU s | µs / evaluation (wall) | µs / evaluation (CPU) | U |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (std::size_t n : sizes) {
    const Packing start = testing::random_packing(n, 0.9, 1);
    ForceField field = make_field(threads);
    Packing p;
    FireResult r;
    long evaluations = 0;
    const auto t0 = Clock::now();
    const double c0 = cpu_seconds();
    while (static_cast<double>(evaluations * static_cast<long>(n)) < work) {
      p = start;
      r = minimise(p, field);
      evaluations += r.evaluations;
    }
    const double cpu = cpu_seconds() - c0;
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double evals = static_cast<double>(evaluations);
    std::printf("| %zu | %d | %ld | %.3f | %.3f | %.2f | %.2f | %.17g |\n", n, threads, evaluations, wall, cpu,
                1e6 * wall / evals, 1e6 * cpu / evals, r.energy);
    std::fflush(stdout);
  }
}
