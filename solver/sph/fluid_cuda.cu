// The SPH stage on CUDA: the same SphStage template instantiated over CudaExec. The cell sort's
// count/scan/fill still runs on the host (keys copied back each step); a device counting sort
// is the next step for speed.
#include "core/exec_cuda.cuh"
#include "sph/sph_stage.hpp"

namespace qdemsph {

std::unique_ptr<FluidStage> make_fluid_stage_cuda(const FluidSetup& setup,
                                                  const SolidViews* solid) {
  return std::make_unique<SphStage<CudaExec>>(setup, solid);
}

}  // namespace qdemsph
