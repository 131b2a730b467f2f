#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "sph/sph_stage.hpp"

namespace qdemsph {

#ifdef QDEMSPH_HAVE_CUDA
std::unique_ptr<FluidStage> make_fluid_stage_cuda(
    const FluidSetup& setup, const SolidViews* solid,
    std::unique_ptr<FluidExchange> exchange);  // fluid_cuda.cu
#endif

std::unique_ptr<FluidStage> make_fluid_stage(const std::string& backend, const FluidSetup& setup,
                                             const SolidViews* solid,
                                             std::unique_ptr<FluidExchange> exchange) {
  if (backend == "cpu")
    return std::make_unique<SphStage<HostExec>>(setup, solid, std::move(exchange));
#ifdef QDEMSPH_HAVE_CUDA
  if (backend == "cuda") return make_fluid_stage_cuda(setup, solid, std::move(exchange));
#endif
  throw InputError("the SPH fluid stage has no '" + backend + "' backend in this build");
}

}  // namespace qdemsph
