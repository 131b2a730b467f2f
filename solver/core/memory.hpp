// Device-neutral memory: Buffer<T> owns an array in a memory space (host or CUDA device);
// View<T> is the trivially copyable handle that kernels receive. Access intent is explicit:
// View<const T> for read-only inputs, View<T> for outputs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/hd.hpp"
#include "core/vec.hpp"

namespace qdemsph {

enum class Space { Host, Cuda };

// Implemented in memory.cpp (host) and memory_cuda.cu (device; a clear error without CUDA).
void* space_alloc(Space s, std::size_t bytes);
void space_free(Space s, void* p) noexcept;
void space_copy(void* dst, Space dst_space, const void* src, Space src_space, std::size_t bytes);
void space_zero(Space s, void* p, std::size_t bytes);
// Indexed copies within one space (all pointers in it): gather dst[k] = src[idx[k]] and
// scatter dst[idx[k]] = src[k], k < n, for elements of `elem` bytes (1, 4 or 8).
void space_gather(Space s, void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                  std::size_t elem);
void space_scatter(Space s, void* dst, const std::int64_t* idx, const void* src, std::int64_t n,
                   std::size_t elem);
bool cuda_available();
// The GPU of this process: device `index` modulo the visible devices, chosen at the process's
// first use of a GPU (allocation or gpu_info); default 0. An MPI rank passes its rank on the
// node (parallel/world.cpp), so the ranks of a node spread over its GPUs.
void cuda_prefer_device(int index);
int cuda_device_for(int index, int devices);  // index mod devices (0 without devices)
// Waits for this process's device work (cudaDeviceSynchronize; nothing without CUDA).
void cuda_sync();
// Device-to-device copies (from another GPU of the node too) on this process's copy stream,
// which does not wait for the kernels (they run in order on the default stream): a halo's
// peer copies overlap the interior work. cuda_copy_wait returns when those copies are done.
void cuda_copy_async(void* dst, const void* src, std::size_t bytes);
void cuda_copy_wait();
// A copy between page-locked host memory and this process's device memory (either way), queued
// on the default stream (the side stream in a SideQueue): after the kernels queued so far,
// before those queued later. It returns at once; the bytes are there once a DeviceMark recorded
// after it has been waited for.
void cuda_copy_queued(void* dst, const void* src, std::size_t bytes);
// A point in this process's default-stream work (a CUDA event; the side stream's in a
// SideQueue): record() after the work queued so far, wait() returns once that work is done
// while work queued later runs on; follow() makes the work queued from now on wait for that
// work on the device (the host does not wait: a side stream's result joins the default
// stream). wait() and follow() before any record() do nothing. Only for device work: record()
// makes the process's GPU context.
class DeviceMark {
 public:
  DeviceMark() = default;
  ~DeviceMark();
  DeviceMark(const DeviceMark&) = delete;
  DeviceMark& operator=(const DeviceMark&) = delete;
  void record();
  void wait();
  void follow() const;

 private:
  friend class SideQueue;
  void* event_ = nullptr;
  bool pending_ = false;
};
// Device work beside the default stream's: while a SideQueue lives, this thread's for_each
// kernels, reductions, cuda_copy_queued, cuda_zero (Buffer::zero) and DeviceMark::record go to
// this process's side stream (CUDA sorts and scans do not: they share one scratch), which
// starts after the default stream's work queued before the scope, or, given `from`, the work
// queued before that mark was recorded (kernels queued since run beside). The default stream does
// not wait for the side's work: a DeviceMark recorded inside says when it is done. The side stream
// has the GPU's greatest priority: its blocks start before the default stream's waiting ones.
// For short work that the step's next kernels do not read and other ranks wait for (a halo's
// packing, the contact shares' compaction), off the default stream's path, and for a pass
// split in two launches that should not drain one after the other (the SPH passes over
// particles near ghosts, beside those over the others). `on` false, or no CUDA: nothing
// changes. Not nested.
class SideQueue {
 public:
  explicit SideQueue(bool on, const DeviceMark* from = nullptr);
  ~SideQueue();
  SideQueue(const SideQueue&) = delete;
  SideQueue& operator=(const SideQueue&) = delete;

