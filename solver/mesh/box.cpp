#include "mesh/box.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>

#include "core/error.hpp"

namespace qdemsph {

namespace {

double signed_volume6(const TetMesh& m, const std::array<int32_t, 4>& t) {
  const Vec3 x0 = m.points[t[0]];
  return det(Mat3::from_columns(m.points[t[1]] - x0, m.points[t[2]] - x0, m.points[t[3]] - x0));
}

}  // namespace

TetMesh make_box(Vec3 origin, Vec3 size, std::array<int, 3> cells) {
  for (int d = 0; d < 3; ++d) {
    if (!(size[d] > 0.0))
      throw InputError("make_box: size[" + std::to_string(d) + "] must be > 0, got " +
                       std::to_string(size[d]));
    if (cells[d] < 1)
      throw InputError("make_box: cells[" + std::to_string(d) + "] must be >= 1, got " +
                       std::to_string(cells[d]));
  }
  const int64_t nx = cells[0], ny = cells[1], nz = cells[2];
  const int64_t n_grid = (nx + 1) * (ny + 1) * (nz + 1);
  const int64_t n_hex = nx * ny * nz;
  if (n_grid + n_hex > std::numeric_limits<int32_t>::max() || 12 * n_hex > (int64_t{1} << 31) - 1)
    throw InputError("make_box: too many cells for 32-bit vertex indices");

  TetMesh m;
  m.points.reserve(n_grid + n_hex);
  m.tets.reserve(12 * n_hex);
  const Vec3 h{size.x / nx, size.y / ny, size.z / nz};

  auto node = [&](int64_t i, int64_t j, int64_t k) {
    return static_cast<int32_t>(i + (nx + 1) * (j + (ny + 1) * k));
  };
  for (int64_t k = 0; k <= nz; ++k)
    for (int64_t j = 0; j <= ny; ++j)
      for (int64_t i = 0; i <= nx; ++i)
        m.points.push_back({origin.x + i * h.x, origin.y + j * h.y, origin.z + k * h.z});
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i)
        m.points.push_back(
            {origin.x + (i + 0.5) * h.x, origin.y + (j + 0.5) * h.y, origin.z + (k + 0.5) * h.z});

  // The 6 faces of a unit hex as 4 corners in cyclic order; corner c = (cx, cy, cz) bits.
  static constexpr int kFaces[6][4][3] = {
      {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},  // x-
      {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}},  // x+
      {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}},  // y-
      {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}},  // y+
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},  // z-
      {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},  // z+
  };
  int32_t centre = static_cast<int32_t>(n_grid);
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i, ++centre)
        for (const auto& face : kFaces) {
          std::array<int32_t, 4> c;
          for (int q = 0; q < 4; ++q) c[q] = node(i + face[q][0], j + face[q][1], k + face[q][2]);
          // Diagonal through the corner with the smallest global index: both hexes sharing
          // this face see the same four indices, hence the same split.
          const int s = static_cast<int>(std::min_element(c.begin(), c.end()) - c.begin());
          const int32_t a = c[s], b = c[(s + 1) % 4], d = c[(s + 2) % 4], e = c[(s + 3) % 4];
          for (std::array<int32_t, 4> t :
               {std::array<int32_t, 4>{a, b, d, centre}, std::array<int32_t, 4>{a, d, e, centre}}) {
            if (signed_volume6(m, t) < 0) std::swap(t[1], t[2]);
            m.tets.push_back(t);
          }
        }
  return m;
}

}  // namespace qdemsph
