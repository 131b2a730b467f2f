// Prefix sums and atomic counters for the two-pass (count, scan, fill) builders of the
// neighbour layer. Host versions here; the CUDA twin of exclusive_scan (cub::DeviceScan) is in
// neighbor_cuda.cuh. Atomics are usable inside QDEMSPH_LAMBDA bodies on both.
#pragma once

#include <omp.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "core/exec_host.hpp"
#include "core/memory.hpp"

namespace qdemsph {

// Returns the old value.
QDEMSPH_HD int atomic_inc(int* p) {
#if defined(__CUDA_ARCH__)
  return atomicAdd(p, 1);
#else
  return __atomic_fetch_add(p, 1, __ATOMIC_RELAXED);
#endif
}

// *p = max(*p, v) for v > 0 and *p >= 0 (a NaN or a v <= 0 changes nothing): non-negative
// doubles order as their bit patterns do.
QDEMSPH_HD void atomic_max_positive(double* p, double v) {
  if (!(v > 0)) return;
#if defined(__CUDA_ARCH__)
  atomicMax(reinterpret_cast<unsigned long long*>(p),
            static_cast<unsigned long long>(__double_as_longlong(v)));
#else
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  auto* q = reinterpret_cast<std::uint64_t*>(p);
  std::uint64_t old = __atomic_load_n(q, __ATOMIC_RELAXED);
  while (old < bits &&
         !__atomic_compare_exchange_n(q, &old, bits, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
  }
#endif
}

// In place exclusive prefix sum of the counts c[0..n); returns the total. c must have n + 1
// entries: c[n] receives the total too, so c is a CSR offset array afterwards. On the host a
// long array (a layout rebuild's per-particle counts) is summed on the threads, in as many
// contiguous blocks as threads: each block's total, then each block from its offset. Integer
// sums are exact, so the result does not depend on the thread count. Bytes: 8 read and 8
// written per entry, and 8 more read on several threads.
template <class T>
std::int64_t exclusive_scan(HostExec, View<T> c, std::int64_t n) {
  // The running sum from `first` over block b of nb (entries [n b / nb, n (b + 1) / nb)), each
  // entry replaced by the sum before it when `write`; through a pointer of its own: read through
  // the parallel region's captures, the loop ran 5 x slower on one thread.
  const auto block = [p = c.p, n](std::int64_t b, std::int64_t nb, std::int64_t first, bool write) {
    std::int64_t s = first;
    const std::int64_t e = n * (b + 1) / nb;
    for (std::int64_t i = n * b / nb; i < e; ++i) {
      const std::int64_t v = p[i];
      if (write) p[i] = static_cast<T>(s);
      s += v;
    }
    return s;
  };
  const std::int64_t nb = n >= kMinParallel ? omp_get_max_threads() : 1;
  if (nb == 1) {
    const std::int64_t s = block(0, 1, 0, true);
    c[n] = static_cast<T>(s);
    return s;
  }
  std::vector<std::int64_t> at(nb + 1, 0);  // each block's offset
#pragma omp parallel for schedule(static)
  for (std::int64_t b = 0; b < nb; ++b) at[b + 1] = block(b, nb, 0, false);
  for (std::int64_t b = 0; b < nb; ++b) at[b + 1] += at[b];
#pragma omp parallel for schedule(static)
  for (std::int64_t b = 0; b < nb; ++b) block(b, nb, at[b], true);
  c[n] = static_cast<T>(at[nb]);
  return at[nb];
}

// exclusive_scan for a caller that needs no total on the host: on a GPU the scan is queued and
// nothing waits (c[n] holds the total on the device; neighbor_cuda.cuh).
template <class T>
void queue_exclusive_scan(HostExec, View<T> c, std::int64_t n) {
  exclusive_scan(HostExec{}, c, n);
}

// Reads one element of a buffer back to the host (a size after a scan).
template <class T>
T read_back(const Buffer<T>& b, std::int64_t i) {
  T v{};
  space_copy(&v, Space::Host, b.cview().p + i, b.space(), sizeof(T));
  return v;
}

}  // namespace qdemsph