 private:
  bool on_;
};
// CUDA IPC between processes of one node: the handle of this process's IpcDeviceBytes, and
// another process's mapped into this one by its handle (a device pointer here; peer copies
// from it go over NVLink where there is one).
struct CudaIpcHandle {
  unsigned char bytes[64];
};
CudaIpcHandle cuda_ipc_handle(void* p);
void* cuda_ipc_open(const CudaIpcHandle& h);
void cuda_ipc_close(void* p) noexcept;
// Device memory an IPC handle can name: a plain cudaMalloc allocation (Buffer's device memory
// comes from the stream-ordered pool, which cudaIpcGetMemHandle does not accept). Freeing it
// waits for the device.
void* cuda_ipc_alloc(std::size_t bytes);
void cuda_ipc_free(void* p) noexcept;
// Host memory for staging (StagingBytes): page-locked once this process has allocated GPU
// memory, plain heap memory before (a CPU run never makes a GPU context); *pinned says which.
void* staging_alloc(std::size_t bytes, bool* pinned);
void staging_free(void* p, bool pinned) noexcept;

template <class T>
struct View {
  T* p = nullptr;
  std::int64_t n = 0;
  QDEMSPH_HD T& operator[](std::int64_t i) const { return p[i]; }
  QDEMSPH_HD std::int64_t size() const { return n; }
};

// While one lives on a thread, a Buffer's first allocation there takes the 1/8 room of a later
// one too: for the arrays of a model uploaded again and again at a few per cent other sizes
// (a distributed rank's part, rebuilt at every layout, whose band widens as rebuilds get
// dear), so that the first layout larger than the set-up's reuses them as well (on the host no
// fresh pages to fault in, on a GPU no cudaFree and cudaMalloc; GPU-size dominoes on the CPU
// backend, one thread: that layout's upload 56-72 ms against 23-29 ms for the next, before).
// Other buffers stay exact.
class BufferRoom {
 public:
  BufferRoom() : was_(on_) { on_ = true; }
  ~BufferRoom() { on_ = was_; }
  BufferRoom(const BufferRoom&) = delete;
  BufferRoom& operator=(const BufferRoom&) = delete;
  static bool on() { return on_; }

 private:
  bool was_;
  static inline thread_local bool on_ = false;
};

// The allocation grows only: a resize or assign to a size within the capacity keeps it (no
// free and allocate), so rebuilding a model of about the same size reuses its memory, and
// view() keeps its pointer until a size beyond the capacity. Device memory comes from the
// device's stream-ordered pool (memory_cuda.cu): a reallocation neither waits for the device nor
// maps fresh pages where earlier frees left room. A buffer outgrowing an earlier allocation takes
// 1/8 more room, so a size creeping up reallocates rarely (its first allocation too under a
// BufferRoom). Only the destructor (or moving another buffer in) frees.
template <class T>
class Buffer {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  explicit Buffer(Space s = Space::Host) : space_(s) {}
  Buffer(Space s, std::int64_t n) : space_(s) { resize(n); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& o) noexcept { swap(o); }
  Buffer& operator=(Buffer&& o) noexcept {
    swap(o);
    return *this;
  }
  ~Buffer() { space_free(space_, p_); }

