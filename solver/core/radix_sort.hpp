// Host sort of (key, value) records by a 64-bit key: LSD radix, 8 bits a pass, on OpenMP
// threads; merge_runs for records that come in a few sorted runs. For the host work of a layout
// rebuild (parallel/balance.cpp: items by curve key; sph/sph_stage.hpp: particles by order key; a
// rank's vertices by global id), where a comparison sort was serial.
//
// Stable, so the result is the same for any thread count: each thread counts the digits of its
// block, the counts are scanned in (digit, thread) order, and each thread scatters its block in
// order. A pass whose digit is the same in every key moves nothing. Bytes: one read of the
// records to count and one read and write to scatter per pass, bits / 8 passes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "core/exec_host.hpp"
#include "core/select_host.hpp"

namespace qdemsph {

// Sorts a by key (the low `bits` bits of each key; the others must be 0). tmp: scratch,
// resized to a's size (kept by a caller that sorts again).
template <class V>
void radix_sort(std::vector<std::pair<std::uint64_t, V>>& a,
                std::vector<std::pair<std::uint64_t, V>>& tmp, int bits = 64) {
  const std::int64_t n = static_cast<std::int64_t>(a.size());
  resize_for_overwrite(tmp, a.size());
  int most = 1;
#ifdef _OPENMP
  if (n >= kMinParallel) most = omp_get_max_threads();
#endif
  std::vector<std::int64_t> count(256 * static_cast<std::size_t>(most));  // per (thread, digit)
  for (int shift = 0; shift < bits; shift += 8) {
    bool moves = true;
#pragma omp parallel num_threads(most) if (most > 1)
    {
      int nt = 1, t = 0;
#ifdef _OPENMP
      nt = omp_get_num_threads(), t = omp_get_thread_num();
#endif
      const std::int64_t b = n * t / nt, e = n * (t + 1) / nt;
      std::int64_t* c = &count[256 * t];
      std::fill(c, c + 256, std::int64_t{0});
      for (std::int64_t i = b; i < e; ++i) ++c[(a[i].first >> shift) & 255];
#pragma omp barrier
#pragma omp single
      {
        std::int64_t s = 0;
        for (int d = 0; d < 256; ++d)
          for (int u = 0; u < nt; ++u) {
            const std::int64_t k = count[256 * u + d];
            if (k == n) moves = false;
            count[256 * u + d] = s;
            s += k;
          }
      }  // implied barrier
      if (moves)
        for (std::int64_t i = b; i < e; ++i) tmp[c[(a[i].first >> shift) & 255]++] = a[i];
    }
    if (moves) a.swap(tmp);
  }
}

// Sorts a by key, stably, where a comes in a few ascending runs (a distributed rank's vertices:
// its owned ones, each neighbour's ghosts, the fixed bodies', each run in global id order):
// adjacent runs merged pairwise, round after round, the merges of a round on the threads; O(n
// log runs), nothing moved when a is sorted. tmp: scratch, as radix_sort's.
template <class V>
void merge_runs(std::vector<std::pair<std::uint64_t, V>>& a,
                std::vector<std::pair<std::uint64_t, V>>& tmp) {
  const auto n = static_cast<std::int64_t>(a.size());
  std::vector<std::int64_t> start = select_indices(
      HostExec{}, n, [&](std::int64_t i) { return i == 0 || a[i].first < a[i - 1].first; });
  if (start.size() <= 1) return;
  start.push_back(n);
  resize_for_overwrite(tmp, a.size());
  const auto by_key = [](const auto& x, const auto& y) { return x.first < y.first; };
  while (start.size() > 2) {  // runs [start[r], start[r + 1])
    const auto runs = static_cast<std::int64_t>(start.size()) - 1;
    for_each(HostExec{}, (runs + 1) / 2, [&](std::int64_t j) {
      const auto b = a.begin() + start[2 * j], m = a.begin() + start[std::min(2 * j + 1, runs)],
                 e = a.begin() + start[std::min(2 * j + 2, runs)];
      std::merge(b, m, m, e, tmp.begin() + start[2 * j], by_key);
    });
    a.swap(tmp);
    std::vector<std::int64_t> next;
    for (std::int64_t r = 0; r < runs; r += 2) next.push_back(start[r]);
    next.push_back(n);
    start.swap(next);
  }
}

// The permutation that sorts `keys` (non-negative integers): keys[order[0]] <= keys[order[1]]
// <= ..., equal keys in input order.
template <class K>
std::vector<std::int64_t> sorted_order(const std::vector<K>& keys) {
  const auto n = static_cast<std::int64_t>(keys.size());
  std::vector<std::pair<std::uint64_t, std::int64_t>> kv(n), tmp;
  for_each(HostExec{}, n, [&](std::int64_t i) {
    kv[i] = {static_cast<std::uint64_t>(keys[i]), i};
  });
  radix_sort(kv, tmp);
  std::vector<std::int64_t> order(n);
  for_each(HostExec{}, n, [&](std::int64_t i) { order[i] = kv[i].second; });
  return order;
}

// out[i] = in[order[i]] for every i, into the caller's array (kept by a caller that gathers
// again: resized without zeroing, written on the threads).
template <class Out, class T>
void gather_into(std::vector<Out>& out, const std::vector<T>& in,
                 const std::vector<std::int64_t>& order) {
  const auto n = static_cast<std::int64_t>(order.size());
  resize_for_overwrite(out, order.size());
  for_each(HostExec{}, n, [&](std::int64_t i) { out[i] = static_cast<Out>(in[order[i]]); });
}

// in[order[i]] for every i, as type Out.
template <class Out, class T>
std::vector<Out> gathered(const std::vector<T>& in, const std::vector<std::int64_t>& order) {
  std::vector<Out> out;
  gather_into(out, in, order);
  return out;
}

}  // namespace qdemsph
