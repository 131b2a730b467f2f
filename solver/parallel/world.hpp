// The MPI world of the qdemsph process, without <mpi.h> (callers outside parallel/ include
// this). MPI is started only when a launcher started the process (mpirun, mpiexec, srun: seen
// in its environment: OMPI_COMM_WORLD_SIZE, PMI_SIZE, PMIX_RANK, ...) or QDEMSPH_MPI=1 is set, so a
// plain `qdemsph run` pays nothing for it.
#pragma once

namespace qdemsph {

struct World {
  int rank = 0, size = 1;
  int local_size = 1;  // ranks on this node (MPI_COMM_TYPE_SHARED)
  int local_rank = 0;  // this rank's place among them (its GPU: core/memory.hpp)
  bool mpi = false;    // MPI_Init was called
  bool root() const { return rank == 0; }
};

// MPI_Init_thread (funneled: MPI is called from the main thread only) when launched by MPI;
// the rank's GPU, should it use one, is its local rank modulo the visible GPUs.
const World& world_start(int* argc, char*** argv);
// MPI_Finalize when started.
void world_stop();
const World& world();
// True on every rank when `ok` is true on every rank (collective; `ok` itself without MPI).
bool world_all(bool ok);
// Waits for every rank (MPI_Barrier; nothing without MPI).
void world_barrier();
// Ends every rank with this exit code (MPI_Abort), for an error that only some ranks saw.
[[noreturn]] void world_abort(int code);

}  // namespace qdemsph
