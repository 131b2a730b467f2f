// Stream compaction on the host: a stable counting sort of the indices [0, n) by a key in
// [0, K) (keys outside are dropped), and its one-key case select_indices. Two passes over as
// many contiguous blocks as threads (count per block and key, then write at each block's
// offset), so the result does not depend on the thread count; key(i) is called twice per index.
// For host orchestration code (a distributed rank's layout; a GPU stage's too, in its host
// code).
#pragma once

#include <omp.h>

#include <cstdint>
#include <vector>

#include "core/exec_host.hpp"
#include "core/memory.hpp"

namespace qdemsph {

// index: the kept indices, key 0 first, each key's in increasing order; start: K + 1 offsets
// into index (key k at [start[k], start[k + 1])).
struct Buckets {
  std::vector<std::int64_t> index, start;
};

// Into the caller's buckets, whose index storage a later call reuses (a layout rebuild's: no
// fresh pages to fault in and zero for the whole index, only a grown tail).
template <class Key>
void bucket_indices(HostExec, std::int64_t n, int nkeys, Key key, Buckets& out) {
  const std::int64_t nb = n >= kMinParallel ? omp_get_max_threads() : 1, K = nkeys;
  const auto lo = [&](std::int64_t b) { return n * b / nb; };
  std::vector<std::int64_t> at(nb * K, 0);  // block b's count, then its next slot, of key k
#pragma omp parallel for schedule(static) if (nb > 1)
  for (std::int64_t b = 0; b < nb; ++b)
    for (std::int64_t i = lo(b); i < lo(b + 1); ++i) {
      const std::int64_t k = key(i);
      if (k >= 0 && k < K) ++at[b * K + k];
    }
  out.start.assign(K + 1, 0);
  std::int64_t s = 0;
  for (std::int64_t k = 0; k < K; ++k) {
    out.start[k] = s;
    for (std::int64_t b = 0; b < nb; ++b) {
      const std::int64_t c = at[b * K + k];
      at[b * K + k] = s;
      s += c;
    }
  }
  out.start[K] = s;
  resize_for_overwrite(out.index, static_cast<std::size_t>(s));
#pragma omp parallel for schedule(static) if (nb > 1)
  for (std::int64_t b = 0; b < nb; ++b)
    for (std::int64_t i = lo(b); i < lo(b + 1); ++i) {
      const std::int64_t k = key(i);
      if (k >= 0 && k < K) out.index[at[b * K + k]++] = i;
    }
}
template <class Key>
Buckets bucket_indices(HostExec e, std::int64_t n, int nkeys, Key key) {
  Buckets out;
  bucket_indices(e, n, nkeys, key, out);
  return out;
}

// The indices i in [0, n) with keep(i), in increasing order: into out, its storage reused.
template <class Keep>
void select_indices(HostExec e, std::int64_t n, Keep keep, std::vector<std::int64_t>& out) {
  Buckets b;
  b.index.swap(out);
  bucket_indices(
      e, n, 1, [&](std::int64_t i) { return keep(i) ? 0 : 1; }, b);
  out.swap(b.index);
}
template <class Keep>
std::vector<std::int64_t> select_indices(HostExec e, std::int64_t n, Keep keep) {
  std::vector<std::int64_t> out;
  select_indices(e, n, keep, out);
  return out;
}

}  // namespace qdemsph