  void swap(Buffer& o) noexcept {
    std::swap(space_, o.space_);
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    std::swap(cap_, o.cap_);
  }
  // Discards the contents; the n elements are zero-filled.
  void resize(std::int64_t n) {
    resize_for_overwrite(n);
    zero();
  }
  // Size n, contents unspecified (earlier values or fresh memory): for a caller that writes
  // every element next.
  void resize_for_overwrite(std::int64_t n) {
    if (n > cap_) {
      const std::int64_t want = cap_ > 0 || BufferRoom::on() ? n + n / 8 : n;
      space_free(space_, p_);
      p_ = nullptr, n_ = 0, cap_ = 0;  // consistent should the allocation throw
      p_ = static_cast<T*>(space_alloc(space_, sizeof(T) * want));
      cap_ = want;
    }
    n_ = n;
  }
  // Size n, the first min(n, size()) entries kept (copied into the new allocation when n
  // outgrows the capacity).
  void resize_keep(std::int64_t n) {
    if (n > cap_) {
      Buffer grown(space_);
      grown.resize_for_overwrite(n);
      if (n_ > 0) space_copy(grown.p_, space_, p_, space_, sizeof(T) * n_);
      swap(grown);
    }
    n_ = n;
  }
  void assign(const T* host, std::int64_t n) {
    resize_for_overwrite(n);
    if (n_ > 0) space_copy(p_, space_, host, Space::Host, sizeof(T) * n_);
  }
  void assign(const std::vector<T>& host) {
    assign(host.data(), static_cast<std::int64_t>(host.size()));
  }
  std::vector<T> to_host() const { return to_host(n_); }
  // The first n entries (n <= size()).
  std::vector<T> to_host(std::int64_t n) const {
    if (n > n_) throw std::out_of_range("Buffer::to_host: more entries than the buffer holds");
    std::vector<T> h(n);
    if (n > 0) space_copy(h.data(), Space::Host, p_, space_, sizeof(T) * n);
    return h;
  }
  void zero() { zero_from(0); }
  void zero_from(std::int64_t first) {
    if (n_ > first) space_zero(space_, p_ + first, sizeof(T) * (n_ - first));
  }
  View<T> view() { return {p_, n_}; }
  View<const T> view() const { return {p_, n_}; }
  View<const T> cview() const { return {p_, n_}; }
  std::int64_t size() const { return n_; }
  std::int64_t capacity() const { return cap_; }
  Space space() const { return space_; }
  std::size_t bytes() const { return sizeof(T) * cap_; }  // the allocation's

 private:
  Space space_ = Space::Host;
  T* p_ = nullptr;
  std::int64_t n_ = 0, cap_ = 0;
};

// A field of 3-vectors stored as three component arrays (SoA) so that consecutive threads
// read consecutive doubles.
template <class D>
struct Vec3ViewT {
  D* x = nullptr;
  D* y = nullptr;
  D* z = nullptr;
  std::int64_t n = 0;
  QDEMSPH_HD Vec3 operator[](std::int64_t i) const { return {x[i], y[i], z[i]}; }
  QDEMSPH_HD void set(std::int64_t i, Vec3 v) const {
    x[i] = v.x;
    y[i] = v.y;
    z[i] = v.z;
  }
  QDEMSPH_HD std::int64_t size() const { return n; }
};
using Vec3View = Vec3ViewT<double>;
using Vec3CView = Vec3ViewT<const double>;
static_assert(std::is_trivially_copyable_v<Vec3View>);
static_assert(std::is_trivially_copyable_v<View<double>>);

class Vec3Buffer {
 public:
  explicit Vec3Buffer(Space s = Space::Host) : x_(s), y_(s), z_(s) {}
  void resize(std::int64_t n) {
    x_.resize(n);
    y_.resize(n);
    z_.resize(n);
  }
  void resize_for_overwrite(std::int64_t n) {
    x_.resize_for_overwrite(n);
    y_.resize_for_overwrite(n);
    z_.resize_for_overwrite(n);
  }
  void resize_keep(std::int64_t n) {
    x_.resize_keep(n);
    y_.resize_keep(n);
    z_.resize_keep(n);
  }
  void assign(const std::vector<Vec3>& h);
  std::vector<Vec3> to_host() const { return to_host(size()); }
  std::vector<Vec3> to_host(std::int64_t n) const;  // the first n (n <= size())
  Buffer<double>& component(int a) { return a == 0 ? x_ : (a == 1 ? y_ : z_); }
  void zero() {
    x_.zero();
    y_.zero();
    z_.zero();
  }
  Vec3View view() { return {x_.view().p, y_.view().p, z_.view().p, x_.size()}; }
  Vec3CView cview() const { return {x_.cview().p, y_.cview().p, z_.cview().p, x_.size()}; }
  std::int64_t size() const { return x_.size(); }
  std::size_t bytes() const { return 3 * x_.bytes(); }

