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
// Launch hint for for_each: on CUDA, blocks of T threads, at least N of them resident per SM
// (caps the registers a thread at 65536 / (T N)); the host ignores it. For register-heavy
// loops whose occupancy, not their arithmetic, limits them (sph/sph_stage.hpp). A block keeps
// its place on the SM until its slowest warp ends, so loops whose items take unequal times
// (neighbour lists of different lengths) fill the SM better in small blocks.
template <int N, int T = 256>
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
