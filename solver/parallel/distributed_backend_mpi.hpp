// make_distributed_backend and make_fluid_exchange on a given communicator (tests run several
// decompositions side by side on sub-communicators). Includes <mpi.h>; code outside parallel/
// and tests/mpi uses distributed_backend.hpp and fluid_exchange.hpp, which run on
// MPI_COMM_WORLD.
#pragma once

#include "parallel/comm_plan.hpp"
#include "parallel/distributed_backend.hpp"
#include "parallel/fluid_exchange.hpp"

namespace qdemsph {

std::unique_ptr<DistributedBackend> make_distributed_backend(MPI_Comm comm,
                                                             std::unique_ptr<Backend> local,
                                                             const ParallelOptions& options);
std::unique_ptr<FluidExchange> make_fluid_exchange(MPI_Comm comm, const ParallelOptions& options,
                                                   const FluidSetup& fluid,
                                                   Space space = Space::Host);

}  // namespace qdemsph
