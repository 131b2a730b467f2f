// CUDA twins of the neighbour layer's orchestration (nvcc only; include after
// core/exec_cuda.cuh): exclusive_scan (scan.hpp) and sort_by_key (cell_grid.hpp). Data stays on
// the device; only a scan's total comes back to the host (one synchronising 8-byte copy), and
// not even that from queue_exclusive_scan.
//
//  - exclusive_scan: cub::DeviceScan::ExclusiveSum in place over n + 1 entries, so c[n] gets
//    the total as on the host. Integer sums: the same result as the serial host scan.
//  - sort_order: cub::DeviceRadixSort::SortPairs of (key, index) over the bits keys need
//    (stable: equal keys keep increasing index); sort_by_key: it, then start[k] = lower bound of
//    k in the sorted keys. The same order and offsets as the host's sorts.
#pragma once

#include <cstdint>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include "core/exec_cuda.cuh"
#include "core/memory.hpp"

namespace qdemsph {

template <class T>
void queue_exclusive_scan(CudaExec, View<T> c, std::int64_t n) {
  static CubBytes size;
  std::size_t bytes = size(n + 1, 0, [&](std::int64_t m) {
    std::size_t b = 0;
    QDEMSPH_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, b, c.p, c.p, m),
                       "cub::DeviceScan::ExclusiveSum (size)");
    return b;
  });
  QDEMSPH_CUDA_CHECK(
      cub::DeviceScan::ExclusiveSum(cuda_temp_storage(bytes), bytes, c.p, c.p, n + 1),
      "cub::DeviceScan::ExclusiveSum");
}

template <class T>
std::int64_t exclusive_scan(CudaExec, View<T> c, std::int64_t n) {
  queue_exclusive_scan(CudaExec{}, c, n);
  T total{};
  QDEMSPH_CUDA_CHECK(cudaMemcpy(&total, c.p + n, sizeof(T), cudaMemcpyDeviceToHost),
                     "scan total copy (an earlier kernel may have faulted)");
  return static_cast<std::int64_t>(total);
}

// The stable order of items [0, n) by the low `bits` bits of their keys (cell_grid.hpp's
// sort_order); scratch's entries n .. 2 n get the sorted keys.
inline void sort_order(CudaExec, View<const std::int64_t> keys, int bits, View<std::int64_t> order,
                       Buffer<std::int64_t>& scratch) {
  const std::int64_t n = keys.n;
  if (scratch.size() < 2 * n) scratch.resize(2 * n + n / 4);
  const auto s = scratch.view();
  for_each(CudaExec{}, n, [=] __device__(std::int64_t i) { s[i] = i; });
  // Keys are non-negative: sorting their bits as unsigned gives the same order.
  const auto* kin = reinterpret_cast<const unsigned long long*>(keys.p);
  auto* kout = reinterpret_cast<unsigned long long*>(s.p + n);
  if (n == 0) return;
  static CubBytes size;
  std::size_t bytes = size(n, bits, [&](std::int64_t m) {
    std::size_t b = 0;
    QDEMSPH_CUDA_CHECK(
        cub::DeviceRadixSort::SortPairs(nullptr, b, kin, kout, s.p, order.p, m, 0, bits),
        "cub::DeviceRadixSort::SortPairs (size)");
    return b;
  });
  QDEMSPH_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(cuda_temp_storage(bytes), bytes, kin, kout,
                                                     s.p, order.p, n, 0, bits),
                     "cub::DeviceRadixSort::SortPairs");
}

inline void sort_by_key(CudaExec, View<const std::int64_t> keys, std::int64_t nkeys,
                        View<std::int64_t> start, View<std::int64_t> order,
                        Buffer<std::int64_t>& scratch) {
  const std::int64_t n = keys.n;
  int end_bit = 1;
  while (end_bit < 63 && (std::int64_t{1} << end_bit) < nkeys) ++end_bit;
  sort_order(CudaExec{}, keys, end_bit, order, scratch);
  const std::int64_t* sorted = scratch.view().p + n;
  for_each(CudaExec{}, nkeys + 1, [=] __device__(std::int64_t k) {
    start[k] = lower_bound_index(n, [&](std::int64_t m) { return sorted[m] < k; });
  });
}

}  // namespace qdemsph
