#include "mesh/gmsh_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.hpp"
#include "mesh/msh_reader.hpp"

namespace qdemsph {

// ---------------------------------------------------------------- read_gmsh

namespace {

// The path in single quotes. (Built with append: `"'" + std::string` trips GCC 12's -Wrestrict
// false positive.)
std::string quoted(const std::filesystem::path& p) {
  std::string s(1, '\'');
  s.append(p.string());
  s.push_back('\'');
  return s;
}

std::string format_g(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

double signed_volume(const std::vector<Vec3>& p, const std::array<int32_t, 4>& t) {
  const Vec3 x0 = p[t[0]];
  return det(Mat3::from_columns(p[t[1]] - x0, p[t[2]] - x0, p[t[3]] - x0)) / 6.0;
}

}  // namespace

TetMesh tet_mesh_from_gmsh(const std::vector<std::size_t>& node_tags,
                           const std::vector<double>& coords,
                           const std::vector<std::size_t>& elem_tags,
                           const std::vector<std::size_t>& elem_nodes, const std::string& source) {
  if (elem_tags.empty())
    throw InputError(source + ": no linear tetrahedra (gmsh element type 4) found");
  if (elem_nodes.size() != 4 * elem_tags.size() || coords.size() != 3 * node_tags.size())
    throw InputError(source + ": inconsistent node/element data");

  // Nodes sorted by tag; each tet vertex tag is looked up by binary search.
  std::vector<std::pair<std::size_t, std::size_t>> by_tag(node_tags.size());  // (tag, position)
  for (std::size_t i = 0; i < node_tags.size(); ++i) by_tag[i] = {node_tags[i], i};
  std::sort(by_tag.begin(), by_tag.end());
  for (std::size_t i = 1; i < by_tag.size(); ++i)
    if (by_tag[i].first == by_tag[i - 1].first)
      throw InputError(source + ": node tag " + std::to_string(by_tag[i].first) +
                       " is defined twice");
  auto position_of = [&](std::size_t tag, std::size_t elem) -> std::size_t {
    auto it =
        std::lower_bound(by_tag.begin(), by_tag.end(), std::pair<std::size_t, std::size_t>{tag, 0});
    if (it == by_tag.end() || it->first != tag)
      throw InputError(source + ": element " + std::to_string(elem) + " refers to missing node " +
                       std::to_string(tag));
    return static_cast<std::size_t>(it - by_tag.begin());
  };

  // Mark the used nodes (in sorted-tag order), then number them compactly in that order.
  std::vector<std::size_t> sorted_pos(elem_nodes.size());
  std::vector<int64_t> new_index(by_tag.size(), -1);
  for (std::size_t k = 0; k < elem_nodes.size(); ++k) {
    sorted_pos[k] = position_of(elem_nodes[k], elem_tags[k / 4]);
    new_index[sorted_pos[k]] = 0;
  }
  int64_t n_used = 0;
  for (auto& v : new_index)
    if (v == 0) v = n_used++;
  if (n_used > std::numeric_limits<int32_t>::max() ||
      elem_tags.size() > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
    throw InputError(source + ": too large for 32-bit indices");

  TetMesh mesh;
  mesh.points.resize(n_used);
  for (std::size_t s = 0; s < by_tag.size(); ++s)
    if (new_index[s] >= 0) {
      const std::size_t i = by_tag[s].second;
      mesh.points[new_index[s]] = {coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};
    }
  mesh.tets.resize(elem_tags.size());
  for (std::size_t e = 0; e < elem_tags.size(); ++e)
    for (int q = 0; q < 4; ++q)
      mesh.tets[e][q] = static_cast<int32_t>(new_index[sorted_pos[4 * e + q]]);

  // Orientation and degeneracy.
  std::vector<double> vol(mesh.tets.size());
  double mean = 0.0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    vol[e] = signed_volume(mesh.points, mesh.tets[e]);
    if (!std::isfinite(vol[e]))
      throw InputError(source + ": element " + std::to_string(elem_tags[e]) +
                       " has non-finite coordinates");
    mean += std::abs(vol[e]);
  }
  mean /= static_cast<double>(mesh.tets.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    if (!(std::abs(vol[e]) >= 1e-12 * mean) || mean == 0.0)
      throw InputError(source + ": degenerate tetrahedron, element tag " +
                       std::to_string(elem_tags[e]) + " (volume " + format_g(vol[e]) +
                       ", mean volume " + format_g(mean) + ")");
    if (vol[e] < 0) std::swap(mesh.tets[e][1], mesh.tets[e][2]);
  }
  return mesh;
}

TetMesh parse_gmsh(std::string_view bytes, const std::string& source) {
  const MshData d = parse_msh(bytes, source);
  return tet_mesh_from_gmsh(d.node_tags, d.coords, d.tet_tags, d.tet_nodes, source);
}

TetMesh read_gmsh(const std::filesystem::path& path) {
  const std::string source = "mesh file " + quoted(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(source + ": no such file");
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(source + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(source + ": cannot be opened for reading");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(source + ": read error");
  if (bytes.empty()) throw InputError(source + ": empty file");
  return parse_gmsh(bytes, source);
}

// ---------------------------------------------------------------- write_gmsh

void write_gmsh(const std::filesystem::path& path, const TetMesh& mesh) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw InputError("mesh file " + quoted(path) + ": cannot be opened for writing");
  std::FILE* o = f.get();
  const std::size_t n = mesh.points.size(), m = mesh.tets.size();

  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  if (n > 0) lo = hi = mesh.points[0];
  for (const Vec3& p : mesh.points)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }

  std::fprintf(o, "$MeshFormat\n4.1 0 %zu\n$EndMeshFormat\n", sizeof(std::size_t));
  std::fprintf(o, "$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n");
  // numPoints numCurves numSurfaces numVolumes; then the volume: tag box, 1 physical tag (1),
  // 0 bounding surfaces.
  std::fprintf(o, "$Entities\n0 0 0 1\n1 %.17g %.17g %.17g %.17g %.17g %.17g 1 1 0\n$EndEntities\n",
               lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
  // numEntityBlocks numNodes minNodeTag maxNodeTag; block: entityDim entityTag parametric n.
  std::fprintf(o, "$Nodes\n1 %zu %zu %zu\n3 1 0 %zu\n", n, n > 0 ? std::size_t{1} : 0, n, n);
  for (std::size_t i = 0; i < n; ++i) std::fprintf(o, "%zu\n", i + 1);
  for (const Vec3& p : mesh.points) std::fprintf(o, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
  std::fprintf(o, "$EndNodes\n");
  // numEntityBlocks numElements minElementTag maxElementTag; block: dim tag type n.
  std::fprintf(o, "$Elements\n1 %zu %zu %zu\n3 1 4 %zu\n", m, m > 0 ? std::size_t{1} : 0, m, m);
  for (std::size_t e = 0; e < m; ++e) {
    const auto& t = mesh.tets[e];
    std::fprintf(o, "%zu %d %d %d %d\n", e + 1, t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
  }
  std::fprintf(o, "$EndElements\n");
  if (std::ferror(o) || std::fflush(o) != 0)
    throw InputError("mesh file " + quoted(path) + ": write failed");
}

}  // namespace qdemsph
