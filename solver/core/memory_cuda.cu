// Device memory for Buffer<T> (memory.hpp) and the CUDA runtime services the launch layer
// needs: error reporting, the grid cap, the reduction scratch, and what the GPU offers.
// One GPU per process: the current device (cudaSetDevice by the caller, default 0).
#include <cuda_runtime.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/exec_cuda.cuh"
#include "core/exec_host.hpp"
#include "core/gpu_info.hpp"
#include "core/memory.hpp"

namespace qdemsph {

namespace {

std::string mib(std::size_t b) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f MiB", b / 1048576.0);
  return buf;
}

}  // namespace

void cuda_fail(cudaError_t e, const char* what, const char* file, int line) {
  cudaGetLastError();  // reported here: not again by the next launch's check (a sticky error stays)
  std::string msg = std::string("CUDA error in ") + what + " (" + file + ":" +
                    std::to_string(line) + "): " + cudaGetErrorName(e) + ": " +
                    cudaGetErrorString(e);
  if (e == cudaErrorMemoryAllocation) throw InputError(msg);
  throw std::runtime_error(msg);
}

bool cuda_available() {
  static const bool ok = [] {
    int n = 0;
    const cudaError_t e = cudaGetDeviceCount(&n);
    if (e != cudaSuccess) {
      cudaGetLastError();  // clear: "no device" is an answer, not a fault
      return false;
    }
    return n > 0;
  }();
  return ok;
}

namespace {
int g_prefer = 0;
bool g_device_used = false;  // this process has allocated GPU memory (staging_alloc pins)
// Sets the preferred device once, before this process's first context is made.
void use_preferred_device() {
  static const bool done = [] {
    int n = 0;
    if (cudaGetDeviceCount(&n) == cudaSuccess && n > 0)
      QDEMSPH_CUDA_CHECK(cudaSetDevice(cuda_device_for(g_prefer, n)), "cudaSetDevice");
    else
      cudaGetLastError();
    return true;
  }();
  (void)done;
}
}  // namespace

void cuda_prefer_device(int index) { g_prefer = index; }

void* staging_alloc(std::size_t bytes, bool* pinned) {
  const std::size_t n = bytes > 0 ? bytes : 1;
  *pinned = g_device_used;
  void* p = nullptr;
  if (*pinned) {
    QDEMSPH_CUDA_CHECK(cudaMallocHost(&p, n), "cudaMallocHost");
    return p;
  }
  p = std::malloc(n);
  if (!p) throw std::bad_alloc();
  return p;
}

void staging_free(void* p, bool pinned) noexcept {
  if (!p) return;
  if (pinned)
    cudaFreeHost(p);  // errors at teardown (driver already unloaded) are ignored
  else
    std::free(p);
}

namespace {

// The device's default memory pool, keeping what is freed (release threshold: all of it): a
// Buffer that grows frees and allocates on the default stream, in order with the kernels, so
// neither waits for the device, and the pool hands the freed room out again. cudaFree and
// cudaMalloc waited and mapped afresh: 4-8 ms for the ~18 contact arrays that grow with the
// contact count, a stall every rank waited for (references/benchmarks/scaling/
// 2026-11-27_x4_gather_behind_shares/).
cudaMemPool_t device_pool() {
  static const cudaMemPool_t pool = [] {
    use_preferred_device();
    int dev = 0;
    QDEMSPH_CUDA_CHECK(cudaGetDevice(&dev), "cudaGetDevice");
    cudaMemPool_t p = nullptr;
    QDEMSPH_CUDA_CHECK(cudaDeviceGetDefaultMemPool(&p, dev), "cudaDeviceGetDefaultMemPool");
    std::uint64_t keep = UINT64_MAX;
    QDEMSPH_CUDA_CHECK(cudaMemPoolSetAttribute(p, cudaMemPoolAttrReleaseThreshold, &keep),
                       "cudaMemPoolSetAttribute");
    return p;
  }();
  return pool;
}

[[noreturn]] void out_of_memory(std::size_t bytes) {
  cudaGetLastError();
  std::size_t free_b = 0, total_b = 0;
  cudaMemGetInfo(&free_b, &total_b);
  throw InputError("the problem does not fit on the GPU: allocating " + mib(bytes) +
                   " failed with " + mib(free_b) + " free of " + mib(total_b) +
                   " (use a coarser mesh or more GPUs)");
}

void need_gpu() {
  if (!cuda_available())
    throw InputError(
        "the CUDA backend needs a GPU, and this machine has none visible "
        "(check nvidia-smi and CUDA_VISIBLE_DEVICES)");
}

}  // namespace

