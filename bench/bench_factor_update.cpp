// What a contact event costs the sparse factor of the Hessian (docs/speed.md, "Where the time
// goes"): an event-driven continuation changes the network one contact at a time, and a contact that
// opens or closes at zero force changes the non-rattler Hessian by one rank-1 term k_c g gᵀ
// (g = Jᵀn). Whether such a continuation can beat FIRE at marginality depends on how much cheaper
// updating the factor for that term is than factoring again. Not a test.
//
//   bench_factor_update PACKING [--events K] [--stiffness-only] [--tile T] [--active-set S [--max-updates M]]
//
// On the non-rattler Hessian H of PACKING's load-bearing contacts (both terms; with
// --stiffness-only without the prestress term: the positive semidefinite Gauss–Newton matrix of the
// active-set steps) plus δ1 (δ = 10⁻¹⁰ × its largest diagonal entry, as the stability test): the CPU
// seconds of the first LDLᵀ factor (ordering and numeric factorisation), of a numeric
// refactorisation with the ordering kept, of a supernodal LLᵀ refactorisation of the same matrix and
// of the first update of that supernodal factor (CHOLMOD turns it into a simplicial LDLᵀ first), of
// a solve, and of the downdate and update that open and close again each of K load-bearing contacts
// (default 100; CholmodSolver::update). --tile T first replaces PACKING by its T × T periodic images
// in a box T times as wide (unsheared): the same network, T² times as large — a large 2D network of
// the same local structure for the sizes that no replay set reaches. Printed
// with the relative difference between the solve after one downdate and a fresh factor of the
// downdated matrix, and the residual of a solve before the events and after all K round trips.
// --active-set S instead runs S Levenberg–Marquardt steps of the active-set minimiser
// (active_set_minimise) from PACKING as it is — a trial's start, not relaxed — and prints their CPU
// seconds in user and kernel mode with the factorisations and updates done: the factor's cost as a
// minimisation pays it, fresh factor memory and all (io/process_memory.hpp). --max-updates M sets
// the changes of the active set up to which its factor is updated (ActiveSetParams::max_updates;
// default the size rule active_set_max_updates).
#include "budjam/active_set.hpp"
#include "budjam/cholmod_solver.hpp"
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/energy.hpp"
#include "budjam/hessian.hpp"
#include "io/packing_file.hpp"
#include "io/process_memory.hpp"

#include <sys/resource.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using namespace budjam;

namespace {

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// √k (Jᵀn) of contact c in the reduced dofs of `map`: the column whose outer product the contact
// adds to H at zero force.
SparseMatrix contact_term(const Packing& p, const Contact& c, const DofMap& map) {
  const Eigen::Matrix<double, 2, 6> J = contact_jacobian(p, c);
  const Eigen::Matrix<double, 6, 1> g = J.transpose() * Eigen::Vector2d(c.nx, c.ny) * std::sqrt(kSpring);
  const long cells[2] = {map.block[c.i / 2], map.block[c.j / 2]};
  std::vector<Eigen::Triplet<double>> t;
  for (int side = 0; side < 2; ++side)
    if (cells[side] >= 0)
      for (int a = 0; a < 3; ++a) t.emplace_back(static_cast<int>(3 * cells[side] + a), 0, g[3 * side + a]);
  SparseMatrix C(map.size(), 1);
  C.setFromTriplets(t.begin(), t.end());
  return C;
}

// The T × T periodic images of an unsheared packing, in a box T times as wide.
Packing tiled(const Packing& p, int T) {
  if (p.box.shear != 0.0) throw std::runtime_error("--tile needs an unsheared packing");
  Packing t;
  t.box.L = T * p.box.L;
  const std::size_t n = p.size();
  t.q.resize(3 * static_cast<Eigen::Index>(n) * T * T);
  Eigen::Index k = 0;
  for (int a = 0; a < T; ++a)
    for (int c = 0; c < T; ++c)
      for (std::size_t i = 0; i < n; ++i, ++k) {
        const auto at = 3 * static_cast<Eigen::Index>(i);
        t.q.segment<3>(3 * k) << p.q[at] + a * p.box.L, p.q[at + 1] + c * p.box.L, p.q[at + 2];
        t.b.push_back(p.b[i]);
        t.gamma0.push_back(p.gamma0[i]);
        t.id.push_back(k);
        t.parent.push_back(-1);
      }
  t.next_id = k;
  return t;
}

// CPU seconds of this process so far, in user and in kernel mode.
std::pair<double, double> user_and_system_seconds() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return {static_cast<double>(r.ru_utime.tv_sec) + 1e-6 * static_cast<double>(r.ru_utime.tv_usec),
          static_cast<double>(r.ru_stime.tv_sec) + 1e-6 * static_cast<double>(r.ru_stime.tv_usec)};
}

