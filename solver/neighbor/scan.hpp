// Prefix sums and atomic counters for the two-pass (count, scan, fill) builders of the
// neighbour layer. Host versions here; the CUDA twin of exclusive_scan (cub::DeviceScan) is in
// neighbor_cuda.cuh. Atomics are usable inside QDEMSPH_LAMBDA bodies on both.
#pragma once

#include <cstdint>

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

// In place exclusive prefix sum (serial on the host: deterministic) of c[0..n); returns the total.
// c must have n + 1 entries: c[n] receives the total too, so c is a CSR offset array afterwards.
template <class T>
std::int64_t exclusive_scan(HostExec, View<T> c, std::int64_t n) {
  std::int64_t s = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    const std::int64_t v = c[i];
    c[i] = static_cast<T>(s);
    s += v;
  }
  c[n] = static_cast<T>(s);
  return s;
}

// Reads one element of a buffer back to the host (a size after a scan).
template <class T>
T read_back(const Buffer<T>& b, std::int64_t i) {
  T v{};
  space_copy(&v, Space::Host, b.cview().p + i, b.space(), sizeof(T));
  return v;
}

}  // namespace qdemsph
