// Holding a threaded BLAS on one thread (see blas_threads.hpp).
#include "budjam/blas_threads.hpp"

#include <dlfcn.h>

#include <mutex>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace budjam {

namespace {

// OpenBLAS's thread control, looked up in the process: present only when the libblas.so.3 that
// CHOLMOD and ARPACK were linked against resolves to OpenBLAS.
struct OpenBlas {
  int (*get)() = nullptr;
  void (*set)(int) = nullptr;
  bool present() const { return get && set; }
};

const OpenBlas& openblas() {
  static const OpenBlas b = [] {
    OpenBlas o;
    o.get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    o.set = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    return o;
  }();
  return b;
}

// The holders alive and the thread count to restore after the last.
struct SerialBlasHolders {
  std::mutex mutex;
  long alive = 0;
  int restore = 1;
};

SerialBlasHolders& serial_blas_holders() {
  static SerialBlasHolders h;
  return h;
}

}  // namespace

std::string threaded_blas() { return openblas().present() ? "OpenBLAS" : ""; }

int blas_threads() { return openblas().present() ? openblas().get() : 1; }

void set_blas_threads(int threads) {
  if (openblas().present()) openblas().set(threads);
}

SerialBlas::SerialBlas() {
  if (!openblas().present()) return;
  SerialBlasHolders& h = serial_blas_holders();
  const std::lock_guard<std::mutex> lock(h.mutex);
  if (h.alive++ == 0) {
    h.restore = openblas().get();
    if (h.restore != 1) openblas().set(1);
  }
}

SerialBlas::~SerialBlas() {
  if (!openblas().present()) return;
  SerialBlasHolders& h = serial_blas_holders();
  const std::lock_guard<std::mutex> lock(h.mutex);
  if (--h.alive == 0 && h.restore != 1) openblas().set(h.restore);
}

// No active level allowed: a region then gets one thread, whatever its num_threads clause asks.
SerialOpenMp::SerialOpenMp() {
#ifdef _OPENMP
  levels_ = omp_get_max_active_levels();
  omp_set_max_active_levels(0);
#endif
}

SerialOpenMp::~SerialOpenMp() {
#ifdef _OPENMP
  omp_set_max_active_levels(levels_);
#endif
}

}  // namespace budjam
