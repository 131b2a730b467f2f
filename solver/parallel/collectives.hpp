// Variable-size gathers of trivially copyable items over a communicator (the distributed
// backend's and the fluid exchange's output, owner changes and band cells).
#pragma once

#include <cstdint>
#include <vector>

#include "parallel/comm_plan.hpp"

namespace qdemsph {

// All ranks' items (any trivially copyable type), in rank order. bytes += what this rank sent.
template <class T>
std::vector<T> allgatherv(MPI_Comm comm, const std::vector<T>& mine,
                          std::int64_t* bytes = nullptr) {
  int np = 1;
  MPI_Comm_size(comm, &np);
  int n = static_cast<int>(mine.size() * sizeof(T));
  std::vector<int> counts(np), displs(np + 1, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 0; r < np; ++r) displs[r + 1] = displs[r] + counts[r];
  std::vector<T> all(displs[np] / sizeof(T));
  MPI_Allgatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE,
                 comm);
  if (bytes) *bytes += std::int64_t(n) * (np - 1);
  return all;
}

// All ranks' items on rank 0 (empty elsewhere).
template <class T>
std::vector<T> gatherv(MPI_Comm comm, const std::vector<T>& mine) {
  int np = 1, me = 0;
  MPI_Comm_size(comm, &np);
  MPI_Comm_rank(comm, &me);
  int n = static_cast<int>(mine.size() * sizeof(T));
  std::vector<int> counts(np), displs(np + 1, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  for (int r = 0; r < np; ++r) displs[r + 1] = displs[r] + counts[r];
  std::vector<T> all(me == 0 ? displs[np] / sizeof(T) : 0);
  MPI_Gatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0,
              comm);
  return all;
}

}  // namespace qdemsph
