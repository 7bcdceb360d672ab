// Holding a threaded BLAS on one thread (see blas_threads.hpp).
#include "budjam/blas_threads.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>
#include <sstream>

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

std::string blas_library() {
  Dl_info where{};
  const void* gemm = dlsym(RTLD_DEFAULT, "dgemm_");
  if (!gemm || !dladdr(gemm, &where) || !where.dli_fname) return "unknown";
  // The alternatives' symlink (libblas.so.3) says nothing; the file it leads to names the BLAS.
  std::error_code ec;
  const std::filesystem::path canonical = std::filesystem::canonical(where.dli_fname, ec);
  const std::string file = ec ? std::string(where.dli_fname) : canonical.string();
  // OpenBLAS, itself or behind Debian's libblas.so.3 that forwards to it (a dependency, which dlsym
  // on the library's handle also searches), says which version and kernel run.
  using Text = char* (*)();
  Text config = nullptr, core = nullptr;
  if (void* library = dlopen(where.dli_fname, RTLD_LAZY | RTLD_NOLOAD)) {
    config = reinterpret_cast<Text>(dlsym(library, "openblas_get_config"));
    core = reinterpret_cast<Text>(dlsym(library, "openblas_get_corename"));
    dlclose(library);  // only the reference taken above: the library stays loaded
  }
  if (!config || !core) return file;
  std::istringstream words(config());  // "OpenBLAS 0.3.21 NO_LAPACKE DYNAMIC_ARCH ...": name, version, options
  std::string name, version;
  words >> name >> version;
  return name + " " + version + ", " + core() + " kernel (" + file + ")";
}

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
