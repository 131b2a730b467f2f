// The CUDA backend: the same QDEM stages as the CPU (qdem_backend.hpp) instantiated over the
// CUDA launch layer. State lives on the GPU for the whole run; download() is the only copy
// back. Selected by `--backend cuda` or the scene's run.backend: cuda. The contact stage's
// sorts and scans are the device twins in neighbor_cuda.cuh and contact_sort_cuda.cuh.
#include "contact/contact_sort_cuda.cuh"
#include "core/error.hpp"
#include "core/exec_cuda.cuh"
#include "core/gpu_info.hpp"
#include "integrate/qdem_backend.hpp"
#include "neighbor/neighbor_cuda.cuh"

namespace qdemsph {

template class QdemBackend<CudaExec>;

std::unique_ptr<Backend> make_cuda_backend() {
  const GpuInfo g = gpu_info();
  if (!g.available) throw InputError("backend 'cuda' is not available: " + g.why);
  return std::make_unique<QdemBackend<CudaExec>>("cuda");
}

}  // namespace qdemsph
