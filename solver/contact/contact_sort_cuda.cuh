// Orchestration twin (CUDA, nvcc only): the order that sorts contact records by key, from their
// packed keys (sort_key), by cub::DeviceRadixSort over the bits the keys use (the host twin is
// contact_sort_host.hpp). Keys are unique (one record per feature pair), so both give the same
// order.
#pragma once

#include <cstdint>
#include <cub/device/device_radix_sort.cuh>

#include "core/exec_cuda.cuh"
#include "core/memory.hpp"

namespace qdemsph {

// The indices order[0, n) permuted so that keys[order[k]] ascend (keys: their low `bits` bits,
// the others 0). keys and order have room for 2n entries, the second halves scratch; returns
// where the sorted order is (order.p or order.p + n).
inline const std::int32_t* sorted_order(CudaExec, View<std::uint64_t> keys,
                                        View<std::int32_t> order, std::int64_t n, int bits) {
  if (n < 2) return order.p;
  cub::DoubleBuffer<std::uint64_t> k(keys.p, keys.p + n);
  cub::DoubleBuffer<std::int32_t> v(order.p, order.p + n);
  const int end_bit = bits > 0 ? bits : 1;
  static CubBytes size;
  std::size_t bytes = size(n, end_bit, [&](std::int64_t m) {
    std::size_t b = 0;
    QDEMSPH_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, b, k, v, m, 0, end_bit),
                       "cub::DeviceRadixSort::SortPairs (size)");
    return b;
  });
  QDEMSPH_CUDA_CHECK(
      cub::DeviceRadixSort::SortPairs(cuda_temp_storage(bytes), bytes, k, v, n, 0, end_bit),
      "cub::DeviceRadixSort::SortPairs");
  return v.Current();
}

}  // namespace qdemsph
