// The host launch layer: for_each / reductions over an index range as OpenMP loops.
// The CUDA twin is exec_cuda.cuh; stage code is written once against either.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/hd.hpp"
#include "core/memory.hpp"

namespace qdemsph {

struct HostExec {
  static constexpr Space space = Space::Host;
};

// A GPU rank's host threads build its layouts and launch its kernels; between layouts they
// idle, spinning in OpenMP's barrier. 32 of them a rank made a 4 x H200 VM steal its cores
// (52-76 s of CPU over a 10 s run), and the dominoes' four layouts (the set-up's and three
// in the run) took 3.5-4.3 s, against 0.53-0.56 s with 8 (scaling/README.md, "Host threads
// of a GPU rank").
inline constexpr int kGpuRankThreads = 8;

// A rank's OpenMP threads when neither the scene nor OMP_NUM_THREADS says: its share of the
// node's cores among the node's ranks, no more than the cores it is bound to, and on a GPU
// at most kGpuRankThreads.
inline int default_host_threads(int bound_cores, int node_cores, int ranks_on_node, bool gpu) {
  int n = std::min(bound_cores, node_cores / std::max(1, ranks_on_node));
  if (gpu) n = std::min(n, kGpuRankThreads);
  return std::max(1, n);
}

// Loops shorter than this run on one thread: a parallel region costs microseconds, more
// than a small loop's work, and far more when the cores are shared.
inline constexpr std::int64_t kMinParallel = 4096;

template <class F, int N = 1, int T = 256>
void for_each(HostExec, std::int64_t n, F f, MinBlocks<N, T> = {}) {
#pragma omp parallel for schedule(static) if (n >= kMinParallel)
  for (std::int64_t i = 0; i < n; ++i) f(i);
}

// f(i) for i in [0, n) on the threads whenever n > 1: for a few items of much work each (a
// body's vertices, a copy's blocks), which for_each would run on one thread (kMinParallel).
template <class F>
void for_each_coarse(HostExec, std::int64_t n, F f) {
#pragma omp parallel for schedule(static) if (n > 1)
  for (std::int64_t i = 0; i < n; ++i) f(i);
}

// Sum of f(i) over [0, n). OpenMP's reduction order depends on the thread count only, so
// results are reproducible run to run with a fixed thread count.
template <class F>
double reduce_sum(HostExec, std::int64_t n, F f) {
  double s = 0;
#pragma omp parallel for schedule(static) reduction(+ : s) if (n >= kMinParallel)
  for (std::int64_t i = 0; i < n; ++i) s += f(i);
  return s;
}

// *acc += reduce_sum (the CUDA twin queues it into a device accumulator).
template <class F>
void reduce_sum_into(HostExec, std::int64_t n, F f, double* acc) {
  *acc += reduce_sum(HostExec{}, n, f);
}

template <class F>
double reduce_max(HostExec, std::int64_t n, F f, double init) {
  double m = init;
#pragma omp parallel for schedule(static) reduction(max : m) if (n >= kMinParallel)
  for (std::int64_t i = 0; i < n; ++i) {
    const double v = f(i);
    m = v > m ? v : m;
  }
  return m;
}

// The largest f(i)[k] over [0, n) for each of K values at once (init where n is 0): one pass
// where K reduce_max calls would take K (host orchestration: a layout rebuild's extremes). The
// maximum is exact, so the result does not depend on the thread count; NaNs are skipped.
template <int K, class F>
std::array<double, K> reduce_max_each(HostExec, std::int64_t n, F f, double init) {
  std::array<double, K> m;
  m.fill(init);
#pragma omp parallel if (n >= kMinParallel)
  {
    std::array<double, K> t = m;
#pragma omp for schedule(static) nowait
    for (std::int64_t i = 0; i < n; ++i) {
      const std::array<double, K> v = f(i);
      for (int k = 0; k < K; ++k) t[k] = v[k] > t[k] ? v[k] : t[k];
    }
#pragma omp critical
    for (int k = 0; k < K; ++k) m[k] = t[k] > m[k] ? t[k] : m[k];
  }
  return m;
}

// reduce_max queued (exec_cuda.cuh): on the host done at once.
template <class F>
void reduce_max_to(HostExec, std::int64_t n, F f, double init, double* out) {
  *out = reduce_max(HostExec{}, n, f, init);
}

// Entries [begin, end) of b (within its size) <- value(i), computed on the host's threads; the
// others stay. A device buffer's go through `stage` (one copy, at the link's speed when it is
// page-locked, as on a GPU rank), as write_on_host's.
template <class T, class Value>
void write_range_on_host(Buffer<T>& b, std::int64_t begin, std::int64_t end, StagingBytes& stage,
                         Value value) {
  const std::int64_t n = end - begin;
  if (n <= 0) return;
  T* out = b.view().p + begin;
  if (b.space() != Space::Host) {
    stage.resize(sizeof(T) * n);
    out = reinterpret_cast<T*>(stage.data());
  }
  for_each(HostExec{}, n, [&](std::int64_t i) { out[i] = value(begin + i); });
  if (b.space() != Space::Host)
    space_copy(b.view().p + begin, b.space(), out, Space::Host, sizeof(T) * n);
}

// b at n entries <- value(i) for i from `first` on, on the host's threads: the first ones stand
// (a distributed rank's owned vertices, when only its ghosts changed).
template <class T, class Value>
void write_tail_on_host(Buffer<T>& b, std::int64_t n, std::int64_t first, StagingBytes& stage,
                        Value value) {
  first == 0 ? b.resize_for_overwrite(n) : b.resize_keep(n);  // before `stage`: see write_on_host
  write_range_on_host(b, first, n, stage, value);
}

// b <- h where only entries from `first` on are copied; 3-vectors a component at a time.
template <class T>
void assign_tail_on_threads(Buffer<T>& b, const std::vector<T>& h, std::int64_t first,
                            StagingBytes& stage) {
  write_tail_on_host(b, static_cast<std::int64_t>(h.size()), first, stage,
                     [&](std::int64_t i) { return h[i]; });
}
inline void assign_tail_on_threads(Vec3Buffer& b, const std::vector<Vec3>& h, std::int64_t first,
                                   StagingBytes& stage) {
  for (int a = 0; a < 3; ++a)
    write_tail_on_host(b.component(a), static_cast<std::int64_t>(h.size()), first, stage,
                       [&](std::int64_t i) { return h[i][a]; });
}

// b <- h on the host's threads: in place for a host buffer, through `stage` (page-locked on a
// GPU rank: one copy at the link's speed) for a device. For a model's large arrays, which
// Buffer::assign copies on one thread, or from pageable memory to a device.
template <class T>
void assign_on_threads(Buffer<T>& b, const std::vector<T>& h, StagingBytes& stage) {
  assign_tail_on_threads(b, h, 0, stage);
}

}  // namespace qdemsph

namespace qdemsph {
inline void exec_sync(HostExec) {}
}  // namespace qdemsph
