#pragma once
// The threads of the BLAS under CHOLMOD's supernodal factorisation and ARPACK.
//
// Debian's libblas.so.3 is an alternative: the reference BLAS (one thread) or OpenBLAS, which splits
// the dense kernels of a supernodal factor among its threads. Its rounding then depends on how many:
// the same factorisation solved with one and with two OpenBLAS threads differs in the last bits
// (docs/speed.md, "Large packings"). budjam's results must not depend on the thread count, so its
// factorisations, solves and Lanczos iterations run the BLAS on one thread: a SerialBlas holds
// OpenBLAS there while it lives, and the thread count the process had is restored when the last one
// ends, so that other users of the BLAS in the same process (numpy's, in the Python module) keep
// theirs. Single-threaded, OpenBLAS's kernels still pay: they are faster than the reference BLAS's.
#include <string>

namespace budjam {

// The BLAS loaded in this process, if its thread count can be held ("OpenBLAS"), else empty.
std::string threaded_blas();
// The BLAS's thread count (1 for a BLAS without threads), and setting it (ignored there). For
// tests and benchmarks; budjam's own BLAS calls are under a SerialBlas.
int blas_threads();
void set_blas_threads(int threads);

// While at least one lives, the BLAS runs on one thread. Any thread may hold one.
class SerialBlas {
 public:
  SerialBlas();
  ~SerialBlas();
  SerialBlas(const SerialBlas&) = delete;
  SerialBlas& operator=(const SerialBlas&) = delete;
};

}  // namespace budjam
