// Portability macros: physics is written once as host+device inline functions.
#pragma once
#include <cstdint>

#if defined(__CUDACC__)
#define QDEMSPH_HD __host__ __device__ __forceinline__
#define QDEMSPH_LAMBDA [=] __host__ __device__
#else
#define QDEMSPH_HD inline
#define QDEMSPH_LAMBDA [=]
#endif

// Before a loop of constant trip count: unrolled in device code, so that a small array it
// indexes stays in registers (the host compiler decides for itself).
#if defined(__CUDA_ARCH__)
#define QDEMSPH_UNROLL _Pragma("unroll")
#else
#define QDEMSPH_UNROLL
#endif

namespace qdemsph {
// Launch hint for for_each: keep at least N blocks of 256 threads resident per SM on CUDA
// (caps the registers a thread at 65536 / (256 N)); the host ignores it. For register-heavy
// loops whose occupancy, not their arithmetic, limits them (sph/sph_stage.hpp).
template <int N>
struct MinBlocks {};

// The first index in [0, n) at which before(index) is false, for a predicate true on a prefix
// (n when it holds everywhere): std::lower_bound over indices, in a kernel too.
template <class Before>
QDEMSPH_HD std::int64_t lower_bound_index(std::int64_t n, const Before& before) {
  std::int64_t lo = 0, hi = n;
  while (lo < hi) {
    const std::int64_t mid = (lo + hi) / 2;
    if (before(mid))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}
}  // namespace qdemsph
