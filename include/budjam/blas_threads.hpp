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
//
// CHOLMOD's supernodal factorisation also opens OpenMP regions of its own, with a team size fixed
// when Debian built it (CHOLMOD_OMP_NUM_THREADS = 4) and no run-time setting: they only clear
// workspace, so they change no bit, but on every factorisation they wake three threads that then
// wait on futexes (an L = 15 run with the Newton finish: 4.3 → 3.6 CPU s without them, the same
// packings). A SerialOpenMp makes every OpenMP region its thread opens run on that thread alone.
#include <string>

namespace budjam {

// The BLAS loaded in this process, if its thread count can be held ("OpenBLAS"), else empty.
std::string threaded_blas();
// Which BLAS this process computes with, for a run's record: a factor's last bits depend on it and,
// for an OpenBLAS built for several CPUs, on the kernel it chose for this one at load time (or that
// OPENBLAS_CORETYPE named). The file that provides dgemm_, links resolved, with OpenBLAS's version
// and kernel when it is OpenBLAS: "OpenBLAS 0.3.21, Haswell kernel (/usr/lib/.../libblas.so.3)";
// "unknown" if no loaded library provides dgemm_.
std::string blas_library();
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

// While it lives, the OpenMP regions that the thread holding it opens (in a library it calls) run
// on that thread alone; held around a call, not across budjam's own threaded force loops.
class SerialOpenMp {
 public:
  SerialOpenMp();
  ~SerialOpenMp();
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  int levels_ = 0;  // the max-active-levels setting to restore
};

}  // namespace budjam
