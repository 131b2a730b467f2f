#include "parallel/world.hpp"

#include <cstdlib>
#include <cstring>

#include "core/memory.hpp"
#include "parallel/comm_plan.hpp"  // <mpi.h>

namespace qdemsph {

namespace {
World g_world;

bool launched_by_mpi() {
  for (const char* v :
       {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS", "MV2_COMM_WORLD_SIZE"})
    if (std::getenv(v)) return true;
  const char* force = std::getenv("QDEMSPH_MPI");
  return force && std::strcmp(force, "1") == 0;
}
}  // namespace

const World& world_start(int* argc, char*** argv) {
  if (g_world.mpi || !launched_by_mpi()) return g_world;
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  g_world.mpi = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_world.size);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, g_world.rank, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &g_world.local_size);
  MPI_Comm_rank(node, &g_world.local_rank);
  MPI_Comm_free(&node);
  cuda_prefer_device(g_world.local_rank);
  return g_world;
}

void world_stop() {
  if (!g_world.mpi) return;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

const World& world() { return g_world; }

bool world_all(bool ok) {
  if (!g_world.mpi) return ok;
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return all != 0;
}

void world_barrier() {
  if (g_world.mpi) MPI_Barrier(MPI_COMM_WORLD);
}

void world_abort(int code) {
  if (g_world.mpi) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

}  // namespace qdemsph
