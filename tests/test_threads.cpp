// Threaded force evaluations (energy.hpp, docs/minimiser.md "Threads"): results are bit-identical
// for every thread count, and to one thread, from a single evaluation to a whole growth run. The
// BLAS under the sparse factorisation is held on one thread (blas_threads.hpp): a factor's bits do
// not depend on how many threads the BLAS was given, and CHOLMOD's own OpenMP regions start none.
#include "budjam/blas_threads.hpp"
#include "budjam/cholmod_solver.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/fire.hpp"
#include "budjam/growth_driver.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_file.hpp"
#include "support/random_packing.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace budjam;

namespace {

constexpr int kThreadCounts[] = {2, 3, 4};

// The threads the field really uses (1 in a build without OpenMP, where the test is trivial).
int expected_threads(int requested) {
#ifdef _OPENMP
  return requested == 0 ? omp_get_num_procs() : requested;
#else
  (void)requested;
  return 1;
#endif
}

struct Evaluation {
  double U = 0.0;
  Eigen::VectorXd F;
  Eigen::Matrix2d stress;
};

// Three evaluations with `threads` threads: the packing as given, after a small move (the
// neighbour list is reused) and after a large one (rebuilt).
std::vector<Evaluation> evaluate_moving(Packing p, int threads) {
  ForceField field(0.3, threads);
  CHECK(field.threads() == expected_threads(threads));
  std::vector<Evaluation> out;
  for (double shift : {0.0, 0.01, 0.4}) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      p.q[3 * i] += shift * std::sin(static_cast<double>(i));
      p.q[3 * i + 2] += shift * std::cos(static_cast<double>(i));
    }
    Evaluation e;
    e.U = field.evaluate(p, e.F);
    CHECK(e.U == field.energy(p));
    e.stress = stress_tensor(find_contacts(p, field.lobes(), field.neighbours()), p.box);
    out.push_back(e);
  }
  return out;
}

// Runs `run` on one thread and on 2, 3 and 4, and checks each result against one thread's.
template <class Run, class Check>
void compare_with_one_thread(Run run, Check check) {
  const auto one = run(1);
  for (int threads : kThreadCounts) {
    INFO("threads = " << threads);
    check(run(threads), one);
  }
}

// The stiffness matrix of a periodic triangular spring network of n × n nodes (two degrees of
// freedom each, random spring constants in [0.5, 1.5], a weak on-site spring 10⁻³ that removes the
// translations): symmetric positive definite, and large enough (n = 120: 28 800 rows) for CHOLMOD
// to factor it supernodally, with the BLAS.
Eigen::SparseMatrix<double> spring_network_stiffness(int n) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> spring(0.5, 1.5);
  std::vector<Eigen::Triplet<double>> t;
  const auto node = [n](int i, int j) { return ((i + n) % n) * n + (j + n) % n; };
  const double bonds[3][2] = {{1.0, 0.0}, {0.5, std::sqrt(3.0) / 2.0}, {-0.5, std::sqrt(3.0) / 2.0}};
  const int steps[3][2] = {{1, 0}, {0, 1}, {-1, 1}};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = node(i, j);
      for (int d = 0; d < 2; ++d) t.emplace_back(2 * a + d, 2 * a + d, 1e-3);
      for (int b = 0; b < 3; ++b) {
        const int c = node(i + steps[b][0], j + steps[b][1]);
        const double k = spring(rng);
        for (int x = 0; x < 2; ++x)
          for (int y = 0; y < 2; ++y) {
            const double kxy = k * bonds[b][x] * bonds[b][y];  // k ê êᵀ
            t.emplace_back(2 * a + x, 2 * a + y, kxy);
            t.emplace_back(2 * c + x, 2 * c + y, kxy);
            t.emplace_back(2 * a + x, 2 * c + y, -kxy);
            t.emplace_back(2 * c + x, 2 * a + y, -kxy);
          }
      }
    }
  Eigen::SparseMatrix<double> K(2 * n * n, 2 * n * n);
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

bool same_packing(const Packing& a, const Packing& b) {
  return a.q == b.q && a.b == b.b && a.gamma0 == b.gamma0 && a.id == b.id && a.parent == b.parent;
}

}  // namespace

TEST_CASE("energy, forces, torques and stress are bit-identical for 1, 2, 3 and 4 threads", "[fast]") {
  const Packing p = testing::random_packing(2 * ForceField::kThreadedCells, 0.85, 11, 0.01, 1.02, 1);
  compare_with_one_thread([&](int threads) { return evaluate_moving(p, threads); },
                          [](const std::vector<Evaluation>& threaded, const std::vector<Evaluation>& serial) {
                            REQUIRE(serial.front().U > 0.0);
                            for (std::size_t k = 0; k < serial.size(); ++k) {
                              CHECK(threaded[k].U == serial[k].U);
                              CHECK(threaded[k].F == serial[k].F);
                              CHECK(threaded[k].stress == serial[k].stress);
                            }
                          });
}

TEST_CASE("threads = 0 means one thread per core, with the same forces", "[fast]") {
  const Packing p = testing::random_packing(ForceField::kThreadedCells, 0.8, 5);
  ForceField all(0.3, 0), one(0.3, 1);
  CHECK(all.threads() == expected_threads(0));
  Eigen::VectorXd F_all, F_one;
  CHECK(all.evaluate(p, F_all) == one.evaluate(p, F_one));
  CHECK(F_all == F_one);
}

