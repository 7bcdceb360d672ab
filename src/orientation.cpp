// Cell axes (cos θ, sin θ), several cells at a time (orientation.hpp).
#include "budjam/orientation.hpp"

#include <algorithm>
#include <cmath>

#ifdef BUDJAM_HAVE_LIBMVEC
#include <immintrin.h>
// glibc's vector functions, named by the x86-64 vector function ABI: b = SSE2, d = AVX2; N lanes;
// v = one vector argument.
extern "C" __m128d _ZGVbN2v_cos(__m128d);
extern "C" __m128d _ZGVbN2v_sin(__m128d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_cos(__m256d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_sin(__m256d);
#endif

namespace budjam {

namespace {

#ifdef BUDJAM_HAVE_LIBMVEC
__attribute__((target("avx2"))) void four_axes(const double* theta, double* c, double* s) {
  const __m256d t = _mm256_loadu_pd(theta);
  _mm256_storeu_pd(c, _ZGVdN4v_cos(t));
  _mm256_storeu_pd(s, _ZGVdN4v_sin(t));
}

void two_axes(const double* theta, double* c, double* s) {
  const __m128d t = _mm_loadu_pd(theta);
  _mm_storeu_pd(c, _ZGVbN2v_cos(t));
  _mm_storeu_pd(s, _ZGVbN2v_sin(t));
}

struct Lanes {
  void (*kernel)(const double*, double*, double*);
  std::size_t width;
};

const Lanes& lanes() {
  static const Lanes chosen = __builtin_cpu_supports("avx2") ? Lanes{four_axes, 4} : Lanes{two_axes, 2};
  return chosen;
}
#endif

}  // namespace

void axes(const double* theta, std::size_t n, double* c, double* s) {
#ifdef BUDJAM_HAVE_LIBMVEC
  const Lanes& lane = lanes();
  std::size_t k = 0;
  for (; k + lane.width <= n; k += lane.width) lane.kernel(theta + k, c + k, s + k);
  if (k == n) return;
  // The last few angles, padded with copies: lanes are computed independently, so each gets the
  // value a full vector would give it.
  double t[4], ct[4], st[4];
  for (std::size_t l = 0; l < lane.width; ++l) t[l] = theta[std::min(k + l, n - 1)];
  lane.kernel(t, ct, st);
  for (std::size_t l = 0; k + l < n; ++l) {
    c[k + l] = ct[l];
    s[k + l] = st[l];
  }
#else
  for (std::size_t k = 0; k < n; ++k) {
    c[k] = std::cos(theta[k]);
    s[k] = std::sin(theta[k]);
  }
#endif
}

Axis axis(double theta) {
  Axis a;
  axes(&theta, 1, &a.c, &a.s);
  return a;
}

}  // namespace budjam