void* cuda_alloc(std::size_t bytes) {
  need_gpu();
  device_pool();
  void* p = nullptr;
  const cudaError_t e = cudaMallocAsync(&p, bytes, cudaStreamLegacy);
  if (e == cudaErrorMemoryAllocation) out_of_memory(bytes);
  QDEMSPH_CUDA_CHECK(e, "cudaMallocAsync");
  g_device_used = true;
  return p;
}

void cuda_free(void* p) noexcept {
  if (p) cudaFreeAsync(p, cudaStreamLegacy);  // errors at teardown (driver unloaded) are ignored
}

void* cuda_ipc_alloc(std::size_t bytes) {
  need_gpu();
  use_preferred_device();
  void* p = nullptr;
  cudaError_t e = cudaMalloc(&p, bytes);
  if (e == cudaErrorMemoryAllocation) {  // the pool may hold the room: give it back, once
    cudaGetLastError();
    QDEMSPH_CUDA_CHECK(cudaDeviceSynchronize(), "cudaDeviceSynchronize");
    QDEMSPH_CUDA_CHECK(cudaMemPoolTrimTo(device_pool(), 0), "cudaMemPoolTrimTo");
    e = cudaMalloc(&p, bytes);
  }
  if (e == cudaErrorMemoryAllocation) out_of_memory(bytes);
  QDEMSPH_CUDA_CHECK(e, "cudaMalloc");
  g_device_used = true;
  return p;
}

void cuda_ipc_free(void* p) noexcept {
  if (p) cudaFree(p);  // errors at teardown (driver already unloaded) are ignored
}

namespace {

// Copies between device memory and pageable host memory of at least kBounceMin bytes (a layout
// rebuild's uploads and downloads) go through two page-locked chunks of kBounceChunk bytes: the
// host side's memcpy runs on the threads while the other chunk's DMA is in flight, on the
// default stream (ordered as cudaMemcpy is). The runtime's own pageable path ran at 8.4 GB/s on
// the H100 host against 38.7 GB/s page-locked (references/benchmarks/scaling/2026-11-25_h100x2/).
constexpr std::size_t kBounceMin = std::size_t{4} << 20, kBounceChunk = std::size_t{8} << 20;

struct Bounce {
  std::mutex busy;        // one copy at a time through the chunks
  StagingBytes chunk[2];  // page-locked: this process uses the GPU (staging_alloc)
  std::byte* buf[2] = {nullptr, nullptr};
  cudaEvent_t done[2] = {nullptr, nullptr};
  Bounce() {
    for (int i = 0; i < 2; ++i) {
      chunk[i].resize(kBounceChunk);
      buf[i] = chunk[i].data();
      QDEMSPH_CUDA_CHECK(cudaEventCreateWithFlags(&done[i], cudaEventDisableTiming),
                         "cudaEventCreate (bounce)");
    }
  }
  ~Bounce() {  // errors at teardown (driver already unloaded) are ignored
    for (int i = 0; i < 2; ++i) cudaEventDestroy(done[i]);
  }
};
Bounce& bounce() {
  static Bounce b;
  return b;
}

bool pageable(const void* host) {
  cudaPointerAttributes a{};
  if (cudaPointerGetAttributes(&a, host) != cudaSuccess) {
    cudaGetLastError();
    return true;
  }
  return a.type == cudaMemoryTypeUnregistered;
}

// dst[0, n) <- src[0, n) on the host's threads, in blocks of 256 KiB (a chunk's 32).
void host_copy(std::byte* dst, const std::byte* src, std::size_t n) {
  constexpr std::size_t kBlock = std::size_t{1} << 18;
  const auto blocks = static_cast<std::int64_t>((n + kBlock - 1) / kBlock);
  for_each_coarse(HostExec{}, blocks, [&](std::int64_t b) {
    const std::size_t o = static_cast<std::size_t>(b) * kBlock;
    std::memcpy(dst + o, src + o, std::min(kBlock, n - o));
  });
}

void upload_bounced(std::byte* dst, const std::byte* src, std::size_t bytes) {
  Bounce& b = bounce();
  const std::lock_guard<std::mutex> lock(b.busy);
  for (std::size_t o = 0, c = 0; o < bytes; o += kBounceChunk, ++c) {
    const int i = static_cast<int>(c % 2);
    const std::size_t n = std::min(kBounceChunk, bytes - o);
    QDEMSPH_CUDA_CHECK(cudaEventSynchronize(b.done[i]), "cudaEventSynchronize");  // chunk free
    host_copy(b.buf[i], src + o, n);
    QDEMSPH_CUDA_CHECK(cudaMemcpyAsync(dst + o, b.buf[i], n, cudaMemcpyHostToDevice, 0),
                       "cudaMemcpyAsync (upload)");
    QDEMSPH_CUDA_CHECK(cudaEventRecord(b.done[i], 0), "cudaEventRecord");
  }
  QDEMSPH_CUDA_CHECK(cudaStreamSynchronize(0), "cudaStreamSynchronize");
}

void download_bounced(std::byte* dst, const std::byte* src, std::size_t bytes) {
  Bounce& b = bounce();
  const std::lock_guard<std::mutex> lock(b.busy);
  const std::size_t chunks = (bytes + kBounceChunk - 1) / kBounceChunk;
  auto start = [&](std::size_t c) {  // chunk c's DMA into buffer c % 2
    const std::size_t o = c * kBounceChunk, n = std::min(kBounceChunk, bytes - o);
    QDEMSPH_CUDA_CHECK(cudaMemcpyAsync(b.buf[c % 2], src + o, n, cudaMemcpyDeviceToHost, 0),
                       "cudaMemcpyAsync (download)");
    QDEMSPH_CUDA_CHECK(cudaEventRecord(b.done[c % 2], 0), "cudaEventRecord");
  };
  start(0);
  for (std::size_t c = 0; c < chunks; ++c) {
    if (c + 1 < chunks) start(c + 1);  // its buffer's last chunk was copied out below
    QDEMSPH_CUDA_CHECK(cudaEventSynchronize(b.done[c % 2]), "cudaEventSynchronize");
    const std::size_t o = c * kBounceChunk;
    host_copy(dst + o, b.buf[c % 2], std::min(kBounceChunk, bytes - o));
  }
}

}  // namespace

