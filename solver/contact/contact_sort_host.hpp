// Orchestration twin (host): the order that sorts contact records by key, from their packed
// keys (sort_key). The CUDA twin (contact_sort_cuda.cuh) computes it on the device. Keys are
// unique (one record per feature pair), so both give the same order.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "core/exec_host.hpp"
#include "core/memory.hpp"
#include "core/radix_sort.hpp"

namespace qdemsph {

// The indices order[0, n) permuted so that keys[order[k]] ascend (keys: their low `bits` bits,
// the others 0). keys and order have room for 2n entries, the second halves scratch (the
// device's); returns where the sorted order is.
inline const std::int32_t* sorted_order(HostExec, View<std::uint64_t> keys,
                                        View<std::int32_t> order, std::int64_t n, int bits) {
  std::vector<std::pair<std::uint64_t, std::int32_t>> a(n), tmp;
  for_each(HostExec{}, n, [&](std::int64_t i) { a[i] = {keys[i], order[i]}; });
  radix_sort(a, tmp, bits);
  for_each(HostExec{}, n, [&](std::int64_t i) { order[i] = a[i].second; });
  return order.p;
}

}  // namespace qdemsph
