// Portability macros: physics is written once as host+device inline functions.
#pragma once

#if defined(__CUDACC__)
#define QDEMSPH_HD __host__ __device__ __forceinline__
#define QDEMSPH_LAMBDA [=] __host__ __device__
#else
#define QDEMSPH_HD inline
#define QDEMSPH_LAMBDA [=]
#endif

namespace qdemsph {
// Launch hint for for_each: keep at least N blocks of 256 threads resident per SM on CUDA
// (caps the registers a thread at 65536 / (256 N)); the host ignores it. For register-heavy
// loops whose occupancy, not their arithmetic, limits them (sph/sph_stage.hpp).
template <int N>
struct MinBlocks {};
}  // namespace qdemsph