void cuda_copy(void* dst, Space ds, const void* src, Space ss, std::size_t bytes) {
  if (bytes >= kBounceMin && ds != ss) {
    if (ss == Space::Host && pageable(src))
      return upload_bounced(static_cast<std::byte*>(dst), static_cast<const std::byte*>(src),
                            bytes);
    if (ds == Space::Host && pageable(dst))
      return download_bounced(static_cast<std::byte*>(dst), static_cast<const std::byte*>(src),
                              bytes);
  }
  // Unified addressing: the runtime infers the direction from the pointers.
  QDEMSPH_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDefault), "cudaMemcpy");
}

void cuda_sync() { QDEMSPH_CUDA_CHECK(cudaDeviceSynchronize(), "cudaDeviceSynchronize"); }

namespace {
// A stream that does not wait for the default stream's work (the copy stream, the side stream);
// `urgent`: at the device's greatest priority, whose kernels' blocks the GPU starts before the
// default stream's waiting ones.
cudaStream_t non_blocking_stream(bool urgent = false) {
  use_preferred_device();
  int least = 0, greatest = 0;
  if (urgent)
    QDEMSPH_CUDA_CHECK(cudaDeviceGetStreamPriorityRange(&least, &greatest),
                       "cudaDeviceGetStreamPriorityRange");
  cudaStream_t t = nullptr;
  QDEMSPH_CUDA_CHECK(cudaStreamCreateWithPriority(&t, cudaStreamNonBlocking, greatest),
                     "cudaStreamCreateWithPriority");
  return t;
}
cudaStream_t copy_stream() {
  static const cudaStream_t s = non_blocking_stream();
  return s;
}
}  // namespace

void cuda_copy_async(void* dst, const void* src, std::size_t bytes) {
  QDEMSPH_CUDA_CHECK(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDefault, copy_stream()),
                     "cudaMemcpyAsync");
}

void cuda_copy_wait() {
  QDEMSPH_CUDA_CHECK(cudaStreamSynchronize(copy_stream()), "cudaStreamSynchronize");
}

void cuda_copy_queued(void* dst, const void* src, std::size_t bytes) {
  QDEMSPH_CUDA_CHECK(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDefault, cuda_stream()),
                     "cudaMemcpyAsync (queued)");
}

namespace {
thread_local cudaStream_t queue_stream = 0;
cudaStream_t side_stream() {
  static const cudaStream_t s = non_blocking_stream(true);
  return s;
}
}  // namespace

