// A tetrahedral mesh on the host: vertex coordinates and 4 vertex indices per tet
// (positively oriented: det[X1-X0, X2-X0, X3-X0] > 0). The input of a body.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

struct TetMesh {
  std::vector<Vec3> points;
  std::vector<std::array<int32_t, 4>> tets;
};

// A surface triangle of a tet mesh: three vertex indices ordered so that the normal
// (p1-p0) x (p2-p0) points out of the body, plus the owning tet and its local face (0..3,
// the face opposite local vertex `face`).
struct SurfaceTriangle {
  std::array<int32_t, 3> v;
  int32_t tet;
  int32_t face;
};

}  // namespace qdemsph
