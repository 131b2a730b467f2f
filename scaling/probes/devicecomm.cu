// Two ranks on two GPUs of one host, one rank per GPU: what a halo whose records stay in device
// memory would cost, for the GPU-resident halo of scaling/model.py. Prints one JSON object.
//  - "mpi_cuda_aware": whether the MPI library reports CUDA support (MPIX_Query_cuda_support),
//    and, when it does, a ping-pong of device buffers (one-way time per message size);
//  - "ipc": rank 1's device buffer mapped into rank 0 (cudaIpcGetMemHandle / OpenMemHandle), a
//    copy of n bytes from it into rank 0's device buffer and a stream synchronisation (the
//    peer copy over NVLink that a CUDA-aware MPI makes of a device message on one host), and
//    the same copy bracketed by two host messages (ready, done: the hand-shake a halo needs).
//   nvcc -O2 $(mpicc --showme:compile) -o devicecomm scaling/probes/devicecomm.cu \
//     $(mpicc --showme:link) && mpirun -np 2 ./devicecomm
#include <cuda_runtime.h>
#include <mpi.h>
#if __has_include(<mpi-ext.h>)
#include <mpi-ext.h>
#endif

#include <cstdio>

namespace {

constexpr size_t kSizes[] = {8, 65536, 1 << 20, 16 << 20};
constexpr size_t kMax = 16 << 20;

int iters_for(size_t n) { return n <= 65536 ? 1000 : (n <= (1u << 20) ? 200 : 20); }

bool cuda_aware() {
#if defined(MPIX_CUDA_AWARE_SUPPORT) && MPIX_CUDA_AWARE_SUPPORT
  return MPIX_Query_cuda_support() == 1;
#else
  return false;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1, ngpu = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size != 2 || cudaGetDeviceCount(&ngpu) != cudaSuccess || ngpu < 2) {
    if (rank == 0)
      std::printf("{\"probe\": \"device_comm\", \"error\": \"needs 2 ranks and 2 GPUs\"}\n");
    MPI_Finalize();
    return 0;
  }
  cudaSetDevice(rank);
  char* buf = nullptr;
  char* dst = nullptr;
  cudaMalloc(&buf, kMax);
  cudaMalloc(&dst, kMax);
  cudaMemset(buf, rank + 1, kMax);
  cudaDeviceSynchronize();
  const bool aware = cuda_aware();
  if (rank == 0)
    std::printf("{\"probe\": \"device_comm\", \"mpi_cuda_aware\": %s", aware ? "true" : "false");
  if (aware) {
    if (rank == 0) std::printf(", \"mpi_device_pingpong\": [");
    for (size_t s = 0; s < sizeof kSizes / sizeof kSizes[0]; ++s) {
      const size_t n = kSizes[s];
      const int it = iters_for(n);
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = MPI_Wtime();
      for (int i = 0; i < it; ++i) {
        if (rank == 0) {
          MPI_Send(buf, static_cast<int>(n), MPI_BYTE, 1, 1, MPI_COMM_WORLD);
          MPI_Recv(buf, static_cast<int>(n), MPI_BYTE, 1, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        } else {
          MPI_Recv(buf, static_cast<int>(n), MPI_BYTE, 0, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          MPI_Send(buf, static_cast<int>(n), MPI_BYTE, 0, 1, MPI_COMM_WORLD);
        }
      }
      const double one_way = (MPI_Wtime() - t0) / (2.0 * it);
      if (rank == 0)
        std::printf("%s{\"bytes\": %zu, \"one_way_s\": %.4e, \"bandwidth_Bps\": %.4e}",
                    s ? ", " : "", n, one_way, n / one_way);
    }
    if (rank == 0) std::printf("]");
  }
  // IPC: rank 0 maps rank 1's buffer.
  cudaIpcMemHandle_t h{};
  if (rank == 1) cudaIpcGetMemHandle(&h, buf);
  MPI_Bcast(&h, sizeof h, MPI_BYTE, 1, MPI_COMM_WORLD);
  char* peer = nullptr;
  const bool mapped =
      rank == 1 || cudaIpcOpenMemHandle(reinterpret_cast<void**>(&peer), h,
                                        cudaIpcMemLazyEnablePeerAccess) == cudaSuccess;
  int ok = mapped ? 1 : 0, all = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (rank == 0) std::printf(", \"ipc_mapped\": %s", all ? "true" : "false");
  if (all) {
    cudaStream_t st;
    cudaStreamCreateWithFlags(&st, cudaStreamNonBlocking);
    if (rank == 0) std::printf(", \"ipc\": [");
    for (size_t s = 0; s < sizeof kSizes / sizeof kSizes[0]; ++s) {
      const size_t n = kSizes[s];
      const int it = iters_for(n);
      double copy = 0, handshake = 0;
      MPI_Barrier(MPI_COMM_WORLD);
      if (rank == 0) {
        double t0 = MPI_Wtime();
        for (int i = 0; i < it; ++i) {
          cudaMemcpyAsync(dst, peer, n, cudaMemcpyDeviceToDevice, st);
          cudaStreamSynchronize(st);
        }
        copy = (MPI_Wtime() - t0) / it;
        t0 = MPI_Wtime();
        for (int i = 0; i < it; ++i) {
          char c = 0;
          MPI_Recv(&c, 1, MPI_BYTE, 1, 2, MPI_COMM_WORLD, MPI_STATUS_IGNORE);  // ready
          cudaMemcpyAsync(dst, peer, n, cudaMemcpyDeviceToDevice, st);
          cudaStreamSynchronize(st);
          MPI_Send(&c, 1, MPI_BYTE, 1, 3, MPI_COMM_WORLD);  // done
        }
        handshake = (MPI_Wtime() - t0) / it;
        std::printf(
            "%s{\"bytes\": %zu, \"copy_s\": %.4e, \"copy_Bps\": %.4e, \"with_handshake_s\": %.4e}",
            s ? ", " : "", n, copy, n / copy, handshake);
      } else {
        for (int i = 0; i < it; ++i) {
          char c = 0;
          MPI_Send(&c, 1, MPI_BYTE, 0, 2, MPI_COMM_WORLD);
          MPI_Recv(&c, 1, MPI_BYTE, 0, 3, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        }
      }
    }
    if (rank == 0) std::printf("]");
    if (rank == 0) cudaIpcCloseMemHandle(peer);
    cudaStreamDestroy(st);
  }
  if (rank == 0) std::printf("}\n");
  cudaFree(buf);
  cudaFree(dst);
  MPI_Finalize();
  return 0;
}
