#include "core/memory.hpp"

#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>

#include "core/exec_host.hpp"

namespace qdemsph {

#ifndef QDEMSPH_HAVE_CUDA
namespace {
[[noreturn]] void no_cuda() {
  throw std::runtime_error("the CUDA backend is not built into this qdemsph (rebuild with nvcc)");
}
}  // namespace
void* cuda_alloc(std::size_t) { no_cuda(); }
void cuda_free(void*) noexcept {}
void cuda_copy(void*, Space, const void*, Space, std::size_t) { no_cuda(); }
void cuda_zero(void*, std::size_t) { no_cuda(); }
void cuda_prefer_device(int) {}
void cuda_index_copy(void*, const void*, const std::int64_t*, std::int64_t, std::size_t, bool) {
  no_cuda();
}
bool cuda_available() { return false; }
void cuda_sync() {}
void cuda_copy_async(void*, const void*, std::size_t) { no_cuda(); }
void cuda_copy_wait() {}
void cuda_copy_queued(void*, const void*, std::size_t) { no_cuda(); }
SideQueue::SideQueue(bool on, const DeviceMark*) : on_(on) {
  if (on_) no_cuda();
}
SideQueue::~SideQueue() = default;
DeviceMark::~DeviceMark() = default;
void DeviceMark::record() { no_cuda(); }
void DeviceMark::wait() {}
void DeviceMark::follow() const {}
CudaIpcHandle cuda_ipc_handle(void*) { no_cuda(); }
void* cuda_ipc_open(const CudaIpcHandle&) { no_cuda(); }
void cuda_ipc_close(void*) noexcept {}
void* cuda_ipc_alloc(std::size_t) { no_cuda(); }
void cuda_ipc_free(void*) noexcept {}
void* staging_alloc(std::size_t bytes, bool* pinned) {
  *pinned = false;
  void* p = std::malloc(bytes > 0 ? bytes : 1);
  if (!p) throw std::bad_alloc();
  return p;
}
void staging_free(void* p, bool) noexcept { std::free(p); }
#else
void* cuda_alloc(std::size_t bytes);
void cuda_free(void* p) noexcept;
void cuda_copy(void* dst, Space ds, const void* src, Space ss, std::size_t bytes);
void cuda_zero(void* p, std::size_t bytes);
void cuda_index_copy(void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                     std::size_t elem, bool scatter);
#endif

namespace {
template <class T>
void host_index_copy(void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                     bool scatter) {
  T* d = static_cast<T*>(dst);
  const T* s = static_cast<const T*>(src);
  for (std::int64_t k = 0; k < n; ++k) {
    if (scatter)
      d[idx[k]] = s[k];
    else
      d[k] = s[idx[k]];
  }
}

void index_copy(Space sp, void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                std::size_t elem, bool scatter) {
  if (elem != 1 && elem != 4 && elem != 8)
    throw std::logic_error("space_gather/space_scatter: elements of 1, 4 or 8 bytes");
  if (n <= 0) return;
  if (sp == Space::Cuda) return cuda_index_copy(dst, src, idx, n, elem, scatter);
  if (elem == 1) return host_index_copy<std::uint8_t>(dst, src, idx, n, scatter);
  if (elem == 4) return host_index_copy<std::uint32_t>(dst, src, idx, n, scatter);
  host_index_copy<std::uint64_t>(dst, src, idx, n, scatter);
}
}  // namespace

void space_gather(Space s, void* dst, const void* src, const std::int64_t* idx, std::int64_t n,
                  std::size_t elem) {
  index_copy(s, dst, src, idx, n, elem, false);
}
void space_scatter(Space s, void* dst, const std::int64_t* idx, const void* src, std::int64_t n,
                   std::size_t elem) {
  index_copy(s, dst, src, idx, n, elem, true);
}

int cuda_device_for(int index, int devices) {
  if (devices <= 0) return 0;
  const int d = index % devices;
  return d < 0 ? d + devices : d;
}

void* space_alloc(Space s, std::size_t bytes) {
  if (s == Space::Cuda) return cuda_alloc(bytes);
  // 64-byte alignment for vectorised host loops.
  void* p = std::aligned_alloc(64, (bytes + 63) / 64 * 64);
  if (!p) throw std::bad_alloc();
  return p;
}

void space_free(Space s, void* p) noexcept {
  if (!p) return;
  if (s == Space::Cuda)
    cuda_free(p);
  else
    std::free(p);
}

void space_copy(void* dst, Space ds, const void* src, Space ss, std::size_t bytes) {
  if (ds == Space::Host && ss == Space::Host)
    std::memcpy(dst, src, bytes);
  else
    cuda_copy(dst, ds, src, ss, bytes);
}

void space_zero(Space s, void* p, std::size_t bytes) {
  if (s == Space::Cuda)
    cuda_zero(p, bytes);
  else
    std::memset(p, 0, bytes);
}

namespace {
// Vec3Buffer's host side of a device's components (assign, to_host), kept from one call to the
// next (its pages stay mapped: a layout rebuild's uploads do not fault them in again) and
// page-locked on a GPU rank: a component of a few MB, below the bounced copies' 4 MiB, would
// otherwise take the runtime's pageable path (8.4 GB/s against 38.7 on the H100 host,
// memory_cuda.cu).
thread_local StagingBytes vec3_stage;
}  // namespace

// Component by component, in parallel: in place on the host, through vec3_stage for a device.
void Vec3Buffer::assign(const std::vector<Vec3>& h) {
  const auto n = static_cast<std::int64_t>(h.size());
  Buffer<double>* comp[3] = {&x_, &y_, &z_};
  constexpr double Vec3::*member[3] = {&Vec3::x, &Vec3::y, &Vec3::z};
  for (int a = 0; a < 3; ++a) {
    const double Vec3::*m = member[a];
    write_on_host(*comp[a], n, vec3_stage, [&](double* out) {
      for_each(HostExec{}, n, [&](std::int64_t i) { out[i] = h[i].*m; });
    });
  }
}

// The components read in place on the host, from a device through vec3_stage; interleaved on
// the threads.
std::vector<Vec3> Vec3Buffer::to_host(std::int64_t n) const {
  if (n > size())
    throw std::out_of_range("Vec3Buffer::to_host: more entries than the buffer holds");
  const double* c[3] = {x_.cview().p, y_.cview().p, z_.cview().p};
  if (x_.space() != Space::Host) {
    const std::size_t bytes = sizeof(double) * static_cast<std::size_t>(n);
    vec3_stage.resize(3 * bytes);
    for (int a = 0; a < 3; ++a) {
      double* to = reinterpret_cast<double*>(vec3_stage.data()) + a * n;
      if (n > 0) space_copy(to, Space::Host, c[a], x_.space(), bytes);
      c[a] = to;
    }
  }
  std::vector<Vec3> h(n);
  for_each(HostExec{}, n, [&](std::int64_t i) { h[i] = {c[0][i], c[1][i], c[2][i]}; });
  return h;
}

}  // namespace qdemsph
