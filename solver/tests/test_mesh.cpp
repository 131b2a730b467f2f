// Tests of the mesh module: box generator, surface extraction, gmsh import/export, shogi
// pieces.
#include <gmsh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <string>

#include "core/error.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh_io.hpp"
#include "mesh/gmsh_session.hpp"
#include "mesh/shogi.hpp"
#include "mesh/surface.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

double tet_volume(const TetMesh& m, const std::array<int32_t, 4>& t) {
  const Vec3 x0 = m.points[t[0]];
  return det(Mat3::from_columns(m.points[t[1]] - x0, m.points[t[2]] - x0, m.points[t[3]] - x0)) /
         6.0;
}

double total_volume(const TetMesh& m) {
  double v = 0;
  for (const auto& t : m.tets) v += tet_volume(m, t);
  return v;
}

Vec3 tri_area_normal(const TetMesh& m, const SurfaceTriangle& s) {  // area * unit normal
  const Vec3 p0 = m.points[s.v[0]];
  return 0.5 * cross(m.points[s.v[1]] - p0, m.points[s.v[2]] - p0);
}

// Number of tets sharing each face (sorted vertex triple).
std::map<std::array<int32_t, 3>, int> face_counts(const TetMesh& m) {
  std::map<std::array<int32_t, 3>, int> c;
  for (const auto& t : m.tets)
    for (int f = 0; f < 4; ++f) {
      std::array<int32_t, 3> k;
      for (int q = 0, j = 0; q < 4; ++q)
        if (q != f) k[j++] = t[q];
      std::sort(k.begin(), k.end());
      ++c[k];
    }
  return c;
}

int euler_characteristic(const SurfaceInfo& s) {
  return static_cast<int>(s.vertices.size()) - static_cast<int>(s.edges.size()) +
         static_cast<int>(s.triangles.size());
}

// A fresh temporary directory per test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("qdemsph_test_mesh_" + std::string(info->name()) + "_" +
            std::to_string(std::hash<std::string>{}(fs::current_path().string()) % 100000));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  fs::path operator/(const std::string& name) const { return dir_ / name; }

 private:
  fs::path dir_;
};

// ------------------------------------------------------------------------------ box

TEST(Box, ReportCubeCounts) {
  const TetMesh m = make_box({0, 0, 0}, {0.05, 0.05, 0.05}, {8, 8, 8});
  EXPECT_EQ(m.tets.size(), 6144u);
  EXPECT_EQ(m.points.size(), 1241u);
  const SurfaceInfo s = analyse_surface(m);
  EXPECT_EQ(s.vertices.size(), 386u);
  // The report's Fig. 7 study: 2,028 surface tets per cube.
  EXPECT_EQ(std::count(s.tet_is_surface.begin(), s.tet_is_surface.end(), 1), 2028);
  EXPECT_EQ(s.triangles.size(), 6u * 64 * 2);
  EXPECT_EQ(std::count(s.face_is_surface.begin(), s.face_is_surface.end(), 1), 768);
}

TEST(Box, VolumeAndPositiveOrientation) {
  const Vec3 size{0.3, 0.2, 0.7};
  const TetMesh m = make_box({-1, 2, 0.5}, size, {3, 2, 4});
  double v = 0;
  for (const auto& t : m.tets) {
    const double vt = tet_volume(m, t);
    EXPECT_GT(vt, 0.0);
    v += vt;
  }
  EXPECT_NEAR(v, size.x * size.y * size.z, 1e-12);
  EXPECT_NEAR(total_volume(make_box({0, 0, 0}, {1, 1, 1}, {8, 8, 8})), 1.0, 1e-12);
}

