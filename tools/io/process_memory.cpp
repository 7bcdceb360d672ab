#include "io/process_memory.hpp"

#include <climits>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace budjam::io {

bool keep_freed_memory() {
#if defined(__GLIBC__)
  // No block is served by mmap (glibc still falls back to it when the heap cannot grow), and the heap's
  // free top is not returned below INT_MAX bytes. Setting either also stops glibc's own adjustment of
  // its thresholds, which stop at 32 MiB — below a large packing's factors.
  return mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
#else
  return false;
#endif
}

}  // namespace budjam::io
