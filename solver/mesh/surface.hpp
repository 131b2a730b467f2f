// Surface of a tet mesh: the faces that belong to exactly one tet, oriented outward, plus the
// derived sets contact needs (METHOD.md section 3): surface edges and vertices, a per-tet
// surface flag and a per-face surface-polygon flag.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mesh/tet_mesh.hpp"

namespace qdemsph {

struct SurfaceInfo {
  // Boundary faces, outward oriented, sorted by (tet, face).
  std::vector<SurfaceTriangle> triangles;
  // Unique edges of the surface triangles as (a, b) with a < b, sorted lexicographically.
  std::vector<std::array<int32_t, 2>> edges;
  // Vertices of the surface triangles, sorted and unique.
  std::vector<int32_t> vertices;
  // 1 when one of the tet's edges is a surface edge, so every tet that owns a surface face,
  // plus those touching the surface along an edge only (size = number of tets). This is the
  // report's classification: its 8x8x8 cube has 2,028 surface tets (768 own a surface face).
  std::vector<uint8_t> tet_is_surface;
  // face_is_surface[4 * t + f] = 1 when face f (opposite local vertex f) of tet t is a surface
  // triangle (size = 4 * number of tets).
  std::vector<uint8_t> face_is_surface;
};

// Faces belonging to exactly one tet, each ordered so that (p1-p0) x (p2-p0) points out of the
// body, sorted by (tet, face). O(M log M) in the number of tets M. A face shared by more than
// two tets (non-manifold input) throws InputError.
std::vector<SurfaceTriangle> extract_surface(const TetMesh& mesh);

// extract_surface plus edges, vertices and the per-tet / per-face flags.
SurfaceInfo analyse_surface(const TetMesh& mesh);

}  // namespace qdemsph
