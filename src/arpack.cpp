#include "budjam/arpack.hpp"

#include "budjam/blas_threads.hpp"

#include <arpack/arpack.h>  // arpack-ng's ISO-C bindings dsaupd_c / dseupd_c

#include <algorithm>
#include <mutex>
#include <numeric>
#include <random>
#include <vector>

namespace budjam {

ArpackError::ArpackError(const std::string& r, int code, const std::string& what)
    : std::runtime_error(what), routine(r), info(code) {}

std::string arpack_info_message(const std::string& routine, int info) {
  // Texts from the dsaupd.f / dseupd.f headers (arpack-ng 3.8).
  const std::string head = "ARPACK " + routine + " info " + std::to_string(info) + ": ";
  switch (info) {
    case 0: return head + "normal exit";
    case 1:
      return head +
             "maximum number of restarts reached before all Ritz values converged "
             "(raise max_restarts, ncv or tol)";
    case 3: return head + "no shifts could be applied during an implicit restart (raise ncv)";
    case -1: return head + "n must be positive";
    case -2: return head + "nev must be positive";
    case -3: return head + "ncv must satisfy nev < ncv <= n";
    case -4: return head + "the maximum number of restarts must be positive";
    case -5: return head + "'which' must be one of LM, SM, LA, SA, BE";
    case -6: return head + "bmat must be 'I' or 'G'";
    case -7: return head + "the private work array workl is too short";
    case -8: return head + "error in the LAPACK tridiagonal eigenvalue computation";
    case -9: return head + "the starting vector is zero";
    case -10: return head + "mode (iparam(7)) must be 1 to 5";
    case -11: return head + "mode 1 and bmat 'G' are incompatible";
    case -12:
      return head + (routine == "dsaupd" ? "iparam(1) must be 0 or 1" : "nev and which = 'BE' are incompatible");
    case -13: return head + "nev and which = 'BE' are incompatible";
    case -14: return head + "dsaupd did not find any eigenvalue to sufficient accuracy";
    case -15: return head + "howmny must be 'A' or 'S' when eigenvectors are wanted";
    case -16: return head + "howmny = 'S' is not implemented";
    case -17:
      return head +
             "dseupd found a different number of converged Ritz values than dsaupd "
             "(raise ncv)";
    case -9999:
      return head +
             "could not build a Lanczos factorisation (the operator may be "
             "singular or the starting vector deficient)";
    default: return head + "unknown code";
  }
}

namespace {

std::mutex& arpack_mutex() {
  static std::mutex m;
  return m;
}

// Runs dsaupd's reverse-communication loop for mode 1 (OP = A) or mode 3 (OP = (A − σI)⁻¹),
// both with bmat = 'I' (a standard problem), then dseupd.
LanczosResult run(int n, int mode, const char* which, double sigma, const LinearOperator& op,
                  const LanczosOptions& opt) {
  if (n <= 0) throw ArpackError("dsaupd", -1, arpack_info_message("dsaupd", -1));
  if (opt.nev <= 0 || opt.nev >= n)
    throw ArpackError("dsaupd", -2,
                      "ARPACK: nev must satisfy 0 < nev < n (got nev " + std::to_string(opt.nev) + ", n " +
                          std::to_string(n) + "); use a dense solver for the whole spectrum");
  const int nev = opt.nev;
  const int ncv = opt.ncv > 0 ? opt.ncv : std::min(n, std::max(2 * nev + 1, nev + 20));
  if (ncv <= nev || ncv > n)
    throw ArpackError("dsaupd", -3,
                      arpack_info_message("dsaupd", -3) + " (got nev " + std::to_string(nev) + ", ncv " +
                          std::to_string(ncv) + ", n " + std::to_string(n) + ")");
  if (opt.start.size() != 0 && opt.start.size() != n)
    throw std::invalid_argument("lanczos: start vector has length " + std::to_string(opt.start.size()) + ", expected " +
                                std::to_string(n));

  std::vector<double> resid(n);
  if (opt.start.size() == n) {
    std::copy(opt.start.data(), opt.start.data() + n, resid.begin());
  } else {
    std::mt19937_64 rng(opt.seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (auto& r : resid) r = U(rng);
  }
  const int lworkl = ncv * (ncv + 8);
  std::vector<double> v(static_cast<std::size_t>(n) * ncv), workd(3 * static_cast<std::size_t>(n)), workl(lworkl);
  int iparam[11] = {0};
  int ipntr[11] = {0};
  iparam[0] = 1;  // exact shifts
  iparam[2] = opt.max_restarts;
  iparam[6] = mode;
  int ido = 0, info = 1;  // info = 1: resid holds the starting vector

  std::lock_guard<std::mutex> lock(arpack_mutex());
  const SerialBlas serial_blas;  // ARPACK's dense steps call the BLAS and LAPACK (blas_threads.hpp)
  for (;;) {
    dsaupd_c(&ido, "I", n, which, nev, opt.tol, resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(),
             workl.data(), lworkl, &info);
    if (ido == -1 || ido == 1) {
      op(&workd[ipntr[0] - 1], &workd[ipntr[1] - 1]);
    } else if (ido == 99) {
      break;
    } else {
      throw ArpackError("dsaupd", info, "ARPACK dsaupd asked for unsupported action ido " + std::to_string(ido));
    }
  }
  if (info != 0) throw ArpackError("dsaupd", info, arpack_info_message("dsaupd", info));

  LanczosResult res;
  res.ncv = ncv;
  res.restarts = iparam[2];
  res.operator_applications = iparam[8];
  std::vector<int> select(ncv, 0);
  std::vector<double> d(nev);
  std::vector<double> z(opt.vectors ? static_cast<std::size_t>(n) * nev : 1);
  int info2 = 0;
  dseupd_c(opt.vectors ? 1 : 0, "A", select.data(), d.data(), opt.vectors ? z.data() : v.data(), n, sigma, "I", n,
           which, nev, opt.tol, resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(), workl.data(), lworkl,
           &info2);
  if (info2 != 0) throw ArpackError("dseupd", info2, arpack_info_message("dseupd", info2));
  const int nconv = iparam[4];
  if (nconv < nev)
    throw ArpackError("dseupd", -14,
                      "ARPACK: only " + std::to_string(nconv) + " of " + std::to_string(nev) +
                          " Ritz values converged (raise ncv, max_restarts or tol)");

  // dseupd returns the values in ascending order already; sort anyway (cheap, and the
  // contract of LanczosResult does not depend on an ARPACK implementation detail).
  std::vector<int> order(nev);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d[a] < d[b]; });
  res.values.resize(nev);
  if (opt.vectors) res.vectors.resize(n, nev);
  for (int k = 0; k < nev; ++k) {
    res.values[k] = d[order[k]];
    if (opt.vectors)
      res.vectors.col(k) = Eigen::Map<const Eigen::VectorXd>(z.data() + static_cast<std::size_t>(order[k]) * n, n);
  }
  return res;
}

}  // namespace

LanczosResult lanczos_extremal(int n, const LinearOperator& apply_A, bool largest, const LanczosOptions& options) {
  return run(n, 1, largest ? "LA" : "SA", 0.0, apply_A, options);
}

LanczosResult lanczos_shift_invert(int n, double sigma, const LinearOperator& solve_shifted,
                                   const LanczosOptions& options) {
  return run(n, 3, "LM", sigma, solve_shifted, options);
}

}  // namespace budjam