cudaStream_t cuda_stream() { return queue_stream; }

SideQueue::SideQueue(bool on, const DeviceMark* from) : on_(on) {
  if (!on_) return;
  if (queue_stream != 0) throw std::logic_error("SideQueue inside a SideQueue");
  static const cudaEvent_t now = [] {
    use_preferred_device();
    cudaEvent_t t = nullptr;
    QDEMSPH_CUDA_CHECK(cudaEventCreateWithFlags(&t, cudaEventDisableTiming), "cudaEventCreate");
    return t;
  }();
  cudaEvent_t fork = from ? static_cast<cudaEvent_t>(from->event_) : nullptr;
  if (!fork) {
    fork = now;
    QDEMSPH_CUDA_CHECK(cudaEventRecord(fork, 0), "cudaEventRecord (side queue)");
  }
  QDEMSPH_CUDA_CHECK(cudaStreamWaitEvent(side_stream(), fork, 0), "cudaStreamWaitEvent (side)");
  queue_stream = side_stream();
}

SideQueue::~SideQueue() {
  if (on_) queue_stream = 0;
}

DeviceMark::~DeviceMark() {
  if (event_) cudaEventDestroy(static_cast<cudaEvent_t>(event_));
}

void DeviceMark::record() {
  if (!event_) {
    use_preferred_device();
    cudaEvent_t e = nullptr;
    QDEMSPH_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming), "cudaEventCreate");
    event_ = e;
  }
  QDEMSPH_CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(event_), cuda_stream()),
                     "cudaEventRecord");
  pending_ = true;
}

void DeviceMark::follow() const {
  if (!pending_) return;
  QDEMSPH_CUDA_CHECK(cudaStreamWaitEvent(cuda_stream(), static_cast<cudaEvent_t>(event_), 0),
                     "cudaStreamWaitEvent (follow)");
}

void DeviceMark::wait() {
  if (!pending_) return;
  pending_ = false;
  QDEMSPH_CUDA_CHECK(cudaEventSynchronize(static_cast<cudaEvent_t>(event_)),
                     "cudaEventSynchronize (an earlier kernel may have faulted)");
}

static_assert(sizeof(cudaIpcMemHandle_t) == sizeof(CudaIpcHandle));

CudaIpcHandle cuda_ipc_handle(void* p) {
  cudaIpcMemHandle_t h;
  QDEMSPH_CUDA_CHECK(cudaIpcGetMemHandle(&h, p), "cudaIpcGetMemHandle");
  CudaIpcHandle out;
  std::memcpy(out.bytes, &h, sizeof h);
  return out;
}

void* cuda_ipc_open(const CudaIpcHandle& h) {
  cudaIpcMemHandle_t c;
  std::memcpy(&c, h.bytes, sizeof c);
  void* p = nullptr;
  QDEMSPH_CUDA_CHECK(cudaIpcOpenMemHandle(&p, c, cudaIpcMemLazyEnablePeerAccess),
                     "cudaIpcOpenMemHandle");
  return p;
}

void cuda_ipc_close(void* p) noexcept {
  if (p) cudaIpcCloseMemHandle(p);  // errors at teardown are ignored
}

void cuda_zero(void* p, std::size_t bytes) {
  QDEMSPH_CUDA_CHECK(cudaMemsetAsync(p, 0, bytes, cuda_stream()), "cudaMemsetAsync");
}

template <class T>
void cuda_index_copy_t(void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                       bool scatter) {
  T* d = static_cast<T*>(dst);
  const T* s = static_cast<const T*>(src);
  if (scatter)
    for_each(
        CudaExec{}, n, QDEMSPH_LAMBDA(std::int64_t k) { d[idx[k]] = s[k]; });
  else
    for_each(
        CudaExec{}, n, QDEMSPH_LAMBDA(std::int64_t k) { d[k] = s[idx[k]]; });
}

void cuda_index_copy(void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                     std::size_t elem, bool scatter) {
  if (elem == 1)
    cuda_index_copy_t<unsigned char>(dst, src, idx, n, scatter);
  else if (elem == 4)
    cuda_index_copy_t<unsigned int>(dst, src, idx, n, scatter);
  else
    cuda_index_copy_t<unsigned long long>(dst, src, idx, n, scatter);
}