int active_set_steps(Packing p, long steps, long max_updates) {
  ForceField field;
  ActiveSetParams params;
  params.max_steps = steps;
  params.max_updates = max_updates;
  const auto [user0, system0] = user_and_system_seconds();
  const ActiveSetResult r = active_set_minimise(p, field, params);
  const auto [user, system] = user_and_system_seconds();
  std::printf(
      "N %zu: %ld active-set steps (%s), %ld inner iterations, %ld factorisations, %ld rank-1 updates, E/N %.6e\n",
      p.size(), r.steps, to_string(r.stop), r.inner, r.factorisations, r.updates,
      r.energy / static_cast<double>(p.size()));
  std::printf("CPU %.2f s: user %.2f s, system %.2f s\n", user - user0 + system - system0, user - user0,
              system - system0);
  return 0;
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: bench_factor_update PACKING [--events K] [--stiffness-only] [--tile T] [--active-set S "
                 "[--max-updates M]]\n");
    return 2;
  }
  long events = 100, steps = 0, max_updates = -1;
  int tile = 1;
  HessianTerms terms;
  for (int k = 2; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--events" && k + 1 < argc) {
      events = std::atol(argv[++k]);
    } else if (a == "--tile" && k + 1 < argc) {
      tile = std::atoi(argv[++k]);
      if (tile < 1) throw std::runtime_error("--tile needs a positive integer");
    } else if (a == "--active-set" && k + 1 < argc) {
      steps = std::atol(argv[++k]);
      if (steps < 1) throw std::runtime_error("--active-set needs a positive integer");
    } else if (a == "--max-updates" && k + 1 < argc) {
      char* end = nullptr;
      max_updates = std::strtol(argv[++k], &end, 10);
      if (end == argv[k] || *end != '\0' || max_updates < 0)
        throw std::runtime_error("--max-updates needs a non-negative integer");
    } else if (a == "--stiffness-only") {
      terms.prestress = false;
    } else {
      std::fprintf(stderr, "bench_factor_update: unknown argument %s\n", argv[k]);
      return 2;
    }
  }
  Packing p = io::read_packing(argv[1]).packing;
  if (tile > 1) p = tiled(p, tile);
  if (steps > 0) return active_set_steps(std::move(p), steps, max_updates);
  ForceField field;
  Eigen::VectorXd F;
  field.evaluate(p, F);
  const std::vector<Contact> contacts = find_contacts(p, field.lobes(), field.neighbours());
  const ContactNetwork net = analyse_network(p.size(), contacts);
  const std::vector<Contact> lb = load_bearing(contacts, net);
  if (lb.empty()) {
    std::fprintf(stderr, "bench_factor_update: %s has no load-bearing contact\n", argv[1]);
    return 1;
  }
  const DofMap map = non_rattler_dofs(net);
  SparseMatrix H = restrict_matrix(hessian(p, lb, terms), map);
  const double delta = 1e-10 * H.diagonal().cwiseAbs().maxCoeff();
  for (Eigen::Index k = 0; k < H.rows(); ++k) H.coeffRef(k, k) += delta;

  CholmodSolver ldl(Factorisation::ldlt);
  double t0 = cpu_seconds();
  if (!ldl.factor(H)) throw std::runtime_error("zero pivot in the LDLᵀ factor of H + δ1");
  const double first = cpu_seconds() - t0;
  const int repeats = 3;
  t0 = cpu_seconds();
  for (int r = 0; r < repeats; ++r) ldl.factor(H);
  const double numeric = (cpu_seconds() - t0) / repeats;
  const long nnz_L = ldl.factor_nonzeros();
  // The same matrix in CHOLMOD's supernodal LLᵀ (BLAS-3 kernels): the cheapest fresh factor.
  // cholmod_updown works on a simplicial LDLᵀ factor and converts any other to one first.
  CholmodSolver llt(Factorisation::updatable);
  double supernodal = -1.0, first_update = -1.0;
  if (llt.factor(H) && llt.negative_pivots() == 0) {
    t0 = cpu_seconds();
    for (int r = 0; r < repeats; ++r) llt.factor(H);
    supernodal = (cpu_seconds() - t0) / repeats;
    const bool was_supernodal = llt.supernodal();
    const SparseMatrix C = contact_term(p, lb.front(), map);
    t0 = cpu_seconds();
    llt.update(C, false);
    first_update = cpu_seconds() - t0;
    if (!was_supernodal) first_update = -1.0;  // the ordinary rank-1 update timed below
  }

  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(H.rows(), -1.0, 1.0);
  t0 = cpu_seconds();
  Eigen::VectorXd x0;
  for (int r = 0; r < repeats; ++r) x0 = ldl.solve(b);
  const double solve = (cpu_seconds() - t0) / repeats;
  const double residual0 = (H * x0 - b).norm() / b.norm();
  events = std::min<long>(events, static_cast<long>(lb.size()));
  const std::size_t stride = lb.size() / static_cast<std::size_t>(events);
  double down = 0, up = 0, agreement = 0;
  for (long e = 0; e < events; ++e) {
    const SparseMatrix C = contact_term(p, lb[static_cast<std::size_t>(e) * stride], map);
    t0 = cpu_seconds();
    ldl.update(C, false);
    down += cpu_seconds() - t0;
    if (e == 0) {
      // The downdated factor against a fresh factor of the downdated matrix.
      CholmodSolver fresh(Factorisation::ldlt);
      const SparseMatrix opened = H - SparseMatrix(C * SparseMatrix(C.transpose()));
      if (!fresh.factor(opened)) throw std::runtime_error("zero pivot in the factor of the opened network");
      const Eigen::VectorXd x = fresh.solve(b);
      agreement = (ldl.solve(b) - x).norm() / x.norm();
    }
    t0 = cpu_seconds();
    ldl.update(C, true);
    up += cpu_seconds() - t0;
  }
  const double residual = (H * ldl.solve(b) - b).norm() / b.norm();
  std::printf("packing %s: N %zu, non-rattler dofs %ld, load-bearing contacts %zu\n", argv[1], p.size(),
              static_cast<long>(H.rows()), lb.size());
  std::printf("first factor (ordering + numeric)   %.4f CPU s, nnz(L) %ld\n", first, nnz_L);
  std::printf("numeric refactorisation              %.4f CPU s (mean of %d)\n", numeric, repeats);
  if (supernodal >= 0.0) {
    std::printf("supernodal LLT refactorisation       %.4f CPU s (mean of %d; %s)\n", supernodal, repeats,
                first_update >= 0.0 ? "supernodal" : "CHOLMOD chose simplicial");
    if (first_update >= 0.0) std::printf("its first update (to LDLT + rank-1)  %.4f CPU s\n", first_update);
  } else
    std::printf("supernodal LLT refactorisation       not positive definite\n");
  std::printf("solve                                %.4f CPU s (mean of %d)\n", solve, repeats);
  std::printf("contact opened (rank-1 downdate)     %.6f CPU s (mean of %ld)\n", down / events, events);
  std::printf("contact closed (rank-1 update)       %.6f CPU s (mean of %ld)\n", up / events, events);
  std::printf("refactorisation / event              %.0fx\n", numeric / (0.5 * (down + up) / events));
  std::printf(
      "downdate vs fresh factor: relative difference of a solve %.2e; residual %.2e before the events, "
      "%.2e after %ld round trips\n",
      agreement, residual0, residual, events);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  budjam::io::keep_freed_memory();  // large factors reuse freed pages (io/process_memory.hpp)
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_factor_update: %s\n", e.what());
    return 1;
  }
}