TEST(Box, VertexNumberingGridFirstThenCentres) {
  const TetMesh m = make_box({0, 0, 0}, {3, 2, 1}, {3, 2, 1});
  ASSERT_EQ(m.points.size(), 4u * 3 * 2 + 6);
  EXPECT_DOUBLE_EQ(m.points[1].x, 1.0);  // i fastest
  EXPECT_DOUBLE_EQ(m.points[4].y, 1.0);
  EXPECT_DOUBLE_EQ(m.points[12].z, 1.0);
  EXPECT_DOUBLE_EQ(m.points[24].x, 0.5);  // first centre
  EXPECT_DOUBLE_EQ(m.points[24].y, 0.5);
  EXPECT_DOUBLE_EQ(m.points[24].z, 0.5);
  EXPECT_DOUBLE_EQ(m.points[25].x, 1.5);
}

TEST(Box, ConformingInteriorFaces) {
  const TetMesh m = make_box({0, 0, 0}, {1, 1, 1}, {3, 2, 4});
  const auto counts = face_counts(m);
  std::size_t boundary = 0;
  for (const auto& [face, n] : counts) {
    EXPECT_TRUE(n == 1 || n == 2) << "face shared by " << n << " tets";
    if (n == 1) {
      ++boundary;
      // A face seen once must lie on the box boundary (otherwise hexes do not conform).
      bool on_plane = false;
      for (int d = 0; d < 3; ++d) {
        const double c0 = m.points[face[0]][d];
        const bool same = c0 == m.points[face[1]][d] && c0 == m.points[face[2]][d];
        on_plane |= same && (c0 == 0.0 || c0 == 1.0);
      }
      EXPECT_TRUE(on_plane);
    }
  }
  EXPECT_EQ(boundary, 2u * 2 * (3 * 2 + 2 * 4 + 3 * 4));
}

TEST(Box, RejectsBadInput) {
  EXPECT_THROW(make_box({0, 0, 0}, {1, 0, 1}, {1, 1, 1}), InputError);
  EXPECT_THROW(make_box({0, 0, 0}, {1, 1, 1}, {1, 0, 1}), InputError);
}

// -------------------------------------------------------------------------- surface

TEST(Surface, BoxAreaNormalsEuler) {
  const Vec3 size{1.0, 2.0, 0.5};
  const TetMesh m = make_box({0, 0, 0}, size, {3, 2, 4});
  const SurfaceInfo s = analyse_surface(m);
  double area = 0;
  Vec3 sum{0, 0, 0};
  const Vec3 centre = 0.5 * size;
  for (const auto& tri : s.triangles) {
    const Vec3 an = tri_area_normal(m, tri);
    area += norm(an);
    sum += an;
    const Vec3 c = (m.points[tri.v[0]] + m.points[tri.v[1]] + m.points[tri.v[2]]) / 3.0;
    EXPECT_GT(dot(an, c - centre), 0.0);
    // The owning tet and face are consistent: the face is opposite local vertex `face`.
    const auto& t = m.tets[tri.tet];
    for (int q = 0; q < 3; ++q) EXPECT_NE(tri.v[q], t[tri.face]);
    EXPECT_EQ(s.face_is_surface[4 * tri.tet + tri.face], 1);
  }
  EXPECT_NEAR(area, 2 * (size.x * size.y + size.y * size.z + size.x * size.z), 1e-12);
  EXPECT_NEAR(norm(sum), 0.0, 1e-12);
  EXPECT_EQ(euler_characteristic(s), 2);
  EXPECT_TRUE(std::is_sorted(s.edges.begin(), s.edges.end()));
  EXPECT_TRUE(std::adjacent_find(s.edges.begin(), s.edges.end()) == s.edges.end());
  for (const auto& e : s.edges) EXPECT_LT(e[0], e[1]);
  EXPECT_TRUE(std::is_sorted(s.vertices.begin(), s.vertices.end()));
  EXPECT_EQ(s.tet_is_surface.size(), m.tets.size());
  EXPECT_EQ(s.face_is_surface.size(), 4 * m.tets.size());
  // Every surface edge is shared by exactly two surface triangles (closed 2-manifold).
  std::map<std::array<int32_t, 2>, int> edge_use;
  for (const auto& tri : s.triangles)
    for (int q = 0; q < 3; ++q)
      ++edge_use[{std::min(tri.v[q], tri.v[(q + 1) % 3]), std::max(tri.v[q], tri.v[(q + 1) % 3])}];
  for (const auto& [e, n] : edge_use) EXPECT_EQ(n, 2);
}

