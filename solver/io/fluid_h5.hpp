// SPH particle snapshots as HDF5 + XDMF 3 point clouds (Polyvertex), beside fields.h5.
//
// DIR/fluid.h5:
//   /steps/<k:06d>/   attributes time (double), step (int64)
//       position (N,3), velocity (N,3), pressure (N), density (N)   doubles
//       type (N) int32: 0 fluid, 1 wall, 2 body marker;  id (N) int64: global particle id
// Particles are stored in the solver's (cell-sorted) order of that frame: use `id` to follow a
// particle across frames. DIR/fluid.xdmf lists the frames written so far (rewritten
// atomically after each frame, the .h5 flushed first).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

class FluidWriter {
 public:
  // resume_frames >= 0 (a restart): continue the existing file after that many frames, as
  // FieldWriter does (io/fields_h5.hpp).
  explicit FluidWriter(const std::filesystem::path& dir, std::int64_t resume_frames = -1);
  ~FluidWriter();
  FluidWriter(const FluidWriter&) = delete;
  FluidWriter& operator=(const FluidWriter&) = delete;

  void write(double time, std::int64_t step, std::span<const Vec3> x, std::span<const Vec3> v,
             std::span<const double> pressure, std::span<const double> density,
             std::span<const std::uint8_t> type, std::span<const std::uint64_t> id);
  std::string xdmf() const;
  std::int64_t frames() const { return static_cast<std::int64_t>(times_.size()); }

 private:
  std::filesystem::path h5_path_, xdmf_path_;
  std::vector<double> times_;
  std::vector<std::size_t> counts_;
  std::int64_t file_ = -1;
};

}  // namespace qdemsph
