// The SPH stage on CUDA: the same SphStage template instantiated over CudaExec. The cell sort
// runs on the device (sort_by_key in neighbor/neighbor_cuda.cuh): no copy to the host per step.
#include "core/exec_cuda.cuh"
#include "neighbor/neighbor_cuda.cuh"
#include "sph/sph_stage.hpp"

namespace qdemsph {

std::unique_ptr<FluidStage> make_fluid_stage_cuda(const FluidSetup& setup, const SolidViews* solid,
                                                  std::unique_ptr<FluidExchange> exchange) {
  return std::make_unique<SphStage<CudaExec>>(setup, solid, std::move(exchange));
}

}  // namespace qdemsph