TEST(Surface, CubeNormalsPointAwayFromCentre) {
  const TetMesh m = make_box({-0.5, -0.5, -0.5}, {1, 1, 1}, {2, 2, 2});
  for (const auto& tri : extract_surface(m)) {
    const Vec3 an = tri_area_normal(m, tri);
    const Vec3 c = (m.points[tri.v[0]] + m.points[tri.v[1]] + m.points[tri.v[2]]) / 3.0;
    EXPECT_GT(dot(an, c), 0.0);
  }
}

TEST(Surface, SingleTetAndNegativeOrientation) {
  TetMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{0, 1, 2, 3}};
  auto s = analyse_surface(m);
  EXPECT_EQ(s.triangles.size(), 4u);
  EXPECT_EQ(euler_characteristic(s), 2);
  m.tets = {{0, 2, 1, 3}};  // negatively oriented: normals must still point outward
  for (const auto& tri : extract_surface(m)) {
    const Vec3 c = (m.points[tri.v[0]] + m.points[tri.v[1]] + m.points[tri.v[2]]) / 3.0;
    EXPECT_GT(dot(tri_area_normal(m, tri), c - Vec3{0.25, 0.25, 0.25}), 0.0);
  }
}

// ------------------------------------------------------------------------- gmsh i/o

TEST(GmshIo, RoundTrip) {
  TempDir tmp;
  const TetMesh m = make_box({0.1, -0.2, 0.3}, {0.7, 0.11, 1.3}, {3, 2, 4});
  const fs::path p = tmp / "box.msh";
  write_gmsh(p, m);
  const TetMesh r = read_gmsh(p);
  ASSERT_EQ(r.points.size(), m.points.size());
  ASSERT_EQ(r.tets.size(), m.tets.size());
  for (std::size_t i = 0; i < m.points.size(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(r.points[i][d], m.points[i][d]);
  for (std::size_t e = 0; e < m.tets.size(); ++e) EXPECT_EQ(r.tets[e], m.tets[e]);
  // A second read works too (gmsh state is cleaned up between calls).
  EXPECT_EQ(read_gmsh(p).tets.size(), m.tets.size());
}

TEST(GmshIo, FileLayoutIsMsh41) {
  TempDir tmp;
  const fs::path p = tmp / "one.msh";
  TetMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{0, 1, 2, 3}};
  write_gmsh(p, m);
  std::ifstream in(p);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* s : {"$MeshFormat\n4.1 0 8\n$EndMeshFormat", "$PhysicalNames\n1\n3 1 \"body\"",
                        "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n$EndEntities",
                        "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n",
                        "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements"})
    EXPECT_NE(text.find(s), std::string::npos) << s;
}

TEST(GmshIo, ReorientsNegativeTetsDropsUnusedNodesAndIgnoresOtherElements) {
  TempDir tmp;
  const fs::path p = tmp / "hand.msh";
  std::ofstream(p) << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                      "$Entities\n1 0 0 1\n3 5 5 5 0\n7 0 0 0 1 1 1 0 0\n$EndEntities\n"
                      "$Nodes\n1 6 2 20\n3 7 0 6\n20\n2\n5\n9\n11\n12\n"
                      "0 0 1\n0 0 0\n1 0 0\n0 1 0\n5 5 5\n1 1 1\n$EndNodes\n"
                      "$Elements\n2 2 1 42\n3 7 4 1\n42 2 9 5 20\n0 3 15 1\n1 11\n$EndElements\n";
  const TetMesh m = read_gmsh(p);
  ASSERT_EQ(m.points.size(), 4u);  // tags 2, 5, 9, 20 (11 only in a point element, 12 unused)
  EXPECT_EQ(m.points[0].x, 0.0);   // tag 2
  EXPECT_EQ(m.points[1].x, 1.0);   // tag 5
  EXPECT_EQ(m.points[2].y, 1.0);   // tag 9
  EXPECT_EQ(m.points[3].z, 1.0);   // tag 20
  ASSERT_EQ(m.tets.size(), 1u);
  EXPECT_NEAR(tet_volume(m, m.tets[0]), 1.0 / 6.0, 1e-15);
}

