// make_distributed_backend on a given communicator (tests run several decompositions side
// by side on sub-communicators). Includes <mpi.h>; code outside parall/ and tests/mpi uses
// distributed_backend.hpp, which runs on MPI_COMM_WORLD.
#pragma once

#include "parallel/comm_plan.hpp"
#include "parallel/distributed_backend.hpp"

namespace qdemsph {

std::unique_ptr<DistributedBackend> make_distributed_backend(MPI_Comm comm,
                                                             std::unique_ptr<Backend> local,
                                                             const ParallelOptions& options);

}  // namespace qdemsph
