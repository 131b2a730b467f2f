#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "sph/sph_stage.hpp"

namespace qdemsph {

std::unique_ptr<FluidStage> make_fluid_stage(const std::string& backend, const FluidSetup& setup) {
  if (backend == "cpu") return std::make_unique<SphStage<HostExec>>(setup);
  throw InputError("the SPH fluid stage has no '" + backend +
                   "' backend yet (sph/sph_stage.hpp needs a CudaExec instantiation)");
}

}  // namespace qdemsph
