// Stream compaction on the host: the indices i in [0, n) with keep(i), in increasing order.
// Two passes over as many contiguous blocks as threads (count, then write at the block's
// offset), so the result does not depend on the thread count; keep is called twice per index.
// For host orchestration code (a distributed rank's layout), not for files nvcc compiles.
#pragma once

#include <omp.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include "core/exec_host.hpp"

namespace qdemsph {

template <class Keep>
std::vector<std::int64_t> select_indices(HostExec, std::int64_t n, Keep keep) {
  const std::int64_t nb = n >= kMinParallel ? omp_get_max_threads() : 1;
  const auto lo = [&](std::int64_t b) { return n * b / nb; };
  std::vector<std::int64_t> off(nb + 1, 0);
#pragma omp parallel for schedule(static) if (nb > 1)
  for (std::int64_t b = 0; b < nb; ++b)
    for (std::int64_t i = lo(b); i < lo(b + 1); ++i) off[b + 1] += keep(i) ? 1 : 0;
  std::partial_sum(off.begin(), off.end(), off.begin());
  std::vector<std::int64_t> out(off[nb]);
#pragma omp parallel for schedule(static) if (nb > 1)
  for (std::int64_t b = 0; b < nb; ++b) {
    std::int64_t k = off[b];
    for (std::int64_t i = lo(b); i < lo(b + 1); ++i)
      if (keep(i)) out[k++] = i;
  }
  return out;
}

}  // namespace qdemsph
