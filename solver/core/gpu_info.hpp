// What the GPU offers, for `qdemsph info` / `version`, benchmarks and run summaries.
// Plain C++ (no CUDA headers): defined in memory_cuda.cu, or in gpu_info.cpp when the CUDA
// backend is not built (then available = false and `why` says so).
#pragma once

#include <cstddef>
#include <string>

namespace qdemsph {

struct GpuInfo {
  bool available = false;
  std::string why;   // when not available: the reason
  std::string name;  // e.g. "NVIDIA H100 80GB HBM3"
  int device = 0;    // CUDA device index in use
  int device_count = 0;
  int sm_count = 0;
  int cc_major = 0, cc_minor = 0;
  std::size_t total_bytes = 0, free_bytes = 0;  // device memory, at the time of the call
  int runtime_version = 0, driver_version = 0;  // e.g. 13000
};

GpuInfo gpu_info();

// Device-to-device cudaMemcpy bandwidth in bytes/s, counting bytes read plus bytes written
// (2 x size per copy), best of `reps` copies of `bytes`; 0 without a GPU. The roofline that
// benchmarks compare their achieved bandwidth against.
double gpu_copy_bandwidth(std::size_t bytes, int reps);

// One line for people: "NVIDIA H100 80GB HBM3 (sm_90, 132 SMs): 79.1 GiB free of 79.6 GiB"
// or "no GPU: <why>".
std::string gpu_summary(const GpuInfo& g);

}  // namespace qdemsph
