// The CUDA launch layer, twin of exec_host.hpp: stage code written once against
// for_each / reduce_sum / reduce_max runs here as CUDA kernels. nvcc only (.cu files).
//
//  - for_each(CudaExec, n, f): a grid-stride kernel, 256 threads a block (MinBlocks<N, T>: T),
//    at most 8192 threads per SM (4 waves of 8 resident blocks of 256), f(i) once for every i
//    in [0, n).
//    Asynchronous: the host does not wait; exec_sync() waits and reports kernel faults.
//  - reduce_sum / reduce_max: two levels in one kernel. Level 1: B = min(ceil(n / 256), 1024)
//    blocks, thread j of block b folds i = b*256 + j, + 256 B, ... in increasing order, then a
//    CUB BlockReduce (fixed tree for a fixed block size) gives one partial per block. Level 2:
//    the last block to finish folds the B partials the same way. B depends on n only, so the
//    result has the same bits on every run and on every GPU for a given n (it differs from the
//    host's OpenMP order by round-off). The result returns to the host (a synchronising copy).
//  - Work is queued on cuda_stream(): the default stream, or the side stream inside a
//    SideQueue (memory.hpp).
// Kernel launch errors and asynchronous faults become std::runtime_error naming the call.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <cub/block/block_reduce.cuh>

#include "core/hd.hpp"
#include "core/memory.hpp"

namespace qdemsph {

struct CudaExec {
  static constexpr Space space = Space::Cuda;
};

// Throws std::runtime_error "CUDA error in WHAT (file:line): cudaErrorName: description"
// (InputError for an out-of-memory allocation: the problem is too large for the GPU).
[[noreturn]] void cuda_fail(cudaError_t e, const char* what, const char* file, int line);

#define QDEMSPH_CUDA_CHECK(call, what)                                                             \
  do {                                                                                             \
    const cudaError_t qdemsph_err_ = (call);                                                       \
    if (qdemsph_err_ != cudaSuccess) ::qdemsph::cuda_fail(qdemsph_err_, what, __FILE__, __LINE__); \
  } while (0)

// memory_cuda.cu: the grid cap for for_each (32 blocks of 256 per SM of the current device), the
// stream this thread queues on, a device scratch for the reductions of that stream
// (cuda_detail::kMaxPartials partials, the result, the count of finished blocks), and a
// grow-only device scratch of at least `bytes` for CUB's temporary storage (sorts, scans; one
// user at a time: every call is ordered on the default stream).
int cuda_grid_cap();
cudaStream_t cuda_stream();
double* cuda_reduce_scratch();
void* cuda_temp_storage(std::size_t bytes);

// CUB's temporary storage bytes for a call over n items, from its size query query(m) (a
// nullptr call, which repeats the call's host-side dispatch: a contact step sorts and scans
// every step, and its host launches, not the GPU, set the pace of a slow rank). Queried for
// half as many items again as asked, and again only for more items or another `shape` (a
// sort's bits): the storage for more items serves fewer. One per call site.
class CubBytes {
 public:
  template <class Query>
  std::size_t operator()(std::int64_t n, int shape, Query query) {
    if (n > n_ || shape != shape_) {
      n_ = n + n / 2;
      shape_ = shape;
      bytes_ = query(n_);
    }
    return bytes_;
  }

