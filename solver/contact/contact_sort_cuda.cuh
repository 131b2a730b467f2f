// Orchestration twin (CUDA, nvcc only): sorts contact records by key on the device with
// cub::DeviceMergeSort (the host twin is contact_sort_host.hpp). Keys are unique (one record per
// feature pair), so both give the same order.
#pragma once

#include <cstdint>
#include <cub/device/device_merge_sort.cuh>

#include "contact/contact_record.hpp"
#include "core/exec_cuda.cuh"
#include "core/memory.hpp"

namespace qdemsph {

struct ContactKeyLess {
  __device__ bool operator()(const ContactRecord& a, const ContactRecord& b) const {
    return key_less(a, b);
  }
};

inline void sort_records(CudaExec, View<ContactRecord> r, std::int64_t n) {
  if (n < 2) return;
  std::size_t bytes = 0;
  QDEMSPH_CUDA_CHECK(cub::DeviceMergeSort::SortKeys(nullptr, bytes, r.p, n, ContactKeyLess{}),
                     "cub::DeviceMergeSort::SortKeys (size)");
  QDEMSPH_CUDA_CHECK(
      cub::DeviceMergeSort::SortKeys(cuda_temp_storage(bytes), bytes, r.p, n, ContactKeyLess{}),
      "cub::DeviceMergeSort::SortKeys");
}

}  // namespace qdemsph
