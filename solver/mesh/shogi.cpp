#include "mesh/shogi.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "mesh/gmsh_io.hpp"
#include "mesh/gmsh_session.hpp"

namespace qdemsph {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kBaseAngle = 81.0 * kDeg;       // interior angle at the base corners
constexpr double kShoulderAngle = 117.0 * kDeg;  // interior angle at the shoulders
// Target edge length giving about 2,500 tets for the king (measured; see make_shogi_piece).
constexpr double kKingMeshSize = 0.00232;

void check(const ShogiSize& s) {
  if (!(s.height > 0) || !(s.width > 0) || !(s.thickness > 0))
    throw InputError("shogi piece: height, width and thickness must be > 0");
  if (!(s.top_thickness_ratio > 0) || s.top_thickness_ratio > 1)
    throw InputError("shogi piece: top_thickness_ratio must be in (0, 1], got " +
                     std::to_string(s.top_thickness_ratio));
}

double thickness_at(const ShogiSize& s, double z) {
  return s.thickness * (1.0 - (1.0 - s.top_thickness_ratio) * z / s.height);
}

}  // namespace

std::array<std::array<double, 2>, 5> shogi_outline(const ShogiSize& s) {
  check(s);
  // Walking counter-clockwise the direction turns by 180 - 81 deg at a base corner and by
  // 180 - 117 deg at a shoulder, so the sides lean inward at 81 deg from the base and each
  // shoulder-apex edge rises at 81 + 117 - 180 = 18 deg above the horizontal (apex 144 deg).
  const double cot_side = 1.0 / std::tan(kBaseAngle);
  const double top_slope = std::tan(kBaseAngle + kShoulderAngle - std::numbers::pi);  // tan 18
  const double half = 0.5 * s.width;
  // Shoulder (xs, zs): xs = half - zs cot81, apex height h = zs + xs tan18.
  const double zs = (s.height - half * top_slope) / (1.0 - cot_side * top_slope);
  const double xs = half - zs * cot_side;
  if (!(zs > 0) || !(zs < s.height) || !(xs > 0))
    throw InputError("shogi piece: height " + std::to_string(s.height) + " and width " +
                     std::to_string(s.width) +
                     " admit no pentagon with 81 deg base corners and 117 deg shoulders");
  return {{{-half, 0.0}, {half, 0.0}, {xs, zs}, {0.0, s.height}, {-xs, zs}}};
}

double shogi_volume(const ShogiSize& s) {
  // V = integral over the pentagon of t(z) dA = T (A - (1 - r) / h * integral z dA).
  const auto p = shogi_outline(s);
  double area2 = 0, zmoment6 = 0;  // 2 A and 6 * integral z dA (shoelace formulas)
  for (int i = 0; i < 5; ++i) {
    const auto& a = p[i];
    const auto& b = p[(i + 1) % 5];
    const double c = a[0] * b[1] - b[0] * a[1];
    area2 += c;
    zmoment6 += (a[1] + b[1]) * c;
  }
  const double area = 0.5 * area2, zmoment = zmoment6 / 6.0;
  return s.thickness * (area - (1.0 - s.top_thickness_ratio) / s.height * zmoment);
}

double shogi_default_mesh_size(const ShogiSize& s) {
  // Calibrated on the king (about 2,500 tets); the tet count scales like volume / size^3.
  const double king_volume = shogi_volume(ShogiSize::king());
  return kKingMeshSize * std::cbrt(shogi_volume(s) / king_volume);
}

TetMesh make_shogi_piece(const ShogiSize& s, double mesh_size) {
  const auto outline = shogi_outline(s);
  if (mesh_size <= 0) mesh_size = shogi_default_mesh_size(s);
  if (!(mesh_size < s.height))
    throw InputError("shogi piece: mesh size " + std::to_string(mesh_size) +
                     " must be smaller than the height");

  std::vector<std::size_t> node_tags, elem_tags, elem_nodes;
  std::vector<double> coords, param;
  {
    GmshSession session;
    // Options this function sets; their previous values are restored afterwards so that an
    // enclosing session is unaffected.
    const std::pair<const char*, double> options[] = {
        {"General.NumThreads", 1},  // deterministic meshes
        {"Mesh.MeshSizeMin", mesh_size},
        {"Mesh.MeshSizeMax", mesh_size},
        {"Mesh.MeshSizeFromPoints", 0},
        {"Mesh.MeshSizeFromCurvature", 0},
        {"Mesh.MeshSizeExtendFromBoundary", 0},
    };
    std::vector<double> saved;
    auto restore = [&] {
      for (std::size_t i = 0; i < saved.size(); ++i)
        gmsh::option::setNumber(options[i].first, saved[i]);
    };
    try {
      for (const auto& [name, value] : options) {
        double old = 0;
        gmsh::option::getNumber(name, old);
        saved.push_back(old);
        gmsh::option::setNumber(name, value);
      }
      gmsh::model::add("qdemsph_shogi");
      namespace occ = gmsh::model::occ;
      // Corners: back (y < 0) ring 0..4, front (y > 0) ring 5..9.
      int pt[2][5];
      for (int side = 0; side < 2; ++side)
        for (int i = 0; i < 5; ++i) {
          const double x = outline[i][0], z = outline[i][1];
          const double y = (side == 0 ? -0.5 : 0.5) * thickness_at(s, z);
          pt[side][i] = occ::addPoint(x, y, z, mesh_size);
        }
      // Each edge is created once and shared by its two faces, so the shell is closed.
      std::map<std::pair<int, int>, int> edge_line;
      auto line = [&](int a, int b) {
        const auto key = std::minmax(a, b);
        auto it = edge_line.find(key);
        if (it == edge_line.end()) it = edge_line.emplace(key, occ::addLine(a, b)).first;
        return it->second;
      };
      auto face = [&](const std::vector<int>& corners) {
        std::vector<int> lines;
        for (std::size_t i = 0; i < corners.size(); ++i)
          lines.push_back(line(corners[i], corners[(i + 1) % corners.size()]));
        return occ::addPlaneSurface({occ::addCurveLoop(lines)});
      };
      std::vector<int> faces;
      faces.push_back(face({pt[0][0], pt[0][1], pt[0][2], pt[0][3], pt[0][4]}));
      faces.push_back(face({pt[1][0], pt[1][1], pt[1][2], pt[1][3], pt[1][4]}));
      for (int i = 0; i < 5; ++i) {
        const int j = (i + 1) % 5;
        faces.push_back(face({pt[0][i], pt[0][j], pt[1][j], pt[1][i]}));
      }
      occ::addVolume({occ::addSurfaceLoop(faces)});
      occ::synchronize();
      gmsh::model::mesh::generate(3);
      gmsh::model::mesh::getNodes(node_tags, coords, param, -1, -1, false, false);
      gmsh::model::mesh::getElementsByType(4, elem_tags, elem_nodes);
      gmsh::model::remove();
      restore();
    } catch (...) {
      std::string e;
      try {
        gmsh::logger::getLastError(e);
        gmsh::model::remove();
        restore();
      } catch (...) {
      }
      throw InputError("shogi piece: gmsh failed to build or mesh the solid (" +
                       (e.empty() ? std::string("unknown error") : e) + ")");
    }
  }
  return tet_mesh_from_gmsh(node_tags, coords, elem_tags, elem_nodes, "shogi piece");
}

}  // namespace qdemsph