void expect_input_error(const fs::path& p, const std::string& needle) {
  try {
    read_gmsh(p);
    ADD_FAILURE() << "no InputError for " << p;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
  }
}

TEST(GmshIo, Errors) {
  TempDir tmp;
  const fs::path good = tmp / "good.msh";
  write_gmsh(good, make_box({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
  std::ifstream in(good, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  expect_input_error(tmp / "missing.msh", "no such file");

  for (std::size_t cut : {text.size() / 3, text.size() - 40}) {
    const fs::path p = tmp / ("truncated_" + std::to_string(cut) + ".msh");
    std::ofstream(p, std::ios::binary) << text.substr(0, cut);
    expect_input_error(p, "truncated");
  }

  const fs::path garbage = tmp / "garbage.msh";
  {
    std::ofstream out(garbage, std::ios::binary);
    uint32_t x = 12345;
    for (int i = 0; i < 400; ++i) {
      x = x * 1664525u + 1013904223u;
      out.put(static_cast<char>(x >> 24));
    }
  }
  expect_input_error(garbage, "corrupt");

  const fs::path words = tmp / "words.msh";
  std::ofstream(words) << "this is not a mesh\n";
  expect_input_error(words, "corrupt");

  const fs::path empty = tmp / "empty.msh";
  std::ofstream{empty};
  expect_input_error(empty, "empty file");

  const fs::path tris = tmp / "triangles.msh";
  std::ofstream(tris) << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                         "$Entities\n0 0 1 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n"
                         "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n"
                         "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
  expect_input_error(tris, "no linear tetrahedra");

  // A flat tet among good ones: the message names its element tag (97).
  TetMesh m = make_box({0, 0, 0}, {1, 1, 1}, {2, 2, 2});
  m.points.push_back({0.5, 0.5, 2.0});
  m.points.push_back({0.6, 0.5, 2.0});
  m.points.push_back({0.5, 0.6, 2.0});
  m.points.push_back({0.6, 0.6, 2.0});
  const auto n = static_cast<int32_t>(m.points.size());
  m.tets.push_back({n - 4, n - 3, n - 2, n - 1});
  const fs::path flat = tmp / "flat.msh";
  write_gmsh(flat, m);
  expect_input_error(flat, "element tag 97");

  // After all these failures gmsh still reads a good file.
  EXPECT_EQ(read_gmsh(good).tets.size(), 96u);
}

// ---------------------------------------------------------------------------- shogi

double interior_angle_deg(const std::array<double, 2>& prev, const std::array<double, 2>& at,
                          const std::array<double, 2>& next) {
  const double ax = prev[0] - at[0], az = prev[1] - at[1];
  const double bx = next[0] - at[0], bz = next[1] - at[1];
  return std::acos((ax * bx + az * bz) / (std::hypot(ax, az) * std::hypot(bx, bz))) * 180.0 /
         std::acos(-1.0);
}

TEST(Shogi, OutlineAngles) {
  for (const ShogiSize& s : {ShogiSize::king(), ShogiSize::pawn(), ShogiSize::lance()}) {
    const auto p = shogi_outline(s);
    const double expected[5] = {81, 81, 117, 144, 117};
    for (int i = 0; i < 5; ++i)
      EXPECT_NEAR(interior_angle_deg(p[(i + 4) % 5], p[i], p[(i + 1) % 5]), expected[i], 1e-9);
    EXPECT_DOUBLE_EQ(p[1][0] - p[0][0], s.width);
    EXPECT_DOUBLE_EQ(p[3][1], s.height);
  }
  EXPECT_THROW(shogi_outline({0.01, 0.1, 0.005, 0.6}), InputError);  // too wide for the angles
}

void check_piece(const ShogiSize& s, const TetMesh& m) {
  EXPECT_GE(m.tets.size(), 2000u);
  EXPECT_LE(m.tets.size(), 3500u);
  for (const auto& t : m.tets) EXPECT_GT(tet_volume(m, t), 0.0);
  EXPECT_NEAR(total_volume(m) / shogi_volume(s), 1.0, 1e-6);  // planar faces: exact
  const SurfaceInfo surf = analyse_surface(m);
  EXPECT_EQ(euler_characteristic(surf), 2);
  Vec3 lo = m.points[0], hi = m.points[0];
  for (const Vec3& p : m.points)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  const double eps = 1e-12;
  EXPECT_NEAR(lo.x, -0.5 * s.width, eps);
  EXPECT_NEAR(hi.x, 0.5 * s.width, eps);
  EXPECT_NEAR(lo.y, -0.5 * s.thickness, eps);
  EXPECT_NEAR(hi.y, 0.5 * s.thickness, eps);
  EXPECT_NEAR(lo.z, 0.0, eps);
  EXPECT_NEAR(hi.z, s.height, eps);
  // The apex vertex exists, with the thinner top: the thickness there is ratio * base.
  double apex_half = 0;
  for (const Vec3& p : m.points)
    if (std::abs(p.z - s.height) < eps) apex_half = std::max(apex_half, std::abs(p.y));
  EXPECT_NEAR(2 * apex_half, s.top_thickness_ratio * s.thickness, eps);
  // Closed outward surface: area-weighted normals sum to zero.
  Vec3 sum{0, 0, 0};
  for (const auto& tri : surf.triangles) sum += tri_area_normal(m, tri);
  EXPECT_LT(norm(sum), 1e-12);
}

TEST(Shogi, KingAndPawnMeshes) {
  check_piece(ShogiSize::king(), make_shogi_piece(ShogiSize::king()));
  check_piece(ShogiSize::pawn(), make_shogi_piece(ShogiSize::pawn()));
}

TEST(Shogi, DeterministicAndNestedInsideAGmshSession) {
  const TetMesh a = make_shogi_piece(ShogiSize::king());
  TempDir tmp;
  {
    GmshSession outer;  // gmsh stays initialised across the calls below
    gmsh::option::setNumber("Mesh.MeshSizeMax", 7.0);
    const TetMesh b = make_shogi_piece(ShogiSize::king());
    double size_max = 0;
    gmsh::option::getNumber("Mesh.MeshSizeMax", size_max);
    EXPECT_EQ(size_max, 7.0);  // the caller's options are restored
    EXPECT_EQ(a.tets, b.tets);
    write_gmsh(tmp / "king.msh", b);
    EXPECT_EQ(read_gmsh(tmp / "king.msh").tets, b.tets);
  }
  EXPECT_EQ(make_shogi_piece(ShogiSize::king()).tets.size(), a.tets.size());
}

TEST(Shogi, RejectsBadSizes) {
  EXPECT_THROW(make_shogi_piece({-0.03, 0.028, 0.01, 0.6}), InputError);
  EXPECT_THROW(make_shogi_piece({0.03, 0.028, 0.01, 1.5}), InputError);
  EXPECT_THROW(make_shogi_piece(ShogiSize::king(), 1.0), InputError);
}

}  // namespace
}  // namespace qdemsph