 private:
  Buffer<double> x_, y_, z_;
};

// A host work array of n elements that the caller rewrites (a layout rebuild's, kept from one
// rebuild to the next): within its capacity the allocation stands; outgrowing it, nothing is
// copied and 1/8 more room is taken, so that a size creeping up reallocates (copies, and
// faults fresh pages in) rarely.
template <class T>
void resize_for_overwrite(std::vector<T>& v, std::size_t n) {
  if (n > v.capacity()) {
    v.clear();
    v.reserve(n + n / 8);
  }
  v.resize(n);
}

// Host bytes copied to or from a device at every step: a GPU rank's packed halo records, which
// MPI sends from and receives into (parallel/comm_plan.hpp). Page-locked when this process uses
// a GPU, so those copies run at the link's speed (H100 host, 1 MB: 38.7 GB/s pinned against
// 8.4 GB/s pageable; references/benchmarks/scaling/2026-11-25_h100x2/); plain memory otherwise.
// Storage grows only, with 1/8 room (a layout rebuild's arrays grow a little); resize() keeps no
// contents.
class StagingBytes {
 public:
  StagingBytes() = default;
  ~StagingBytes() { staging_free(p_, pinned_); }
  StagingBytes(const StagingBytes&) = delete;
  StagingBytes& operator=(const StagingBytes&) = delete;
  void resize(std::size_t n) {
    if (n > cap_) {
      const std::size_t want = n + n / 8;  // page-locking again is slow: room from the first
      staging_free(p_, pinned_);
      p_ = nullptr, cap_ = 0;  // consistent should the allocation throw
      p_ = static_cast<std::byte*>(staging_alloc(want, &pinned_));
      cap_ = want;
    }
    size_ = n;
  }
  std::byte* data() { return p_; }
  const std::byte* data() const { return p_; }
  std::size_t size() const { return size_; }
  std::byte& operator[](std::size_t i) { return p_[i]; }
  bool pinned() const { return pinned_; }

 private:
  std::byte* p_ = nullptr;
  std::size_t size_ = 0, cap_ = 0;
  bool pinned_ = false;
};

// Grow-only device bytes that other processes of the node map by cuda_ipc_handle (a halo's
// send buffer, CommEngine); contents are not kept across a growth.
class IpcDeviceBytes {
 public:
  IpcDeviceBytes() = default;
  ~IpcDeviceBytes() { cuda_ipc_free(p_); }
  IpcDeviceBytes(const IpcDeviceBytes&) = delete;
  IpcDeviceBytes& operator=(const IpcDeviceBytes&) = delete;
  // Room for 1/8 more from the first allocation: a growth makes every process that maps the
  // bytes close and open them again (CommEngine), and a halo's next layout often holds a few
  // more records.
  void reserve(std::size_t n) {
    if (n <= cap_) return;
    const std::size_t want = n + n / 8;
    release();
    p_ = static_cast<std::byte*>(cuda_ipc_alloc(want));
    cap_ = want;
  }
  void release() noexcept {
    cuda_ipc_free(p_);
    p_ = nullptr, cap_ = 0;
  }
  std::byte* data() const { return p_; }
  std::size_t capacity() const { return cap_; }

 private:
  std::byte* p_ = nullptr;
  std::size_t cap_ = 0;
};

// A buffer's n elements computed on the host (a model's upload): write(out) stores them into
// out[0, n), typically in a for_each(HostExec{}, ...). A host buffer is written in place, a
// device one through `stage`, which the caller keeps: the next upload reuses its pages, and on a
// GPU rank they are page-locked (the copy runs at the link's speed).
template <class T, class Write>
void write_on_host(Buffer<T>& b, std::int64_t n, StagingBytes& stage, Write write) {
  b.resize_for_overwrite(n);  // first: staging allocated after a device allocation is pinned
  if (b.space() == Space::Host) {
    write(b.view().p);
    return;
  }
  stage.resize(sizeof(T) * n);
  T* out = reinterpret_cast<T*>(stage.data());
  write(out);
  b.assign(out, n);
}
// The same for 3-vectors, a component at a time: write(out, a) stores component a.
template <class Write>
void write_on_host(Vec3Buffer& b, std::int64_t n, StagingBytes& stage, Write write) {
  for (int a = 0; a < 3; ++a)
    write_on_host(b.component(a), n, stage, [&](double* out) { write(out, a); });
}

}  // namespace qdemsph
