// Host<->device copy time per message size, pageable and pinned host memory: the staging
// term of scaling/model.py (halos packed on the host cross PCIe twice per exchange).
// Prints one JSON object.   nvcc -O2 -o copybw scaling/probes/copybw.cu && ./copybw
#include <cuda_runtime.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

static double time_copy(void* dst, const void* src, size_t n, cudaMemcpyKind kind, int iters) {
  double best = 1e30;
  for (int rep = 0; rep < 3; ++rep) {
    cudaDeviceSynchronize();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < iters; ++i) cudaMemcpy(dst, src, n, kind);
    cudaDeviceSynchronize();
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / iters;
    if (dt < best) best = dt;
  }
  return best;
}

int main() {
  const size_t sizes[] = {8, 65536, 1 << 20, 16 << 20};
  const size_t max = 16 << 20;
  void *dev, *pinned;
  if (cudaMalloc(&dev, max) != cudaSuccess || cudaMallocHost(&pinned, max) != cudaSuccess) {
    std::fprintf(stderr, "copybw: no GPU\n");
    return 1;
  }
  std::vector<char> pageable(max, 1);
  std::printf("{\"probe\": \"cuda_copy\", \"runs\": [");
  bool first = true;
  for (size_t n : sizes) {
    const int iters = n <= 65536 ? 2000 : (n <= (1u << 20) ? 200 : 20);
    for (int p = 0; p < 2; ++p) {
      void* host = p ? pinned : pageable.data();
      const double d2h = time_copy(host, dev, n, cudaMemcpyDeviceToHost, iters);
      const double h2d = time_copy(dev, host, n, cudaMemcpyHostToDevice, iters);
      std::printf("%s{\"bytes\": %zu, \"host\": \"%s\", \"d2h_s\": %.4e, \"h2d_s\": %.4e, \"d2h_Bps\": %.4e, \"h2d_Bps\": %.4e}",
                  first ? "" : ", ", n, p ? "pinned" : "pageable", d2h, h2d, n / d2h, n / h2d);
      first = false;
    }
  }
  std::printf("]}\n");
  return 0;
}
