#include "core/memory.hpp"

#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>

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
bool cuda_available() { return false; }
#else
void* cuda_alloc(std::size_t bytes);
void cuda_free(void* p) noexcept;
void cuda_copy(void* dst, Space ds, const void* src, Space ss, std::size_t bytes);
void cuda_zero(void* p, std::size_t bytes);
#endif

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

void Vec3Buffer::assign(const std::vector<Vec3>& h) {
  std::vector<double> c(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) c[i] = h[i].x;
  x_.assign(c);
  for (std::size_t i = 0; i < h.size(); ++i) c[i] = h[i].y;
  y_.assign(c);
  for (std::size_t i = 0; i < h.size(); ++i) c[i] = h[i].z;
  z_.assign(c);
}

std::vector<Vec3> Vec3Buffer::to_host() const {
  auto x = x_.to_host(), y = y_.to_host(), z = z_.to_host();
  std::vector<Vec3> h(x.size());
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = {x[i], y[i], z[i]};
  return h;
}

}  // namespace qdemsph
