#include "mesh/surface.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"

namespace qdemsph {

namespace {

// Local vertex triples of the face opposite vertex f, outward for a positively oriented tet.
constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
  std::array<int32_t, 3> v;  // sorted vertex indices
  int32_t tet_face;          // 4 * tet + face
  bool operator<(const FaceKey& o) const { return v != o.v ? v < o.v : tet_face < o.tet_face; }
};

}  // namespace

std::vector<SurfaceTriangle> extract_surface(const TetMesh& mesh) {
  const auto n_tets = static_cast<int32_t>(mesh.tets.size());
  std::vector<FaceKey> keys(4 * mesh.tets.size());
  for (int32_t t = 0; t < n_tets; ++t)
    for (int f = 0; f < 4; ++f) {
      FaceKey& k = keys[4 * t + f];
      for (int q = 0; q < 3; ++q) k.v[q] = mesh.tets[t][kFaceVertices[f][q]];
      std::sort(k.v.begin(), k.v.end());
      k.tet_face = 4 * t + f;
    }
  std::sort(keys.begin(), keys.end());

  std::vector<SurfaceTriangle> out;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j].v == keys[i].v) ++j;
    if (j - i > 2)
      throw InputError("extract_surface: face (" + std::to_string(keys[i].v[0]) + ", " +
                       std::to_string(keys[i].v[1]) + ", " + std::to_string(keys[i].v[2]) +
                       ") is shared by " + std::to_string(j - i) +
                       " tets (non-manifold mesh); first tet " +
                       std::to_string(keys[i].tet_face / 4));
    if (j - i == 1) {
      const int32_t t = keys[i].tet_face / 4, f = keys[i].tet_face % 4;
      const auto& tv = mesh.tets[t];
      SurfaceTriangle s{
          {tv[kFaceVertices[f][0]], tv[kFaceVertices[f][1]], tv[kFaceVertices[f][2]]}, t, f};
      // Robust to a negatively oriented tet: the normal must point away from the opposite vertex.
      const Vec3 p0 = mesh.points[s.v[0]];
      const Vec3 n = cross(mesh.points[s.v[1]] - p0, mesh.points[s.v[2]] - p0);
      if (dot(n, mesh.points[tv[f]] - p0) > 0) std::swap(s.v[1], s.v[2]);
      out.push_back(s);
    }
    i = j;
  }
  std::sort(out.begin(), out.end(), [](const SurfaceTriangle& a, const SurfaceTriangle& b) {
    return a.tet != b.tet ? a.tet < b.tet : a.face < b.face;
  });
  return out;
}

SurfaceInfo analyse_surface(const TetMesh& mesh) {
  SurfaceInfo s;
  s.triangles = extract_surface(mesh);
  s.tet_is_surface.assign(mesh.tets.size(), 0);
  s.face_is_surface.assign(4 * mesh.tets.size(), 0);
  s.edges.reserve(3 * s.triangles.size());
  s.vertices.reserve(3 * s.triangles.size());
  for (const SurfaceTriangle& tri : s.triangles) {
    s.face_is_surface[4 * tri.tet + tri.face] = 1;
    for (int q = 0; q < 3; ++q) {
      const int32_t a = tri.v[q], b = tri.v[(q + 1) % 3];
      s.edges.push_back({std::min(a, b), std::max(a, b)});
      s.vertices.push_back(a);
    }
  }
  std::sort(s.edges.begin(), s.edges.end());
  s.edges.erase(std::unique(s.edges.begin(), s.edges.end()), s.edges.end());
  std::sort(s.vertices.begin(), s.vertices.end());
  s.vertices.erase(std::unique(s.vertices.begin(), s.vertices.end()), s.vertices.end());
  // A tet is a surface tet when one of its 6 edges is a surface edge (this includes every tet
  // with a surface face; the report's cube has 2,028 such tets).
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const auto& v = mesh.tets[t];
    for (int a = 0; a < 4 && !s.tet_is_surface[t]; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const std::array<int32_t, 2> e{std::min(v[a], v[b]), std::max(v[a], v[b])};
        if (std::binary_search(s.edges.begin(), s.edges.end(), e)) {
          s.tet_is_surface[t] = 1;
          break;
        }
      }
  }
  return s;
}

}  // namespace qdemsph
