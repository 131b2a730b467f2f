#include "core/gpu_info.hpp"

#include <cstdio>

namespace qdemsph {

std::string gpu_summary(const GpuInfo& g) {
  if (!g.available) return "no GPU: " + g.why;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s (sm_%d%d, %d SMs): %.1f GiB free of %.1f GiB", g.name.c_str(),
                g.cc_major, g.cc_minor, g.sm_count, g.free_bytes / 1073741824.0,
                g.total_bytes / 1073741824.0);
  return buf;
}

#ifndef QDEMSPH_HAVE_CUDA
GpuInfo gpu_info() {
  GpuInfo g;
  g.why = "this qdemsph was built without the CUDA backend";
  return g;
}
double gpu_copy_bandwidth(std::size_t, int) { return 0.0; }
#endif

}  // namespace qdemsph