TEST_CASE("a FIRE minimisation ends in the same packing, bit for bit, on 1 to 4 threads", "[fast]") {
  const Packing start = testing::random_packing(ForceField::kThreadedCells, 0.8, 7);
  FireParams prm;
  prm.max_iterations = 300;
  auto relax = [&](int threads) {
    Packing p = start;
    ForceField field(0.3, threads);
    const FireResult r = minimise(p, field, prm);
    return std::pair{p, r};
  };
  using Relaxed = std::pair<Packing, FireResult>;
  compare_with_one_thread(relax, [](const Relaxed& threaded, const Relaxed& serial) {
    CHECK(threaded.first.q == serial.first.q);
    CHECK(threaded.second.iterations == serial.second.iterations);
    CHECK(threaded.second.evaluations == serial.second.evaluations);
    CHECK(threaded.second.energy == serial.second.energy);
    CHECK(threaded.second.max_force == serial.second.max_force);
  });
}

TEST_CASE("a growth run of 600 cells is bit-identical on 1, 2, 3 and 4 threads", "[.slow]") {
  Scene s;
  s.name = "threads";
  s.init = InitialState::random_seeds;
  s.n_seeds = 600;
  s.L = 35.0;
  s.seed = 2;
  s.P0 = 1e-3;
  s.targets = {1e-2};
  s.max_steps = 60;  // the run stops at the step limit: the state there is compared
  auto grow = [&](int threads) {
    Scene t = s;
    t.threads = threads;
    GrowthDriver d(t);
    d.run();
    CHECK(d.packing().size() >= ForceField::kThreadedCells);
    return std::pair{d.result(), d.packing()};
  };
  using Grown = std::pair<RunResult, Packing>;
  compare_with_one_thread(grow, [](const Grown& threaded, const Grown& serial) {
    CHECK(threaded.first.status == serial.first.status);
    CHECK(threaded.first.accepted == serial.first.accepted);
    CHECK(threaded.first.rejected == serial.first.rejected);
    CHECK(threaded.first.force_evaluations == serial.first.force_evaluations);
    CHECK(same_packing(threaded.second, serial.second));
  });
}

TEST_CASE("a supernodal factorisation solves to the same bits whatever the BLAS's thread count", "[fast]") {
  if (threaded_blas().empty())
    WARN("the BLAS of this process has no threads budjam can set (reference BLAS): the comparison is trivial");
  const Eigen::SparseMatrix<double> K = spring_network_stiffness(120);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(K.rows(), -1.0, 1.0);
  const auto solve_with_blas_threads = [&](int threads) {
    set_blas_threads(threads);
    CholmodSolver solver;
    REQUIRE(solver.factor(K));
    CHECK(solver.supernodal());
    return Eigen::VectorXd(solver.solve(f));
  };
  const int before = blas_threads();
  const Eigen::VectorXd one = solve_with_blas_threads(1);
  for (int threads : kThreadCounts) {
    INFO("BLAS threads = " << threads);
    CHECK(solve_with_blas_threads(threads) == one);
    // The process's own thread count is back once the solver is gone.
    if (!threaded_blas().empty()) CHECK(blas_threads() == threads);
  }
  set_blas_threads(before);
  CHECK((K * one - f).norm() < 1e-8 * f.norm());
}

namespace {

long threads_of_this_process() {
  long n = 0;
  for ([[maybe_unused]] const auto& task : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

}  // namespace

// libgomp keeps a pool of threads per thread that opened a region; a fresh thread has none, so any
// thread the factorisation starts is still there when it returns.
TEST_CASE("a supernodal factorisation starts no OpenMP threads, and budjam's own regions keep theirs", "[fast]") {
  const Eigen::SparseMatrix<double> K = spring_network_stiffness(120);
  long before = 0, after = 0;
  bool supernodal = false, factored = false;
  std::thread fresh([&] {
    before = threads_of_this_process();
    CholmodSolver solver;
    factored = solver.factor(K);
    supernodal = solver.supernodal();
    after = threads_of_this_process();
  });
  fresh.join();
  REQUIRE(factored);
  CHECK(supernodal);
  CHECK(after == before);
#ifdef _OPENMP
  // The hold ends with the call: a region of budjam's own still gets the threads it asks for.
  int team = 0;
#pragma omp parallel num_threads(2)
#pragma omp single
  team = omp_get_num_threads();
  CHECK(team == 2);
#endif
}

TEST_CASE("minimiser.threads accepts 0 and positive counts and rejects negative ones", "[fast]") {
  CHECK(io::parse_scene("[minimiser]\nthreads = 4\n").threads == 4);
  CHECK(io::parse_scene("[minimiser]\nthreads = 0\n").threads == 0);
  CHECK(io::parse_scene("[run]\n").threads == 1);
  try {
    io::parse_scene("[minimiser]\nthreads = -1\n", "t.toml");
    FAIL("threads = -1 accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("minimiser.threads") != std::string::npos);
  }
}

TEST_CASE("a checkpoint of a run on 4 threads resumes under any thread count, not under other physics", "[fast]") {
  Scene s;
  s.name = "threads";
  s.L = 5.0;
  s.seed = 3;
  s.targets = {1e-3};
  s.max_steps = 30;
  s.threads = 4;
  GrowthDriver d(s);
  d.run();
  const std::string text = io::format_checkpoint(s, d.state(), {});
  Scene resumed = s;
  resumed.threads = 1;
  CHECK_NOTHROW(io::parse_checkpoint(text, "checkpoint.txt", resumed, s.seed, {}));
  resumed.P0 = 2e-3;  // other physics
  CHECK_THROWS_AS(io::parse_checkpoint(text, "checkpoint.txt", resumed, s.seed, {}), InputError);
}
