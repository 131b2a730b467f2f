// Sorting on the host over the OpenMP threads: libstdc++'s parallel mode (a multiway
// mergesort), sequential with one thread or a short range. Where no two keys tie every correct
// sort gives the same order, so the result does not depend on the thread count; equal keys may
// come out in another order. For host code (the rebuild of a distributed rank's layout), not
// for files nvcc compiles.
#pragma once

#include <cstdint>
#include <functional>
#include <parallel/algorithm>
#include <utility>
#include <vector>

#include "core/exec_host.hpp"

namespace qdemsph {

template <class It, class Less = std::less<>>
void parallel_sort(It first, It last, Less less = {}) {
  __gnu_parallel::sort(first, last, less);
}

// The permutation that sorts `keys` (no two equal): keys[order[0]] < keys[order[1]] < ...
template <class K>
std::vector<std::int64_t> sorted_order(const std::vector<K>& keys) {
  const auto n = static_cast<std::int64_t>(keys.size());
  std::vector<std::pair<K, std::int64_t>> kv(n);
  for_each(HostExec{}, n, [&](std::int64_t i) { kv[i] = {keys[i], i}; });
  parallel_sort(kv.begin(), kv.end());
  std::vector<std::int64_t> order(n);
  for_each(HostExec{}, n, [&](std::int64_t i) { order[i] = kv[i].second; });
  return order;
}

// in[order[i]] for every i, as type Out.
template <class Out, class T>
std::vector<Out> gathered(const std::vector<T>& in, const std::vector<std::int64_t>& order) {
  std::vector<Out> out(order.size());
  for_each(HostExec{}, static_cast<std::int64_t>(order.size()),
           [&](std::int64_t i) { out[i] = static_cast<Out>(in[order[i]]); });
  return out;
}

}  // namespace qdemsph
