// Field snapshots as HDF5 + XDMF 3, the pair ParaView opens as a time series.
//
// DIR/fields.h5 (serial HDF5, doubles unless noted):
//   /mesh/points  (N,3)   reference vertex positions
//   /mesh/tets    (M,4)   int64 vertex indices per tetrahedron
//   /mesh/body    (N)     int32 body index of each vertex
//   /steps/<k:06d>/       k = 0, 1, 2, ... frame counter; attributes time (double), step (int64)
//       position (N,3), displacement (N,3) = position - /mesh/points, velocity (N,3),
//       stress (M,6) in XDMF Tensor6 order xx,xy,xz,yy,yz,zz (attribute `components` says so),
//       von_mises (M)
// DIR/fields.xdmf lists every frame written so far; it is rewritten atomically after each
// frame (and the .h5 flushed first), so a running or crashed simulation can be opened.
//
// Note on stress order: callers pass Voigt order (xx,yy,zz,yz,xz,xy), the order the physics
// uses; the writer reorders because ParaView reads Tensor6 as xx,xy,xz,yy,yz,zz.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

class FieldWriter {
 public:
  // Creates DIR if needed, DIR/fields.h5 (truncating) with the /mesh group.
  // Throws InputError when the folder is not writable. With resume_frames >= 0 (a restart)
  // the existing file is continued after its first resume_frames frames (later ones are
  // deleted); a file that cannot be continued (damaged by a kill during a write, or of
  // another mesh) is renamed to fields.h5.unreadable, with a warning, and a new one begun.
  FieldWriter(const std::filesystem::path& dir, std::span<const Vec3> points,
              std::span<const std::array<int32_t, 4>> tets, std::span<const int32_t> vertex_body,
              int64_t resume_frames = -1);
  ~FieldWriter();
  FieldWriter(const FieldWriter&) = delete;
  FieldWriter& operator=(const FieldWriter&) = delete;

  // Writes one frame. Sizes must match the mesh: N positions and velocities, M stresses
  // (Voigt order xx,yy,zz,yz,xz,xy) and M von Mises values.
  void write(double time, int64_t step, std::span<const Vec3> positions,
             std::span<const Vec3> velocities, std::span<const std::array<double, 6>> stress,
             std::span<const double> von_mises);

  int frames() const { return static_cast<int>(times_.size()); }
  const std::filesystem::path& h5_path() const { return h5_path_; }
  const std::filesystem::path& xdmf_path() const { return xdmf_path_; }

  // The XDMF text for the frames written so far (exposed for tests).
  std::string xdmf() const;

 private:
  std::filesystem::path h5_path_, xdmf_path_;
  std::vector<Vec3> reference_;
  size_t num_tets_ = 0;
  std::vector<double> times_;
  int64_t file_ = -1;  // hid_t; kept as int64_t so this header does not include hdf5.h
};

}  // namespace qdemsph
