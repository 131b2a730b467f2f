/* MPI ping-pong between ranks 0 and 1 (host memory): one-way latency and bandwidth per
 * message size, for the interconnect parameters of scaling/model.py. Prints one JSON object.
 *   mpicc -O2 -o pingpong scaling/probes/pingpong.c && mpirun -np 2 ./pingpong */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2) {
    if (rank == 0) fprintf(stderr, "pingpong: needs 2 ranks\n");
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  const long sizes[] = {8, 1024, 65536, 1 << 20, 16 << 20};
  const int n_sizes = sizeof(sizes) / sizeof(sizes[0]);
  char* buf = malloc(16 << 20);
  memset(buf, 1, 16 << 20);
  if (rank == 0) printf("{\"probe\": \"mpi_pingpong_host\", \"ranks\": %d, \"runs\": [", size);
  for (int s = 0; s < n_sizes; ++s) {
    const long n = sizes[s];
    const int iters = n <= 65536 ? 2000 : (n <= (1 << 20) ? 200 : 20);
    double best = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = MPI_Wtime();
      for (int i = 0; i < iters; ++i) {
        if (rank == 0) {
          MPI_Send(buf, (int)n, MPI_CHAR, 1, 0, MPI_COMM_WORLD);
          MPI_Recv(buf, (int)n, MPI_CHAR, 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        } else if (rank == 1) {
          MPI_Recv(buf, (int)n, MPI_CHAR, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          MPI_Send(buf, (int)n, MPI_CHAR, 0, 0, MPI_COMM_WORLD);
        }
      }
      const double dt = (MPI_Wtime() - t0) / (2.0 * iters); /* one way */
      if (dt < best) best = dt;
    }
    if (rank == 0)
      printf("%s{\"bytes\": %ld, \"one_way_s\": %.4e, \"bandwidth_Bps\": %.4e}", s ? ", " : "", n, best, n / best);
  }
  if (rank == 0) printf("]}\n");
  free(buf);
  MPI_Finalize();
  return 0;
}
