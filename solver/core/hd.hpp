// Portability macros: physics is written once as host+device inline functions.
#pragma once

#if defined(__CUDACC__)
#define QDEMSPH_HD __host__ __device__ __forceinline__
#define QDEMSPH_LAMBDA [=] __host__ __device__
#else
#define QDEMSPH_HD inline
#define QDEMSPH_LAMBDA [=]
#endif
