// Kernels report a failure by storing (index + 1) of an offender in a flag word; 0 means
// no error. Any one offender is kept (the smallest is not guaranteed). Host code reads
// the flag after the stage and turns it into a SimulationError naming the element.
#pragma once

#include <cstdint>

#include "core/hd.hpp"

namespace qdemsph {

// Returns true for the one call that set the flag (it may then record details of its
// offender: no other call writes them until the flag is cleared).
QDEMSPH_HD bool raise_flag(unsigned long long* flag, std::int64_t index) {
#if defined(__CUDA_ARCH__)
  return atomicCAS(flag, 0ULL, static_cast<unsigned long long>(index) + 1ULL) == 0ULL;
#else
  unsigned long long expected = 0;
  return __atomic_compare_exchange_n(flag, &expected, static_cast<unsigned long long>(index) + 1ULL,
                                     false, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
#endif
}

}  // namespace qdemsph