int cuda_grid_cap() {
  static const int cap = [] {
    int dev = 0, sms = 0;
    QDEMSPH_CUDA_CHECK(cudaGetDevice(&dev), "cudaGetDevice");
    QDEMSPH_CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev),
                       "cudaDeviceGetAttribute");
    return 32 * (sms > 0 ? sms : 1);
  }();
  return cap;
}

namespace {
struct ReduceScratch {
  double* p = nullptr;
  ~ReduceScratch() { cuda_free(p); }
};
struct TempStorage {
  void* p = nullptr;
  std::size_t bytes = 0;
  ~TempStorage() { cuda_free(p); }
};
}  // namespace

void* cuda_temp_storage(std::size_t bytes) {
  static TempStorage s;
  if (bytes > s.bytes) {
    cuda_free(s.p);  // in stream order: kernels queued before still have the old storage
    s.p = nullptr;
    s.bytes = 0;
    const std::size_t want = bytes + bytes / 2 + 4096;
    s.p = cuda_alloc(want);
    s.bytes = want;
  }
  return s.p;
}

// One scratch a stream (default, side): kMaxPartials partials, the result, the count of finished
// blocks (zero between reductions: the last block resets it).
double* cuda_reduce_scratch() {
  static ReduceScratch s[2];
  ReduceScratch& r = s[cuda_stream() == 0 ? 0 : 1];
  if (!r.p) {
    const std::size_t bytes = sizeof(double) * (cuda_detail::kMaxPartials + 2);
    r.p = static_cast<double*>(cuda_alloc(bytes));
    QDEMSPH_CUDA_CHECK(cudaMemset(r.p, 0, bytes), "cudaMemset (reduction scratch)");
  }
  return r.p;
}

GpuInfo gpu_info() {
  GpuInfo g;
  cudaRuntimeGetVersion(&g.runtime_version);
  cudaDriverGetVersion(&g.driver_version);
  const cudaError_t e = cudaGetDeviceCount(&g.device_count);
  if (e != cudaSuccess || g.device_count == 0) {
    cudaGetLastError();
    g.why = e != cudaSuccess ? std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e)
                             : "no CUDA device visible";
    return g;
  }
  use_preferred_device();
  cudaDeviceProp p{};
  if (cudaGetDevice(&g.device) != cudaSuccess ||
      cudaGetDeviceProperties(&p, g.device) != cudaSuccess ||
      cudaMemGetInfo(&g.free_bytes, &g.total_bytes) != cudaSuccess) {
    g.why = std::string("CUDA runtime error: ") + cudaGetErrorString(cudaGetLastError());
    return g;
  }
  g.available = true;
  g.name = p.name;
  g.sm_count = p.multiProcessorCount;
  g.cc_major = p.major;
  g.cc_minor = p.minor;
  return g;
}

double gpu_copy_bandwidth(std::size_t bytes, int reps) {
  if (!cuda_available()) return 0.0;
  void* a = cuda_alloc(bytes);
  void* b = cuda_alloc(bytes);
  cudaEvent_t e0, e1;
  QDEMSPH_CUDA_CHECK(cudaEventCreate(&e0), "cudaEventCreate");
  QDEMSPH_CUDA_CHECK(cudaEventCreate(&e1), "cudaEventCreate");
  QDEMSPH_CUDA_CHECK(cudaMemset(a, 1, bytes), "cudaMemset");
  QDEMSPH_CUDA_CHECK(cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice), "cudaMemcpy (warm-up)");
  float best_ms = 0;
  for (int r = 0; r < reps; ++r) {
    QDEMSPH_CUDA_CHECK(cudaEventRecord(e0), "cudaEventRecord");
    QDEMSPH_CUDA_CHECK(cudaMemcpy(r % 2 ? a : b, r % 2 ? b : a, bytes, cudaMemcpyDeviceToDevice),
                       "cudaMemcpy (device to device)");
    QDEMSPH_CUDA_CHECK(cudaEventRecord(e1), "cudaEventRecord");
    QDEMSPH_CUDA_CHECK(cudaEventSynchronize(e1), "cudaEventSynchronize");
    float ms = 0;
    QDEMSPH_CUDA_CHECK(cudaEventElapsedTime(&ms, e0, e1), "cudaEventElapsedTime");
    if (r == 0 || ms < best_ms) best_ms = ms;
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  cuda_free(a);
  cuda_free(b);
  return best_ms > 0 ? 2.0 * bytes / (best_ms * 1e-3) : 0.0;
}

}  // namespace qdemsph