 private:
  std::int64_t n_ = -1;
  int shape_ = 0;
  std::size_t bytes_ = 0;
};

namespace cuda_detail {

inline constexpr int kBlock = 256;
inline constexpr int kMaxPartials = 1024;
// MinBlocks<B, T>: blocks of T threads, B of them resident per SM asked of the register
// allocator (B = 1: no cap; T B = 768: at most 85 registers a thread; 1024: 64).
template <int B, int T, class F>
__global__ void __launch_bounds__(T, B) for_each_kernel(std::int64_t n, F f) {
  const std::int64_t stride = static_cast<std::int64_t>(blockDim.x) * gridDim.x;
  for (std::int64_t i = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n;
       i += stride)
    f(i);
}

struct SumOp {
  __device__ __forceinline__ double operator()(double acc, double v) const { return acc + v; }
};
// Same rule as the host loop (m = v > m ? v : m): a NaN value never becomes the maximum.
struct MaxOp {
  __device__ __forceinline__ double operator()(double acc, double v) const {
    return v > acc ? v : acc;
  }
};

// Both levels: each block writes its partial and counts itself done; the last one folds the
// partials (a launch fewer than a second kernel), writes the result to *out (adds it when
// `add`) and resets the count (atomicInc wraps to 0).
template <class F, class Op>
__global__ void __launch_bounds__(kBlock)
    reduce_kernel(std::int64_t n, F f, Op op, double init, double* partial, unsigned* done,
                  double* out, bool add) {
  double acc = init;
  const std::int64_t stride = static_cast<std::int64_t>(kBlock) * gridDim.x;
  for (std::int64_t i = static_cast<std::int64_t>(blockIdx.x) * kBlock + threadIdx.x; i < n;
       i += stride)
    acc = op(acc, f(i));
  using BlockReduce = cub::BlockReduce<double, kBlock>;
  __shared__ typename BlockReduce::TempStorage tmp;
  __shared__ bool last;
  const double r = BlockReduce(tmp).Reduce(acc, op);
  if (threadIdx.x == 0) {
    partial[blockIdx.x] = r;
    __threadfence();  // the partial is visible before the count says so
    last = atomicInc(done, gridDim.x - 1) == gridDim.x - 1;
  }
  __syncthreads();
  if (!last) return;
  acc = init;
  for (unsigned i = threadIdx.x; i < gridDim.x; i += kBlock) acc = op(acc, __ldcg(partial + i));
  __syncthreads();  // tmp is used again
  const double s = BlockReduce(tmp).Reduce(acc, op);
  if (threadIdx.x == 0) *out = add ? *out + s : s;
}

// Queues the reduction (n > 0); the result lands in the device slot returned: `out`, or the
// scratch's (added to *out when `add`).
template <class F, class Op>
const double* reduce_queue(std::int64_t n, F f, Op op, double init, double* out = nullptr,
                           bool add = false) {
  const std::int64_t want = (n + kBlock - 1) / kBlock;
  const int blocks = static_cast<int>(want < kMaxPartials ? want : kMaxPartials);
  double* scratch = cuda_reduce_scratch();
  if (!out) out = scratch + kMaxPartials;
  reduce_kernel<<<blocks, kBlock, 0, cuda_stream()>>>(
      n, f, op, init, scratch, reinterpret_cast<unsigned*>(scratch + kMaxPartials + 1), out, add);
  QDEMSPH_CUDA_CHECK(cudaGetLastError(), "reduce_kernel launch");
  return out;
}

template <class F, class Op>
double reduce(std::int64_t n, F f, Op op, double init) {
  if (n <= 0) return init;
  const double* r = reduce_queue(n, f, op, init);
  double h = init;
  QDEMSPH_CUDA_CHECK(cudaMemcpyAsync(&h, r, sizeof(double), cudaMemcpyDeviceToHost, cuda_stream()),
                     "reduction result copy");
  QDEMSPH_CUDA_CHECK(cudaStreamSynchronize(cuda_stream()),
                     "reduction result copy (an earlier kernel may have faulted)");
  return h;
}

}  // namespace cuda_detail

template <class F, int B = 1, int T = cuda_detail::kBlock>
void for_each(CudaExec, std::int64_t n, F f, MinBlocks<B, T> = {}) {
  static_assert(T % 32 == 0 && cuda_detail::kBlock % T == 0, "whole warps, dividing 256");
  if (n <= 0) return;
  const std::int64_t want = (n + T - 1) / T;
  const std::int64_t cap = cuda_grid_cap() * std::int64_t{cuda_detail::kBlock / T};
  const int blocks = static_cast<int>(want < cap ? want : cap);
  cuda_detail::for_each_kernel<B, T><<<blocks, T, 0, cuda_stream()>>>(n, f);
  QDEMSPH_CUDA_CHECK(cudaGetLastError(), "for_each kernel launch");
}

template <class F>
double reduce_sum(CudaExec, std::int64_t n, F f) {
  return cuda_detail::reduce(n, f, cuda_detail::SumOp{}, 0.0);
}

template <class F>
double reduce_max(CudaExec, std::int64_t n, F f, double init) {
  return cuda_detail::reduce(n, f, cuda_detail::MaxOp{}, init);
}

// *acc += the sum of f(i) over [0, n), queued (acc: device memory): an accumulator the host
// reads when it needs it, not every step.
template <class F>
void reduce_sum_into(CudaExec, std::int64_t n, F f, double* acc) {
  if (n > 0) cuda_detail::reduce_queue(n, f, cuda_detail::SumOp{}, 0.0, acc, true);
}

// reduce_max queued: the result is copied to *out (host memory; page-locked for the copy to
// be asynchronous) after the work queued before it, without waiting. A DeviceMark recorded
// next says when it is there.
template <class F>
void reduce_max_to(CudaExec, std::int64_t n, F f, double init, double* out) {
  if (n <= 0) {
    *out = init;
    return;
  }
  cuda_copy_queued(out, cuda_detail::reduce_queue(n, f, cuda_detail::MaxOp{}, init),
                   sizeof(double));
}

inline void exec_sync(CudaExec) {
  QDEMSPH_CUDA_CHECK(cudaDeviceSynchronize(), "kernel execution (exec_sync)");
}

}  // namespace qdemsph
